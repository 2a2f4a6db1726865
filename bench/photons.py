#!/usr/bin/env python3
"""Convergence tables of the photon-mapping family against the references (issue 22).

usage: bench/photons.py [--penumbra BIN] [--out DIR] [--iterations 16 64 256 1024]

For `mitsuba-cbox` and `cbox-specular` (128², their references in ../shared/references):
SPPM and PPM at each iteration count, the photon mapper with final gathering, and the path
tracer; each row gives the wall time, relMSE and the image mean over the reference's, per
channel. Then the caustic under the glass sphere of `cbox-specular` (a crop): SPPM at 256
iterations against the path tracer given the same wall time (`--time`).

Needs numpy and OpenEXR (bench/.venv, see bench/README.md). Run on a quiet machine.
"""

import argparse
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
try:
    import numpy as np
    import OpenEXR
    import Imath
except ImportError:
    venv = ROOT / "bench" / ".venv" / "bin" / "python"
    if venv.exists() and Path(sys.executable) != venv:
        sys.exit(subprocess.call([str(venv), __file__, *sys.argv[1:]]))
    raise

SCENES = {
    "mitsuba-cbox": "scenes/standard/mitsuba-cbox/cbox-rgb.xml",
    "cbox-specular": "references/scenes/cbox-specular.xml",
}
# Rows × columns of the caustic under the glass sphere (128² image of cbox-specular).
CAUSTIC = (slice(100, 110), slice(30, 52))


def read(path):
    f = OpenEXR.InputFile(str(path))
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    return np.stack(
        [np.frombuffer(f.channel(c, pt), dtype=np.float32).reshape(h, w) for c in "RGB"], -1
    ).astype(np.float64)


def rel_mse(a, r):
    return float(np.mean((a - r) ** 2 / (r**2 + 0.01)))


def run(binary, scene, out, args):
    cmd = [binary, "render", str(scene), "-q", "-D", "res=128", "-o", str(out), *args]
    t = time.perf_counter()
    subprocess.run(cmd, check=True)
    return time.perf_counter() - t


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--penumbra", default=str(ROOT / "target" / "release" / "penumbra"))
    p.add_argument("--out", default="/tmp/penumbra-photons")
    p.add_argument("--shared", default=str(ROOT.parent / "shared"))
    p.add_argument("--iterations", type=int, nargs="+", default=[16, 64, 256, 1024])
    a = p.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    shared = Path(a.shared)
    print("| scene | integrator | iterations / spp | wall | relMSE | mean / reference (R, G, B) |")
    print("|---|---|---|---|---|---|")
    for name, rel in SCENES.items():
        scene = shared / rel
        ref = read(shared / "references" / f"{name}.exr")
        rows = []
        for kind in ["sppm", "ppm"]:
            for n in a.iterations:
                img = out / f"{name}-{kind}-{n}.exr"
                wall = run(a.penumbra, scene, img, ["--integrator", kind, "--spp", str(n)])
                rows.append((kind, n, wall, read(img)))
        img = out / f"{name}-photon.exr"
        wall = run(a.penumbra, scene, img, ["--integrator", "photon:1000000,16", "--spp", "16"])
        rows.append(("photon, 10⁶ photons, 16 gather rays", 16, wall, read(img)))
        img = out / f"{name}-path.exr"
        wall = run(a.penumbra, scene, img, ["--spp", "256"])
        rows.append(("path", 256, wall, read(img)))
        for kind, n, wall, im in rows:
            ratio = im.mean((0, 1)) / ref.mean((0, 1))
            print(
                f"| {name} | {kind} | {n} | {wall:.2f} s | {rel_mse(im, ref):.2e} | "
                + " / ".join(f"{x:.4f}" for x in ratio)
                + " |"
            )
    # The caustic: SPPM against the path tracer at equal wall time.
    name = "cbox-specular"
    scene = shared / SCENES[name]
    ref = read(shared / "references" / f"{name}.exr")[CAUSTIC]
    img = out / "caustic-sppm.exr"
    wall = run(a.penumbra, scene, img, ["--integrator", "sppm", "--spp", "256"])
    sppm = rel_mse(read(img)[CAUSTIC], ref)
    img = out / "caustic-path.exr"
    wall_pt = run(a.penumbra, scene, img, ["--spp", "1000000", "--time", f"{wall:.2f}"])
    path = rel_mse(read(img)[CAUSTIC], ref)
    print()
    print(f"caustic crop (rows {CAUSTIC[0].start}-{CAUSTIC[0].stop}, cols "
          f"{CAUSTIC[1].start}-{CAUSTIC[1].stop}): SPPM 256 iterations {wall:.2f} s relMSE "
          f"{sppm:.3e}; path tracer {wall_pt:.2f} s relMSE {path:.3e} ({path / sppm:.2f}×)")


if __name__ == "__main__":
    main()
