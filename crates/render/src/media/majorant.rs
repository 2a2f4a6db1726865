//! A majorant grid (pbrt-v4's `MajorantGrid`): a coarse grid over a density grid's [0,1]³
//! holding, per cell, bounds on the extinction anywhere in the cell, walked along a ray by a
//! 3D DDA. Trackers then sample tentative collisions at each cell's own majorant instead of
//! the whole grid's maximum: empty and thin regions of a sparse volume cost (almost) nothing.

use super::grid::VoxelGrid;
use crate::math::Vec3;

/// Cells per axis.
pub const RES: usize = 16;

#[derive(Clone, Debug)]
pub struct MajorantGrid {
    /// Per cell, the smallest and largest extinction (scale · density) the grid can take
    /// in the cell, `x + RES·(y + RES·z)`.
    min: Vec<f32>,
    max: Vec<f32>,
}

impl MajorantGrid {
    /// Bounds for `grid` (any filter: the voxels a trilinear lookup in a cell can touch, with
    /// one voxel of margin against rounding at cell borders) times `scale`.
    pub fn new(grid: &VoxelGrid, scale: f32) -> MajorantGrid {
        let range = |axis: usize, k: usize| {
            let n = grid.res[axis] as f32;
            let lo = ((k as f32 / RES as f32) * n - 0.5).floor() as i64 - 1;
            let hi = (((k + 1) as f32 / RES as f32) * n - 0.5).floor() as i64 + 2;
            let max = grid.res[axis] as i64 - 1;
            // A cell reaching past the voxels of a zero-outside grid can see 0 there.
            let beyond = grid.zero_outside && (lo < 0 || hi > max);
            (lo.clamp(0, max) as usize, hi.clamp(0, max) as usize, beyond)
        };
        let mut min = vec![f32::INFINITY; RES * RES * RES];
        let mut max = vec![0.0f32; RES * RES * RES];
        for cz in 0..RES {
            let (z0, z1, bz) = range(2, cz);
            for cy in 0..RES {
                let (y0, y1, by) = range(1, cy);
                for cx in 0..RES {
                    let (x0, x1, bx) = range(0, cx);
                    let c = cx + RES * (cy + RES * cz);
                    for z in z0..=z1 {
                        for y in y0..=y1 {
                            for x in x0..=x1 {
                                let i = ((z * grid.res[1] + y) * grid.res[0] + x) * grid.channels;
                                let v = grid.data[i];
                                min[c] = min[c].min(v);
                                max[c] = max[c].max(v);
                            }
                        }
                    }
                    if bx || by || bz {
                        min[c] = 0.0;
                    }
                    min[c] *= scale;
                    max[c] *= scale;
                }
            }
        }
        MajorantGrid { min, max }
    }

    /// Calls `f(t_enter, t_exit, σ_min, σ_max)` for each cell the segment `o + t·d`,
    /// t ∈ [t0, t1) (grid space, inside [0,1]³), crosses, in order, until `f` returns false.
    #[inline]
    pub fn walk(
        &self,
        o: Vec3,
        d: Vec3,
        t0: f32,
        t1: f32,
        mut f: impl FnMut(f32, f32, f32, f32) -> bool,
    ) {
        let r = RES as f32;
        let p = (o + d * t0) * r;
        let mut cell = [0, 1, 2].map(|k| (p[k].max(0.0) as i64).min(RES as i64 - 1));
        let step = [0, 1, 2].map(|k| if d[k] >= 0.0 { 1i64 } else { -1 });
        // Parameter of the next crossing per axis, and between crossings.
        let mut next = [0, 1, 2].map(|k| {
            if d[k] == 0.0 {
                f32::INFINITY
            } else {
                let edge = (cell[k] + (step[k] > 0) as i64) as f32 / r;
                (edge - o[k]) / d[k]
            }
        });
        let delta = [0, 1, 2].map(|k| {
            if d[k] == 0.0 {
                f32::INFINITY
            } else {
                1.0 / (r * d[k].abs())
            }
        });
        let mut t = t0;
        loop {
            let axis = if next[0] < next[1] {
                if next[0] < next[2] { 0 } else { 2 }
            } else if next[1] < next[2] {
                1
            } else {
                2
            };
            let exit = next[axis].min(t1);
            let c = (cell[0] + RES as i64 * (cell[1] + RES as i64 * cell[2])) as usize;
            if exit > t && !f(t, exit, self.min[c], self.max[c]) {
                return;
            }
            if exit >= t1 {
                return;
            }
            t = exit;
            cell[axis] += step[axis];
            if !(0..RES as i64).contains(&cell[axis]) {
                return;
            }
            next[axis] += delta[axis];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells' bounds hold the trilinear density at many random points (clamped or zero
    /// beyond the voxels), and the walk
    /// covers the segment exactly, cell after cell.
    #[test]
    fn bounds_hold_and_the_walk_covers_the_segment() {
        let n = 20usize;
        let mut x = 12345u32;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1u32 << 24) as f32
        };
        let data: Vec<f32> = (0..n * n * n)
            .map(|i| if i % 7 == 0 { 0.0 } else { rnd() * 3.0 })
            .collect();
        for zero_outside in [false, true] {
            let grid = VoxelGrid {
                res: [n, n, n],
                channels: 1,
                data: data.clone(),
                trilinear: true,
                zero_outside,
            };
            let m = MajorantGrid::new(&grid, 2.0);
            for _ in 0..200 {
                let o = Vec3::new(rnd(), rnd(), rnd());
                let d = (Vec3::new(rnd(), rnd(), rnd()) - Vec3::splat(0.5)).normalize();
                let inv = d.recip();
                let (a, b) = ((Vec3::ZERO - o) * inv, (Vec3::ONE - o) * inv);
                let t1 = a.max(b).min_element();
                let mut t_prev = 0.0;
                m.walk(o, d, 0.0, t1, |ta, tb, lo, hi| {
                    assert!((ta - t_prev).abs() < 1e-5, "gap at {ta} after {t_prev}");
                    t_prev = tb;
                    for k in 0..8 {
                        let t = ta + (tb - ta) * (k as f32 + 0.5) / 8.0;
                        let s = 2.0 * grid.scalar(o + d * t);
                        assert!(s <= hi * (1.0 + 1e-6) + 1e-6 && s >= lo * (1.0 - 1e-6) - 1e-6);
                    }
                    true
                });
                assert!(
                    (t_prev - t1).abs() < 1e-4,
                    "walk ended at {t_prev}, segment at {t1}"
                );
            }
        }
    }
}
