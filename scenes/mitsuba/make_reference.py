#!/usr/bin/env python3
"""Render a Mitsuba 3 reference for one scene of `scenes/mitsuba/` (issue 38).

The rule is `../shared/references/README.md`'s: 32 independent batches (seeds 1000-1031),
their mean written as `refs/NAME.exr` and the standard error of that mean (spread of the
batch means / sqrt(32)) as `refs/NAME.stderr.exr`; both linear float32 RGB, so
`render::compare::load_reference` reads them as it reads the shared references. The
noise-parity figure (relMSE of one more 256-spp render, seed 2000, against the mean) and
the exact command go to `refs/NAME.json`, which the tests read.

    python3 scenes/mitsuba/make_reference.py scenes/mitsuba/principled.xml \
        [--spp 512] [--variant llvm_ad_rgb] [-D key=value ...] [--name NAME]

Needs `pip install mitsuba numpy` (and LLVM >= 16 for the llvm variants: `apt-get install
llvm-19`, found through DRJIT_LIBLLVM_PATH or the usual places).
"""

import argparse
import glob
import json
import os
import sys

import numpy as np

BATCHES = 32
SEED0 = 1000
PARITY_SPP = 256
PARITY_SEED = 2000


def find_llvm():
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return
    for pattern in ("/usr/lib/llvm-*/lib/libLLVM*.so*", "/usr/lib/x86_64-linux-gnu/libLLVM*.so*"):
        for path in sorted(glob.glob(pattern), reverse=True):
            os.environ["DRJIT_LIBLLVM_PATH"] = path
            return


def rel_mse(test, ref):
    return float(np.mean((test - ref) ** 2 / (ref**2 + 0.01)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--spp", type=int, default=512, help="samples per pixel of one batch")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("-D", dest="defines", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--name", help="reference name (default: the scene's file stem)")
    ap.add_argument("--batches", type=int, default=BATCHES)
    args = ap.parse_args()

    find_llvm()
    import mitsuba as mi

    mi.set_variant(args.variant)
    defines = dict(d.split("=", 1) for d in args.defines)
    scene = mi.load_file(args.scene, **defines)
    name = args.name or os.path.splitext(os.path.basename(args.scene))[0]
    out_dir = os.path.join(os.path.dirname(os.path.abspath(__file__)), "refs")
    os.makedirs(out_dir, exist_ok=True)

    means = []
    for b in range(args.batches):
        img = np.array(mi.render(scene, spp=args.spp, seed=SEED0 + b), dtype=np.float64)[..., :3]
        means.append(img)
        print(f"batch {b + 1}/{args.batches}", file=sys.stderr, flush=True)
    stack = np.stack(means)
    mean = stack.mean(axis=0)
    stderr = stack.std(axis=0, ddof=1) / np.sqrt(args.batches)
    parity = np.array(mi.render(scene, spp=PARITY_SPP, seed=PARITY_SEED), dtype=np.float64)[..., :3]

    for suffix, data in ((".exr", mean), (".stderr.exr", stderr)):
        mi.Bitmap(data.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(
            os.path.join(out_dir, name + suffix)
        )
    meta = {
        "scene": os.path.relpath(os.path.abspath(args.scene), os.path.dirname(out_dir)),
        "defines": defines,
        "variant": args.variant,
        "mitsuba": mi.__version__,
        "batches": args.batches,
        "spp_per_batch": args.spp,
        "seeds": [SEED0, SEED0 + args.batches - 1],
        "resolution": [int(mean.shape[1]), int(mean.shape[0])],
        "relmse_256spp": rel_mse(parity, mean),
        "command": "python3 scenes/mitsuba/make_reference.py " + " ".join(sys.argv[1:]),
    }
    with open(os.path.join(out_dir, name + ".json"), "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")
    print(json.dumps(meta, indent=1))


if __name__ == "__main__":
    main()
