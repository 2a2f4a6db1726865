#!/usr/bin/env python3
"""Bitterli's pbrt-v4 scenes against their Tungsten references (issue 37).

Renders each `../shared/scenes/standard/bitterli-*/pbrt/scene-v4.pbrt` with penumbra at a
quarter of the reference's resolution (`--res`), 256 spp by default, and compares it with
`TungstenRender.exr` box-filtered 4×4 to that size: the ratio of the image means per channel
and the relMSE (mean of (x − r)² / (r² + 0.01), the metric of
`../shared/references/imgcmp.py`). Tungsten used path length 65 where the shipped pbrt files
say otherwise; `--max-depth` sets both alike (default 65). Pixels where the reference is not finite are left
out of both images' figures.

    python3 bench/bitterli.py                       # all four scenes
    python3 bench/bitterli.py --scenes coffee --spp 64
"""

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench  # noqa: E402  (venv, shared folder, EXR reading)

SCENES = ["cornell-box", "veach-mis", "coffee", "water-caustic"]


def ensure_venv() -> None:
    """Re-execute this script with bench/.venv's python (made by bench.py) when numpy or
    OpenEXR is missing here."""
    try:
        import numpy  # noqa: F401
        import OpenEXR  # noqa: F401
    except ImportError:
        py = bench.VENV / "bin" / "python"
        if not py.exists():
            sys.exit("bitterli: run bench/bench.py once first (it sets up bench/.venv)")
        os.execv(str(py), [str(py), str(Path(__file__).resolve()), *sys.argv[1:]])


def main() -> None:
    ensure_venv()
    import numpy as np

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", choices=SCENES, default=SCENES)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--max-depth", type=int, default=65)
    ap.add_argument("--factor", type=int, default=4, help="resolution divisor")
    ap.add_argument("--penumbra", default=str(bench.REPO / "target/release/penumbra"))
    ap.add_argument("--out", default=str(bench.BENCH_DIR / "out" / "bitterli"))
    ap.add_argument("--shared", default=None)
    args = ap.parse_args()
    shared = bench.find_shared(args.shared)
    if shared is None:
        print("bitterli: ../shared not found; nothing to do")
        return
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    k = args.factor
    print("| scene | resolution | spp | time | mean ratio R G B | relMSE |")
    print("|---|---|---|---|---|---|")
    for name in args.scenes:
        d = shared / "scenes" / "standard" / f"bitterli-{name}" / "pbrt"
        ref = bench.read_exr_rgb(d / "TungstenRender.exr")
        h, w = ref.shape[0] // k, ref.shape[1] // k
        ref = ref[: h * k, : w * k].reshape(h, k, w, k, 3).mean(axis=(1, 3))
        img = out / f"{name}.exr"
        cmd = [args.penumbra, "render", str(d / "scene-v4.pbrt"), "--res", f"{w}x{h}",
               "--spp", str(args.spp), "--max-depth", str(args.max_depth), "-q", "-o", str(img)]
        t0 = time.perf_counter()
        r = subprocess.run(cmd, capture_output=True, text=True)
        dt = time.perf_counter() - t0
        if r.returncode != 0:
            print(f"| {name} | failed: {r.stderr.strip()[:200]} |")
            continue
        warn = [l for l in r.stderr.splitlines() if "warning" in l]
        x = bench.read_exr_rgb(img)
        # Tungsten's water-caustic has infinite pixels: both images are compared where the
        # reference is finite.
        ok = np.isfinite(ref).all(-1)
        ratio = x[ok].mean(0) / ref[ok].mean(0)
        rel = float(np.mean((x[ok] - ref[ok]) ** 2 / (ref[ok] ** 2 + 1e-2)))
        print(f"| {name} | {w}×{h} | {args.spp} | {dt:.1f} s | "
              f"{ratio[0]:.4f} {ratio[1]:.4f} {ratio[2]:.4f} | {rel:.3e} |"
              + (f" {len(warn)} warning(s): {warn[0][:120]}" if warn else ""))


if __name__ == "__main__":
    main()
