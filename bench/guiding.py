#!/usr/bin/env python3
"""Path guiding (issue 42): time × relMSE of guided against unguided path tracing.

Not a test (no timing in tests) and not run by CI. Usage, from the repository root, after
`cargo build --release -p penumbra`:

    python3 bench/guiding.py [--bin PATH] [--spp 256] [--runs 3] [--ref-spp 8192] [--scenes ...]

For every scene it renders the unguided and the guided path tracer (`--guiding on`) at the
same spp, `--runs` times each with different seeds, alternating, on one thread, and measures
the CPU time of each render process (user + system, from wait4: robust to other load on the
machine) and its relMSE against a reference, as `penumbra compare` computes it (mean over
pixels and channels of (test − ref)² / (ref² + 0.01), `../shared/references/README.md`). The
figure of merit is time × relMSE (lower is better; independent of the spp for an unbiased
estimator at fixed cost per sample); the table gives its mean over the runs and the ratio
unguided / guided (> 1: guiding helps).

References: `door-ajar` (scenes/guiding/door-ajar.xml, the scene lit through a gap) against our
own high-spp render (unguided, `--ref-spp`, made once and kept in /tmp/penumbra-guiding/);
`mitsuba-cbox`, `veach-plates`, `lights`, `cbox-specular` against Mitsuba 3's references in
../shared/references (skipped when absent).
"""
from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("SHARED", ROOT.parent / "shared"))
WORK = Path("/tmp/penumbra-guiding")

# name -> (scene file, defines, reference prefix or None for our own)
SCENES = {
    "door-ajar": (ROOT / "scenes/guiding/door-ajar.xml", [], None),
    "mitsuba-cbox": (
        SHARED / "scenes/standard/mitsuba-cbox/cbox-rgb.xml",
        ["res=128"],
        SHARED / "references/mitsuba-cbox",
    ),
    "veach-plates": (
        SHARED / "references/scenes/veach-plates.xml",
        [],
        SHARED / "references/veach-plates",
    ),
    "lights": (SHARED / "references/scenes/lights.xml", [], SHARED / "references/lights"),
    "cbox-specular": (
        SHARED / "references/scenes/cbox-specular.xml",
        [],
        SHARED / "references/cbox-specular",
    ),
}


def run_timed(cmd: list[str]) -> float:
    """Runs `cmd`, returns its CPU time (user + system) in seconds."""
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, ru = os.wait4(p.pid, 0)
    err = p.stderr.read().decode() if p.stderr else ""
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{err}")
    return ru.ru_utime + ru.ru_stime


def render(binary, scene, defines, spp, seed, guided, out: Path, threads=1) -> float:
    cmd = [binary, "render", str(scene), "--spp", str(spp), "--seed", str(seed),
           "--threads", str(threads), "-q", "-o", str(out), "--stderr",
           str(out.with_suffix(".stderr.exr"))]
    for d in defines:
        cmd += ["-D", d]
    if guided:
        cmd += ["--guiding", "on"]
    return run_timed(cmd)


def rel_mse(binary, ref_prefix: Path, test: Path) -> float:
    r = subprocess.run(
        [binary, "compare", str(ref_prefix) + ".exr", str(test), "--stderr",
         str(test.with_suffix(".stderr.exr"))],
        capture_output=True, text=True)
    m = re.search(r"relMSE=([0-9.eE+-]+)", r.stdout + r.stderr)
    if not m:
        sys.exit(f"no relMSE in compare's output:\n{r.stdout}{r.stderr}")
    return float(m.group(1))


def main() -> None:
    ap = argparse.ArgumentParser()
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    ap.add_argument("--bin", default=str(target / "release/penumbra"))
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--ref-spp", type=int, default=8192)
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    a = ap.parse_args()
    WORK.mkdir(parents=True, exist_ok=True)
    rows = []
    for name in a.scenes:
        scene, defines, ref = SCENES[name]
        if not scene.exists():
            print(f"{name}: {scene} absent, skipped")
            continue
        if ref is None:
            ref = WORK / f"{name}-ref-{a.ref_spp}"
            if not ref.with_suffix(".exr").exists():
                print(f"{name}: rendering the reference ({a.ref_spp} spp, 2 threads)...",
                      flush=True)
                t = render(a.bin, scene, defines, a.ref_spp, 999, False,
                           ref.with_suffix(".exr"), threads=2)
                print(f"{name}: reference took {t:.0f} s CPU", flush=True)
        res = {False: [], True: []}
        for run in range(a.runs):
            for guided in (False, True):
                out = WORK / f"{name}-{'g' if guided else 'u'}-{run}.exr"
                t = render(a.bin, scene, defines, a.spp, 1 + run, guided, out)
                e = rel_mse(a.bin, ref, out)
                res[guided].append((t, e))
                print(f"{name} {'guided  ' if guided else 'unguided'} run {run}: "
                      f"{t:.2f} s, relMSE {e:.4e}, time×relMSE {t * e:.4e}", flush=True)
        summary = {}
        for g in (False, True):
            ts = [t for t, _ in res[g]]
            es = [e for _, e in res[g]]
            summary[g] = (statistics.mean(ts), statistics.mean(es))
        (tu, eu), (tg, eg) = summary[False], summary[True]
        rows.append((name, tu, eu, tg, eg, (tu * eu) / (tg * eg)))
    print()
    print(f"{a.spp} spp, {a.runs} runs each, 1 thread, CPU seconds")
    print(f"{'scene':14} {'unguided s':>10} {'relMSE':>10} {'guided s':>9} {'relMSE':>10} "
          f"{'time×relMSE unguided/guided':>28}")
    for name, tu, eu, tg, eg, r in rows:
        print(f"{name:14} {tu:10.2f} {eu:10.3e} {tg:9.2f} {eg:10.3e} {r:28.2f}")


if __name__ == "__main__":
    main()
