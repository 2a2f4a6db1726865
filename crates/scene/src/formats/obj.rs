//! Wavefront OBJ mesh reader (geometry only; materials are the CS-E5520 loader's business).
//!
//! Supported: `v` (extra components such as `w` or vertex colours are ignored), `vn`, `vt`
//! (one to three components, the first two are used), `f` with `v`, `v/vt`, `v//vn` and
//! `v/vt/vn` corners, positive and negative (relative) indices, polygons (fan-triangulated),
//! `#` comments, tabs and `\r\n`. `g`, `o`, `s`, `l`, `p`, `mtllib` and unknown keywords are
//! ignored by the geometry; [`read_obj_groups`] additionally reports the `mtllib` files and the
//! `usemtl` material of every triangle.
//!
//! OBJ indexes positions, texture coordinates and normals separately, while [`TriMesh`] has one
//! attribute set per vertex: every distinct (position, uv, normal) triple becomes one vertex.
//! If some face corners lack an attribute the attribute is dropped for the whole mesh rather
//! than invented. A corner that names a uv (or normal) while the file has not defined any is
//! tolerated and treated as having none (a common exporter quirk).

use std::borrow::Cow;
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::hash::{BuildHasherDefault, Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::{LoadError, Loc, Result, TriMesh, Vec2, Vec3};

/// Read an OBJ file into one triangle mesh (all groups merged).
pub fn read_obj(path: &Path) -> Result<TriMesh> {
    read_obj_groups(path).map(|o| o.mesh)
}

/// Read an OBJ file into one triangle mesh plus its material assignment.
pub fn read_obj_groups(path: &Path) -> Result<ObjMesh> {
    let bytes = crate::read_file(path)
        .map_err(|e| LoadError::new(Loc::file(path), format!("cannot read OBJ file: {e}")))?;
    // Geometry is ASCII; comments and names in legacy encodings must not make the file fail.
    let text = match std::str::from_utf8(&bytes) {
        Ok(s) => Cow::Borrowed(s),
        Err(_) => String::from_utf8_lossy(&bytes),
    };
    parse_obj_groups(&text, path)
}

/// Parse OBJ text; `file` is only used for error locations.
pub fn parse_obj(text: &str, file: &Path) -> Result<TriMesh> {
    parse_obj_groups(text, file).map(|o| o.mesh)
}

/// A name given on an OBJ line (`mtllib` file, `usemtl` material) and where it was given.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjName {
    pub name: String,
    pub loc: Loc,
}

/// An OBJ file's geometry and material assignment.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjMesh {
    pub mesh: TriMesh,
    /// `mtllib` arguments in file order, as written (paths relative to the OBJ file).
    pub mtllibs: Vec<ObjName>,
    /// Distinct `usemtl` names in order of first use (`loc` is the first use).
    pub materials: Vec<ObjName>,
    /// One entry per triangle of `mesh`: an index into `materials`, `None` before any `usemtl`.
    pub triangle_materials: Vec<Option<u32>>,
}

/// Parse OBJ text into geometry plus material assignment; `file` names error locations.
pub fn parse_obj_groups(text: &str, file: &Path) -> Result<ObjMesh> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut p = Parser {
        file: Arc::new(file.to_path_buf()),
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        corners: Vec::new(),
        face: Vec::new(),
        mtllibs: Vec::new(),
        materials: Vec::new(),
        material_ids: HashMap::new(),
        current_material: None,
        triangle_materials: Vec::new(),
    };
    for (i, raw) in text.split('\n').enumerate() {
        let line_no = u32::try_from(i + 1).unwrap_or(u32::MAX);
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        p.line(line, line_no)?;
    }
    p.finish()
}

/// Sentinel for "this corner has no uv / normal".
const NONE: u32 = u32::MAX;

/// One face corner: 0-based indices into the position, uv and normal lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Corner {
    p: u32,
    t: u32,
    n: u32,
}

impl Hash for Corner {
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_u64((u64::from(self.p) << 32 | u64::from(self.t)) ^ u64::from(self.n) << 17);
    }
}

/// A small, fast hasher for the corner de-duplication map (keys are not attacker-controlled in
/// any way that matters: worst case a slow load of a hostile file).
#[derive(Default)]
struct CornerHasher(u64);

impl Hasher for CornerHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0 ^ v)
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .rotate_left(23);
    }
    fn finish(&self) -> u64 {
        // MurmurHash3's 64-bit finaliser: every input bit affects the low (bucket) and high
        // (control byte) bits.
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }
}

struct Parser {
    file: Arc<PathBuf>,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    /// Three corners per triangle.
    corners: Vec<Corner>,
    /// Corners of the face being parsed (reused).
    face: Vec<Corner>,
    mtllibs: Vec<ObjName>,
    materials: Vec<ObjName>,
    material_ids: HashMap<String, u32>,
    current_material: Option<u32>,
    triangle_materials: Vec<Option<u32>>,
}

/// Whitespace-separated tokens of a line with their byte offsets.
struct Tokens<'a> {
    s: &'a str,
    pos: usize,
}

impl<'a> Iterator for Tokens<'a> {
    type Item = (&'a str, usize);
    fn next(&mut self) -> Option<Self::Item> {
        let b = self.s.as_bytes();
        while self.pos < b.len() && is_space(b[self.pos]) {
            self.pos += 1;
        }
        if self.pos >= b.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < b.len() && !is_space(b[self.pos]) {
            self.pos += 1;
        }
        // Token boundaries are ASCII bytes, so the slice is on char boundaries.
        Some((&self.s[start..self.pos], start))
    }
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\x0b' | b'\x0c')
}

impl Parser {
    fn err(&self, line: &str, line_no: u32, byte: usize, msg: impl Into<String>) -> LoadError {
        let byte = byte.min(line.len());
        let col = line
            .get(..byte)
            .map_or(byte, |s| s.chars().count())
            .saturating_add(1);
        LoadError::new(
            Loc::new(&self.file, line_no, u32::try_from(col).unwrap_or(u32::MAX)),
            msg,
        )
    }

    fn line(&mut self, line: &str, line_no: u32) -> Result<()> {
        let content = line.find('#').map_or(line, |k| &line[..k]);
        let mut toks = Tokens { s: content, pos: 0 };
        let Some((kw, kw_at)) = toks.next() else {
            return Ok(());
        };
        match kw {
            "v" => {
                let [x, y, z] = self.floats::<3>(&mut toks, line, line_no, "v")?;
                if self.positions.len() >= NONE as usize {
                    return Err(self.err(line, line_no, kw_at, "too many vertices"));
                }
                self.positions.push(Vec3::new(x, y, z));
            }
            "vn" => {
                let [x, y, z] = self.floats::<3>(&mut toks, line, line_no, "vn")?;
                if self.normals.len() >= NONE as usize {
                    return Err(self.err(line, line_no, kw_at, "too many normals"));
                }
                self.normals.push(Vec3::new(x, y, z));
            }
            "vt" => {
                let [u] = self.floats::<1>(&mut toks, line, line_no, "vt")?;
                // `vt u` alone is legal (v defaults to 0).
                let v = match toks.next() {
                    Some((tok, at)) => self.float(tok, line, line_no, at)?,
                    None => 0.0,
                };
                if self.uvs.len() >= NONE as usize {
                    return Err(self.err(line, line_no, kw_at, "too many texture coordinates"));
                }
                self.uvs.push(Vec2::new(u, v));
            }
            "f" => self.face(toks, line, line_no, kw_at)?,
            "usemtl" => {
                let name = content[toks.pos..].trim();
                if name.is_empty() {
                    return Err(self.err(line, line_no, content.len(), "usemtl without a name"));
                }
                let id = match self.material_ids.get(name) {
                    Some(&id) => id,
                    None => {
                        let id = self.materials.len() as u32;
                        self.material_ids.insert(name.to_owned(), id);
                        self.materials.push(ObjName {
                            name: name.to_owned(),
                            loc: Loc::new(&self.file, line_no, 1),
                        });
                        id
                    }
                };
                self.current_material = Some(id);
            }
            "mtllib" => {
                let name = content[toks.pos..].trim();
                if !name.is_empty() {
                    self.mtllibs.push(ObjName {
                        name: name.to_owned(),
                        loc: Loc::new(&self.file, line_no, 1),
                    });
                }
            }
            // g, o, s, l, p, and everything we do not know.
            _ => {}
        }
        Ok(())
    }

    fn float(&self, tok: &str, line: &str, line_no: u32, at: usize) -> Result<f32> {
        match tok.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.err(
                line,
                line_no,
                at,
                format!("'{tok}' is not a finite single-precision number"),
            )),
            Err(_) => Err(self.err(line, line_no, at, format!("invalid number '{tok}'"))),
        }
    }

    fn floats<const N: usize>(
        &self,
        toks: &mut Tokens<'_>,
        line: &str,
        line_no: u32,
        kw: &str,
    ) -> Result<[f32; N]> {
        let mut out = [0.0; N];
        for (k, o) in out.iter_mut().enumerate() {
            let Some((tok, at)) = toks.next() else {
                return Err(self.err(
                    line,
                    line_no,
                    toks.pos,
                    format!("'{kw}' needs {N} numbers, found {k}"),
                ));
            };
            *o = self.float(tok, line, line_no, at)?;
        }
        Ok(out)
    }

    /// Resolve a 1-based or negative (relative) OBJ index into a 0-based one.
    fn index(
        &self,
        tok: &str,
        count: usize,
        what: &str,
        line: &str,
        line_no: u32,
        at: usize,
    ) -> Result<u32> {
        let i: i64 = tok
            .parse()
            .map_err(|_| self.err(line, line_no, at, format!("invalid {what} index '{tok}'")))?;
        let resolved = if i > 0 {
            i - 1
        } else if i < 0 {
            count as i64 + i
        } else {
            return Err(self.err(
                line,
                line_no,
                at,
                format!("{what} index 0 is invalid (OBJ indices start at 1)"),
            ));
        };
        if resolved < 0 || resolved >= count as i64 {
            return Err(self.err(
                line,
                line_no,
                at,
                format!("{what} index {i} out of range ({count} defined so far)"),
            ));
        }
        Ok(resolved as u32)
    }

    fn face(&mut self, toks: Tokens<'_>, line: &str, line_no: u32, kw_at: usize) -> Result<()> {
        let mut face = std::mem::take(&mut self.face);
        face.clear();
        for (tok, at) in toks {
            // Up to three '/'-separated parts with their byte offsets in the line.
            let mut parts = [("", at); 3];
            let mut offset = at;
            for (k, part) in tok.split('/').enumerate() {
                if k == 3 {
                    return Err(self.err(
                        line,
                        line_no,
                        at,
                        format!("face corner '{tok}' has more than three indices"),
                    ));
                }
                parts[k] = (part, offset);
                offset += part.len() + 1;
            }
            let [(v, v_at), (t, t_at), (n, n_at)] = parts;
            let p = self.index(v, self.positions.len(), "vertex", line, line_no, v_at)?;
            // An empty part, or a reference to an attribute list the file does not have at
            // all, means "no attribute" for this corner.
            let t = if t.is_empty() || self.uvs.is_empty() {
                NONE
            } else {
                self.index(t, self.uvs.len(), "texture coordinate", line, line_no, t_at)?
            };
            let n = if n.is_empty() || self.normals.is_empty() {
                NONE
            } else {
                self.index(n, self.normals.len(), "normal", line, line_no, n_at)?
            };
            face.push(Corner { p, t, n });
        }
        if face.len() < 3 {
            let msg = format!("face has {} vertices (at least 3 needed)", face.len());
            return Err(self.err(line, line_no, kw_at, msg));
        }
        for k in 1..face.len() - 1 {
            self.corners
                .extend_from_slice(&[face[0], face[k], face[k + 1]]);
            self.triangle_materials.push(self.current_material);
        }
        self.face = face;
        Ok(())
    }

    fn finish(self) -> Result<ObjMesh> {
        let has = |f: fn(&Corner) -> bool| !self.corners.is_empty() && self.corners.iter().all(f);
        let use_t = has(|c| c.t != NONE);
        let use_n = has(|c| c.n != NONE);
        let mut map: HashMap<Corner, u32, BuildHasherDefault<CornerHasher>> =
            HashMap::with_capacity_and_hasher(
                self.positions.len().min(self.corners.len()),
                Default::default(),
            );
        let mut mesh = TriMesh {
            positions: Vec::with_capacity(self.positions.len()),
            normals: Vec::new(),
            uvs: Vec::new(),
            indices: Vec::with_capacity(self.corners.len() / 3),
        };
        let mut tri = [0u32; 3];
        for (k, c) in self.corners.iter().enumerate() {
            let key = Corner {
                p: c.p,
                t: if use_t { c.t } else { NONE },
                n: if use_n { c.n } else { NONE },
            };
            let v = match map.entry(key) {
                Entry::Occupied(e) => *e.get(),
                Entry::Vacant(e) => {
                    let next = u32::try_from(mesh.positions.len())
                        .ok()
                        .filter(|&n| n != NONE)
                        .ok_or_else(|| {
                            LoadError::new(
                                Loc::new(&self.file, 0, 0),
                                "too many distinct vertices for 32-bit indices",
                            )
                        })?;
                    e.insert(next);
                    // Indices were range-checked when the face was parsed.
                    mesh.positions.push(self.positions[key.p as usize]);
                    if use_t {
                        mesh.uvs.push(self.uvs[key.t as usize]);
                    }
                    if use_n {
                        mesh.normals.push(self.normals[key.n as usize]);
                    }
                    next
                }
            };
            tri[k % 3] = v;
            if k % 3 == 2 {
                mesh.indices.push(tri);
            }
        }
        Ok(ObjMesh {
            mesh,
            mtllibs: self.mtllibs,
            materials: self.materials,
            triangle_materials: self.triangle_materials,
        })
    }
}
