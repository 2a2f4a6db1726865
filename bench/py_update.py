#!/usr/bin/env python3
"""Reload vs `scene.update` on the classroom (104k triangles, issue 40's acceptance: an
update takes < 10 % of a reload).

Each measure is the time to the next image: a reload is `load_file` (parse, read the meshes)
plus the first render (which builds: textures decoded, BVH built); an update is
`scene.update` plus the next render (which rebuilds what the edit made stale and reuses the
rest). The render itself is made negligible (a 16x16 image at 1 spp) and is the same on both
sides. Medians of `--runs` repetitions, after one warm-up of each.

    python3 bench/py_update.py [--scene ../shared/scenes/bench/classroom/scene.xml] [--runs 7]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import penumbra

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT.parent / "shared" / "scenes" / "bench" / "classroom" / "scene.xml"
TINY = dict(spp=1, resolution=(16, 16), seed=0)


def timed(f) -> float:
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", type=Path, default=DEFAULT)
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--threads", type=int, default=None)
    args = ap.parse_args()
    if not args.scene.is_file():
        raise SystemExit(f"{args.scene} is absent (the shared scenes)")
    kw = dict(TINY, threads=args.threads)

    def reload() -> None:
        s = penumbra.load_file(args.scene)
        penumbra.render(s, **kw)

    scene = penumbra.load_file(args.scene)
    penumbra.render(scene, **kw)
    edits = {
        # A rough plastic's roughness recomputes its coating tables (64 x 16k integrand
        # evaluations; the reload computes 4 of them); a rough conductor's has none.
        "roughness (roughplastic)": lambda i: {"CeilingLightBSDF.brdf_0.alpha": 0.05 + 0.01 * (i % 10)},
        "roughness (roughconductor)": lambda i: {"ChairFrameBSDF.brdf_0.alpha": 0.05 + 0.01 * (i % 10)},
        "light": lambda i: {"emitter_0.radiance": (1.0, 0.95 - 0.01 * (i % 10), 0.9)},
        "material colour": lambda i: {"WallsBSDF.brdf_0.reflectance": (0.6, 0.6, 0.8 - 0.01 * (i % 10))},
    }
    for name, edit in edits.items():
        assert next(iter(edit(0))) in scene.parameters(), name

    def update(values) -> None:
        scene.update(values)
        penumbra.render(scene, **kw)

    reload()  # warm-up (file cache)
    reloads = [timed(reload) for _ in range(args.runs)]
    r = statistics.median(reloads)
    print(f"{args.scene} ({args.runs} runs, medians; the render is 16x16 at 1 spp)")
    print(f"  reload (load_file + render):                {r * 1e3:8.1f} ms   "
          f"(min {min(reloads) * 1e3:.1f}, max {max(reloads) * 1e3:.1f})")
    only_render = statistics.median(timed(lambda: penumbra.render(scene, **kw)) for _ in range(args.runs))
    print(f"  render alone, nothing edited:               {only_render * 1e3:8.1f} ms")
    for name, edit in edits.items():
        update(edit(0))  # warm-up
        ups = [timed(lambda i=i: update(edit(i + 1))) for i in range(args.runs)]
        calls = [timed(lambda i=i: scene.update(edit(i))) for i in range(args.runs)]
        u = statistics.median(ups)
        print(f"  update {name + ' + render:':37s}{u * 1e3:8.1f} ms   ratio {u / r * 100:5.2f} % "
              f"of a reload  (update() call alone {statistics.median(calls) * 1e3:.2f} ms)")
    # A shape's transform (set to its own value: the geometry is rebuilt all the same).
    params = scene.parameters()
    key = next(k for k in params if k.endswith(".to_world") and not k.startswith("sensor"))
    geo = {key: params[key]}
    moves = [timed(lambda: update(geo)) for _ in range(args.runs)]
    m = statistics.median(moves)
    print(f"  update shape to_world + render:             {m * 1e3:8.1f} ms   ratio {m / r * 100:5.2f} % "
          f"(rebuilds the BVH; textures and meshes kept)")


if __name__ == "__main__":
    main()
