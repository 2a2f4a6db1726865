//! A counting-sorted hash grid over spheres (the visible points and their radii): cells as
//! wide as the largest radius, each sphere listed in every cell it touches, in sphere order
//! (so the grid is the same whatever the thread count).

use crate::math::Vec3;

/// Counting-sorted hash grid over spheres.
pub(super) struct Grid {
    lo: Vec3,
    inv_cell: f32,
    res: [i64; 3],
    /// Table slot → range in `items`.
    starts: Vec<u32>,
    items: Vec<u32>,
}

fn hash_cell(c: [i64; 3], slots: usize) -> usize {
    let h = (c[0].wrapping_mul(73_856_093))
        ^ (c[1].wrapping_mul(19_349_663))
        ^ (c[2].wrapping_mul(83_492_791));
    (h as u64 % slots as u64) as usize
}

impl Grid {
    /// The grid over `n` spheres, sphere `i` at `sphere(i)` = (centre, radius).
    pub(super) fn build(n: usize, sphere: impl Fn(usize) -> (Vec3, f32)) -> Option<Grid> {
        let max_r = (0..n).map(|i| sphere(i).1).fold(0.0f32, f32::max);
        if n == 0 || !(max_r > 0.0 && max_r.is_finite()) {
            return None;
        }
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for i in 0..n {
            let p = sphere(i).0;
            lo = lo.min(p);
            hi = hi.max(p);
        }
        lo -= Vec3::splat(max_r);
        hi += Vec3::splat(max_r);
        let inv_cell = 1.0 / max_r;
        let ext = (hi - lo) * inv_cell;
        let res = [ext.x, ext.y, ext.z].map(|e| (e.ceil() as i64).clamp(1, 1 << 20));
        let slots = n.next_power_of_two().max(1);
        let cell = |p: Vec3, res: &[i64; 3]| -> [i64; 3] {
            let q = (p - lo) * inv_cell;
            let q = [q.x, q.y, q.z];
            std::array::from_fn(|k| (q[k].floor() as i64).clamp(0, res[k] - 1))
        };
        // Count, then fill, in sphere order.
        let mut counts = vec![0u32; slots + 1];
        let each = |f: &mut dyn FnMut(usize, u32)| {
            for i in 0..n {
                let (p, r) = sphere(i);
                let r = Vec3::splat(r);
                let (a, b) = (cell(p - r, &res), cell(p + r, &res));
                for z in a[2]..=b[2] {
                    for y in a[1]..=b[1] {
                        for x in a[0]..=b[0] {
                            f(hash_cell([x, y, z], slots), i as u32);
                        }
                    }
                }
            }
        };
        each(&mut |s, _| counts[s + 1] += 1);
        for s in 0..slots {
            counts[s + 1] += counts[s];
        }
        let mut items = vec![0u32; counts[slots] as usize];
        let mut fill = counts.clone();
        each(&mut |s, i| {
            items[fill[s] as usize] = i;
            fill[s] += 1;
        });
        Some(Grid {
            lo,
            inv_cell,
            res,
            starts: counts,
            items,
        })
    }

    /// The spheres whose cells may hold `p`.
    pub(super) fn near(&self, p: Vec3) -> &[u32] {
        let q = (p - self.lo) * self.inv_cell;
        let mut c = [0i64; 3];
        for (k, x) in [q.x, q.y, q.z].into_iter().enumerate() {
            let x = x.floor();
            if !(x >= 0.0 && (x as i64) < self.res[k]) {
                return &[];
            }
            c[k] = x as i64;
        }
        let s = hash_cell(c, self.starts.len() - 1);
        &self.items[self.starts[s] as usize..self.starts[s + 1] as usize]
    }
}
