//! OpenVDB `.vdb` grids: read by the `vdb-rs` crate, densified into a [`VoxelGrid`].
//!
//! Grid space. A VDB grid has an integer index space (voxel `(i, j, k)` is centred on the
//! index point `(i, j, k)`) and its own transform from index space to its local space (what
//! OpenVDB calls world space; the scene's `to_world` places that in the scene). We densify the
//! active voxels' bounding box `[imin, imax]` into a grid of `res = imax − imin + 1` voxels
//! (inactive voxels inside it read the background value) and return with it the affine map
//! from the dense grid's `[0,1]³` to the VDB's local space, `p ↦ M·(imin + p·res − ½)` with
//! `M` the VDB transform: the dense grid's voxel centres `(n + ½)/res` land on the VDB's, and
//! its `[0,1]³` is the box of the active voxels' cells. Outside that box a heterogeneous medium
//! is empty; inside, lookups between the outermost voxel centres and the box's faces clamp,
//! as Mitsuba's `gridvolume` does at the faces of a `.vol`. (Padding the box with a voxel of
//! background, as OpenVDB's samplers see a sparse grid, fades those outer half voxels to the
//! background instead; `plume.vdb`, cut off at the top of its box, then no longer renders as
//! `plume-density.vol` does.)
//!
//! Robustness. vdb-rs 0.6 trusts the file: it allocates buffers of any size a length field
//! names (a corrupt length aborts the process when the allocation fails), hands compressed
//! blocks to the C library c-blosc without checking their headers against the block (a corrupt
//! header makes c-blosc read or write out of bounds), and panics on transforms, grid layouts
//! and versions it does not know. So before vdb-rs sees a file, [`preflight`] walks the same
//! path through it that vdb-rs 0.6.0 will take (which is why the dependency is pinned to that
//! version) and checks every length, count and blosc header against the bytes there are; only
//! then does vdb-rs read it, and inside `catch_unwind`, so that a panic we did not foresee
//! becomes an error too. The walk decodes no values: vdb-rs does all the reading.

use std::cell::{Cell, RefCell};
use std::io::{Cursor, Read, Seek, SeekFrom};
use std::panic::AssertUnwindSafe;
use std::path::Path;

use vdb_rs::{Map, ParseError, VdbReader};

use super::grid::{GridError, VoxelGrid};
use crate::math::Mat4;

/// Dense grids larger than this many voxels (1 GiB of f32) are refused.
const MAX_DENSE_VOXELS: u64 = 1 << 28;

impl VoxelGrid {
    /// Read the float grid `grid_name` of an OpenVDB file, densified over its active voxels'
    /// bounding box, and the map from the dense grid's `[0,1]³` to the VDB grid's local space
    /// (see the module doc).
    pub fn read_vdb(
        path: &Path,
        grid_name: &str,
        trilinear: bool,
    ) -> Result<(VoxelGrid, Mat4), GridError> {
        let fail = |offset: Option<usize>, message: String| GridError {
            path: path.display().to_string(),
            offset,
            message,
        };
        let bytes = base::read_file(path).map_err(|e| fail(None, e.to_string()))?;
        let checked = preflight::check(&bytes, grid_name).map_err(|e| fail(e.0, e.1))?;

        let position = Cell::new(0u64);
        let read = guarded(|| {
            let mut reader = VdbReader::new(Tracked {
                inner: Cursor::new(&bytes[..]),
                position: &position,
            })?;
            reader.read_grid::<f32>(grid_name)
        });
        let at = Some(position.get() as usize);
        let grid = match read {
            Ok(Ok(grid)) => grid,
            Ok(Err(e)) => {
                let why = match e {
                    ParseError::IoError(io) => io.to_string(),
                    other => other.to_string(),
                };
                return Err(fail(at, format!("grid '{grid_name}': {why}")));
            }
            Err(panic) => {
                return Err(fail(
                    at,
                    format!(
                        "grid '{grid_name}': the VDB reader (vdb-rs) failed on this file: {panic}"
                    ),
                ));
            }
        };

        // Index → local: OpenVDB's maps apply the scale, then the translation.
        let (scale, translation) = match grid.transform {
            Map::UniformScaleMap { scale_values, .. } => (scale_values.to_array(), [0.0; 3]),
            Map::ScaleTranslateMap {
                translation,
                scale_values,
                ..
            } => (scale_values.to_array(), translation.to_array()),
        };
        if scale.iter().chain(&translation).any(|v| !v.is_finite()) || scale.contains(&0.0) {
            return Err(fail(
                None,
                format!(
                    "grid '{grid_name}': its transform (scale {scale:?}, translation {translation:?}) is singular or not finite"
                ),
            ));
        }

        let value_error = |what: String, v: f32| {
            fail(
                None,
                format!("grid '{grid_name}': {what} is {v}; values must be finite and ≥ 0"),
            )
        };
        let background = checked.background;
        if !background.is_finite() || background < 0.0 {
            return Err(value_error("the background value".into(), background));
        }

        // The active voxels' bounding box (tiles cover 8³ or 128³ voxels), and their values
        // checked; coordinates are exact in the f32 vdb-rs gives them in, the preflight having
        // bounded them by 2^24. Two passes, so that nothing the size of the active set is kept.
        let voxels = || {
            grid.iter().map(|(p, v, level)| {
                (
                    [p.x as i64, p.y as i64, p.z as i64],
                    v,
                    level.scale() as i64,
                )
            })
        };
        let reader_failed = |panic: String| {
            fail(
                None,
                format!("grid '{grid_name}': the VDB reader (vdb-rs) failed on this file: {panic}"),
            )
        };
        let bounds = guarded(|| {
            let mut lo = [i64::MAX; 3];
            let mut hi = [i64::MIN; 3];
            for (c, v, n) in voxels() {
                if !v.is_finite() || v < 0.0 {
                    return Err((c, v));
                }
                for k in 0..3 {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k] + n - 1);
                }
            }
            // No active voxel: one voxel of background.
            Ok(if lo[0] > hi[0] {
                ([0; 3], [0; 3])
            } else {
                (lo, hi)
            })
        })
        .map_err(reader_failed)?;
        let (lo, hi) = bounds.map_err(|(c, v)| {
            value_error(
                format!("the voxel at index ({}, {}, {})", c[0], c[1], c[2]),
                v,
            )
        })?;
        let res = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as u64);
        let count = res[0].saturating_mul(res[1]).saturating_mul(res[2]);
        if count > MAX_DENSE_VOXELS {
            return Err(fail(
                None,
                format!(
                    "grid '{grid_name}': its active voxels span {res:?} voxels ({count} when dense); more than 2^28 are not read"
                ),
            ));
        }
        let res = res.map(|r| r as usize);
        let data = guarded(|| {
            let mut data = vec![background; count as usize];
            for (c, v, n) in voxels() {
                let o = [0, 1, 2].map(|k| (c[k] - lo[k]) as usize);
                let n = n as usize;
                for z in o[2]..o[2] + n {
                    for y in o[1]..o[1] + n {
                        let row = (z * res[1] + y) * res[0];
                        data[row + o[0]..row + o[0] + n].fill(v);
                    }
                }
            }
            data
        })
        .map_err(reader_failed)?;

        // [0,1]³ → index: p ↦ lo + p·res − ½; index → local: i ↦ scale·i + translation.
        let mut m = Mat4::IDENTITY;
        for k in 0..3 {
            m.col_mut(k)[k] = (scale[k] * res[k] as f64) as f32;
            m.w_axis[k] = (scale[k] * (lo[k] as f64 - 0.5) + translation[k]) as f32;
        }
        let grid = VoxelGrid {
            res,
            channels: 1,
            data,
            trilinear,
            zero_outside: false,
        };
        Ok((grid, m))
    }
}

/// A reader that records how far vdb-rs got (for the byte offset of its errors).
struct Tracked<'a> {
    inner: Cursor<&'a [u8]>,
    position: &'a Cell<u64>,
}

impl Read for Tracked<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.position.set(self.inner.position());
        Ok(n)
    }
}

impl Seek for Tracked<'_> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        let p = self.inner.seek(pos)?;
        self.position.set(p);
        Ok(p)
    }
}

thread_local! {
    /// Set while [`guarded`] runs on this thread: the panic hook then keeps the panic's
    /// message here instead of printing it.
    static CAUGHT: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Run `f` (a call into vdb-rs), turning a panic into an error message. The preflight should
/// leave vdb-rs nothing to panic on; this is the second line. A panic hook, installed once,
/// stays silent for panics inside `guarded` on this thread and defers to the previous hook
/// for all others. (This needs `panic = "unwind"`, the default of every profile here.)
fn guarded<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let quiet = CAUGHT.with(|c| {
                let mut c = c.borrow_mut();
                if let Some(slot) = c.as_mut() {
                    let message = info
                        .payload()
                        .downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| info.payload().downcast_ref::<String>().cloned())
                        .unwrap_or_else(|| "a panic".into());
                    *slot = match info.location() {
                        Some(l) => format!("{message} (at {}:{})", l.file(), l.line()),
                        None => message,
                    };
                    true
                } else {
                    false
                }
            });
            if !quiet {
                previous(info);
            }
        }));
    });
    let outer = CAUGHT.with(|c| c.borrow_mut().replace(String::new()));
    let result = std::panic::catch_unwind(AssertUnwindSafe(f));
    let message = CAUGHT.with(|c| std::mem::replace(&mut *c.borrow_mut(), outer));
    result.map_err(|_| message.unwrap_or_default())
}

/// The bounds walk: the path vdb-rs 0.6.0 takes through a file to read one grid, with every
/// length, count, offset and blosc header checked against the bytes there are. It reads only
/// what it must to follow that path, and returns the grid's background value (which vdb-rs
/// reads but does not keep).
mod preflight {
    /// File format versions from 222 (OpenVDB 3.0, per-node mask compression) on. vdb-rs has
    /// older paths, partly unfinished (`todo!`); files that old are rare.
    const MIN_VERSION: u32 = 222;
    /// Node origins beyond ±this are refused: vdb-rs returns voxel coordinates as f32, exact
    /// below 2^24, and computes them in i32.
    const MAX_COORD: i64 = (1 << 24) - 4096;
    const ZIP: u32 = 0x1;
    const ACTIVE_MASK: u32 = 0x2;
    const BLOSC: u32 = 0x4;

    /// An error: where (a byte offset, when there is one) and what.
    pub type Error = (Option<usize>, String);
    type R<T> = Result<T, Error>;

    pub struct Checked {
        pub background: f32,
    }

    struct At<'a> {
        b: &'a [u8],
        pos: usize,
    }

    impl<'a> At<'a> {
        fn err<T>(&self, at: usize, message: String) -> R<T> {
            Err((Some(at), message))
        }
        fn take(&mut self, n: u64, what: &str) -> R<&'a [u8]> {
            let left = self.b.len() - self.pos;
            if n > left as u64 {
                return self.err(
                    self.pos,
                    format!(
                        "{what}: {n} bytes, but the file has {left} left (truncated or corrupt)"
                    ),
                );
            }
            let s = &self.b[self.pos..self.pos + n as usize];
            self.pos += n as usize;
            Ok(s)
        }
        fn array<const N: usize>(&mut self, what: &str) -> R<[u8; N]> {
            let mut a = [0; N];
            a.copy_from_slice(self.take(N as u64, what)?);
            Ok(a)
        }
        fn u8(&mut self, what: &str) -> R<u8> {
            Ok(self.array::<1>(what)?[0])
        }
        fn u32(&mut self, what: &str) -> R<u32> {
            Ok(u32::from_le_bytes(self.array(what)?))
        }
        fn i32(&mut self, what: &str) -> R<i32> {
            Ok(i32::from_le_bytes(self.array(what)?))
        }
        fn u64(&mut self, what: &str) -> R<u64> {
            Ok(u64::from_le_bytes(self.array(what)?))
        }
        fn i64(&mut self, what: &str) -> R<i64> {
            Ok(i64::from_le_bytes(self.array(what)?))
        }
        /// A length-prefixed string, decoded as vdb-rs does (a char per byte).
        fn name(&mut self, what: &str) -> R<String> {
            let n = self.u32(what)?;
            Ok(self
                .take(n as u64, what)?
                .iter()
                .map(|&b| b as char)
                .collect())
        }
        fn seek(&mut self, to: u64, what: &str) -> R<()> {
            if to > self.b.len() as u64 {
                return self.err(
                    self.pos,
                    format!(
                        "{what} ({to}) is past the end of the file ({} bytes)",
                        self.b.len()
                    ),
                );
            }
            self.pos = to as usize;
            Ok(())
        }
    }

    fn ones(mask: &[u8]) -> u64 {
        mask.iter().map(|b| b.count_ones() as u64).sum()
    }

    /// Set bits of a mask, in order (the order vdb-rs visits children in).
    fn bits(mask: &[u8]) -> impl Iterator<Item = usize> + '_ {
        (0..mask.len() * 8).filter(|&i| mask[i / 8] >> (i % 8) & 1 == 1)
    }

    /// Metadata: vdb-rs reads fixed sizes for the types it knows, `len` bytes for others.
    /// Returns whether it says the grid is saved as half floats.
    fn metadata(a: &mut At) -> R<bool> {
        let count = a.u32("metadata count")?;
        let mut half = false;
        for _ in 0..count {
            let name = a.name("metadata name")?;
            let ty = a.name("metadata type")?;
            let len = a.u32("metadata length")?;
            match ty.as_str() {
                "bool" => {
                    let v = a.u8("metadata value")?;
                    if name == "is_saved_as_half_float" {
                        half = v != 0;
                    }
                    continue;
                }
                "int32" | "float" => a.take(4, "metadata value")?,
                "int64" => a.take(8, "metadata value")?,
                "vec3i" => a.take(12, "metadata value")?,
                _ => a.take(len as u64, "metadata value")?,
            };
            if name == "is_saved_as_half_float" {
                half = false;
            }
        }
        Ok(half)
    }

    struct Desc {
        at: usize,
        name: String,
        ty: String,
        parent: String,
        grid_pos: u64,
        block_pos: u64,
        compression: u32,
        half: bool,
    }

    pub fn check(b: &[u8], grid_name: &str) -> R<Checked> {
        let mut a = At { b, pos: 0 };
        if a.take(8, "the header")? != b" BDV\0\0\0\0" {
            return a.err(0, "not an OpenVDB file (no ' BDV' magic number)".into());
        }
        let version = a.u32("file format version")?;
        if version < MIN_VERSION {
            return a.err(
                8,
                format!("file format version {version} is not read (only {MIN_VERSION} and later: OpenVDB 3.0 on)"),
            );
        }
        a.take(8, "library version")?;
        if a.u8("grid offsets flag")? != 1 {
            return a.err(
                a.pos - 1,
                "the file has no grid offsets (written as a stream); it cannot be read".into(),
            );
        }
        a.take(36, "file UUID")?;
        metadata(&mut a)?;
        let grid_count = a.u32("grid count")?;
        let mut descs: Vec<Desc> = Vec::new();
        let mut names = std::collections::HashSet::new();
        for _ in 0..grid_count {
            let at = a.pos;
            let name = a.name("grid name")?;
            let ty = a.name("grid type")?;
            let parent = a.name("instance parent")?;
            let grid_pos = a.u64("grid position")?;
            let block_pos = a.u64("block position")?;
            let end_pos = a.u64("end position")?;
            // OpenVDB writes a grid right after its descriptor; requiring that order keeps
            // this walk, and vdb-rs's, moving forward.
            if !(a.pos as u64 <= grid_pos
                && grid_pos <= block_pos
                && block_pos <= end_pos
                && end_pos <= b.len() as u64)
            {
                return a.err(
                    at,
                    format!(
                        "grid '{name}': its offsets (grid {grid_pos}, blocks {block_pos}, end {end_pos}) are out of order or past the end of the file ({} bytes)",
                        b.len()
                    ),
                );
            }
            if !names.insert(name.clone()) {
                return a.err(at, format!("two grids are named '{name}'"));
            }
            a.seek(grid_pos, "grid position")?;
            let compression = a.u32("compression flags")?;
            if compression > 7 {
                return a.err(
                    a.pos - 4,
                    format!("grid '{name}': invalid compression flags {compression:#x}"),
                );
            }
            let half = metadata(&mut a)?;
            descs.push(Desc {
                at,
                name,
                ty,
                parent,
                grid_pos,
                block_pos,
                compression,
                half,
            });
            a.seek(end_pos, "end position")?;
        }

        let Some(d) = descs.iter().find(|d| d.name == grid_name) else {
            let mut names: Vec<String> = descs.iter().map(|d| format!("'{}'", d.name)).collect();
            names.sort();
            let has = if names.is_empty() {
                "no grids".to_string()
            } else {
                format!("the grids {}", names.join(", "))
            };
            return Err((
                None,
                format!("no grid named '{grid_name}': the file has {has}"),
            ));
        };
        let name = &d.name;
        if !d.parent.is_empty() {
            return a.err(
                d.at,
                format!(
                    "grid '{name}' is an instance of grid '{}'; instanced grids are not read",
                    d.parent
                ),
            );
        }
        if !d.ty.starts_with("Tree_float_5_4_3") {
            return a.err(
                d.at,
                format!(
                    "grid '{name}' is a '{}', not a float grid (Tree_float_5_4_3)",
                    d.ty
                ),
            );
        }
        if d.half || d.ty != "Tree_float_5_4_3" {
            // vdb-rs 0.6 misreads these (OpenVDB 10's half-float grids fail its size checks).
            return a.err(
                d.at,
                format!("grid '{name}' is saved as half floats ('{}'), which are not read; save it as 32-bit float", d.ty),
            );
        }

        // The grid: compression, metadata (again), transform, tree topology, leaf data.
        let background = grid(&mut a, d).map_err(|(at, m)| (at, format!("grid '{name}': {m}")))?;
        Ok(Checked { background })
    }

    /// The path vdb-rs takes through one grid; returns its background value.
    fn grid(a: &mut At, d: &Desc) -> R<f32> {
        a.seek(d.grid_pos, "grid position")?;
        a.u32("compression flags")?;
        metadata(a)?;
        let at = a.pos;
        let map = a.name("transform type")?;
        match map.as_str() {
            "UniformScaleMap" => a.take(5 * 24, "transform")?,
            "UniformScaleTranslateMap" | "ScaleTranslateMap" => a.take(6 * 24, "transform")?,
            other => {
                return a.err(
                    at,
                    format!(
                        "its transform is a '{other}'; only scale and translation maps (UniformScaleMap, UniformScaleTranslateMap, ScaleTranslateMap) are read"
                    ),
                );
            }
        };
        if a.u32("buffer count")? != 1 {
            return a.err(a.pos - 4, "multi-buffer trees are not read".to_string());
        }
        let background = f32::from_le_bytes(a.array("background value")?);
        // vdb-rs reads both counts, then the tiles, then the children.
        let tiles = a.u32("root tile count")?;
        let roots = a.u32("root child count")?;
        for _ in 0..tiles {
            let at = a.pos;
            let tile = a.take(17, "root tile")?;
            if tile[16] != 0 {
                return a.err(
                    at,
                    "an active root tile (4096³ voxels of one value) is not read".to_string(),
                );
            }
        }
        let mut leaves = 0u64;
        let c = d.compression;
        for _ in 0..roots {
            let at = a.pos;
            let origin = [
                a.i32("node origin")?,
                a.i32("node origin")?,
                a.i32("node origin")?,
            ];
            if origin.iter().any(|&o| (o as i64).abs() > MAX_COORD) {
                return a.err(at, format!("node origin {origin:?} is beyond ±2^24 voxels"));
            }
            let child5 = a.take(4096, "node child mask")?;
            let value5 = a.take(4096, "node value mask")?;
            values(a, c, 32768, ones(value5))?;
            for _ in bits(child5) {
                let child4 = a.take(512, "node child mask")?;
                let value4 = a.take(512, "node value mask")?;
                values(a, c, 4096, ones(value4))?;
                let n = ones(child4);
                a.take(64 * n, "leaf value masks")?;
                leaves += n;
            }
        }
        a.seek(d.block_pos, "block position")?;
        for _ in 0..leaves {
            let mask = a.take(64, "leaf value mask")?;
            values(a, c, 512, ones(mask))?;
        }
        Ok(background)
    }

    /// A node's values as vdb-rs 0.6 reads them (`read_compressed`): a metadata byte, inactive
    /// values and a selection mask as it says, then `count` 4-byte values, stored raw,
    /// zlib- or blosc-compressed.
    fn values(a: &mut At, compression: u32, num_values: u64, active: u64) -> R<()> {
        let at = a.pos;
        let meta = a.u8("node metadata")?;
        if meta > 6 {
            return a.err(at, format!("invalid node metadata {meta}"));
        }
        if matches!(meta, 2 | 4 | 5) {
            a.take(4, "inactive value")?;
        }
        if meta == 5 {
            a.take(4, "inactive value")?;
        }
        if matches!(meta, 3..=5) {
            a.take(num_values / 8, "selection mask")?;
        }
        let count = if compression & ACTIVE_MASK != 0 && meta != 6 {
            active
        } else {
            num_values
        };
        if compression & (BLOSC | ZIP) == 0 {
            a.take(4 * count, "node values")?;
            return Ok(());
        }
        let at = a.pos;
        let n = a.i64("compressed size")?;
        if n <= 0 {
            // Stored raw: −n bytes.
            let stored = (n / 4).unsigned_abs();
            if stored != count {
                return a.err(
                    at,
                    format!("{stored} values stored where the node has {count}"),
                );
            }
            a.take(4 * stored, "node values")?;
            return Ok(());
        }
        let block = a.take(n as u64, "compressed node values")?;
        if compression & BLOSC == 0 || count == 0 {
            // zlib: vdb-rs inflates exactly `count` values and reports a bad stream.
            return Ok(());
        }
        // c-blosc 1.x reads its block's sizes from the block's own 16-byte header and
        // trusts them: they must agree with the block and with the values expected.
        let word =
            |o: usize| i32::from_le_bytes([block[o], block[o + 1], block[o + 2], block[o + 3]]);
        if block.len() < 16 || block[0] != 2 {
            return a.err(at + 8, "not a blosc block (bad header)".into());
        }
        let (nbytes, cbytes) = (word(4) as i64, word(12) as i64);
        if nbytes != 4 * count as i64 || cbytes < 16 || cbytes > block.len() as i64 {
            return a.err(
                at + 8,
                format!(
                    "blosc block of {} bytes says it holds {nbytes} bytes in {cbytes}; expected {} bytes of values",
                    block.len(),
                    4 * count
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use std::path::PathBuf;

    fn fixture(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data")
            .join(name)
    }

    fn temp(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("penumbra-vdb-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    /// The dense grid's value at the voxel centred at `local` (in the VDB's local space), found
    /// through the returned map (so that the map is checked too); `None` outside the grid.
    fn at_index(g: &VoxelGrid, m: &Mat4, local: Vec3) -> Option<f32> {
        let p = m.inverse().transform_point3a(local);
        let f = [0, 1, 2].map(|k| p[k] * g.res[k] as f32 - 0.5);
        for k in 0..3 {
            assert!(
                (f[k] - f[k].round()).abs() < 1e-3,
                "{local:?} is not on a voxel centre of the dense grid ({f:?})"
            );
        }
        let i = f.map(|v| v.round() as i64);
        (0..3)
            .all(|k| (0..g.res[k] as i64).contains(&i[k]))
            .then(|| {
                g.data[((i[2] as usize * g.res[1]) + i[1] as usize) * g.res[0] + i[0] as usize]
            })
    }

    /// plume.vdb holds the values of plume-density.vol and plume-temperature.vol, its
    /// transform putting voxel (i, j, k) at ((i+½)/64, …); its zeros are inactive, so the
    /// dense grid covers only the box of the nonzero voxels. Every voxel agrees (and those
    /// outside the box are 0), the map takes [0,1]³ to that box's cells, and trilinear lookups
    /// agree between the box's outermost voxel centres.
    #[test]
    fn plume_vdb_equals_the_vol_files() {
        let Some(dir) = base::testing::shared_dir("references/scenes") else {
            return;
        };
        // The active boxes, [imin, imax] (as OpenVDB reports them for these grids).
        for (grid, vol, lo, hi) in [
            ("density", "plume-density.vol", [1, 0, 0], [63, 63, 61]),
            (
                "temperature",
                "plume-temperature.vol",
                [15, 2, 4],
                [60, 48, 49],
            ),
        ] {
            let v = VoxelGrid::read_vol(&dir.join(vol), true).unwrap();
            let (g, m) = VoxelGrid::read_vdb(&dir.join("plume.vdb"), grid, true).unwrap();
            assert_eq!(v.res, [64; 3]);
            assert_eq!(g.channels, 1);
            assert_eq!(g.res, [0, 1, 2].map(|k| hi[k] - lo[k] + 1));
            let corner = |c: [usize; 3]| Vec3::from(c.map(|c| c as f32)) / 64.0;
            let max_err = |a: Vec3, b: Vec3| (a - b).abs().max_element();
            assert!(max_err(m.transform_point3a(Vec3::ZERO), corner(lo)) < 1e-6);
            assert!(max_err(m.transform_point3a(Vec3::ONE), corner(hi.map(|h| h + 1))) < 1e-6);
            let mut nonzero = 0;
            for z in 0..64 {
                for y in 0..64 {
                    for x in 0..64 {
                        let c = Vec3::new(x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5) / 64.0;
                        let want = v.data[(z * 64 + y) * 64 + x];
                        let got = at_index(&g, &m, c).unwrap_or(0.0);
                        assert!(
                            (got - want).abs() <= 1e-6 * want.max(1.0),
                            "{grid} ({x}, {y}, {z}): {got} vs {want}"
                        );
                        nonzero += (want != 0.0) as usize;
                    }
                }
            }
            assert!(nonzero > 1000, "{grid}: {nonzero} nonzero voxels");
            let mut rng = 12345u64;
            let mut next = || {
                rng = rng
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (rng >> 40) as f32 / (1u64 << 24) as f32
            };
            // f32 round-off in the two maps moves the point by ~1e-7: with values up to 2500
            // (temperature) changing by that much per voxel, 1e-5 of the largest value.
            let from = Vec3::from(lo.map(|l| l as f32 + 0.5)) / 64.0;
            let span = Vec3::from([0, 1, 2].map(|k| (hi[k] - lo[k]) as f32)) / 64.0;
            for _ in 0..20000 {
                let q = from + Vec3::new(next(), next(), next()) * span;
                let want = v.scalar(q);
                let got = g.scalar(m.inverse().transform_point3a(q));
                assert!(
                    (got - want).abs() <= 1e-5 * v.max_value(),
                    "{grid} at {q:?}: {got} vs {want}"
                );
            }
        }
    }

    fn ball_value(i: i64, j: i64, k: i64) -> f32 {
        (0.5 + 0.01 * i as f64 + 0.02 * j as f64 + 0.03 * k as f64) as f32
    }

    fn in_ball(i: i64, j: i64, k: i64, c: [f64; 3]) -> bool {
        let d = |a: i64, c: f64| (a as f64 - c).powi(2);
        d(i, c[0]) + d(j, c[1]) + d(k, c[2]) <= 36.0
    }

    /// small.vdb (see tests/data/make_vdb.py): a ball straddling index 0, an active 8³ tile,
    /// a scale-translate transform; every index of the padded box reads its value.
    #[test]
    fn sparse_grid_with_tile_and_transform() {
        let (g, m) = VoxelGrid::read_vdb(&fixture("small.vdb"), "density", false).unwrap();
        // The active box, [-3, 23] × [-2, 9] × [0, 12].
        assert_eq!(g.res, [27, 12, 13]);
        assert!(!g.trilinear);
        let scale = [0.25f32, 0.5, 0.125];
        let translation = [0.1f32, -0.2, 0.3];
        let mut tile = 0;
        for k in -1..=13i64 {
            for j in -3..=10i64 {
                for i in -4..=24i64 {
                    let local = Vec3::from([i, j, k].map(|v| v as f32)) * Vec3::from(scale)
                        + Vec3::from(translation);
                    let want =
                        if (16..24).contains(&i) && (0..8).contains(&j) && (0..8).contains(&k) {
                            tile += 1;
                            2.0
                        } else if in_ball(i, j, k, [2.5, 3.5, 6.5]) {
                            ball_value(i, j, k)
                        } else {
                            0.0
                        };
                    let inside =
                        (-3..=23).contains(&i) && (-2..=9).contains(&j) && (0..=12).contains(&k);
                    match at_index(&g, &m, local) {
                        Some(got) => assert!(
                            inside && (got - want).abs() < 1e-6,
                            "({i}, {j}, {k}): {got} vs {want}"
                        ),
                        None => assert!(!inside && want == 0.0, "({i}, {j}, {k})"),
                    }
                }
            }
        }
        assert_eq!(tile, 512);
        // The map: the dense grid's corner (0,0,0) is the box's corner voxel's outer corner,
        // index (-3.5, -2.5, -0.5).
        let corner = m.transform_point3a(Vec3::ZERO);
        let want = Vec3::new(-3.5 * 0.25 + 0.1, -2.5 * 0.5 - 0.2, -0.5 * 0.125 + 0.3);
        assert!((corner - want).abs().max_element() < 1e-6, "{corner:?}");
    }

    /// Inactive voxels inside the active box read the background value.
    #[test]
    fn inactive_voxels_read_the_background() {
        let (g, m) = VoxelGrid::read_vdb(&fixture("small.vdb"), "fog_bg", true).unwrap();
        // The active box, [3, 14] × [2, 13] × [1, 12].
        assert_eq!(g.res, [12, 12, 12]);
        let mut background = 0;
        for k in 1..=12i64 {
            for j in 2..=13i64 {
                for i in 3..=14i64 {
                    let local = Vec3::new(
                        i as f32 * 0.25 + 0.1,
                        j as f32 * 0.5 - 0.2,
                        k as f32 * 0.125 + 0.3,
                    );
                    let want = if in_ball(i, j, k, [8.5, 7.5, 6.5]) {
                        ball_value(i, j, k)
                    } else {
                        background += 1;
                        0.25
                    };
                    assert!((at_index(&g, &m, local).unwrap() - want).abs() < 1e-6);
                }
            }
        }
        assert!(background > 500, "{background}");
    }

    #[test]
    fn unreadable_grids_say_which_and_why() {
        let small = fixture("small.vdb");
        let cases = [
            (
                "smoke",
                "no grid named 'smoke': the file has the grids 'color', 'density', 'fog_bg', 'half', 'nan', 'negative', 'rotated'",
            ),
            ("color", "is a 'Tree_vec3s_5_4_3', not a float grid"),
            ("rotated", "its transform is a 'AffineMap'"),
            ("half", "half floats"),
            (
                "negative",
                "the voxel at index (8, 7, 6) is -1; values must be finite and ≥ 0",
            ),
            ("nan", "the voxel at index (8, 7, 7) is NaN"),
        ];
        for (name, want) in cases {
            let e = VoxelGrid::read_vdb(&small, name, true)
                .unwrap_err()
                .to_string();
            assert!(e.contains(want), "{name}: {e}");
            assert!(e.contains("small.vdb"), "{name}: names the file: {e}");
        }
        // Byte offsets where the file is at fault.
        let e = VoxelGrid::read_vdb(&small, "rotated", true).unwrap_err();
        assert!(e.offset.is_some(), "{e}");
    }

    /// Truncated copies, garbage, a directory, a missing file: errors, never a panic.
    #[test]
    fn bad_files_are_errors() {
        let mut files = vec![std::fs::read(fixture("small.vdb")).unwrap()];
        files.push(std::fs::read(fixture("tiny.vdb")).unwrap());
        if let Some(dir) = base::testing::shared_dir("references/scenes") {
            files.push(std::fs::read(dir.join("plume.vdb")).unwrap());
        }
        for (f, bytes) in files.iter().enumerate() {
            let len = bytes.len();
            let mut cuts = vec![
                0,
                1,
                7,
                8,
                12,
                60,
                100,
                300,
                1000,
                len / 3,
                len / 2,
                len - 100,
                len - 1,
            ];
            cuts.extend((1..40).map(|i| i * len / 40));
            for n in cuts {
                let p = temp(&format!("cut{f}-{n}.vdb"), &bytes[..n]);
                let e = VoxelGrid::read_vdb(&p, "density", true)
                    .err()
                    .unwrap_or_else(|| panic!("file {f} cut at {n} reads"));
                assert!(e.to_string().contains(&format!("cut{f}-{n}.vdb")), "{e}");
            }
        }
        let mut rng = 99u64;
        let garbage: Vec<u8> = (0..5000)
            .map(|_| {
                rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1);
                (rng >> 56) as u8
            })
            .collect();
        let mut headed = b" BDV\0\0\0\0\xe0\0\0\0".to_vec();
        headed.extend(&garbage);
        for (name, bytes) in [("garbage.vdb", &garbage), ("headed.vdb", &headed)] {
            let p = temp(name, bytes);
            assert!(VoxelGrid::read_vdb(&p, "density", true).is_err());
        }
        let dir = std::env::temp_dir();
        let e = VoxelGrid::read_vdb(&dir, "density", true).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        assert!(VoxelGrid::read_vdb(Path::new("/nonexistent/x.vdb"), "density", true).is_err());
    }

    /// Mutated fixtures (bytes flipped, inserted, deleted, duplicated, and lengths and counts
    /// overwritten with edge values): never a panic, and nothing that vdb-rs would fail on gets
    /// past the preflight (its panics would come back as "vdb-rs) failed" errors).
    #[test]
    fn mutated_files_are_errors_or_grids() {
        let mut rng = 7u64;
        let mut next = |n: usize| {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((rng >> 33) % n.max(1) as u64) as usize
        };
        let mut caught = Vec::new();
        let mut read = 0;
        for f in ["tiny.vdb", "small.vdb"] {
            let bytes = std::fs::read(fixture(f)).unwrap();
            for round in 0..1500 {
                let mut v = bytes.clone();
                for _ in 0..1 + next(4) {
                    let i = next(v.len() - 16);
                    match next(6) {
                        0 => v[i] ^= 1 << next(8),
                        1 => v.insert(i, next(256) as u8),
                        2 => {
                            v.drain(i..i + 1 + next(8));
                        }
                        3 => {
                            let chunk = v[i..i + 1 + next(8)].to_vec();
                            let at = next(v.len());
                            v.splice(at..at, chunk);
                        }
                        4 => {
                            let x = [0u32, 1, 2, 16, 512, 4096, u32::MAX, 1 << 31][next(8)];
                            v[i..i + 4].copy_from_slice(&x.to_le_bytes());
                        }
                        _ => {
                            let x = [0i64, -1, -4, -2048, 16, 2048, 1 << 40, i64::MIN][next(8)];
                            v[i..i + 8].copy_from_slice(&x.to_le_bytes());
                        }
                    }
                }
                let p = temp(&format!("mutated-{f}-{round}"), &v);
                for name in ["density", "fog_bg"] {
                    match VoxelGrid::read_vdb(&p, name, true) {
                        Ok(_) => read += 1,
                        Err(e) if e.message.contains("vdb-rs) failed") => {
                            caught.push(e.to_string())
                        }
                        Err(_) => {}
                    }
                }
                let _ = std::fs::remove_file(&p);
            }
        }
        assert!(caught.is_empty(), "{caught:#?}");
        assert!(
            read > 100,
            "{read} mutated files read: the mutations are too harsh"
        );
    }

    /// A mutation of tiny.vdb (a byte inserted, root tile count 32) that a preflight reading
    /// the root's tile and child counts in the wrong order let through to vdb-rs, which
    /// panicked on it (found by 40,000 mutated reads; the test above runs fewer).
    #[test]
    fn root_counts_are_read_in_vdb_rs_order() {
        let e =
            VoxelGrid::read_vdb(&fixture("mutated-root-counts.vdb"), "density", true).unwrap_err();
        assert!(!e.message.contains("vdb-rs) failed"), "{e}");
        assert!(
            e.message.contains("values stored where the node has"),
            "{e}"
        );
    }

    /// The preflight refuses a blosc block whose header disagrees with it before c-blosc sees
    /// it: the header of the first leaf block of tiny.vdb, its byte count doubled.
    #[test]
    fn blosc_headers_are_checked() {
        let mut bytes = std::fs::read(fixture("tiny.vdb")).unwrap();
        // A blosc header: version 2, then the uncompressed size at +4 (2048 bytes = 512 f32 of
        // a full leaf, or fewer with active-mask compression); find the first and corrupt it.
        let at = (0..bytes.len() - 16)
            .find(|&i| {
                bytes[i] == 2
                    && bytes[i + 3] == 4
                    && i32::from_le_bytes(bytes[i + 4..i + 8].try_into().unwrap()) > 0
                    && i64::from_le_bytes(bytes[i - 8..i].try_into().unwrap()) > 16
            })
            .expect("a blosc block");
        let n = i32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap());
        bytes[at + 4..at + 8].copy_from_slice(&(n + 3).to_le_bytes());
        let p = temp("blosc.vdb", &bytes);
        let e = VoxelGrid::read_vdb(&p, "density", true)
            .unwrap_err()
            .to_string();
        assert!(e.contains("blosc"), "{e}");
    }
}
