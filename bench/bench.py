#!/usr/bin/env python3
"""Penumbra vs Mitsuba 3: wall time, CPU time and error on the reference scenes.

Not run by CI. See bench/README.md. Usage (from anywhere):

    python3 bench/bench.py [--runs 3] [--spp 1024] [--bench-spp 64] [--renderers ...]

Every render is a whole process (scene loading, BVH/JIT compilation, rendering, EXR output),
timed for wall clock (perf_counter) and CPU (user + system of the child, from wait4). Runs
alternate between renderers (A B C A B C ...) so that a change in machine load hits all of
them alike; the table shows the median of the runs. relMSE against the Mitsuba references
in ../shared/references is mean over pixels and channels of (test - ref)^2 / (ref^2 + 0.01),
as in ../shared/references/imgcmp.py.

The script sets up what it needs: a venv in bench/.venv with numpy and OpenEXR (it re-runs
itself inside it), `cargo build --release -p penumbra`, and libllvm19 through apt when the
Mitsuba LLVM variant would otherwise have no LLVM >= 16 (only when running as root).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

BENCH_DIR = Path(__file__).resolve().parent
REPO = BENCH_DIR.parent
VENV = BENCH_DIR / ".venv"
VENV_PACKAGES = ["numpy", "OpenEXR"]

# name -> (scene path relative to shared/, defines for both renderers, reference relative to
# shared/ or None, spp option name). "spp" is filled in from --spp / --bench-spp.
SCENES = {
    "cbox-specular": ("references/scenes/cbox-specular.xml", {"res": "128"},
                      "references/cbox-specular.exr", "spp"),
    "mitsuba-cbox": ("scenes/standard/mitsuba-cbox/cbox-rgb.xml", {"res": "128"},
                     "references/mitsuba-cbox.exr", "spp"),
    "bench-cbox": ("references/scenes/bench-cbox.xml", {"resx": "512", "resy": "512"},
                   "references/bench-cbox.exr", "bench_spp"),
    # A real interior (issue 36): Bitterli's classroom, Mitsuba form, 104k triangles, no
    # reference image (relMSE left blank).
    "classroom": ("scenes/bench/classroom/scene.xml", {"resx": "640", "resy": "360"},
                  None, "classroom_spp"),
    # Volumetric path tracing (issue 20): both renderers run the scenes' `volpath`.
    "media-homogeneous": ("references/scenes/media-homogeneous.xml", {"res": "128"},
                          "references/media-homogeneous.exr", "media_spp"),
    "media-heterogeneous": ("references/scenes/media-heterogeneous.xml", {"res": "128"},
                            "references/media-heterogeneous.exr", "media_spp"),
    "media-fog": ("references/scenes/media-fog.xml", {"res": "128"},
                  "references/media-fog.exr", "media_spp"),
    # Spectral rendering (issue 21): penumbra --mode spectral against Mitsuba's *_spectral
    # variant of each Mitsuba renderer asked for (llvm_ad_rgb -> llvm_ad_spectral, ...).
    "mitsuba-cbox-spectral": ("scenes/standard/mitsuba-cbox/cbox-rgb.xml", {"res": "128"},
                              "references/mitsuba-cbox-spectral.exr", "spp"),
    "spectral-materials": ("references/scenes/spectral-materials.xml", {"res": "128"},
                           "references/spectral-materials.exr", "spp"),
}

# Scenes both renderers render in their spectral mode.
SPECTRAL = {"mitsuba-cbox-spectral", "spectral-materials"}

RENDERERS = ["penumbra", "mitsuba-llvm_ad_rgb", "mitsuba-scalar_rgb"]


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------- environment

def ensure_venv() -> None:
    """Re-execute this script with bench/.venv's python once numpy and OpenEXR are in it."""
    if os.environ.get("PENUMBRA_BENCH_IN_VENV") == "1":
        return
    py = VENV / "bin" / "python"
    if not py.exists():
        log(f"setting up {VENV} (numpy, OpenEXR)")
        if subprocess.run([sys.executable, "-m", "venv", str(VENV)]).returncode != 0:
            shutil.rmtree(VENV, ignore_errors=True)
            sys.exit("bench: `python3 -m venv` failed (on Debian/Ubuntu: apt-get install python3-venv)")
    probe = subprocess.run([str(py), "-c", "import numpy, OpenEXR"], capture_output=True)
    if probe.returncode != 0:
        subprocess.run([str(py), "-m", "pip", "install", "--quiet", "--upgrade", "pip"], check=True)
        subprocess.run([str(py), "-m", "pip", "install", "--quiet", *VENV_PACKAGES], check=True)
    env = dict(os.environ, PENUMBRA_BENCH_IN_VENV="1")
    os.execve(str(py), [str(py), str(Path(__file__).resolve()), *sys.argv[1:]], env)


def find_shared(explicit: str | None) -> Path | None:
    """The shared folder: --shared, $PENUMBRA_SHARED, REPO/../shared, or the main checkout's
    ../shared when REPO is a git worktree."""
    cands = []
    if explicit:
        cands.append(Path(explicit))
    if os.environ.get("PENUMBRA_SHARED"):
        cands.append(Path(os.environ["PENUMBRA_SHARED"]))
    cands.append(REPO.parent / "shared")
    try:
        common = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--path-format=absolute",
                                 "--git-common-dir"], capture_output=True, text=True, check=True)
        cands.append(Path(common.stdout.strip()).parent.parent / "shared")
    except (OSError, subprocess.CalledProcessError):
        pass
    for c in cands:
        if (c / "references").is_dir():
            return c.resolve()
    return None


def find_libllvm() -> str | None:
    """A libLLVM >= 16 for Dr.Jit's LLVM backend (Mitsuba's llvm_* variants)."""
    env = os.environ.get("DRJIT_LIBLLVM_PATH")
    if env and Path(env).exists():
        return env
    for ver in range(22, 15, -1):
        for p in (f"/usr/lib/llvm-{ver}/lib/libLLVM-{ver}.so", f"/usr/lib/llvm-{ver}/lib/libLLVM.so",
                  f"/usr/lib/x86_64-linux-gnu/libLLVM-{ver}.so",
                  f"/usr/lib/aarch64-linux-gnu/libLLVM-{ver}.so",
                  f"/usr/lib/x86_64-linux-gnu/libLLVM.so.{ver}.1",
                  f"/usr/lib/aarch64-linux-gnu/libLLVM.so.{ver}.1"):
            if Path(p).exists():
                return p
    return None


def ensure_libllvm() -> str | None:
    lib = find_libllvm()
    if lib or not shutil.which("apt-get") or os.geteuid() != 0:
        return lib
    log("no libLLVM >= 16 found: apt-get install libllvm19")
    try:
        subprocess.run(["apt-get", "update", "-qq"], check=True)
        subprocess.run(["apt-get", "install", "-y", "-qq", "libllvm19"], check=True,
                       env=dict(os.environ, DEBIAN_FRONTEND="noninteractive"))
    except subprocess.CalledProcessError as e:
        log(f"apt-get failed ({e}); the LLVM variant will be skipped")
        return None
    lib = find_libllvm()
    if lib is None and shutil.which("dpkg"):
        out = subprocess.run(["dpkg", "-L", "libllvm19"], capture_output=True, text=True).stdout
        libs = [line for line in out.split() if "libLLVM" in line and ".so" in line]
        lib = libs[0] if libs else None
    return lib


def mitsuba_variants(mitsuba: str) -> set[str]:
    out = subprocess.run([mitsuba, "--help"], capture_output=True, text=True)
    return {w.strip() for w in (out.stdout + out.stderr).split() if w.strip().endswith("_rgb")}


# --------------------------------------------------------------------------- images

def read_exr_rgb(path: Path):
    import numpy as np
    import OpenEXR
    if hasattr(OpenEXR, "File"):  # OpenEXR >= 3.3 bindings
        with OpenEXR.File(str(path), separate_channels=True) as f:
            ch = f.channels()
            if all(c in ch for c in "RGB"):
                planes = [ch[c].pixels for c in "RGB"]
            else:  # interleaved "RGB"/"RGBA"
                key = next(k for k in ch if k.startswith("RGB"))
                planes = [ch[key].pixels[..., i] for i in range(3)]
            return np.stack(planes, -1).astype(np.float64)
    import Imath
    f = OpenEXR.InputFile(str(path))
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    return np.stack([np.frombuffer(f.channel(c, pt), np.float32).reshape(h, w)
                     for c in "RGB"], -1).astype(np.float64)


def relmse(test: Path, ref: Path) -> float | None:
    import numpy as np
    x, r = read_exr_rgb(test), read_exr_rgb(ref)
    if x.shape != r.shape:
        log(f"  {test.name}: size {x.shape} != reference {r.shape}, no relMSE")
        return None
    if not np.all(np.isfinite(x)):
        log(f"  {test.name}: non-finite pixels, no relMSE")
        return None
    return float(np.mean((x - r) ** 2 / (r ** 2 + 1e-2)))


# --------------------------------------------------------------------------- running

def timed_run(cmd: list[str], env: dict, log_path: Path) -> tuple[float, float, float, int]:
    """Run cmd; return (wall s, CPU s = user + sys of the child, max RSS MiB, exit code)."""
    with open(log_path, "w") as lf:
        lf.write(" ".join(cmd) + "\n")
        lf.flush()
        t0 = time.perf_counter()
        p = subprocess.Popen(cmd, stdout=lf, stderr=subprocess.STDOUT, env=env)
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    return wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024.0, p.returncode


def command(renderer: str, exe: dict, scene: Path, defines: dict, spp: int, out: Path,
            threads: int | None, spectral: bool = False) -> list[str]:
    if renderer == "penumbra":
        cmd = [exe["penumbra"], "render", str(scene), "-q", "--spp", str(spp), "-o", str(out)]
        if spectral:
            cmd += ["--mode", "spectral"]
        for k, v in defines.items():
            cmd += ["-D", f"{k}={v}"]
        if threads:
            cmd += ["--threads", str(threads)]
        return cmd
    variant = renderer.split("-", 1)[1]
    if spectral:
        variant = variant.replace("_rgb", "_spectral")
    cmd = [exe["mitsuba"], "-m", variant, "-D", f"spp={spp}", "-o", str(out)]
    for k, v in defines.items():
        cmd += ["-D", f"{k}={v}"]
    if threads:
        cmd += ["-t", str(threads)]
    return cmd + [str(scene)]


def fmt(x: float | None, spec: str) -> str:
    return "—" if x is None else format(x, spec)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", "-n", type=int, default=3, help="timed runs per scene and renderer (median)")
    ap.add_argument("--spp", type=int, default=1024, help="spp of the 128x128 scenes")
    ap.add_argument("--bench-spp", type=int, default=64, help="spp of bench-cbox (512x512)")
    ap.add_argument("--classroom-spp", type=int, default=32, help="spp of classroom (640x360)")
    ap.add_argument("--media-spp", type=int, default=256, help="spp of the media scenes (128x128)")
    ap.add_argument("--scenes", nargs="+", choices=list(SCENES), default=list(SCENES))
    ap.add_argument("--renderers", nargs="+", choices=RENDERERS, default=RENDERERS)
    ap.add_argument("--threads", type=int, help="threads for both renderers (default: each one's own)")
    ap.add_argument("--warmup", type=int, default=1,
                    help="untimed rounds first (Dr.Jit kernel cache, page cache); default 1")
    ap.add_argument("--shared", help="the shared folder (default: ../shared of the checkout)")
    ap.add_argument("--penumbra", help="penumbra binary (default: build target/release/penumbra)")
    ap.add_argument("--no-build", action="store_true", help="do not run cargo build")
    ap.add_argument("--out", default=str(BENCH_DIR / "out"), help="images, logs, results.json")
    args = ap.parse_args()

    shared = find_shared(args.shared)
    if shared is None:
        print("bench: ../shared (references and scenes) not found; nothing to do. "
              "Pass --shared DIR or set PENUMBRA_SHARED.")
        return 0
    ensure_venv()

    exe: dict[str, str] = {}
    env = dict(os.environ)
    env.pop("PENUMBRA_BENCH_IN_VENV", None)
    renderers = list(args.renderers)
    if "penumbra" in renderers:
        if args.penumbra:
            exe["penumbra"] = args.penumbra
        else:
            if not args.no_build:
                log("cargo build --release -p penumbra")
                subprocess.run(["cargo", "build", "--release", "-p", "penumbra", "-j1"],
                               cwd=REPO, check=True)
            exe["penumbra"] = str(REPO / "target" / "release" / "penumbra")
    mits = [r for r in renderers if r.startswith("mitsuba-")]
    if mits:
        m = shutil.which("mitsuba")
        if m is None:
            log("bench: no `mitsuba` command (pip install mitsuba); Mitsuba skipped")
            renderers = [r for r in renderers if not r.startswith("mitsuba-")]
        else:
            exe["mitsuba"] = m
            have = mitsuba_variants(m)
            for r in mits:
                if r.split("-", 1)[1] not in have:
                    log(f"bench: mitsuba has no variant {r.split('-', 1)[1]}; skipped")
                    renderers.remove(r)
            if "mitsuba-llvm_ad_rgb" in renderers:
                lib = ensure_libllvm()
                if lib is None:
                    log("bench: no libLLVM >= 16 (apt-get install libllvm19 and set "
                        "DRJIT_LIBLLVM_PATH); llvm_ad_rgb skipped")
                    renderers.remove("mitsuba-llvm_ad_rgb")
                else:
                    env["DRJIT_LIBLLVM_PATH"] = lib
    if not renderers:
        print("bench: no renderer to run")
        return 1

    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    mversion = ""
    if "mitsuba" in exe:
        mv = subprocess.run([exe["mitsuba"], "--help"], capture_output=True, text=True)
        mversion = (mv.stdout + mv.stderr).splitlines()[0] if (mv.stdout + mv.stderr) else ""
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    log(f"shared: {shared}\nrenderers: {', '.join(renderers)}\nmitsuba: {mversion}\n"
        f"penumbra: {exe.get('penumbra', '-')} @ {commit}\nLLVM: {env.get('DRJIT_LIBLLVM_PATH', '-')}")

    jobs = []  # (scene name, renderer, cmd, out image)
    for name in args.scenes:
        rel, defines, _, spp_key = SCENES[name]
        spp = getattr(args, spp_key)
        for r in renderers:
            img = out_dir / f"{name}.{r}.exr"
            cmd = command(r, exe, shared / rel, defines, spp, img, args.threads, name in SPECTRAL)
            jobs.append((name, r, cmd, img))

    load_before = os.getloadavg()
    samples: dict[tuple[str, str], list[tuple[float, float, float]]] = {}
    failed: set[tuple[str, str]] = set()
    total_rounds = args.warmup + args.runs
    for rnd in range(total_rounds):
        warm = rnd < args.warmup
        for name, r, cmd, img in jobs:
            if (name, r) in failed:
                continue
            tag = "warm-up" if warm else f"run {rnd - args.warmup + 1}/{args.runs}"
            logp = out_dir / f"{name}.{r}.log"
            wall, cpu, rss, rc = timed_run(cmd, env, logp)
            if rc != 0:
                log(f"  {name:14} {r:20} {tag}: FAILED (exit {rc}), see {logp}")
                failed.add((name, r))
                continue
            log(f"  {name:14} {r:20} {tag}: wall {wall:7.2f} s  cpu {cpu:7.2f} s  "
                f"rss {rss:6.0f} MiB  load {os.getloadavg()[0]:.2f}")
            if not warm:
                samples.setdefault((name, r), []).append((wall, cpu, rss))
    load_after = os.getloadavg()

    # ---- table
    rows = []
    for name in args.scenes:
        _, _, ref_rel, spp_key = SCENES[name]
        ref = shared / ref_rel if ref_rel else None
        base = samples.get((name, "penumbra"))
        pw = statistics.median(s[0] for s in base) if base else None
        pc = statistics.median(s[1] for s in base) if base else None
        for r in renderers:
            s = samples.get((name, r))
            if not s:
                continue
            wall = statistics.median(x[0] for x in s)
            cpu = statistics.median(x[1] for x in s)
            rss = max(x[2] for x in s)
            img = out_dir / f"{name}.{r}.exr"
            err = relmse(img, ref) if ref and ref.exists() else None
            rows.append(dict(scene=name, renderer=r, spp=getattr(args, spp_key), runs=len(s),
                             wall=wall, cpu=cpu, rss_mib=rss, relmse=err,
                             wall_ratio=(pw / wall) if (pw and r != "penumbra") else None,
                             cpu_ratio=(pc / cpu) if (pc and r != "penumbra") else None,
                             walls=[x[0] for x in s], cpus=[x[1] for x in s]))

    hdr = ("| scene | renderer | spp | wall (median) | CPU (median) | penumbra/this wall "
           "| penumbra/this CPU | relMSE | wall × relMSE |")
    print(f"\nmedian of {args.runs} run(s) per row (+{args.warmup} untimed warm-up round(s)); "
          f"load average before {load_before[0]:.2f} {load_before[1]:.2f}, "
          f"after {load_after[0]:.2f} {load_after[1]:.2f}; {os.cpu_count()} CPUs "
          f"({platform.processor() or platform.machine()})\n")
    print(hdr)
    print("|---|---|---|---|---|---|---|---|---|")
    for row in rows:
        wr = row["relmse"] * row["wall"] if row["relmse"] is not None else None
        print(f"| {row['scene']} | {row['renderer']} | {row['spp']} | {row['wall']:.2f} s "
              f"| {row['cpu']:.2f} s | {fmt(row['wall_ratio'], '.2f')} | {fmt(row['cpu_ratio'], '.2f')} "
              f"| {fmt(row['relmse'], '.3g')} | {fmt(wr, '.3g')} |")
    for name, r in sorted(failed):
        print(f"| {name} | {r} | FAILED (see {out_dir / f'{name}.{r}.log'}) |||||||")

    res = dict(commit=commit, mitsuba=mversion, load_before=load_before, load_after=load_after,
               cpus=os.cpu_count(), runs=args.runs, warmup=args.warmup, threads=args.threads,
               rows=rows, failed=sorted(failed))
    (out_dir / "results.json").write_text(json.dumps(res, indent=2))
    print(f"\nimages, logs and results.json in {out_dir}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
