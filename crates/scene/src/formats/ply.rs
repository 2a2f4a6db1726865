//! Stanford PLY mesh reader (ascii, binary little- and big-endian) and a binary writer.
//!
//! Vertex properties used: `x y z`, `nx ny nz`, and the first complete uv pair among
//! `u v`, `s t`, `texture_u texture_v`, `texture_s texture_t`; any scalar type is accepted for
//! them and every other property is skipped. Faces come from the `face` element's list
//! property `vertex_indices` (or `vertex_index`), with any integer count and index types, and
//! are fan-triangulated. Other elements are skipped, including binary ones with list
//! properties.
//!
//! Untrusted input: every read is bounds-checked, element counts from the header are never
//! trusted for preallocation beyond what the file size allows, and every index is checked
//! against the vertex count. Errors name the header line, the data line and column (ascii), or
//! the byte offset (binary).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::{LoadError, Loc, Result, TriMesh, Vec2, Vec3};

/// Read a PLY file into a triangle mesh.
///
/// A file without a `face` element yields a mesh without triangles (it is not malformed).
pub fn read_ply(path: &Path) -> Result<TriMesh> {
    let data = crate::read_file(path)
        .map_err(|e| LoadError::new(Loc::file(path), format!("cannot read PLY file: {e}")))?;
    parse_ply(&data, path)
}

/// Parse PLY bytes; `file` is only used for error locations.
pub fn parse_ply(data: &[u8], file: &Path) -> Result<TriMesh> {
    let file = Arc::new(file.to_path_buf());
    let header = parse_header(data, &file)?;
    let mut reader = Reader::new(&header, &file)?;
    match header.format {
        Format::Ascii => {
            let mut src = Ascii {
                data,
                pos: header.data_start,
                line: header.data_line,
                line_start: header.data_start,
                file: &file,
            };
            for elem in &header.elements {
                reader.element_generic(elem, &mut src)?;
            }
        }
        Format::BinaryLe | Format::BinaryBe => {
            let mut src = Binary {
                data,
                pos: header.data_start,
                big: header.format == Format::BinaryBe,
                file: &file,
            };
            for elem in &header.elements {
                reader.element_binary(elem, &mut src)?;
            }
        }
    }
    Ok(reader.mesh)
}

/// Write `mesh` as a binary little-endian PLY, with normals and uvs when the mesh has them
/// (one per position).
pub fn write_ply(path: &Path, mesh: &TriMesh) -> std::io::Result<()> {
    let n = mesh.positions.len();
    let invalid = |msg: &str| std::io::Error::new(std::io::ErrorKind::InvalidInput, msg.to_owned());
    if !mesh.normals.is_empty() && mesh.normals.len() != n {
        return Err(invalid(
            "mesh has a normal count different from its position count",
        ));
    }
    if !mesh.uvs.is_empty() && mesh.uvs.len() != n {
        return Err(invalid(
            "mesh has a uv count different from its position count",
        ));
    }
    if mesh.indices.iter().flatten().any(|&i| i as usize >= n) {
        return Err(invalid("mesh has an index out of range"));
    }
    let has_n = !mesh.normals.is_empty();
    let has_uv = !mesh.uvs.is_empty();
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by Penumbra\nelement vertex {n}\n\
         property float x\nproperty float y\nproperty float z\n"
    );
    if has_n {
        header.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if has_uv {
        header.push_str("property float u\nproperty float v\n");
    }
    // `int` is what every reader understands; `uint` only when indices need the 32nd bit.
    let index_type = if n > i32::MAX as usize { "uint" } else { "int" };
    header.push_str(&format!(
        "element face {}\nproperty list uchar {index_type} vertex_indices\nend_header\n",
        mesh.indices.len()
    ));
    let floats_per_vertex = 3 + if has_n { 3 } else { 0 } + if has_uv { 2 } else { 0 };
    let mut buf =
        Vec::with_capacity(header.len() + n * floats_per_vertex * 4 + mesh.indices.len() * 13);
    buf.extend_from_slice(header.as_bytes());
    for i in 0..n {
        for v in mesh.positions[i].to_array() {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        if has_n {
            for v in mesh.normals[i].to_array() {
                buf.extend_from_slice(&v.to_le_bytes());
            }
        }
        if has_uv {
            for v in mesh.uvs[i].to_array() {
                buf.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    for tri in &mesh.indices {
        buf.push(3);
        for &i in tri {
            buf.extend_from_slice(&i.to_le_bytes());
        }
    }
    let mut f = std::fs::File::create(path)?;
    f.write_all(&buf)?;
    f.flush()
}

// ---------------------------------------------------------------------------------------------
// Header

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
    line: u32,
}

impl Element {
    /// Size of one record when every property is a scalar.
    fn fixed_size(&self) -> Option<usize> {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => Some(s.size()),
                Kind::List { .. } => None,
            })
            .sum()
    }
    /// A lower bound on the bytes one record takes in a binary file (lists may be empty).
    fn min_binary_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }
    fn find(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the first data byte.
    data_start: usize,
    /// Line number of the first data line (ascii).
    data_line: u32,
}

fn parse_header(data: &[u8], file: &Arc<PathBuf>) -> Result<Header> {
    let err = |line: u32, col: u32, msg: String| LoadError::new(Loc::new(file, line, col), msg);
    if !data.starts_with(b"ply") || !matches!(data.get(3), Some(b'\n' | b'\r')) {
        return Err(err(
            1,
            1,
            "not a PLY file (it does not start with a 'ply' line)".into(),
        ));
    }
    let lone_cr = data.get(3) == Some(&b'\r') && data.get(4) != Some(&b'\n');
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0usize;
    let mut line_no = 0u32;
    loop {
        if pos >= data.len() {
            return Err(err(
                line_no,
                0,
                "PLY header ends without an 'end_header' line".into(),
            ));
        }
        line_no = line_no.saturating_add(1);
        let rest = &data[pos..];
        let eol = rest
            .iter()
            .position(|&b| b == b'\n' || b == b'\r')
            .unwrap_or(rest.len());
        let raw = &rest[..eol];
        // Terminators: "\n", "\r\n" or a lone "\r" (as announced by the "ply" line). After
        // `end_header` of a lone-"\r" file, a following "\n" is binary data, not a terminator.
        pos += eol;
        if data.get(pos) == Some(&b'\r') {
            pos += 1;
            if data.get(pos) == Some(&b'\n') && !(lone_cr && raw == b"end_header") {
                pos += 1;
            }
        } else if data.get(pos) == Some(&b'\n') {
            pos += 1;
        }
        let Ok(line) = std::str::from_utf8(raw) else {
            return Err(err(line_no, 1, "PLY header line is not text".into()));
        };
        let mut toks = line.split_ascii_whitespace();
        let Some(kw) = toks.next() else { continue };
        let col_of = |tok: &str| -> u32 {
            // `tok` is a sub-slice of `line`.
            (tok.as_ptr() as usize - line.as_ptr() as usize + 1) as u32
        };
        match kw {
            "ply" if line_no == 1 => {}
            "comment" | "obj_info" => {}
            "format" => {
                let f = toks.next().unwrap_or("");
                format = Some(match f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    _ => {
                        let col = if f.is_empty() { 1 } else { col_of(f) };
                        return Err(err(line_no, col, format!("unknown PLY format '{f}'")));
                    }
                });
                match toks.next() {
                    Some("1.0" | "1") => {}
                    Some(v) => {
                        return Err(err(
                            line_no,
                            col_of(v),
                            format!("unsupported PLY version '{v}'"),
                        ));
                    }
                    None => {}
                }
            }
            "element" => {
                let (Some(name), Some(count)) = (toks.next(), toks.next()) else {
                    return Err(err(line_no, 1, "'element' needs a name and a count".into()));
                };
                let count: u64 = count.parse().map_err(|_| {
                    err(
                        line_no,
                        col_of(count),
                        format!("invalid element count '{count}'"),
                    )
                })?;
                if elements.iter().any(|e| e.name == name) && matches!(name, "vertex" | "face") {
                    return Err(err(
                        line_no,
                        col_of(name),
                        format!("duplicate '{name}' element"),
                    ));
                }
                elements.push(Element {
                    name: name.to_owned(),
                    count,
                    props: Vec::new(),
                    line: line_no,
                });
            }
            "property" => {
                let Some(elem) = elements.last_mut() else {
                    return Err(err(line_no, 1, "'property' before any 'element'".into()));
                };
                let ty = toks.next().unwrap_or("");
                let scalar = |t: &str| {
                    Scalar::parse(t).ok_or_else(|| {
                        let col = if t.is_empty() { 1 } else { col_of(t) };
                        err(line_no, col, format!("unknown PLY property type '{t}'"))
                    })
                };
                let kind = if ty == "list" {
                    let count_ty = toks.next().unwrap_or("");
                    let count = scalar(count_ty)?;
                    let item = scalar(toks.next().unwrap_or(""))?;
                    if !count.is_int() {
                        return Err(err(
                            line_no,
                            col_of(count_ty),
                            format!("list count type '{count_ty}' is not an integer type"),
                        ));
                    }
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(scalar(ty)?)
                };
                let Some(name) = toks.next() else {
                    return Err(err(line_no, 1, "'property' without a name".into()));
                };
                elem.props.push(Property {
                    name: name.to_owned(),
                    kind,
                });
            }
            "end_header" => break,
            _ => {
                return Err(err(
                    line_no,
                    1,
                    format!("unknown PLY header keyword '{kw}'"),
                ));
            }
        }
    }
    let Some(format) = format else {
        return Err(err(1, 0, "PLY header has no 'format' line".into()));
    };
    Ok(Header {
        format,
        elements,
        data_start: pos,
        data_line: line_no.saturating_add(1),
    })
}

// ---------------------------------------------------------------------------------------------
// Data sources

/// A stream of property values: ascii tokens or binary scalars.
trait Source {
    /// Read one value of type `ty`.
    fn value(&mut self, ty: Scalar) -> Result<f64>;
    /// Read one integer of (integer) type `ty`.
    fn int(&mut self, ty: Scalar) -> Result<i64>;
    /// Skip `n` values of type `ty`.
    fn skip(&mut self, ty: Scalar, n: u64) -> Result<()>;
    /// Prefix an error with what was being read.
    fn context(&self, e: LoadError, what: &dyn Fn() -> String) -> LoadError {
        LoadError::new(e.loc, format!("{}: {}", what(), e.message))
    }
    /// Bytes left to read.
    fn remaining(&self) -> usize;
    /// How many bytes one record of `elem` takes at least.
    fn min_record_size(&self, elem: &Element) -> usize;
    /// An error at the current position.
    fn error(&self, msg: String) -> LoadError;
    /// The position of the next value (for errors about it once it has been read).
    fn mark(&mut self) -> Mark;
    /// An error at a marked position.
    fn error_at(&self, mark: Mark, msg: String) -> LoadError;
}

/// A position in the data: byte offset, and line and column for ascii files.
#[derive(Clone, Copy, Debug)]
struct Mark {
    pos: usize,
    line: u32,
    col: u32,
}

struct Binary<'a> {
    data: &'a [u8],
    pos: usize,
    big: bool,
    file: &'a Arc<PathBuf>,
}

/// Decode a scalar from the start of `b` (which holds at least `ty.size()` bytes).
#[inline(always)]
fn decode(ty: Scalar, b: &[u8], big: bool) -> f64 {
    macro_rules! rd {
        ($t:ty, $n:expr) => {{
            let mut a = [0u8; $n];
            a.copy_from_slice(&b[..$n]);
            if big {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            }
        }};
    }
    match ty {
        Scalar::I8 => f64::from(b[0] as i8),
        Scalar::U8 => f64::from(b[0]),
        Scalar::I16 => f64::from(rd!(i16, 2)),
        Scalar::U16 => f64::from(rd!(u16, 2)),
        Scalar::I32 => f64::from(rd!(i32, 4)),
        Scalar::U32 => f64::from(rd!(u32, 4)),
        Scalar::F32 => f64::from(rd!(f32, 4)),
        Scalar::F64 => rd!(f64, 8),
    }
}

/// Decode an integer scalar from the start of `b`.
#[inline(always)]
fn decode_int(ty: Scalar, b: &[u8], big: bool) -> i64 {
    macro_rules! rd {
        ($t:ty, $n:expr) => {{
            let mut a = [0u8; $n];
            a.copy_from_slice(&b[..$n]);
            i64::from(if big {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            })
        }};
    }
    match ty {
        Scalar::I8 => i64::from(b[0] as i8),
        Scalar::U8 => i64::from(b[0]),
        Scalar::I16 => rd!(i16, 2),
        Scalar::U16 => rd!(u16, 2),
        Scalar::I32 => rd!(i32, 4),
        Scalar::U32 => rd!(u32, 4),
        // Float-typed indices are rejected when the layout is analysed.
        Scalar::F32 | Scalar::F64 => decode(ty, b, big) as i64,
    }
}

impl Binary<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8]> {
        match self.data.get(self.pos..).and_then(|r| r.get(..n)) {
            Some(b) => {
                self.pos += n;
                Ok(b)
            }
            None => Err(self.error(format!(
                "file truncated ({n} bytes needed, {} left)",
                self.remaining()
            ))),
        }
    }
}

impl Source for Binary<'_> {
    fn value(&mut self, ty: Scalar) -> Result<f64> {
        let big = self.big;
        Ok(decode(ty, self.take(ty.size())?, big))
    }
    fn int(&mut self, ty: Scalar) -> Result<i64> {
        let big = self.big;
        Ok(decode_int(ty, self.take(ty.size())?, big))
    }
    fn skip(&mut self, ty: Scalar, n: u64) -> Result<()> {
        let bytes = usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(ty.size()))
            .unwrap_or(usize::MAX);
        self.take(bytes).map(|_| ())
    }
    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }
    fn min_record_size(&self, elem: &Element) -> usize {
        elem.min_binary_size()
    }
    fn error(&self, msg: String) -> LoadError {
        let mark = Mark {
            pos: self.pos,
            line: 0,
            col: 0,
        };
        self.error_at(mark, msg)
    }
    fn mark(&mut self) -> Mark {
        Mark {
            pos: self.pos,
            line: 0,
            col: 0,
        }
    }
    fn error_at(&self, mark: Mark, msg: String) -> LoadError {
        LoadError::new(
            Loc::new(self.file, 0, 0),
            format!("{msg} (at byte offset {})", mark.pos),
        )
    }
}

struct Ascii<'a> {
    data: &'a [u8],
    pos: usize,
    line: u32,
    line_start: usize,
    file: &'a Arc<PathBuf>,
}

impl<'a> Ascii<'a> {
    /// The next whitespace-separated token and its (line, column).
    fn skip_space(&mut self) {
        let d = self.data;
        while self.pos < d.len() && d[self.pos].is_ascii_whitespace() {
            if d[self.pos] == b'\n' {
                self.line = self.line.saturating_add(1);
                self.line_start = self.pos + 1;
            }
            self.pos += 1;
        }
    }

    fn token(&mut self) -> Result<(&'a str, u32, u32)> {
        self.skip_space();
        let d = self.data;
        if self.pos >= d.len() {
            return Err(self.error("unexpected end of file".into()));
        }
        let start = self.pos;
        while self.pos < d.len() && !d[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let col = u32::try_from(start - self.line_start + 1).unwrap_or(u32::MAX);
        let tok = std::str::from_utf8(&d[start..self.pos]).unwrap_or("\u{fffd}");
        Ok((tok, self.line, col))
    }
    fn at(&self, line: u32, col: u32, msg: String) -> LoadError {
        LoadError::new(Loc::new(self.file, line, col), msg)
    }
}

impl Source for Ascii<'_> {
    fn value(&mut self, _ty: Scalar) -> Result<f64> {
        let (tok, line, col) = self.token()?;
        tok.parse::<f64>()
            .map_err(|_| self.at(line, col, format!("invalid number '{tok}'")))
    }
    fn int(&mut self, _ty: Scalar) -> Result<i64> {
        let (tok, line, col) = self.token()?;
        if let Ok(i) = tok.parse::<i64>() {
            return Ok(i);
        }
        // Some writers print integers as "3.0".
        match tok.parse::<f64>() {
            Ok(f) if f.fract() == 0.0 && f.abs() < 9.0e15 => Ok(f as i64),
            _ => Err(self.at(line, col, format!("invalid integer '{tok}'"))),
        }
    }
    fn skip(&mut self, ty: Scalar, n: u64) -> Result<()> {
        for _ in 0..n {
            self.value(ty)?;
        }
        Ok(())
    }
    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }
    fn min_record_size(&self, elem: &Element) -> usize {
        // Every value takes at least one character plus a separator.
        2 * elem.props.len()
    }
    fn error(&self, msg: String) -> LoadError {
        let col = u32::try_from(self.pos - self.line_start + 1).unwrap_or(u32::MAX);
        self.at(self.line, col, msg)
    }
    fn mark(&mut self) -> Mark {
        self.skip_space();
        Mark {
            pos: self.pos,
            line: self.line,
            col: u32::try_from(self.pos - self.line_start + 1).unwrap_or(u32::MAX),
        }
    }
    fn error_at(&self, mark: Mark, msg: String) -> LoadError {
        self.at(mark.line, mark.col, msg)
    }
}

// ---------------------------------------------------------------------------------------------
// Element readers

/// Read one `N`-component attribute from every `stride`-byte record of `block` (component `k`
/// at byte offset `fields[k].0`, of type `fields[k].1`) and append it to `out`.
#[inline(always)]
fn gather<const BIG: bool, const N: usize, T, F: Fn([f32; N]) -> T>(
    block: &[u8],
    stride: usize,
    fields: [(usize, Scalar); N],
    out: &mut Vec<T>,
    make: F,
) {
    let records = block.chunks_exact(stride);
    out.reserve_exact(records.len());
    if fields.iter().all(|&(_, s)| s == Scalar::F32) {
        // The common case: single-precision components.
        let offsets = fields.map(|(o, _)| o);
        out.extend(records.map(|rec| {
            let mut v = [0.0f32; N];
            for (x, &o) in v.iter_mut().zip(&offsets) {
                let b = [rec[o], rec[o + 1], rec[o + 2], rec[o + 3]];
                *x = if BIG {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                };
            }
            make(v)
        }));
    } else {
        out.extend(records.map(|rec| {
            let mut v = [0.0f32; N];
            for (x, &(o, s)) in v.iter_mut().zip(&fields) {
                *x = decode(s, &rec[o..], BIG) as f32;
            }
            make(v)
        }));
    }
}

/// `i` as a vertex index if it is in `0..vertex_count`.
fn checked_index(i: i64, vertex_count: u64) -> Option<u32> {
    u64::try_from(i)
        .ok()
        .filter(|&i| i < vertex_count)
        .and_then(|i| u32::try_from(i).ok())
}

/// Where the vertex attributes live in the vertex element.
struct VertexLayout {
    pos: [usize; 3],
    normal: Option<[usize; 3]>,
    uv: Option<[usize; 2]>,
}

/// Where the index list lives in the face element.
struct FaceLayout {
    prop: usize,
}

struct Reader<'a> {
    file: &'a Arc<PathBuf>,
    mesh: TriMesh,
    /// The vertex count announced by the header (indices are checked against it; the vertex
    /// element must then deliver exactly that many vertices or the load fails).
    vertex_count: u64,
    vertex: Option<VertexLayout>,
    face: Option<FaceLayout>,
}

impl<'a> Reader<'a> {
    fn new(header: &Header, file: &'a Arc<PathBuf>) -> Result<Self> {
        let herr = |line: u32, msg: String| LoadError::new(Loc::new(file, line, 0), msg);
        let mut vertex_count = 0;
        let mut vertex = None;
        let mut face = None;
        for e in &header.elements {
            match e.name.as_str() {
                "vertex" => {
                    vertex_count = e.count;
                    if e.count >= u64::from(u32::MAX) {
                        return Err(herr(e.line, format!("too many vertices ({})", e.count)));
                    }
                    let scalar = |name: &str| {
                        e.find(name)
                            .filter(|&i| matches!(e.props[i].kind, Kind::Scalar(_)))
                    };
                    let (Some(x), Some(y), Some(z)) = (scalar("x"), scalar("y"), scalar("z"))
                    else {
                        return Err(herr(
                            e.line,
                            "the vertex element lacks scalar x, y and z properties".into(),
                        ));
                    };
                    let normal = match (scalar("nx"), scalar("ny"), scalar("nz")) {
                        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
                        _ => None,
                    };
                    let uv = [
                        ("u", "v"),
                        ("s", "t"),
                        ("texture_u", "texture_v"),
                        ("texture_s", "texture_t"),
                    ]
                    .iter()
                    .find_map(|&(u, v)| Some([scalar(u)?, scalar(v)?]));
                    vertex = Some(VertexLayout {
                        pos: [x, y, z],
                        normal,
                        uv,
                    });
                }
                "face" => {
                    let Some(prop) = e.find("vertex_indices").or_else(|| e.find("vertex_index"))
                    else {
                        return Err(herr(
                            e.line,
                            "the face element has no 'vertex_indices' list".into(),
                        ));
                    };
                    match e.props[prop].kind {
                        Kind::List { item, .. } if item.is_int() => {}
                        _ => {
                            return Err(herr(
                                e.line,
                                format!(
                                    "face property '{}' is not a list of integers",
                                    e.props[prop].name
                                ),
                            ));
                        }
                    }
                    face = Some(FaceLayout { prop });
                }
                _ => {}
            }
        }
        if face.is_some() && vertex.is_none() {
            return Err(herr(1, "PLY file has faces but no vertex element".into()));
        }
        Ok(Reader {
            file,
            mesh: TriMesh::default(),
            vertex_count,
            vertex,
            face,
        })
    }

    /// Capacity to reserve for `count` records: never more than the remaining data can hold.
    fn capacity(count: u64, remaining: usize, min_record: usize) -> usize {
        let by_size = remaining / min_record.max(1);
        usize::try_from(count).unwrap_or(usize::MAX).min(by_size)
    }

    fn push_vertex(&mut self, p: [f64; 3], n: Option<[f64; 3]>, uv: Option<[f64; 2]>) -> bool {
        let p = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32);
        if !p.is_finite() {
            return false;
        }
        self.mesh.positions.push(p);
        if let Some(n) = n {
            let n = Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32);
            if !n.is_finite() {
                return false;
            }
            self.mesh.normals.push(n);
        }
        if let Some(uv) = uv {
            let uv = Vec2::new(uv[0] as f32, uv[1] as f32);
            if !uv.is_finite() {
                return false;
            }
            self.mesh.uvs.push(uv);
        }
        true
    }

    fn reserve_vertices(&mut self, n: usize) {
        let layout = self.vertex.as_ref();
        self.mesh.positions.reserve_exact(n);
        if layout.is_some_and(|l| l.normal.is_some()) {
            self.mesh.normals.reserve_exact(n);
        }
        if layout.is_some_and(|l| l.uv.is_some()) {
            self.mesh.uvs.reserve_exact(n);
        }
    }

    /// Read any element from any source, one value at a time.
    fn element_generic<S: Source>(&mut self, elem: &Element, src: &mut S) -> Result<()> {
        if elem.props.is_empty() {
            // Records without properties take no space, however many the header announces.
            return Ok(());
        }
        let cap = Self::capacity(elem.count, src.remaining(), src.min_record_size(elem));
        match elem.name.as_str() {
            "vertex" => {
                self.reserve_vertices(cap);
                let mut vals = vec![0.0f64; elem.props.len()];
                let mut used = vec![false; elem.props.len()];
                if let Some(l) = &self.vertex {
                    let uv = l.uv.iter().flatten();
                    for &k in l.pos.iter().chain(l.normal.iter().flatten()).chain(uv) {
                        used[k] = true;
                    }
                }
                for i in 0..elem.count {
                    let what = || format!("vertex {i}");
                    for (k, prop) in elem.props.iter().enumerate() {
                        match prop.kind {
                            Kind::Scalar(s) => {
                                let mark = src.mark();
                                let v = src.value(s).map_err(|e| src.context(e, &what))?;
                                if used[k] && !(v as f32).is_finite() {
                                    return Err(src.error_at(
                                        mark,
                                        format!(
                                            "vertex {i}: property '{}' is not a finite \
                                             single-precision number ({v:e})",
                                            prop.name
                                        ),
                                    ));
                                }
                                vals[k] = v;
                            }
                            Kind::List { count, item } => {
                                let n = self.list_len(src, count, &what)?;
                                src.skip(item, n).map_err(|e| src.context(e, &what))?;
                            }
                        }
                    }
                    let Some(l) = self.vertex.as_ref() else {
                        continue;
                    };
                    let p = l.pos.map(|k| vals[k]);
                    let n = l.normal.map(|ks| ks.map(|k| vals[k]));
                    let uv = l.uv.map(|ks| ks.map(|k| vals[k]));
                    // Values were checked as they were read.
                    self.push_vertex(p, n, uv);
                }
            }
            "face" => {
                self.mesh.indices.reserve_exact(cap);
                let target = self.face.as_ref().map_or(usize::MAX, |f| f.prop);
                for i in 0..elem.count {
                    let what = || format!("face {i}");
                    for (k, prop) in elem.props.iter().enumerate() {
                        match prop.kind {
                            Kind::Scalar(s) => src.skip(s, 1).map_err(|e| src.context(e, &what))?,
                            Kind::List { count, item } => {
                                let n = self.list_len(src, count, &what)?;
                                if k == target {
                                    self.polygon(src, item, n, &what)?;
                                } else {
                                    src.skip(item, n).map_err(|e| src.context(e, &what))?;
                                }
                            }
                        }
                    }
                }
            }
            _ => {
                for i in 0..elem.count {
                    let what = || format!("element '{}' {i}", elem.name);
                    for prop in &elem.props {
                        match prop.kind {
                            Kind::Scalar(s) => src.skip(s, 1),
                            Kind::List { count, item } => {
                                let n = self.list_len(src, count, &what)?;
                                src.skip(item, n)
                            }
                        }
                        .map_err(|e| src.context(e, &what))?;
                    }
                }
            }
        }
        Ok(())
    }

    fn list_len<S: Source>(
        &self,
        src: &mut S,
        ty: Scalar,
        what: &dyn Fn() -> String,
    ) -> Result<u64> {
        let n = src.int(ty).map_err(|e| src.context(e, what))?;
        u64::try_from(n)
            .map_err(|_| src.context(src.error(format!("negative list length {n}")), what))
    }

    /// Read a face's `n` indices and fan-triangulate them.
    fn polygon<S: Source>(
        &mut self,
        src: &mut S,
        item: Scalar,
        n: u64,
        what: &dyn Fn() -> String,
    ) -> Result<()> {
        if n < 3 {
            return Err(src.context(
                src.error(format!("face has {n} vertices (at least 3 needed)")),
                what,
            ));
        }
        let vertex_count = self.vertex_count;
        let read = |src: &mut S| -> Result<u32> {
            let mark = src.mark();
            let i = src.int(item).map_err(|e| src.context(e, what))?;
            checked_index(i, vertex_count).ok_or_else(|| {
                src.context(
                    src.error_at(
                        mark,
                        format!("vertex index {i} out of range ({vertex_count} vertices)"),
                    ),
                    what,
                )
            })
        };
        let first = read(src)?;
        let mut prev = read(src)?;
        for _ in 2..n {
            let cur = read(src)?;
            self.mesh.indices.push([first, prev, cur]);
            prev = cur;
        }
        Ok(())
    }

    /// Read an element of a binary file, with fast paths for fixed-size vertices and for
    /// triangle faces.
    fn element_binary(&mut self, elem: &Element, src: &mut Binary<'_>) -> Result<()> {
        match (elem.name.as_str(), elem.fixed_size()) {
            ("vertex", Some(stride)) => self.vertices_fixed(elem, stride, src),
            ("face", _) => self.faces_binary(elem, src),
            (_, Some(stride)) => {
                // Skip a fixed-size element in one step.
                let bytes = usize::try_from(elem.count)
                    .ok()
                    .and_then(|c| c.checked_mul(stride))
                    .unwrap_or(usize::MAX);
                src.take(bytes).map(|_| ()).map_err(|e| {
                    src.context(e, &|| {
                        format!("element '{}' ({} records)", elem.name, elem.count)
                    })
                })
            }
            _ => self.element_generic(elem, src),
        }
    }

    fn vertices_fixed(
        &mut self,
        elem: &Element,
        stride: usize,
        src: &mut Binary<'_>,
    ) -> Result<()> {
        let Some(layout) = self.vertex.as_ref() else {
            return Ok(());
        };
        let count = usize::try_from(elem.count).unwrap_or(usize::MAX);
        let start = src.pos;
        let bytes = count.saturating_mul(stride);
        let Some(block) = src.data.get(start..).and_then(|r| r.get(..bytes)) else {
            return Err(src.error(format!(
                "file truncated: {} vertices of {stride} bytes need {bytes} bytes, {} remain",
                elem.count,
                src.remaining()
            )));
        };
        // Byte offset and type of every property within a record.
        let mut offsets = Vec::with_capacity(elem.props.len());
        let mut off = 0;
        for p in &elem.props {
            if let Kind::Scalar(s) = p.kind {
                offsets.push((off, s));
                off += s.size();
            }
        }
        if offsets.len() != elem.props.len() {
            // Not fixed-size after all (the caller checked; stay correct regardless).
            return self.element_generic(elem, src);
        }
        let field = |k: usize| offsets[k];
        let pos = layout.pos.map(field);
        let normal = layout.normal.map(|ks| ks.map(field));
        let uv = layout.uv.map(|ks| ks.map(field));
        let m = &mut self.mesh;
        // One tight pass per attribute over fixed-size records.
        if src.big {
            gather::<true, 3, _, _>(block, stride, pos, &mut m.positions, Vec3::from_array);
            if let Some(f) = normal {
                gather::<true, 3, _, _>(block, stride, f, &mut m.normals, Vec3::from_array);
            }
            if let Some(f) = uv {
                gather::<true, 2, _, _>(block, stride, f, &mut m.uvs, Vec2::from_array);
            }
        } else {
            gather::<false, 3, _, _>(block, stride, pos, &mut m.positions, Vec3::from_array);
            if let Some(f) = normal {
                gather::<false, 3, _, _>(block, stride, f, &mut m.normals, Vec3::from_array);
            }
            if let Some(f) = uv {
                gather::<false, 2, _, _>(block, stride, f, &mut m.uvs, Vec2::from_array);
            }
        }
        let first_bad = [
            m.positions
                .iter()
                .position(|v| !v.is_finite())
                .map(|i| (i, "position")),
            m.normals
                .iter()
                .position(|v| !v.is_finite())
                .map(|i| (i, "normal")),
            m.uvs.iter().position(|v| !v.is_finite()).map(|i| (i, "uv")),
        ]
        .into_iter()
        .flatten()
        .min();
        if let Some((i, what)) = first_bad {
            return Err(LoadError::new(
                Loc::new(self.file, 0, 0),
                format!(
                    "vertex {i}: the {what} is not finite in single precision \
                     (at byte offset {})",
                    start + i * stride
                ),
            ));
        }
        src.pos = start + bytes;
        Ok(())
    }

    fn faces_binary(&mut self, elem: &Element, src: &mut Binary<'_>) -> Result<()> {
        let Some(face) = self.face.as_ref() else {
            return self.element_generic(elem, src);
        };
        // Fast path: the index list is the only property, its count is one byte and its items
        // are 32-bit (the layout every common exporter writes).
        let (count_ty, item) = match elem.props[..] {
            [
                Property {
                    kind: Kind::List { count, item },
                    ..
                },
            ] if face.prop == 0
                && matches!(count, Scalar::U8 | Scalar::I8)
                && matches!(item, Scalar::I32 | Scalar::U32)
                && self.vertex_count <= i32::MAX as u64 =>
            {
                (count, item)
            }
            _ => return self.element_generic(elem, src),
        };
        let cap = Self::capacity(elem.count, src.remaining(), 13);
        self.mesh.indices.reserve_exact(cap);
        // With at most i32::MAX vertices, a negative `int` read as u32 is out of range too.
        let nv = self.vertex_count as u32;
        let mut pos = src.pos;
        let mut i = 0;
        while i < elem.count {
            let run = if src.big {
                triangle_run::<true>(src.data, pos, elem.count - i, nv, &mut self.mesh.indices)
            } else {
                triangle_run::<false>(src.data, pos, elem.count - i, nv, &mut self.mesh.indices)
            };
            i += run;
            pos += 13 * run as usize;
            if i < elem.count {
                // A polygon, or an error (truncation, short face, bad index) reported with
                // the generic reader's messages.
                src.pos = pos;
                let what = || format!("face {i}");
                let n = self.list_len(src, count_ty, &what)?;
                self.polygon(src, item, n, &what)?;
                pos = src.pos;
                i += 1;
            }
        }
        src.pos = pos;
        Ok(())
    }
}

/// Append the consecutive triangle records (`3 a b c`, one count byte and three 32-bit
/// indices, all indices below `nv`) starting at byte `pos`, at most `max` of them; returns how
/// many were consumed.
#[inline(always)]
fn triangle_run<const BIG: bool>(
    data: &[u8],
    mut pos: usize,
    max: u64,
    nv: u32,
    out: &mut Vec<[u32; 3]>,
) -> u64 {
    let mut n = 0;
    while n < max {
        let Some(rec) = data
            .get(pos..)
            .and_then(|r| r.get(..13))
            .and_then(|r| <&[u8; 13]>::try_from(r).ok())
        else {
            break;
        };
        let rd = |o: usize| {
            let b = [rec[o], rec[o + 1], rec[o + 2], rec[o + 3]];
            if BIG {
                u32::from_be_bytes(b)
            } else {
                u32::from_le_bytes(b)
            }
        };
        let tri = [rd(1), rd(5), rd(9)];
        // With at most i32::MAX vertices, a negative `int` read as u32 is out of range too.
        if rec[0] != 3 || tri[0] >= nv || tri[1] >= nv || tri[2] >= nv {
            break;
        }
        out.push(tri);
        pos += 13;
        n += 1;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(data: &[u8]) -> Result<TriMesh> {
        parse_ply(data, Path::new("t.ply"))
    }

    #[test]
    fn scalar_types_and_aliases() {
        for (name, ty, size) in [
            ("char", Scalar::I8, 1),
            ("uint8", Scalar::U8, 1),
            ("int16", Scalar::I16, 2),
            ("ushort", Scalar::U16, 2),
            ("int32", Scalar::I32, 4),
            ("uint", Scalar::U32, 4),
            ("float32", Scalar::F32, 4),
            ("double", Scalar::F64, 8),
        ] {
            assert_eq!(Scalar::parse(name), Some(ty));
            assert_eq!(ty.size(), size);
        }
        assert_eq!(Scalar::parse("int64"), None);
    }

    #[test]
    fn decode_both_endiannesses() {
        let v = -1234.5f32;
        assert_eq!(decode(Scalar::F32, &v.to_le_bytes(), false), f64::from(v));
        assert_eq!(decode(Scalar::F32, &v.to_be_bytes(), true), f64::from(v));
        assert_eq!(decode_int(Scalar::I16, &(-7i16).to_be_bytes(), true), -7);
        assert_eq!(decode_int(Scalar::U8, &[200], false), 200);
        assert_eq!(decode_int(Scalar::I8, &[200], false), -56);
    }

    #[test]
    fn header_line_endings() {
        let text = b"ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\n\
            property float y\r\nproperty float z\r\nelement face 1\r\n\
            property list uchar int vertex_indices\r\nend_header\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n";
        let m = parse(text).unwrap();
        assert_eq!(m.indices, vec![[0, 1, 2]]);
    }

    #[test]
    fn header_errors_have_lines() {
        let e =
            parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n")
                .unwrap_err();
        assert_eq!(e.loc.line, 4);
        assert!(e.message.contains("float128"), "{e}");
        let e = parse(b"ply\nformat ascii 1.0\nelement vertex 1\n").unwrap_err();
        assert!(e.message.contains("end_header"), "{e}");
        let e = parse(b"ply\nproperty float x\nend_header\n").unwrap_err();
        assert_eq!(e.loc.line, 2);
        let e = parse(b"\x00\x01garbage").unwrap_err();
        assert_eq!((e.loc.line, e.loc.col), (1, 1));
    }

    #[test]
    fn capacity_is_bounded_by_data() {
        assert_eq!(Reader::capacity(u64::MAX, 1300, 13), 100);
        assert_eq!(Reader::capacity(5, 1300, 13), 5);
        assert_eq!(Reader::capacity(5, 1300, 0), 5);
    }
}
