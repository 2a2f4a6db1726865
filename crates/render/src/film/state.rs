//! Film state files: a film's exact sums with what they belong to, for shards, merges and
//! checkpoints (`penumbra render --shard`, `--checkpoint`, `--resume`, `penumbra merge`).
//!
//! A state names its render by an identity hash (the caller's: scene, options, version) and
//! a description for messages, and says which of the render's work items its film holds
//! (`drive/work.rs`). Because the film's sums are exact integers ([`super::accum`]), states of
//! disjoint item ranges add up to the film of their union bit for bit, and [`merge`] checks
//! that they cover the render once.
//!
//! Layout (little-endian), version 2:
//! ```text
//! "PENUMBRA-STATE\n"  version u32  identity u64  description (u32 length, UTF-8)
//! items_total u64  items.start u64  items.end u64  spp u32
//! width u32  height u32  min.x min.y max.x max.y u32  filter (u8 tag, 3 × f32)
//! tonemap (u8 tag, 4 × f32)  splat_scale f64  samples u64  nonfinite u64
//! pixels: rows, per stored pixel 11 sums (zigzag LEB128 of i128) and the count (LEB128)
//! splats: u8 0 | 1, then rows, 3 sums per pixel
//! checksum u64 (FNV-1a of everything before)
//! ```
//! where "rows" is the byte length of each of the crop's rows (u32 each), then the rows.
//! Sums are mostly far below 2¹²⁷, so the variable-length integers take about half of the
//! 16 bytes each; the row lengths let a reader decode rows in parallel, and a merge add
//! every state's row into one film without a film per thread. The checksum catches a
//! truncated or damaged file. Files are written to a temporary name beside the target and
//! renamed, so a state on disk is always whole.

use std::io::Write;
use std::ops::Range;
use std::path::Path;

use super::accum::FixedSums;
use super::{Film, Filter};
use crate::math::UVec2;
use base::{CropWindow, Tonemap};

const MAGIC: &[u8] = b"PENUMBRA-STATE\n";
/// The version of the layout this program writes and reads.
pub const FORMAT: u32 = 2;

/// What a state says about its film: the render it belongs to and the part it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct StateInfo {
    /// Identifies the render (scene, options, program version): states of different renders
    /// are not merged or resumed.
    pub identity: u64,
    /// The render in words (scene file, samples, seed), for messages.
    pub description: String,
    /// Work items of the whole render.
    pub items_total: u64,
    /// The items the film holds.
    pub items: Range<u64>,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// How 8-bit outputs of the image are tone mapped.
    pub tonemap: Option<Tonemap>,
}

/// A film with the part of a render it holds.
#[derive(Clone, Debug)]
pub struct FilmState {
    pub info: StateInfo,
    pub film: Film,
}

/// 64-bit FNV-1a, a stable hash (the same on every machine and build) for identities and
/// checksums; `std::fmt::Write` so that `Debug` output can be hashed without a string.
#[derive(Clone, Copy, Debug)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x100_0000_01b3);
        }
    }
}

impl std::fmt::Write for Fnv {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.update(s.as_bytes());
        Ok(())
    }
}

/// The file's checksum: FNV-1a over 8-byte little-endian words (the tail zero-padded),
/// eight times faster than byte by byte on 100 MB states.
fn checksum(data: &[u8]) -> u64 {
    let mut h = Fnv::default().0;
    let mut words = data.chunks_exact(8);
    for w in &mut words {
        h = (h ^ u64::from_le_bytes(w.try_into().unwrap())).wrapping_mul(0x100_0000_01b3);
    }
    let mut tail = [0u8; 8];
    tail[..words.remainder().len()].copy_from_slice(words.remainder());
    (h ^ u64::from_le_bytes(tail) ^ data.len() as u64).wrapping_mul(0x100_0000_01b3)
}

fn put_uleb(out: &mut Vec<u8>, mut v: u128) {
    loop {
        let b = (v & 0x7f) as u8;
        v >>= 7;
        if v == 0 {
            out.push(b);
            return;
        }
        out.push(b | 0x80);
    }
}

fn put_sleb(out: &mut Vec<u8>, v: i128) {
    put_uleb(out, ((v << 1) ^ (v >> 127)) as u128);
}

/// Reads what [`FilmState::to_bytes`] wrote, with clear errors on a short or odd file.
struct Reader<'a> {
    data: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len());
        let end = end.ok_or("the file ends early (truncated?)")?;
        let s = &self.data[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    fn f32(&mut self) -> Result<f32, String> {
        Ok(f32::from_bits(self.u32()?))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn uleb(&mut self) -> Result<u128, String> {
        // Most numbers end within 8 bytes (56 bits): read them from one word, the first
        // byte without its continuation bit ending them.
        if let Some(w) = self.data.get(self.at..self.at + 8) {
            let w = u64::from_le_bytes(w.try_into().unwrap());
            let ends = !w & 0x8080_8080_8080_8080;
            if ends != 0 {
                let n = ends.trailing_zeros() / 8 + 1;
                let mut v = 0u64;
                for i in 0..n {
                    v |= ((w >> (8 * i)) & 0x7f) << (7 * i);
                }
                self.at += n as usize;
                return Ok(v as u128);
            }
        }
        let mut v = 0u128;
        for shift in (0..133).step_by(7) {
            let b = self.u8()?;
            if shift > 126 && b > 0x03 {
                return Err("a number in the file is out of range (damaged file?)".into());
            }
            v |= ((b & 0x7f) as u128) << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err("a number in the file is out of range (damaged file?)".into())
    }
    fn sleb(&mut self) -> Result<i128, String> {
        let u = self.uleb()?;
        Ok((u >> 1) as i128 ^ -((u & 1) as i128))
    }
}

fn filter_fields(f: &Filter) -> (u8, [f32; 3]) {
    match *f {
        Filter::Box { radius } => (0, [radius, 0.0, 0.0]),
        Filter::Tent { radius } => (1, [radius, 0.0, 0.0]),
        Filter::Gaussian { stddev, radius } => (2, [stddev, radius, 0.0]),
        Filter::Mitchell { b, c, radius } => (3, [b, c, radius]),
        Filter::Lanczos { radius, tau } => (4, [radius, tau, 0.0]),
    }
}

fn filter_from(tag: u8, v: [f32; 3]) -> Result<Filter, String> {
    Ok(match tag {
        0 => Filter::Box { radius: v[0] },
        1 => Filter::Tent { radius: v[0] },
        2 => Filter::Gaussian {
            stddev: v[0],
            radius: v[1],
        },
        3 => Filter::Mitchell {
            b: v[0],
            c: v[1],
            radius: v[2],
        },
        4 => Filter::Lanczos {
            radius: v[0],
            tau: v[1],
        },
        t => return Err(format!("unknown filter tag {t} (damaged file?)")),
    })
}

/// The bytes of the state of `film` described by `info` (see the module docs).
pub fn to_bytes(info: &StateInfo, film: &Film) -> Vec<u8> {
    let f = film;
    let (pixels, splats) = f.fixed_sums();
    let mut out = Vec::with_capacity(128 + pixels.len() * 100);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT.to_le_bytes());
    out.extend_from_slice(&info.identity.to_le_bytes());
    out.extend_from_slice(&(info.description.len() as u32).to_le_bytes());
    out.extend_from_slice(info.description.as_bytes());
    for v in [info.items_total, info.items.start, info.items.end] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&info.spp.to_le_bytes());
    let full = f.full_resolution();
    let (min, max) = f.pixel_bounds();
    for v in [full.x, full.y, min.x, min.y, max.x, max.y] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let (tag, v) = filter_fields(f.filter());
    out.push(tag);
    v.iter()
        .for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
    let (tag, v) = match info.tonemap {
        None => (0u8, [0.0f32; 4]),
        Some(Tonemap::Photographic {
            key,
            burn_percent,
            saturation,
            gamma,
        }) => (1, [key, burn_percent, saturation, gamma]),
        Some(Tonemap::DisplayUnits) => (2, [0.0; 4]),
    };
    out.push(tag);
    v.iter()
        .for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
    out.extend_from_slice(&f.splat_scale().to_le_bytes());
    out.extend_from_slice(&f.sample_count().to_le_bytes());
    out.extend_from_slice(&f.nonfinite_count().to_le_bytes());
    let width = (max.x - min.x).max(1) as usize;
    put_rows(&mut out, pixels, width, |out, p| {
        for &v in &p.v {
            put_sleb(out, v);
        }
        put_uleb(out, p.count as u128);
    });
    out.push(!splats.is_empty() as u8);
    if !splats.is_empty() {
        put_rows(&mut out, splats, width, |out, s| {
            for &v in s {
                put_sleb(out, v);
            }
        });
    }
    let sum = checksum(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

/// Appends `values` as rows of `width`: each row's byte length (u32), then the rows, each
/// encoded by `put` value by value (rows in parallel).
fn put_rows<T: Sync>(
    out: &mut Vec<u8>,
    values: &[T],
    width: usize,
    put: impl Fn(&mut Vec<u8>, &T) + Sync,
) {
    use rayon::prelude::*;
    let rows: Vec<Vec<u8>> = values
        .par_chunks(width)
        .map(|row| {
            let mut bytes = Vec::with_capacity(row.len() * 100);
            row.iter().for_each(|v| put(&mut bytes, v));
            bytes
        })
        .collect();
    for row in &rows {
        let len = u32::try_from(row.len()).expect("a row of a film state is under 4 GiB");
        out.extend_from_slice(&len.to_le_bytes());
    }
    rows.iter().for_each(|row| out.extend_from_slice(row));
}

/// Writes the state of `film` described by `info` to `path` atomically (a temporary file
/// beside it, then renamed).
pub fn write(path: &Path, info: &StateInfo, film: &Film) -> std::io::Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(
        ".{}.{}.tmp",
        name.unwrap_or_else(|| "state".into()),
        std::process::id()
    ));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(&to_bytes(info, film))?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

impl FilmState {
    /// Parses a state file's bytes.
    pub fn from_bytes(data: &[u8]) -> Result<FilmState, String> {
        let mut acc = None;
        let info = decode_into(data, &mut acc)?;
        let film = acc.expect("decode_into makes the film");
        Ok(FilmState { info, film })
    }

    /// Writes the state to `path` atomically.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        write(path, &self.info, &self.film)
    }

    /// Reads a state file; errors name the file.
    pub fn read(path: &Path) -> Result<FilmState, String> {
        let data =
            std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        FilmState::from_bytes(&data).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Whether this state can continue (or be merged with) a render of `identity`.
    pub fn check_identity(&self, identity: u64, what: &str) -> Result<(), String> {
        if self.info.identity == identity {
            Ok(())
        } else {
            Err(format!(
                "{what} belongs to another render ({}); the scene, its options or the \
                 program differ",
                self.info.description
            ))
        }
    }
}

/// The header of a state file (everything before the pixels) and where the pixels start.
struct Header {
    info: StateInfo,
    full: (u32, u32),
    crop: CropWindow,
    filter: Filter,
    splat_scale: f64,
    samples: u64,
    nonfinite: u64,
}

fn read_header(r: &mut Reader) -> Result<Header, String> {
    let version = r.u32()?;
    if version != FORMAT {
        return Err(format!(
            "film state version {version}; this penumbra reads version {FORMAT}"
        ));
    }
    let identity = r.u64()?;
    let len = r.u32()? as usize;
    let description = String::from_utf8_lossy(r.take(len)?).into_owned();
    let (items_total, start, end) = (r.u64()?, r.u64()?, r.u64()?);
    let spp = r.u32()?;
    let [w, hgt, x0, y0, x1, y1] = [r.u32()?, r.u32()?, r.u32()?, r.u32()?, r.u32()?, r.u32()?];
    if !(x0 <= x1 && x1 <= w && y0 <= y1 && y1 <= hgt && start <= end && end <= items_total) {
        return Err("inconsistent film bounds or item range (damaged file?)".into());
    }
    let tag = r.u8()?;
    let filter = filter_from(tag, [r.f32()?, r.f32()?, r.f32()?])?;
    let tag = r.u8()?;
    let t = [r.f32()?, r.f32()?, r.f32()?, r.f32()?];
    let tonemap = match tag {
        0 => None,
        1 => Some(Tonemap::Photographic {
            key: t[0],
            burn_percent: t[1],
            saturation: t[2],
            gamma: t[3],
        }),
        2 => Some(Tonemap::DisplayUnits),
        t => return Err(format!("unknown tone mapping tag {t} (damaged file?)")),
    };
    let splat_scale = r.f64()?;
    let (samples, nonfinite) = (r.u64()?, r.u64()?);
    Ok(Header {
        info: StateInfo {
            identity,
            description,
            items_total,
            items: start..end,
            spp,
            tonemap,
        },
        full: (w, hgt),
        crop: CropWindow {
            offset_x: x0,
            offset_y: y0,
            width: x1 - x0,
            height: y1 - y0,
        },
        filter,
        splat_scale,
        samples,
        nonfinite,
    })
}

/// Checks a state file's magic and (with `verify`) its checksum; a reader at its header.
fn open(data: &[u8], verify: bool) -> Result<Reader<'_>, String> {
    if !data.starts_with(MAGIC) {
        return Err("not a penumbra film state (the file does not start with \
                    PENUMBRA-STATE)"
            .into());
    }
    if data.len() < MAGIC.len() + 12 {
        return Err("the file ends early (truncated?)".into());
    }
    let (body, sum) = data.split_at(data.len() - 8);
    let mut r = Reader {
        data: body,
        at: MAGIC.len(),
    };
    // The version first, so that a newer file says so rather than "damaged".
    let version = r.u32()?;
    if version != FORMAT {
        return Err(format!(
            "film state version {version}; this penumbra reads version {FORMAT}"
        ));
    }
    if verify && checksum(body).to_le_bytes() != sum {
        return Err("the checksum does not match: the file is truncated or damaged".into());
    }
    r.at = MAGIC.len();
    Ok(r)
}

/// A checked state file: its header and the encoded rows of its layers.
struct Parsed<'a> {
    h: Header,
    pixel_rows: Vec<&'a [u8]>,
    splat_rows: Option<Vec<&'a [u8]>>,
}

impl Parsed<'_> {
    /// An empty film of the state's size, crop, filter and splat scale.
    fn blank_film(&self) -> Film {
        let h = &self.h;
        let mut f = Film::new(h.full.0, h.full.1, Some(h.crop), h.filter);
        f.set_splat_scale(h.splat_scale);
        f
    }

    /// Whether `film` has this state's size, crop and filter.
    fn fits(&self, film: &Film) -> bool {
        let h = &self.h;
        let (min, max) = film.pixel_bounds();
        film.full_resolution() == UVec2::new(h.full.0, h.full.1)
            && min == UVec2::new(h.crop.offset_x, h.crop.offset_y)
            && max - min == UVec2::new(h.crop.width, h.crop.height)
            && *film.filter() == h.filter
    }
}

/// Reads the row lengths of a layer of `rows` rows and returns the rows' bytes.
fn take_rows<'a>(r: &mut Reader<'a>, rows: usize) -> Result<Vec<&'a [u8]>, String> {
    // Each row length takes 4 bytes: refuse counts the file cannot hold before allocating.
    if rows > (r.data.len() - r.at) / 4 {
        return Err("the film is larger than the file holds (damaged file?)".into());
    }
    let lens = (0..rows)
        .map(|_| r.u32().map(|n| n as usize))
        .collect::<Result<Vec<_>, _>>()?;
    let data = r.data;
    lens.into_iter()
        .map(|n| {
            let at = r.at;
            r.take(n)?;
            Ok(&data[at..at + n])
        })
        .collect()
}

/// Checks a state file (its checksum only with `verify`) and finds its rows.
fn parse(data: &[u8], verify: bool) -> Result<Parsed<'_>, String> {
    let mut r = open(data, verify)?;
    let h = read_header(&mut r)?;
    let rows = if h.crop.width == 0 {
        0
    } else {
        h.crop.height as usize
    };
    let pixel_rows = take_rows(&mut r, rows)?;
    // Each pixel takes at least 12 bytes: refuse a film the rows cannot hold before
    // allocating for it.
    let bytes: usize = pixel_rows.iter().map(|row| row.len()).sum();
    if (h.crop.width as usize).saturating_mul(rows) > bytes / 12 {
        return Err("the film is larger than the file holds (damaged file?)".into());
    }
    let splat_rows = match r.u8()? {
        0 => None,
        1 => Some(take_rows(&mut r, rows)?),
        _ => return Err("unknown splat layer tag (damaged file?)".into()),
    };
    if r.at != r.data.len() {
        return Err("unexpected bytes after the film (damaged file?)".into());
    }
    Ok(Parsed {
        h,
        pixel_rows,
        splat_rows,
    })
}

/// Decodes one encoded row, adding each value (`get` reads one) to `out`'s.
fn add_row<T>(
    bytes: &[u8],
    out: &mut [T],
    mut get: impl FnMut(&mut Reader, &mut T) -> Result<(), String>,
) -> Result<(), String> {
    let mut r = Reader { data: bytes, at: 0 };
    for v in out.iter_mut() {
        get(&mut r, v)?;
    }
    if r.at != bytes.len() {
        return Err("a row of the film has bytes left over (damaged file?)".into());
    }
    Ok(())
}

/// Adds the films of `parts` (each [`Parsed::fits`] `film`) into `film`: rows in parallel,
/// every part's row added into the film's row (exact integer sums, so in any order).
fn add_parts(film: &mut Film, parts: &[(String, Parsed)]) -> Result<(), String> {
    use rayon::prelude::*;
    let (min, max) = film.pixel_bounds();
    let width = ((max.x - min.x) as usize).max(1);
    let named = |name: &str, e: String| {
        if name.is_empty() {
            e
        } else {
            format!("{name}: {e}")
        }
    };
    let (pixels, splats) = film.fixed_sums_mut();
    pixels
        .par_chunks_mut(width)
        .enumerate()
        .try_for_each(|(y, row)| {
            for (name, p) in parts {
                add_row(p.pixel_rows[y], row, |r, px| {
                    let mut add = FixedSums::default();
                    for v in &mut add.v {
                        *v = r.sleb()?;
                    }
                    add.count =
                        u64::try_from(r.uleb()?).map_err(|_| "a sample count is out of range")?;
                    px.add(&add);
                    Ok(())
                })
                .map_err(|e| named(name, e))?;
            }
            Ok::<(), String>(())
        })?;
    if parts.iter().any(|(_, p)| p.splat_rows.is_some()) {
        if splats.is_empty() {
            splats.resize(pixels.len(), [0; 3]);
        }
        splats
            .par_chunks_mut(width)
            .enumerate()
            .try_for_each(|(y, row)| {
                for (name, p) in parts {
                    let Some(rows) = &p.splat_rows else { continue };
                    add_row(rows[y], row, |r, s| {
                        for c in s.iter_mut() {
                            *c = c.wrapping_add(r.sleb()?);
                        }
                        Ok(())
                    })
                    .map_err(|e| named(name, e))?;
                }
                Ok::<(), String>(())
            })?;
    }
    for (_, p) in parts {
        film.add_counts(p.h.samples, p.h.nonfinite);
    }
    Ok(())
}

/// Decodes a state file's bytes, adding its film to `acc` (made from the file's header when
/// `None`; otherwise it must have the same film). Returns its description.
pub fn decode_into(data: &[u8], acc: &mut Option<Film>) -> Result<StateInfo, String> {
    let p = parse(data, true)?;
    let film = acc.get_or_insert_with(|| p.blank_film());
    if !p.fits(film) {
        return Err("its film differs in size, crop or filter from the other states'".into());
    }
    let info = p.h.info.clone();
    add_parts(film, &[(String::new(), p)])?;
    Ok(info)
}

/// Checks that states of one render cover its items once (named states: errors say which
/// file misses or doubles what).
pub fn check_cover(states: &[(String, StateInfo)]) -> Result<(), String> {
    let Some((first_name, first)) = states.first() else {
        return Err("no states to merge".into());
    };
    for (name, s) in &states[1..] {
        if s.identity != first.identity || s.items_total != first.items_total {
            return Err(format!(
                "{name} belongs to another render than {first_name}: {} vs {}",
                s.description, first.description
            ));
        }
    }
    let total = first.items_total;
    let mut order: Vec<usize> = (0..states.len()).collect();
    order.sort_by_key(|&i| (states[i].1.items.start, states[i].1.items.end));
    let mut at = 0u64;
    let mut last = None::<usize>;
    let mut problems = Vec::new();
    for &i in &order {
        let r = &states[i].1.items;
        if r.is_empty() {
            continue;
        }
        if r.start > at {
            problems.push(format!("items {at}..{} are in no state", r.start));
        } else if r.start < at {
            let prev = last.map_or("?", |j| states[j].0.as_str());
            problems.push(format!(
                "items {}..{} are in both {prev} and {}",
                r.start,
                at.min(r.end),
                states[i].0
            ));
        }
        if r.end > at {
            at = r.end;
            last = Some(i);
        }
    }
    if at < total {
        problems.push(format!("items {at}..{total} are in no state"));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "the states do not cover the render once ({total} items): {}",
            problems.join("; ")
        ))
    }
}

/// Merges states of one render (file contents, named for messages) that cover its items
/// once into the state of the whole: headers and checksums first (in parallel), so that a
/// wrong set is refused before anything is decoded; then every state's rows added into one
/// film, rows in parallel.
pub fn merge_bytes(parts: &[(String, &[u8])]) -> Result<FilmState, String> {
    use rayon::prelude::*;
    let parsed = parts
        .par_iter()
        .map(|(name, d)| {
            parse(d, true)
                .map(|p| (name.clone(), p))
                .map_err(|e| format!("{name}: {e}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let infos: Vec<(String, StateInfo)> = parsed
        .iter()
        .map(|(name, p)| (name.clone(), p.h.info.clone()))
        .collect();
    check_cover(&infos)?;
    let (_, first) = parsed.first().ok_or("no states to merge")?;
    let mut whole = first.blank_film();
    if let Some((name, _)) = parsed.iter().find(|(_, p)| !p.fits(&whole)) {
        return Err(format!(
            "{name}: its film differs in size, crop or filter from the other states'"
        ));
    }
    add_parts(&mut whole, &parsed)?;
    let mut info = infos[0].1.clone();
    info.items = 0..info.items_total;
    Ok(FilmState { info, film: whole })
}

/// [`merge_bytes`] of state files (read in parallel); errors name the file.
pub fn merge_files(paths: &[std::path::PathBuf]) -> Result<FilmState, String> {
    use rayon::prelude::*;
    let data: Vec<Vec<u8>> = paths
        .par_iter()
        .map(|p| std::fs::read(p).map_err(|e| format!("{}: cannot read: {e}", p.display())))
        .collect::<Result<_, _>>()?;
    let named: Vec<(String, &[u8])> = paths
        .iter()
        .zip(&data)
        .map(|(p, d)| (p.display().to_string(), d.as_slice()))
        .collect();
    merge_bytes(&named)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Vec2, Vec3};
    use base::FilterDesc;

    fn state(items: Range<u64>, seed: u32) -> FilmState {
        let mut film = Film::new(
            9,
            7,
            Some(CropWindow {
                offset_x: 1,
                offset_y: 2,
                width: 6,
                height: 4,
            }),
            Filter::new(&FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
                radius: 2.0,
            }),
        );
        let mut tile = film.tile(UVec2::ZERO, UVec2::new(9, 7));
        for k in 0..50 {
            let u = ((k * 7919 + seed * 104729) % 1000) as f32 / 1000.0;
            tile.add_sample(
                Vec2::new(1.0 + 6.0 * u, 2.0 + 4.0 * (1.0 - u)),
                Vec3::new(u, -u * 1e5, 1e-9),
            );
        }
        film.merge(&tile);
        film.add_splat(Vec2::new(3.5, 3.5), Vec3::splat(seed as f32));
        film.set_splat_scale(0.25);
        FilmState {
            info: StateInfo {
                identity: 42,
                description: "test.xml, 4 spp".into(),
                items_total: 10,
                items,
                spp: 4,
                tonemap: Some(Tonemap::Photographic {
                    key: 0.18,
                    burn_percent: 1.0,
                    saturation: 1.0,
                    gamma: 2.2,
                }),
            },
            film,
        }
    }

    /// Variable-length integers read back as written, through the one-word path (numbers
    /// that end within 8 bytes with 8 bytes left) and the byte-by-byte one (longer
    /// numbers, the file's last bytes).
    #[test]
    fn leb128_round_trip() {
        let mut values = vec![0i128, 1, -1, 63, -64, 64, i128::MAX, i128::MIN];
        for b in [7, 27, 28, 55, 56, 57, 63, 64, 100, 126] {
            let p = 1i128 << b;
            values.extend([p - 1, p, p + 1, -p, -p - 1, 1 - p]);
        }
        let mut bytes = Vec::new();
        values.iter().for_each(|&v| put_sleb(&mut bytes, v));
        let mut r = Reader {
            data: &bytes,
            at: 0,
        };
        for &v in &values {
            assert_eq!(r.sleb().unwrap(), v);
        }
        assert_eq!(r.at, bytes.len());
        assert!(r.sleb().is_err());
    }

    /// A state reads back as written (every sum, bounds, filter, tone mapping); damage and
    /// truncation are refused with a message, never a panic.
    #[test]
    fn round_trip_and_damage() {
        let s = state(3..7, 1);
        let bytes = to_bytes(&s.info, &s.film);
        let back = FilmState::from_bytes(&bytes).unwrap();
        assert_eq!(back.film.fixed_sums(), s.film.fixed_sums());
        assert_eq!(to_bytes(&back.info, &back.film), bytes);
        assert_eq!(back.info, s.info);
        assert_eq!(back.film.develop().pixels, s.film.develop().pixels);
        for cut in [0, 10, MAGIC.len() + 3, bytes.len() / 2, bytes.len() - 1] {
            assert!(
                FilmState::from_bytes(&bytes[..cut]).is_err(),
                "cut at {cut}"
            );
        }
        for at in (0..bytes.len()).step_by(7) {
            let mut bad = bytes.clone();
            bad[at] ^= 0x5a;
            assert!(FilmState::from_bytes(&bad).is_err(), "flip at {at}");
        }
    }

    /// Merging checks the cover: a gap, a double and a foreign state are named; disjoint
    /// states covering everything add up exactly, in any order.
    #[test]
    fn merge_checks_the_cover() {
        let dir = std::env::temp_dir().join(format!("penumbra-state-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut paths = Vec::new();
        for (name, items, seed) in [
            ("a", 0..3, 1),
            ("b", 3..7, 2),
            ("c", 7..10, 3),
            ("d", 5..8, 4),
        ] {
            let p = dir.join(format!("{name}.state"));
            state(items, seed).write(&p).unwrap();
            paths.push(p);
        }
        let whole = merge_files(&paths[..3]).unwrap();
        let reversed: Vec<_> = paths[..3].iter().rev().cloned().collect();
        assert_eq!(
            merge_files(&reversed).unwrap().film.fixed_sums(),
            whole.film.fixed_sums()
        );
        let mut sum = state(0..3, 1).film;
        sum.add_film(&state(3..7, 2).film);
        sum.add_film(&state(7..10, 3).film);
        assert_eq!(whole.film.fixed_sums(), sum.fixed_sums());
        assert_eq!(whole.info.items, 0..10);
        let e = merge_files(&[paths[0].clone(), paths[2].clone()]).unwrap_err();
        assert!(e.contains("items 3..7 are in no state"), "{e}");
        let e = merge_files(&paths).unwrap_err();
        assert!(e.contains("in both") && e.contains("d.state"), "{e}");
        let mut foreign = state(7..10, 3);
        foreign.info.identity = 7;
        let f = dir.join("foreign.state");
        foreign.write(&f).unwrap();
        let e = merge_files(&[paths[0].clone(), paths[1].clone(), f]).unwrap_err();
        assert!(e.contains("another render"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
