#!/usr/bin/env python3
"""Write media-heterogeneous-grid.pbrt: the plume of ../shared/references/scenes/plume-density.vol
as a pbrt-v4 `uniformgrid` medium named "plume", for media-heterogeneous.pbrt to Include.

Mitsuba's gridvolume looks its 64³ grid up trilinearly with voxel centres at (i + ½)/64 of the
unit cube and clamps at the border; pbrt-v4's uniformgrid has the same centres over p0–p1 but
falls to 0 beyond the outer voxel centres. So the grid is padded by one voxel on every side
with copies of the border voxels (66³) and p0–p1 widened by one voxel, [−1/64, 1 + 1/64]: inside
the unit cube (the boundary box) every trilinear lookup then equals Mitsuba's. The medium's
space is the unit cube, which the including file places with the CTM.

Values are written with 5 significant digits (density ≤ 1, so |error| ≤ 5·10⁻⁶, 7·10⁻⁵ in σt
after the scale of 14: far below what 16 × 32 spp can see).

usage: python3 make_plume_grid.py [PLUME_VOL]   (numpy; default ../../../shared/references/...)"""
import os, struct, sys
import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
src = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
    here, '../../../shared/references/scenes/plume-density.vol')
with open(src, 'rb') as f:
    head = f.read(48)
    assert head[:4] == b'VOL\x03', 'not a version-3 .vol file'
    enc, nx, ny, nz, ch = struct.unpack('<5i', head[4:24])
    assert enc == 1 and ch == 1, 'expected one float32 channel'
    d = np.frombuffer(f.read(), dtype='<f4').reshape(nz, ny, nx)  # x fastest, as pbrt-v4
d = np.pad(d, 1, mode='edge')  # clamp padding: 66³
lo = [-1.0 / n for n in (nx, ny, nz)]
hi = [1.0 + 1.0 / n for n in (nx, ny, nz)]
rows = d.reshape(-1, d.shape[2])  # one line per row of x
vals = '\n    '.join(' '.join('%.5g' % v for v in r) for r in rows)
out = os.path.join(here, 'media-heterogeneous-grid.pbrt')
with open(out, 'w') as f:
    f.write('# Written by make_plume_grid.py from plume-density.vol (see there): the 64³ plume\n'
            '# padded to 66³ with copies of its border voxels, over a box one voxel wider.\n')
    f.write('MakeNamedMedium "plume" "string type" "uniformgrid"\n')
    f.write('  "rgb sigma_a" [ 0.08 0.08 0.08 ] "rgb sigma_s" [ 0.92 0.92 0.92 ]\n')
    f.write('  "float scale" 14 "float g" 0.4\n')
    f.write('  "point3 p0" [ %r %r %r ] "point3 p1" [ %r %r %r ]\n' % (*lo, *hi))
    f.write('  "integer nx" %d "integer ny" %d "integer nz" %d\n' % d.shape[::-1])
    f.write('  "float density" [\n    %s\n  ]\n' % vals)
print(out, os.path.getsize(out), 'bytes')
