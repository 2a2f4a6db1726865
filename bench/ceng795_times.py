#!/usr/bin/env python3
"""Parse and render times of every CENG795 scene under ../shared/scenes/ceng795 (json and xml),
as the course's write-ups give them. Not run by CI.

    python3 bench/ceng795_times.py [--threads 2] [--budget 90] [--no-build] [--only SUBSTRING]

Every camera of every scene is rendered at the scene's own settings (resolution, NumSamples)
by the release binary, one process per camera (`render --sensor I -o OUT.exr`), with
`--threads 2` by default. Figures per camera:

- parse: the `parsed ... in X s` line of `penumbra render` (reading the file, PLY meshes and
  images, building the scene description);
- build: the `built the scene ... in X s` line (BVH, lights, textures);
- render: the `rendered N spp in X s` line (wall clock of the sampling passes);
- wall / CPU: the whole process, wall clock (perf_counter) and user + system CPU of the child
  (os.wait4), so that a machine shared with other jobs can be judged by CPU time too;
- load: the 1-minute load average when the camera started (os.getloadavg).

A camera is first rendered at 1 spp (a probe). If the full render would take longer than
`--budget` seconds it is rendered at a reduced sample count N that fits the budget; the
render time is then extrapolated in proportion to spp, the process wall time by adding the
missing render time, the CPU time in the same proportion as the render time; the table says
so ("extrapolated from N spp").
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared" / "scenes" / "ceng795"
BIN = REPO / "target" / "release" / "penumbra"

SENSOR = re.compile(r"sensor (\d+):.*?(\d+)x(\d+), \w+ (\d+) spp")
PARSED = re.compile(r"parsed .* in ([0-9.]+) s")
BUILT = re.compile(r"built the scene .* in ([0-9.]+) s")
RENDERED = re.compile(r"rendered (\d+) spp in ([0-9.]+) s")


def run(args: list[str]) -> dict:
    """Runs one process; returns wall, cpu, rc, stderr text."""
    t0 = time.perf_counter()
    p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    err = p.stderr.read().decode(errors="replace")
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    return {
        "wall": wall,
        "cpu": ru.ru_utime + ru.ru_stime,
        "rc": p.returncode,
        "err": err,
    }


def figures(r: dict) -> dict:
    def one(rx):
        m = rx.search(r["err"])
        return float(m.group(m.lastindex)) if m else float("nan")

    return {"parse": one(PARSED), "build": one(BUILT), "render": one(RENDERED), **r}


def render(scene: Path, sensor: int, spp: int, out: Path, threads: int) -> dict:
    return figures(
        run(
            [str(BIN), "render", str(scene), "--sensor", str(sensor), "--spp", str(spp),
             "--threads", str(threads), "--seed", "1", "-o", str(out)]
        )
    )


def last_error(text: str) -> str:
    lines = [l for l in text.strip().splitlines() if "warning" not in l]
    return (lines[-1] if lines else text.strip()).replace("|", "\\|")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--budget", type=float, default=90.0, help="seconds per camera before extrapolating")
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--only", default="", help="only scenes whose path contains this")
    a = ap.parse_args()
    if not SHARED.is_dir():
        sys.exit(f"{SHARED} is absent")
    if not a.no_build:
        subprocess.run(["cargo", "build", "--release", "-p", "penumbra"], cwd=REPO, check=True)
    scenes = sorted(p for p in SHARED.rglob("*") if p.suffix in (".json", ".xml") and a.only in str(p))
    out_dir = Path(tempfile.mkdtemp(prefix="ceng795-times-"))
    print(f"machine: {os.cpu_count()} CPUs, load average at start {os.getloadavg()}, "
          f"--threads {a.threads}, budget {a.budget:g} s per camera", file=sys.stderr)
    rows = []
    t_start = time.time()
    for scene in scenes:
        name = str(scene.relative_to(SHARED))
        info = subprocess.run([str(BIN), "info", str(scene)], capture_output=True, text=True)
        sensors = [tuple(int(g) for g in m.groups()) for m in SENSOR.finditer(info.stdout)]
        if info.returncode != 0 or not sensors:
            rows.append(f"| {name} | – | – | – | – | – | – | – | – | – | load error: "
                        f"{last_error(info.stderr)} |")
            print(rows[-1], file=sys.stderr)
            continue
        for sensor, w, h, spp in sensors:
            load = os.getloadavg()[0]
            out = out_dir / f"{name.replace('/', '_')}-{sensor}.exr"
            probe = render(scene, sensor, 1, out, a.threads)
            if probe["rc"] != 0:
                rows.append(f"| {name} | {sensor} | {w}x{h} | {spp} | – | – | – | – | – | {load:.2f} | "
                            f"render error: {last_error(probe['err'])} |")
                print(rows[-1], file=sys.stderr)
                continue
            per_spp = max(probe["render"], 1e-6)
            note = ""
            if spp == 1:
                r = probe
                render_t, wall, cpu = r["render"], r["wall"], r["cpu"]
            else:
                n = spp if per_spp * spp <= a.budget else max(2, int(a.budget / per_spp))
                n = min(n, spp)
                r = render(scene, sensor, n, out, a.threads)
                render_t, wall, cpu = r["render"], r["wall"], r["cpu"]
                if n < spp:
                    # Render time in proportion to spp; the process pays the extra render
                    # time on top of what it measured, its CPU time in the same proportion
                    # (parsing and building take milliseconds).
                    render_t = r["render"] * spp / n
                    wall = r["wall"] + render_t - r["render"]
                    cpu = r["cpu"] * render_t / max(r["render"], 1e-9)
                    note = (f"extrapolated from {n} spp (render {r['render']:.1f} s, "
                            f"CPU {r['cpu']:.1f} s)")
            rows.append(
                f"| {name} | {sensor} | {w}x{h} | {spp} | {r['parse']:.3f} | {r['build']:.3f} | "
                f"{render_t:.2f} | {wall:.2f} | {cpu:.2f} | {load:.2f} | {note} |"
            )
            print(rows[-1], file=sys.stderr)
    print(f"# CENG795 scene times ({os.cpu_count()} CPUs, --threads {a.threads}, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime(t_start))}, "
          f"{time.time() - t_start:.0f} s in all)\n")
    print("| scene | camera | resolution | spp | parse (s) | build (s) | render (s) | wall (s) | "
          "CPU (s) | load | note |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(r)


if __name__ == "__main__":
    main()
