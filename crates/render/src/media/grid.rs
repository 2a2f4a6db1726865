//! Voxel grids: the data of heterogeneous media, looked up in the grid's own space [0,1]³
//! (Mitsuba 3's `gridvolume`: voxel centres at (i + ½)/res, trilinear between them or the
//! nearest voxel, clamped at the border — or, for pbrt-v4's `SampledGrid`, zero beyond the
//! grid's voxels), and the reader of Mitsuba's binary `.vol` files.

use std::path::Path;

use crate::math::Vec3;

/// Whether the grid-space point `q` lies in the grid's box [0,1]³.
#[inline]
pub fn inside(q: Vec3) -> bool {
    q.cmpge(Vec3::ZERO).all() && q.cmple(Vec3::ONE).all()
}

/// The most values a grid may hold (2³⁰ floats: 4 GiB).
const MAX_VALUES: usize = 1 << 30;

#[derive(Clone, Debug)]
pub struct VoxelGrid {
    /// Voxels along x, y, z.
    pub res: [usize; 3],
    /// Values per voxel: 1 (a scalar such as density) or 3 (RGB).
    pub channels: usize,
    /// `((z·res_y + y)·res_x + x)·channels + c`.
    pub data: Vec<f32>,
    pub trilinear: bool,
    /// Voxels beyond the grid read 0 in trilinear lookups (pbrt-v4's `SampledGrid`: the
    /// value falls towards 0 over the outer half voxel) instead of the border voxel's value.
    pub zero_outside: bool,
}

/// A grid file that cannot be read: the file, where in it (byte offset), and what is wrong.
#[derive(Clone, Debug, thiserror::Error)]
#[error("{path}{}: {message}", .offset.map(|o| format!(" (byte {o})")).unwrap_or_default())]
pub struct GridError {
    pub path: String,
    pub offset: Option<usize>,
    pub message: String,
}

impl VoxelGrid {
    /// The largest value of any channel (the majorant of a density grid).
    pub fn max_value(&self) -> f32 {
        self.data.iter().fold(0.0f32, |m, &v| m.max(v))
    }

    #[inline]
    fn voxel(&self, x: usize, y: usize, z: usize) -> usize {
        ((z * self.res[1] + y) * self.res[0] + x) * self.channels
    }

    /// The first channel's value at the grid-space point `p`; points outside [0,1]³ read the
    /// border voxels (or 0, [`VoxelGrid::zero_outside`]).
    #[inline]
    pub fn scalar(&self, p: Vec3) -> f32 {
        self.lookup(p, |g, i| g.data[i])
    }

    /// The RGB value at `p` (a one-channel grid gives grey).
    #[inline]
    pub fn rgb(&self, p: Vec3) -> Vec3 {
        if self.channels == 1 {
            return Vec3::splat(self.scalar(p));
        }
        self.lookup(p, |g, i| Vec3::new(g.data[i], g.data[i + 1], g.data[i + 2]))
    }

    #[inline]
    fn lookup<T>(&self, p: Vec3, at: impl Fn(&Self, usize) -> T) -> T
    where
        T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        let res = Vec3::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32);
        let max = [self.res[0] - 1, self.res[1] - 1, self.res[2] - 1];
        if !self.trilinear {
            let q = (p * res).floor();
            let i = [0, 1, 2].map(|k| (q[k].max(0.0) as usize).min(max[k]));
            return at(self, self.voxel(i[0], i[1], i[2]));
        }
        let q = p * res - Vec3::splat(0.5);
        let f = q.floor();
        let w = q - f;
        let i0 = [0, 1, 2].map(|k| (f[k].max(0.0) as usize).min(max[k]));
        let i1 = [0, 1, 2].map(|k| ((f[k] + 1.0).max(0.0) as usize).min(max[k]));
        // Per axis, whether the lower and upper neighbours exist (both do when clamping):
        // a missing one contributes 0, as a voxel of value 0 would.
        let has = |k: usize, c: f32| !self.zero_outside || (c >= 0.0 && c <= max[k] as f32);
        let m0 = [0, 1, 2].map(|k| has(k, f[k]));
        let m1 = [0, 1, 2].map(|k| has(k, f[k] + 1.0));
        if !(m0.iter().chain(&m1).all(|&b| b)) {
            let w0 = Vec3::ONE - w;
            let mut acc: Option<T> = None;
            for (z, wz) in [
                (i0[2], m0[2] as u8 as f32 * w0.z),
                (i1[2], m1[2] as u8 as f32 * w.z),
            ] {
                for (y, wy) in [
                    (i0[1], m0[1] as u8 as f32 * w0.y),
                    (i1[1], m1[1] as u8 as f32 * w.y),
                ] {
                    for (x, wx) in [
                        (i0[0], m0[0] as u8 as f32 * w0.x),
                        (i1[0], m1[0] as u8 as f32 * w.x),
                    ] {
                        let t = at(self, self.voxel(x, y, z)) * (wx * wy * wz);
                        acc = Some(match acc {
                            Some(a) => a + t,
                            None => t,
                        });
                    }
                }
            }
            return acc.expect("eight terms");
        }
        let v = |x: usize, y: usize, z: usize| at(self, self.voxel(x, y, z));
        let lerp = |a: T, b: T, t: f32| a * (1.0 - t) + b * t;
        let c00 = lerp(v(i0[0], i0[1], i0[2]), v(i1[0], i0[1], i0[2]), w.x);
        let c10 = lerp(v(i0[0], i1[1], i0[2]), v(i1[0], i1[1], i0[2]), w.x);
        let c01 = lerp(v(i0[0], i0[1], i1[2]), v(i1[0], i0[1], i1[2]), w.x);
        let c11 = lerp(v(i0[0], i1[1], i1[2]), v(i1[0], i1[1], i1[2]), w.x);
        lerp(lerp(c00, c10, w.y), lerp(c01, c11, w.y), w.z)
    }

    /// Read a Mitsuba `.vol` file (version 3, float32 data, 1 or 3 channels). Its bounding box
    /// is ignored: the grid fills [0,1]³ of its space, placed by the scene's `to_world`.
    pub fn read_vol(path: &Path, trilinear: bool) -> Result<VoxelGrid, GridError> {
        Self::read_vol_of(path, trilinear, &[1, 3])
    }

    /// [`Self::read_vol`] of a grid of `channels` values per voxel (6: the S matrices of
    /// Mitsuba's `sggx`).
    pub fn read_vol_of(
        path: &Path,
        trilinear: bool,
        channels_allowed: &[i32],
    ) -> Result<VoxelGrid, GridError> {
        let fail = |offset: Option<usize>, message: String| GridError {
            path: path.display().to_string(),
            offset,
            message,
        };
        let bytes = base::read_file(path).map_err(|e| fail(None, e.to_string()))?;
        if bytes.len() < 48 {
            return Err(fail(
                Some(bytes.len()),
                format!(
                    "truncated header: {} bytes, a .vol header has 48",
                    bytes.len()
                ),
            ));
        }
        if &bytes[0..3] != b"VOL" {
            return Err(fail(
                Some(0),
                "not a Mitsuba volume file (no 'VOL' magic)".into(),
            ));
        }
        if bytes[3] != 3 {
            return Err(fail(
                Some(3),
                format!("version {} is not supported (only 3)", bytes[3]),
            ));
        }
        let int =
            |o: usize| i32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
        let encoding = int(4);
        if encoding != 1 {
            return Err(fail(
                Some(4),
                format!("encoding {encoding} is not supported (only 1, float32)"),
            ));
        }
        let dims = [int(8), int(12), int(16)];
        if dims.iter().any(|&d| d <= 0) {
            return Err(fail(Some(8), format!("invalid resolution {dims:?}")));
        }
        let channels = int(20);
        if !channels_allowed.contains(&channels) {
            return Err(fail(
                Some(20),
                format!(
                    "{channels} channels per voxel; only {channels_allowed:?} are supported here"
                ),
            ));
        }
        let res = dims.map(|d| d as usize);
        // Refused before any arithmetic can overflow or an allocation can be attempted.
        let count = res
            .iter()
            .try_fold(channels as usize, |a, &r| a.checked_mul(r))
            .filter(|&n| n <= MAX_VALUES)
            .ok_or_else(|| {
                fail(
                    Some(8),
                    format!("resolution {res:?} × {channels} is too large"),
                )
            })?;
        let need = 48 + count * 4;
        if bytes.len() < need {
            return Err(fail(
                Some(bytes.len()),
                format!(
                    "truncated data: {need} bytes expected, {} found",
                    bytes.len()
                ),
            ));
        }
        let mut data = Vec::with_capacity(count);
        for (i, b) in bytes[48..need].chunks_exact(4).enumerate() {
            let v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            // An S matrix's off-diagonal entries may be negative.
            if !v.is_finite() || (v < 0.0 && channels != 6) {
                return Err(fail(
                    Some(48 + 4 * i),
                    format!("voxel value {v}: values must be finite and ≥ 0"),
                ));
            }
            data.push(v);
        }
        Ok(VoxelGrid {
            res,
            channels: channels as usize,
            data,
            trilinear,
            zero_outside: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vol(res: [i32; 3], channels: i32, data: &[f32]) -> Vec<u8> {
        let mut b = b"VOL\x03".to_vec();
        for v in [1, res[0], res[1], res[2], channels] {
            b.extend(v.to_le_bytes());
        }
        for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
            b.extend(v.to_le_bytes());
        }
        for v in data {
            b.extend(v.to_le_bytes());
        }
        b
    }

    fn write(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("penumbra-grid-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn trilinear_between_voxel_centres_and_clamped_outside() {
        // 2×1×1: voxel centres at x = 0.25 and 0.75.
        let p = write("lin.vol", &vol([2, 1, 1], 1, &[1.0, 3.0]));
        let g = VoxelGrid::read_vol(&p, true).unwrap();
        let at = |x: f32| g.scalar(Vec3::new(x, 0.5, 0.5));
        assert_eq!(at(0.25), 1.0);
        assert_eq!(at(0.75), 3.0);
        assert!((at(0.5) - 2.0).abs() < 1e-6);
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(1.0), 3.0);
        let n = VoxelGrid::read_vol(&p, false).unwrap();
        assert_eq!(n.scalar(Vec3::new(0.49, 0.5, 0.5)), 1.0);
        assert_eq!(n.scalar(Vec3::new(0.51, 0.5, 0.5)), 3.0);
        assert_eq!(g.max_value(), 3.0);
    }

    /// pbrt-v4's `SampledGrid` lookup written out directly: samples at (i + ½)/n, trilinear
    /// between them, every sample outside the grid 0.
    fn pbrt_lookup(res: [usize; 3], data: &[f32], p: Vec3) -> f32 {
        let at = |x: i64, y: i64, z: i64| {
            let inside = |c: i64, n: usize| c >= 0 && c < n as i64;
            if inside(x, res[0]) && inside(y, res[1]) && inside(z, res[2]) {
                data[(z as usize * res[1] + y as usize) * res[0] + x as usize]
            } else {
                0.0
            }
        };
        let s = [0, 1, 2].map(|k| p[k] * res[k] as f32 - 0.5);
        let i = s.map(|c| c.floor() as i64);
        let d = [0, 1, 2].map(|k| s[k] - i[k] as f32);
        let lerp = |t: f32, a: f32, b: f32| (1.0 - t) * a + t * b;
        let d00 = lerp(d[0], at(i[0], i[1], i[2]), at(i[0] + 1, i[1], i[2]));
        let d10 = lerp(d[0], at(i[0], i[1] + 1, i[2]), at(i[0] + 1, i[1] + 1, i[2]));
        let d01 = lerp(d[0], at(i[0], i[1], i[2] + 1), at(i[0] + 1, i[1], i[2] + 1));
        let d11 = lerp(
            d[0],
            at(i[0], i[1] + 1, i[2] + 1),
            at(i[0] + 1, i[1] + 1, i[2] + 1),
        );
        lerp(d[2], lerp(d[1], d00, d10), lerp(d[1], d01, d11))
    }

    #[test]
    fn zero_outside_is_pbrts_sampled_grid() {
        let mut x = 0x9e37_79b9u32;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1u32 << 24) as f32
        };
        for res in [[1, 1, 1], [2, 1, 3], [5, 4, 3]] {
            let data: Vec<f32> = (0..res.iter().product()).map(|_| 0.1 + rnd()).collect();
            let g = VoxelGrid {
                res,
                channels: 1,
                data: data.clone(),
                trilinear: true,
                zero_outside: true,
            };
            // Inside the box, on its faces and corners, and at voxel centres.
            let mut points: Vec<Vec3> = (0..4000).map(|_| Vec3::new(rnd(), rnd(), rnd())).collect();
            points.extend([Vec3::ZERO, Vec3::ONE, Vec3::new(0.0, 1.0, 0.5)]);
            points.push(Vec3::new(
                0.5 / res[0] as f32,
                0.5 / res[1] as f32,
                0.5 / res[2] as f32,
            ));
            for p in points {
                let (ours, pbrt) = (g.scalar(p), pbrt_lookup(res, &data, p));
                assert!(
                    (ours - pbrt).abs() <= 1e-5 * pbrt.abs().max(1.0),
                    "{res:?} at {p}: {ours} vs {pbrt}"
                );
            }
        }
        // A single voxel is a tent: full at the centre, half on a face, an eighth at a corner.
        let one = VoxelGrid {
            res: [1, 1, 1],
            channels: 1,
            data: vec![2.0],
            trilinear: true,
            zero_outside: true,
        };
        assert_eq!(one.scalar(Vec3::splat(0.5)), 2.0);
        assert!((one.scalar(Vec3::new(0.0, 0.5, 0.5)) - 1.0).abs() < 1e-6);
        assert!((one.scalar(Vec3::ZERO) - 0.25).abs() < 1e-6);
    }

    #[test]
    fn bad_files_say_where_and_what() {
        let good = vol([2, 2, 2], 1, &[0.5; 8]);
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (good[..20].to_vec(), "truncated header"),
            (good[..60].to_vec(), "truncated data"),
            (
                b"XYZ\x03".iter().chain(&good[4..]).copied().collect(),
                "magic",
            ),
            (vol([2, 2, 2], 2, &[0.5; 16]), "channels"),
            (
                vol([2, 2, 2], 1, &[0.5, 0.5, -1.0, 0.5, 0.5, 0.5, 0.5, 0.5]),
                "≥ 0",
            ),
            (
                vol([2, 2, 2], 1, &[0.5, f32::NAN, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]),
                "finite",
            ),
            (vol([1 << 30, 1 << 30, 4], 1, &[]), "too large"),
        ];
        for (i, (bytes, want)) in cases.into_iter().enumerate() {
            let p = write(&format!("bad{i}.vol"), &bytes);
            let e = VoxelGrid::read_vol(&p, true).unwrap_err().to_string();
            assert!(e.contains(want), "case {i}: {e}");
            assert!(e.contains("bad"), "names the file: {e}");
        }
        let e = VoxelGrid::read_vol(Path::new("/nonexistent/x.vol"), true).unwrap_err();
        assert!(e.to_string().contains("x.vol"));
    }
}
