#!/usr/bin/python3
"""Write small.vdb and tiny.vdb, the OpenVDB test fixtures of VoxelGrid::read_vdb
(crates/render/src/media/vdb.rs) and the seeds of the `vdb` fuzz target (crates/cli/tests/it/fuzz.rs).
Needs Debian's python3-openvdb (OpenVDB 10.0.1 wrote the committed files).
usage: /usr/bin/python3 make_vdb.py OUTDIR

Grids (all sparse, so the reader's densification and padding are exercised):
- density:  float, a ball of voxels with value 0.5 + 0.01 i + 0.02 j + 0.03 k (computed in double,
            stored as float) around index (2.5, 3.5, 6.5), radius 6, plus one active 8^3 tile
            [16,23] x [0,7] x [0,7] of value 2; transform: scale (0.25, 0.5, 0.125), then
            translation (0.1, -0.2, 0.3) (a ScaleTranslateMap).
- half:     the same values and transform, saved as half floats.
- fog_bg:   a ball around (8.5, 7.5, 6.5), with background 0.25 (inactive voxels read 0.25);
            the grids below use the same ball.
- color:    a vec3s grid (not a float grid).
- rotated:  the ball under a rotation (an AffineMap: a transform kind vdb-rs does not read).
- negative: the ball with one voxel at -1.
- nan:      the ball with one voxel NaN.
tiny.vdb holds one grid, 'density': the ball around (8.5, 7.5, 6.5) with the default transform.
"""
import math, sys
import pyopenvdb as vdb

out = sys.argv[1]

def ball(c):
    for i in range(int(c[0]) - 7, int(c[0]) + 8):
        for j in range(int(c[1]) - 7, int(c[1]) + 8):
            for k in range(int(c[2]) - 7, int(c[2]) + 8):
                if (i - c[0]) ** 2 + (j - c[1]) ** 2 + (k - c[2]) ** 2 <= 36:
                    yield (i, j, k), 0.5 + 0.01 * i + 0.02 * j + 0.03 * k

def scale_translate():
    return vdb.createLinearTransform([[0.25, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 0.125, 0], [0.1, -0.2, 0.3, 1]])

def float_grid(name, centre=(8.5, 7.5, 6.5), background=0.0, tile=False, transform=None, edit=None):
    g = vdb.FloatGrid(background)
    g.name = name
    acc = g.getAccessor()
    for ijk, v in ball(centre):
        acc.setValueOn(ijk, v)
    if edit:
        edit(acc)
    if tile:
        g.fill((16, 0, 0), (23, 7, 7), 2.0, True)
    g.transform = transform or scale_translate()
    return g

# density and half straddle index 0 in x (two root children), the others stay positive (one).
grids = [float_grid('density', centre=(2.5, 3.5, 6.5), tile=True),
         float_grid('half', centre=(2.5, 3.5, 6.5), tile=True), float_grid('fog_bg', background=0.25)]
grids[1].saveFloatAsHalf = True
color = vdb.Vec3SGrid()
color.name = 'color'
color.getAccessor().setValueOn((1, 2, 3), (0.1, 0.2, 0.3))
grids.append(color)
c, s = math.cos(0.3), math.sin(0.3)
grids.append(float_grid('rotated', transform=vdb.createLinearTransform(
    [[c * 0.25, s * 0.25, 0, 0], [-s * 0.25, c * 0.25, 0, 0], [0, 0, 0.25, 0], [0, 0, 0, 1]])))
grids.append(float_grid('negative', edit=lambda a: a.setValueOn((8, 7, 6), -1.0)))
grids.append(float_grid('nan', edit=lambda a: a.setValueOn((8, 7, 7), float('nan'))))
vdb.write(f'{out}/small.vdb', grids=grids)
vdb.write(f'{out}/tiny.vdb', grids=[float_grid('density', transform=vdb.createLinearTransform(1.0))])
for g in grids:
    print(g.name, g.valueTypeName, g.evalActiveVoxelBoundingBox(), g.activeVoxelCount(), g.leafCount())
