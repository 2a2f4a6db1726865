"""A roughness sweep: one rough-plastic sphere rendered at five roughnesses, shown side by side.

    pip install .            # the penumbra package, from the repository root
    python examples/roughness_sweep.py [--spp 64] [--out /tmp/penumbra/roughness_sweep.png]

The scene is a Mitsuba 3 string, loaded once; each roughness is set with
`scene.update({"ball.alpha": ...})` (the material `ball` is rebuilt, the rest of the scene
is kept), which renders what loading the string with that `alpha` would, bit for bit. With
matplotlib installed the images go into one figure; without it, into one PNG strip written
with penumbra.write.
"""

from __future__ import annotations

import argparse
import os

import numpy as np

import penumbra

SCENE = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="6"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="30"/>
        <transform name="to_world"><lookat origin="0, 1.2, 4.5" target="0, 0.3, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm"><integer name="width" value="160"/><integer name="height" value="160"/></film>
    </sensor>
    <shape type="sphere">
        <point name="center" value="0, 0.5, 0"/><float name="radius" value="0.5"/>
        <bsdf type="roughplastic" id="ball">
            <rgb name="diffuse_reflectance" value="0.1, 0.25, 0.6"/>
            <float name="alpha" value="0.1"/>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="-90"/><scale value="4"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="90"/><scale value="0.6"/><translate x="1" y="2.5" z="1"/></transform>
        <emitter type="area"><rgb name="radiance" value="20"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.15"/></emitter>
</scene>
"""

ALPHAS = [0.02, 0.05, 0.1, 0.2, 0.4]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--out", default="/tmp/penumbra/roughness_sweep.png")
    args = ap.parse_args()
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)

    images = []
    scene = penumbra.load_string(SCENE)
    for alpha in ALPHAS:
        scene.update({"ball.alpha": alpha})
        images.append(penumbra.render(scene, spp=args.spp, seed=0))
        print(f"alpha {alpha}: mean {images[-1].mean():.4f}")

    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        strip = np.concatenate(images, axis=1)
        penumbra.write(args.out, strip)  # PNG: clamped and sRGB-encoded
        print(f"matplotlib not installed: wrote the strip {args.out}")
        return
    fig, axes = plt.subplots(1, len(ALPHAS), figsize=(3 * len(ALPHAS), 3.3))
    for ax, alpha, img in zip(axes, ALPHAS, images):
        srgb = np.where(img <= 0.0031308, 12.92 * img, 1.055 * np.power(np.clip(img, 0, None), 1 / 2.4) - 0.055)
        ax.imshow(np.clip(srgb, 0, 1))
        ax.set_title(f"alpha = {alpha}")
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
