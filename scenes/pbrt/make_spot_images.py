#!/usr/bin/env python3
"""Write the goniometric images that express Mitsuba 3's `spot` emitters of lights.xml and
media-fog.xml (../shared/references/scenes) as pbrt-v4 `goniometric` lights, and print the
`Rotate` that points each light's axis (pbrt-v4's goniometric pole is the light's +y: it swaps
y and z before the lookup) along the Mitsuba spot's direction.

Mitsuba 3's spot (spotlight.cpp) is `intensity` × a falloff in the angle θ from its axis: 1 for
θ ≤ beam_width, (cutoff_angle − θ)/(cutoff_angle − beam_width) up to cutoff_angle, 0 beyond.
pbrt-v4's own `spot` is a smoothstep in cos θ instead, so it cannot say this; its goniometric
light can: I(ω) = I · image(EqualAreaSphereToSquare(ω)), the image's nearest pixel. In
pbrt-v4's equal-area square (Clarke's octahedral map) the upper hemisphere is the diamond
|u| + |v| ≤ 1 of [−1, 1]², with cos θ = 1 − (|u| + |v|)², so the falloff is a function of
|u| + |v| alone, and the image's orientation does not matter. Each pixel holds the mean of the
falloff over the pixel (8 × 8 samples), so the nearest-pixel lookup keeps the falloff's integral
over every pixel; at 1024² a pixel spans < 1/20 of the 6–7° transition, and on the floor a
pixel of the image covers about one pixel of the 128² render: the 8 × 8 blocks of the t-test
average the steps away. Written as half-float RGB (grey) OpenEXR, ZIP-compressed (most of the
sphere is 0).

usage: python3 make_spot_images.py   (numpy, OpenEXR)"""
import math, os
import numpy as np
import OpenEXR, Imath

N, SS = 1024, 8
here = os.path.dirname(os.path.abspath(__file__))


def falloff_image(beam_deg, cutoff_deg):
    beam, cutoff = math.radians(beam_deg), math.radians(cutoff_deg)
    s = (np.arange(N * SS) + 0.5) / (N * SS) * 2 - 1  # sample centres in [−1, 1]
    a = np.abs(s)
    img = np.zeros((N, N))
    for row in range(N):  # one row of pixels at a time: SS × N·SS samples
        r = a[row * SS:(row + 1) * SS, None] + a[None, :]
        cos_t = 1 - np.minimum(r, 1) ** 2
        theta = np.arccos(np.clip(cos_t, -1, 1))
        f = np.where(cos_t >= math.cos(beam), 1.0,
                     (cutoff - theta) / (cutoff - beam))
        f = np.where((cos_t > math.cos(cutoff)) & (r <= 1), f, 0.0)
        img[row] = f.reshape(SS, N, SS).mean(axis=(0, 2))
    return img


def write_exr(path, img):
    h = OpenEXR.Header(N, N)
    half = Imath.Channel(Imath.PixelType(Imath.PixelType.HALF))
    h['channels'] = {'R': half, 'G': half, 'B': half}
    h['compression'] = Imath.Compression(Imath.Compression.ZIP_COMPRESSION)
    data = img.astype(np.float16).tobytes()
    out = OpenEXR.OutputFile(path, h)
    out.writePixels({'R': data, 'G': data, 'B': data})
    out.close()


def rotate_y_to(frm, to):
    """pbrt's `Rotate angle x y z` taking +y to the direction from → to."""
    d = np.subtract(to, frm, dtype=float)
    d /= np.linalg.norm(d)
    axis = np.array([d[2], 0.0, -d[0]])  # +y × d
    axis /= np.linalg.norm(axis)
    return math.degrees(math.acos(d[1])), axis


for name, beam, cutoff, frm, to in [
    ('spot-lights.exr', 18, 25, (2.5, 4, 2), (1, 0, -0.5)),
    ('spot-fog.exr', 22, 28, (-2.2, 2.4, -0.4), (0.3, 0, 0.2)),
]:
    path = os.path.join(here, name)
    write_exr(path, falloff_image(beam, cutoff))
    angle, axis = rotate_y_to(frm, to)
    print('%s (%d bytes): Translate %g %g %g  Rotate %.9g %.9g %.9g %.9g' % (
        name, os.path.getsize(path), *frm, angle, *axis))
