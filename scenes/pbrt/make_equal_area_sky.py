#!/usr/bin/env python3
"""Write envmap-materials-sky.exr: Mitsuba's lat-long environment map (scenes/mitsuba/pbrt_sky.exr,
a copy of ../shared/references/scenes/textures/sky.exr) as pbrt-v4's equal-area octahedral
square, for envmap-materials.pbrt's `infinite` light (as pbrt-v4's `imgtool makeequiarea`, but
with Mitsuba's own lookup).

Every pixel of the square is the mean radiance over the pixel of 8 × 8 directions, each
evaluated by Mitsuba 3's `envmap` emitter itself (its bilinear lookup on its lat-long grid).
pbrt-v4 looks the square up at the nearest pixel, and every pixel subtends the same solid
angle (4π/N²), so the map keeps Mitsuba's radiance integrated over every pixel; at 1024² a
pixel is 0.2° across, finer than the lat-long map's 0.7° and the 0.35° of a render pixel, and
the small sun (about 5° wide) spans ~25 pixels. Half-float RGB, ZIP-compressed.

The square is in the light's frame of the pbrt file, `Rotate -90 1 0 0`: light direction
(x, y, z) is world (x, z, −y), so the map's pole (+z) is world up, Mitsuba's +y.

usage: python3 make_equal_area_sky.py [N]   (Mitsuba 3 with an llvm variant, numpy, OpenEXR)"""
import glob, math, os, sys
import numpy as np
import OpenEXR, Imath

here = os.path.dirname(os.path.abspath(__file__))
N = int(sys.argv[1]) if len(sys.argv) > 1 else 1024
SS = 8
if not os.environ.get('DRJIT_LIBLLVM_PATH'):
    for p in sorted(glob.glob('/usr/lib/llvm-*/lib/libLLVM*.so*'), reverse=True):
        os.environ['DRJIT_LIBLLVM_PATH'] = p
        break
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')

env = mi.load_dict({'type': 'envmap',
                    'filename': os.path.join(here, '../mitsuba/pbrt_sky.exr')})


def square_to_sphere(u, v):
    """pbrt-v4's EqualAreaSquareToSphere for (u, v) in [0, 1]²."""
    u, v = 2 * u - 1, 2 * v - 1
    up, vp = np.abs(u), np.abs(v)
    sd = 1 - (up + vp)
    r = 1 - np.abs(sd)
    phi = np.where(r == 0, 1, (vp - up) / np.where(r == 0, 1, r) + 1) * math.pi / 4
    z = np.copysign(1 - r * r, sd)
    cos_phi = np.copysign(np.cos(phi), u)
    sin_phi = np.copysign(np.sin(phi), v)
    s = r * np.sqrt(np.maximum(2 - r * r, 0))
    return cos_phi * s, sin_phi * s, z


img = np.zeros((N, N, 3))
rows = max(1, (1 << 22) // (N * SS * SS))  # pixel rows per batch of evaluations
t = (np.arange(N * SS) + 0.5) / (N * SS)
for r0 in range(0, N, rows):
    r1 = min(N, r0 + rows)
    vv, uu = np.meshgrid(t[r0 * SS:r1 * SS], t, indexing='ij')
    x, y, z = square_to_sphere(uu.ravel(), vv.ravel())
    d = np.stack([x, z, -y])  # the light frame's Rotate -90 1 0 0
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(-d)  # Mitsuba's envmap looks up −wi
    le = np.array(env.eval(si)).reshape(3, (r1 - r0) * SS, N * SS)
    img[r0:r1] = le.reshape(3, r1 - r0, SS, N, SS).mean(axis=(2, 4)).transpose(1, 2, 0)

out = os.path.join(here, 'envmap-materials-sky.exr')
h = OpenEXR.Header(N, N)
half = Imath.Channel(Imath.PixelType(Imath.PixelType.HALF))
h['channels'] = {c: half for c in 'RGB'}
h['compression'] = Imath.Compression(Imath.Compression.ZIP_COMPRESSION)
f = OpenEXR.OutputFile(out, h)
f.writePixels({c: img[..., i].astype(np.float16).tobytes() for i, c in enumerate('RGB')})
f.close()
print(out, os.path.getsize(out), 'bytes; mean', img.mean(axis=(0, 1)), 'max', img.max())
