//! CENG795 (METU) scenes, JSON and XML encodings: FORMATS.md §2. Issue 5.
//!
//! Both encodings are first converted into one tree of [`Node`]s: XML attributes become
//! `_name` keys, element text becomes `_data`, and a JSON array under a key becomes repeated
//! entries of that key, so "one element is an object, several are an array" needs no special
//! case anywhere. Every node keeps its JSON path (`Scene.Objects.Mesh[3].Faces`) and, for
//! XML, its line, which errors and warnings quote.
//!
//! Conventions of the format carried over: ids are 1-based, vertex ids in `Faces`,
//! `Indices`, `Center` and `Point` index `VertexData`; transformations are applied in the
//! order listed (`"t1 s2 r1"` = r1 · s2 · t1).
//!
//! Cameras, as the course's ray generation: the eye e looks along `Gaze` with `Up`; the image
//! is the `NearPlane` window (l r b t) at `NearDistance` (exactly, off-axis and with
//! non-square pixels where the window says so: `Projection::Window`), and a primary ray
//! e + t(s − e) through the image-plane point s counts hits from t = 1 on, i.e. geometry
//! between the eye and the image plane is not seen (a planar near clip at `NearDistance`;
//! `hw3/cornellbox_boxes_dynamic` looks through its box's front wall that way). Only a
//! thin-lens camera (`FocusDistance` + `ApertureSize`) with an off-centre window is
//! approximated by a centred frustum aimed at the window centre (with a warning).
//!
//! Materials: every type keeps the course's ambient/diffuse/specular shading (the `_BRDF` it
//! names, or Lambert + original Blinn–Phong); `mirror`, `conductor` and `dielectric` add the
//! ideal lobe the course traces recursively, with `Roughness` as the homework's perturbation
//! of its direction (render crate `bsdf::course`).
//!
//! Textures (homework 4): `Images` and `TextureMap`s of type `image` (nearest or bilinear,
//! texel (i, j) at uv (i/w, j/h) as the lecture addresses them, values divided by
//! `Normalizer`, default 255), `perlin` (the lecture's noise with its 16 gradients; `NoiseScale`,
//! `NoiseConversion` linear/patch or absval/vein; the permutation is one fixed draw where the
//! course draws one per run) and `checkerboard` (solid, in world space: `BlackColor`,
//! `WhiteColor`, `Scale`, `Offset`). An object's `Textures` list applies them by `DecalMode`:
//! `replace_kd`, `blend_kd` ((kd + t)/2), `replace_ks`, `replace_all` (the texture shown as
//! radiance, in display units 255·t, no shading), `replace_normal` (tangent-space normal map),
//! `bump_normal` (the normal tilted against the height gradient times `BumpFactor`: texel
//! differences along u and v for images, the spatial gradient for Perlin noise). A
//! `replace_background` map is the image's background, texel (i, j) on pixel (i, j).
//! `TexCoordData` is indexed like `VertexData` (a mesh's `_textureOffset` shifts it); spheres
//! with textures take the lecture's uv, u = (π − atan2(z, x))/2π, v = acos(y/r)/π.
//!
//! Output: a camera without `Tonemap` holds radiance in 0–255 display units, so its 8-bit
//! image is clamp(round(L), 0, 255) per channel with no gamma (`Tonemap::DisplayUnits`); with
//! a `Tonemap`, Reinhard's photographic operator. EXR output keeps the radiance either way.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::formats::common::{finite_floats, look_at};
use crate::formats::ply::read_ply;
use crate::model::*;
use crate::textpos::TextIndex;
use crate::{Document, LoadError, LoadOptions, Loc, Result, Warning};

/// Whether an `.xml` file is a CENG795 scene (root element `<Scene>`), not Mitsuba/Nori.
pub fn is_ceng795_xml(path: &Path) -> bool {
    use std::io::Read;
    let mut text = Vec::new();
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    // The head only: the file may be huge, or a device that never ends.
    if file.take(4096).read_to_end(&mut text).is_err() {
        return false;
    }
    let head = String::from_utf8_lossy(&text);
    // The first element that is not a declaration or comment.
    let mut rest: &str = &head;
    while let Some(i) = rest.find('<') {
        rest = &rest[i + 1..];
        if rest.starts_with('?') || rest.starts_with('!') {
            continue;
        }
        return rest.starts_with("Scene") && !rest.starts_with("Scene_");
    }
    false
}

/// Load a CENG795 scene from a `.json` or `.xml` file.
pub fn load(path: &Path, _opts: &LoadOptions) -> Result<Document> {
    let text = crate::textpos::read_text(path, &Loc::file(path))?;
    let file = Arc::new(path.to_path_buf());
    let is_xml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    let root = if is_xml {
        parse_xml(&text, &file)?
    } else {
        parse_json(&text, &file)?
    };
    let scene = root.child("Scene").ok_or_else(|| {
        LoadError::new(
            Loc::file(path),
            "no 'Scene' root element: not a CENG795 scene",
        )
    })?;
    let mut b = Builder::new(file, scene);
    b.build(scene)?;
    Ok(Document::Scene(Box::new(b.desc)))
}

// ---------------------------------------------------------------------------------------------
// The common tree

/// One element of either encoding.
#[derive(Debug)]
pub struct Node {
    /// JSON-style path, e.g. `Scene.Objects.Mesh[3].Faces`.
    pub path: String,
    /// 1-based XML line and column (0 for JSON).
    pub line: u32,
    pub col: u32,
    pub value: Value,
}

#[derive(Debug)]
pub enum Value {
    Text(String),
    /// Children in document order; a key may repeat (JSON arrays, repeated XML elements).
    Map(Vec<(String, Node)>),
}

impl Node {
    /// Every child named `key`.
    pub fn children<'a, 'k>(
        &'a self,
        key: &'k str,
    ) -> impl Iterator<Item = &'a Node> + use<'a, 'k> {
        self.entries()
            .iter()
            .filter(move |(k, _)| k == key)
            .map(|(_, n)| n)
    }
    pub fn child(&self, key: &str) -> Option<&Node> {
        self.children(key).next()
    }
    /// All `(key, node)` children.
    pub fn entries(&self) -> &[(String, Node)] {
        match &self.value {
            Value::Map(m) => m,
            Value::Text(_) => &[],
        }
    }
    /// The node's text: itself, or its `_data` child.
    pub fn text(&self) -> Option<&str> {
        match &self.value {
            Value::Text(s) => Some(s),
            Value::Map(_) => self.child("_data").and_then(|d| d.text()),
        }
    }
}

fn parse_json(text: &str, file: &Arc<PathBuf>) -> Result<Node> {
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| {
        LoadError::new(
            Loc::new(file, e.line() as u32, e.column() as u32),
            format!("invalid JSON: {e}"),
        )
    })?;
    Ok(json_node(&v, String::new()))
}

fn json_node(v: &serde_json::Value, path: String) -> Node {
    use serde_json::Value as J;
    let value = match v {
        J::Object(map) => {
            let mut entries = Vec::with_capacity(map.len());
            for (k, child) in map {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                match child {
                    J::Array(items) => {
                        for (i, item) in items.iter().enumerate() {
                            entries.push((k.clone(), json_node(item, format!("{p}[{i}]"))));
                        }
                    }
                    _ => entries.push((k.clone(), json_node(child, p))),
                }
            }
            Value::Map(entries)
        }
        J::String(s) => Value::Text(s.clone()),
        J::Null => Value::Text(String::new()),
        // Nested arrays and numbers/booleans: their JSON text.
        other => Value::Text(match other {
            J::Array(a) => a
                .iter()
                .map(|x| match x {
                    J::String(s) => s.clone(),
                    y => y.to_string(),
                })
                .collect::<Vec<_>>()
                .join(" "),
            y => y.to_string(),
        }),
    };
    Node {
        path,
        line: 0,
        col: 0,
        value,
    }
}

fn parse_xml(text: &str, file: &Arc<PathBuf>) -> Result<Node> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        LoadError::new(Loc::new(file, p.row, p.col), format!("invalid XML: {e}"))
    })?;
    let index = TextIndex::new(text);
    let root = doc.root_element();
    let (line, col) = index.pos(root.range().start);
    let name = root.tag_name().name().to_string();
    let node = xml_node(&index, file, root, name.clone(), 0)?;
    Ok(Node {
        path: String::new(),
        line,
        col,
        value: Value::Map(vec![(name, node)]),
    })
}

/// Deepest element nesting accepted, checked before recursing: a hostile file can neither
/// overflow the stack nor make the per-node paths (which grow with depth) quadratic in memory.
const MAX_XML_DEPTH: usize = 256;

fn xml_node(
    index: &TextIndex,
    file: &Arc<PathBuf>,
    e: roxmltree::Node,
    path: String,
    depth: usize,
) -> Result<Node> {
    let (line, col) = index.pos(e.range().start);
    if depth >= MAX_XML_DEPTH {
        return Err(LoadError::new(
            Loc::new(file, line, col),
            format!("elements nested more than {MAX_XML_DEPTH} deep"),
        ));
    }
    let elems: Vec<_> = e.children().filter(|c| c.is_element()).collect();
    let text: String = e
        .children()
        .filter(|c| c.is_text())
        .filter_map(|c| c.text())
        .collect();
    let has_attrs = e.attributes().len() > 0;
    if elems.is_empty() && !has_attrs {
        return Ok(Node {
            path,
            line,
            col,
            value: Value::Text(text),
        });
    }
    let mut entries = Vec::new();
    for a in e.attributes() {
        entries.push((
            format!("_{}", a.name()),
            Node {
                path: format!("{path}._{}", a.name()),
                line,
                col,
                value: Value::Text(a.value().to_string()),
            },
        ));
    }
    let mut counts: HashMap<&str, usize> = HashMap::new();
    for c in &elems {
        let name = c.tag_name().name();
        let i = counts.entry(name).or_insert(0);
        let p = format!("{path}.{name}[{i}]");
        *i += 1;
        entries.push((name.to_string(), xml_node(index, file, *c, p, depth + 1)?));
    }
    if !text.trim().is_empty() {
        entries.push((
            "_data".to_string(),
            Node {
                path: format!("{path}._data"),
                line,
                col,
                value: Value::Text(text),
            },
        ));
    }
    Ok(Node {
        path,
        line,
        col,
        value: Value::Map(entries),
    })
}

// ---------------------------------------------------------------------------------------------
// Value parsing helpers

struct Ctx {
    file: Arc<PathBuf>,
}

impl Ctx {
    fn loc(&self, n: &Node) -> Loc {
        Loc::new(&self.file, n.line, n.col)
    }
    fn err(&self, n: &Node, msg: impl std::fmt::Display) -> LoadError {
        LoadError::new(self.loc(n), format!("{}: {msg}", n.path))
    }
    fn text<'a>(&self, n: &'a Node) -> Result<&'a str> {
        n.text()
            .ok_or_else(|| self.err(n, "expected a value (text or '_data')"))
    }
    fn floats(&self, n: &Node) -> Result<Vec<f32>> {
        finite_floats(self.text(n)?).map_err(|m| self.err(n, m))
    }
    fn float(&self, n: &Node) -> Result<f32> {
        let v = self.floats(n)?;
        match v.as_slice() {
            [x] => Ok(*x),
            _ => Err(self.err(n, format!("expected one number, got {}", v.len()))),
        }
    }
    fn vec3(&self, n: &Node) -> Result<Vec3> {
        let v = self.floats(n)?;
        match v.as_slice() {
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(self.err(n, format!("expected 3 numbers, got {}", v.len()))),
        }
    }
    fn uint(&self, n: &Node) -> Result<u32> {
        let t = self.text(n)?.trim();
        t.parse::<u32>()
            .map_err(|_| self.err(n, format!("'{t}' is not a non-negative integer")))
    }
    fn uints(&self, n: &Node) -> Result<Vec<u32>> {
        self.text(n)?
            .split_whitespace()
            .map(|t| {
                t.parse::<u32>()
                    .map_err(|_| self.err(n, format!("'{t}' is not a non-negative integer")))
            })
            .collect()
    }
    fn flag(&self, n: Option<&Node>) -> Result<bool> {
        let Some(n) = n else { return Ok(false) };
        match self.text(n)?.trim().to_ascii_lowercase().as_str() {
            "true" | "1" | "yes" => Ok(true),
            "false" | "0" | "no" | "" => Ok(false),
            t => Err(self.err(n, format!("'{t}' is not a boolean"))),
        }
    }
    fn req<'a>(&self, n: &'a Node, key: &str) -> Result<&'a Node> {
        n.child(key)
            .ok_or_else(|| self.err(n, format!("missing '{key}'")))
    }
    fn id(&self, n: &Node) -> Result<u32> {
        match n.child("_id") {
            Some(i) => self.uint(i),
            None => Err(self.err(n, "missing '_id'")),
        }
    }
}

/// Rotation of `angle` degrees about `axis`.
fn rotation(angle: f32, axis: Vec3) -> Option<Mat4> {
    let a = axis.normalize_or_zero();
    (a != Vec3::ZERO).then(|| Mat4::from_axis_angle(a, angle.to_radians()))
}

/// A frame whose +z is `n` (for rectangles and spot lights).
fn frame_z(origin: Vec3, n: Vec3) -> Option<Mat4> {
    let n = n.normalize_or_zero();
    if n == Vec3::ZERO {
        return None;
    }
    let (s, t) = n.any_orthonormal_pair();
    Some(Mat4::from_cols(
        s.extend(0.0),
        t.extend(0.0),
        n.extend(0.0),
        origin.extend(1.0),
    ))
}

fn degamma(c: Rgb, on: bool) -> Rgb {
    if on { c.max(Vec3::ZERO).powf(2.2) } else { c }
}

// ---------------------------------------------------------------------------------------------
// Builder

/// What a `TextureMap` does to the objects that list it (homework 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Decal {
    ReplaceKd,
    BlendKd,
    ReplaceKs,
    ReplaceAll,
    ReplaceNormal,
    BumpNormal,
    ReplaceBackground,
}

#[derive(Clone, Debug)]
struct TextureMap {
    /// The texture's value in [0, 1] (image texels divided by the normalizer).
    texture: Texture,
    decal: Decal,
    bump_factor: f32,
    loc: Loc,
}

struct BaseMesh {
    mesh: Arc<TriMesh>,
    to_world: Mat4,
    material: Option<MaterialId>,
}

struct Builder {
    ctx: Ctx,
    dir: PathBuf,
    desc: SceneDesc,
    vertices: Vec<Vec3>,
    uvs: Vec<Vec2>,
    transforms: HashMap<(char, u32), Mat4>,
    materials: HashMap<u32, MaterialId>,
    images: HashMap<u32, PathBuf>,
    texture_maps: HashMap<u32, TextureMap>,
    /// Materials derived from a material and the texture maps an object lists.
    textured: HashMap<(Option<MaterialId>, Vec<u32>), Option<MaterialId>>,
    /// Radiance is in 0–255 display units (no camera has a `Tonemap`).
    display_units: bool,
    meshes: HashMap<u32, BaseMesh>,
    /// PLY meshes read so far, by file and shading mode: a file used by several objects is
    /// read once and shared (the renderer instances shared meshes).
    plys: HashMap<(PathBuf, bool), Arc<TriMesh>>,
    /// Unsupported features met, reported once at the end.
    unsupported: Vec<String>,
    max_depth: u32,
}

impl Builder {
    fn new(file: Arc<PathBuf>, _scene: &Node) -> Self {
        let dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
        let desc = SceneDesc {
            source: file.as_ref().clone(),
            ..SceneDesc::default()
        };
        Builder {
            ctx: Ctx { file },
            dir,
            desc,
            vertices: Vec::new(),
            uvs: Vec::new(),
            transforms: HashMap::new(),
            materials: HashMap::new(),
            images: HashMap::new(),
            texture_maps: HashMap::new(),
            textured: HashMap::new(),
            display_units: true,
            meshes: HashMap::new(),
            plys: HashMap::new(),
            unsupported: Vec::new(),
            max_depth: 6,
        }
    }

    fn warn(&mut self, n: &Node, msg: impl std::fmt::Display) {
        let loc = self.ctx.loc(n);
        self.desc.warnings.push(Warning {
            loc,
            message: format!("{}: {msg}", n.path),
        });
    }

    fn unsupported(&mut self, what: impl Into<String>) {
        let w = what.into();
        if !self.unsupported.contains(&w) {
            self.unsupported.push(w);
        }
    }

    fn build(&mut self, scene: &Node) -> Result<()> {
        if let Some(n) = scene.child("MaxRecursionDepth") {
            self.max_depth = self.ctx.uint(n)?;
        }
        if let Some(n) = scene.child("BackgroundColor") {
            let c = self.ctx.vec3(n)?;
            self.desc.background = (c != Vec3::ZERO).then_some(c);
        }
        // `ShadowRayEpsilon` and `IntersectionTestEpsilon` are read by nobody: secondary rays
        // leave from an origin offset by the hit point's floating-point error bound (pbrt's
        // scheme), which needs no scene-dependent epsilon.
        for n in scene.children("VertexData") {
            let v = self.ctx.floats(n)?;
            if !v.len().is_multiple_of(3) {
                return Err(self
                    .ctx
                    .err(n, "vertex data is not a multiple of 3 numbers"));
            }
            self.vertices
                .extend(v.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        }
        for n in scene.children("TexCoordData") {
            let v = self.ctx.floats(n)?;
            self.uvs
                .extend(v.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])));
        }
        for t in scene.children("Transformations") {
            self.transformations(t)?;
        }
        self.display_units = !scene.children("Cameras").any(|c| {
            c.children("Camera")
                .any(|cam| cam.child("Tonemap").is_some())
        });
        for t in scene.children("Textures") {
            self.textures(t)?;
        }
        let brdfs = self.brdfs(scene)?;
        for m in scene.children("Materials") {
            for n in m.children("Material") {
                self.material(n, &brdfs)?;
            }
        }
        for l in scene.children("Lights") {
            self.lights(l)?;
        }
        for o in scene.children("Objects") {
            self.objects(o)?;
        }
        for c in scene.children("Cameras") {
            for n in c.children("Camera") {
                self.camera(n)?;
            }
        }
        if self.desc.sensors.is_empty() {
            return Err(LoadError::new(
                Loc::file(&self.ctx.file),
                "Scene.Cameras: the scene has no camera",
            ));
        }
        self.desc.integrator = IntegratorDesc::Whitted {
            max_depth: self.max_depth,
        };
        if !self.unsupported.is_empty() {
            let list = self.unsupported.join("; ");
            self.desc.warnings.push(Warning {
                loc: Loc::file(&self.ctx.file),
                message: format!("CENG795 features not supported, ignored or approximated: {list}"),
            });
        }
        Ok(())
    }

    // --- transformations -----------------------------------------------------------------

    fn transformations(&mut self, t: &Node) -> Result<()> {
        for (key, n) in t.entries() {
            let c = match key.as_str() {
                "Translation" => 't',
                "Scaling" => 's',
                "Rotation" => 'r',
                "Composite" => 'c',
                _ => {
                    self.warn(n, format!("unknown transformation '{key}' ignored"));
                    continue;
                }
            };
            let id = self.ctx.id(n)?;
            let v = self.ctx.floats(n)?;
            let m = match (c, v.as_slice()) {
                ('t', [x, y, z]) => Mat4::from_translation(Vec3::new(*x, *y, *z)),
                ('s', [x, y, z]) => Mat4::from_scale(Vec3::new(*x, *y, *z)),
                ('r', [a, x, y, z]) => rotation(*a, Vec3::new(*x, *y, *z))
                    .ok_or_else(|| self.ctx.err(n, "rotation axis is zero"))?,
                ('c', m) if m.len() == 16 => {
                    let mut a = [0.0; 16];
                    a.copy_from_slice(m);
                    // Row-major in the file, column-major in glam.
                    Mat4::from_cols_array(&a).transpose()
                }
                _ => {
                    return Err(self
                        .ctx
                        .err(n, format!("wrong number of values ({}) for {key}", v.len())));
                }
            };
            self.transforms.insert((c, id), m);
        }
        Ok(())
    }

    /// `"t1 s2 r1"` → r1 · s2 · t1 (applied in the order listed).
    fn transform_list(&self, n: Option<&Node>) -> Result<Mat4> {
        let Some(n) = n else {
            return Ok(Mat4::IDENTITY);
        };
        let mut m = Mat4::IDENTITY;
        for tok in self.ctx.text(n)?.split_whitespace() {
            let mut chars = tok.chars();
            let kind = chars.next().map(|c| c.to_ascii_lowercase()).unwrap_or(' ');
            let id: u32 = chars.as_str().parse().map_err(|_| {
                self.ctx
                    .err(n, format!("bad transformation reference '{tok}'"))
            })?;
            let t = self.transforms.get(&(kind, id)).ok_or_else(|| {
                self.ctx
                    .err(n, format!("transformation '{tok}' is not defined"))
            })?;
            m = *t * m;
        }
        Ok(m)
    }

    // --- textures --------------------------------------------------------------------------

    fn textures(&mut self, t: &Node) -> Result<()> {
        for images in t.children("Images") {
            for img in images.children("Image") {
                let id = self.ctx.id(img)?;
                let p = self.ctx.text(img)?.trim();
                self.images.insert(id, self.dir.join(p));
            }
        }
        for n in t.children("TextureMap") {
            let id = self.ctx.id(n)?;
            let map = self.texture_map(n)?;
            if map.decal == Decal::ReplaceBackground {
                let mut texture = map.texture.clone();
                centre_texels(&mut texture);
                let tid = self.desc.add_texture(TextureDesc {
                    texture: self.display(texture),
                    name: Some(format!("texture map {id} (background)")),
                    loc: map.loc.clone(),
                });
                // It replaces the background colour.
                self.desc.background_texture = Some(tid);
                self.desc.background = None;
            }
            self.texture_maps.insert(id, map);
        }
        Ok(())
    }

    /// A texture map's parameter: the element `key`, or the attribute `_key` with its first
    /// letter in lower case (`Normalizer` or `_normalizer`).
    fn map_param<'a>(n: &'a Node, key: &str) -> Option<&'a Node> {
        n.child(key).or_else(|| {
            let mut attr = String::from("_");
            let mut chars = key.chars();
            if let Some(c) = chars.next() {
                attr.extend(c.to_lowercase());
            }
            attr.extend(chars);
            n.child(&attr)
        })
    }

    fn map_float(&self, n: &Node, key: &str, default: f32) -> Result<f32> {
        Self::map_param(n, key).map_or(Ok(default), |c| self.ctx.float(c))
    }

    fn map_word(&self, n: &Node, key: &str) -> Result<Option<String>> {
        Self::map_param(n, key)
            .map(|c| Ok(self.ctx.text(c)?.trim().to_ascii_lowercase()))
            .transpose()
    }

    fn texture_map(&self, n: &Node) -> Result<TextureMap> {
        let kind = self.map_word(n, "Type")?.unwrap_or_default();
        let decal = match self.map_word(n, "DecalMode")?.as_deref() {
            Some("replace_kd") => Decal::ReplaceKd,
            Some("blend_kd") => Decal::BlendKd,
            Some("replace_ks") => Decal::ReplaceKs,
            Some("replace_all") => Decal::ReplaceAll,
            Some("replace_normal") => Decal::ReplaceNormal,
            Some("bump_normal") => Decal::BumpNormal,
            Some("replace_background") => Decal::ReplaceBackground,
            Some(o) => {
                return Err(self.ctx.err(
                    n,
                    format!(
                        "unknown decal mode '{o}' (expected replace_kd, blend_kd, replace_ks, \
                         replace_all, replace_normal, bump_normal or replace_background)"
                    ),
                ));
            }
            None => return Err(self.ctx.err(n, "texture map without a 'DecalMode'")),
        };
        let bump_factor = self.map_float(n, "BumpFactor", 1.0)?;
        let texture = match kind.as_str() {
            "image" => {
                let idn = Self::map_param(n, "ImageId")
                    .ok_or_else(|| self.ctx.err(n, "image texture map without an 'ImageId'"))?;
                let image = self.ctx.uint(idn)?;
                let path = self
                    .images
                    .get(&image)
                    .ok_or_else(|| self.ctx.err(idn, format!("image {image} is not defined")))?
                    .clone();
                let filter = match self.map_word(n, "Interpolation")?.as_deref() {
                    Some("nearest") => TextureFilter::Nearest,
                    Some("bilinear") | None => TextureFilter::Bilinear,
                    Some(o) => {
                        return Err(self.ctx.err(
                            n,
                            format!("unknown interpolation '{o}' (expected nearest or bilinear)"),
                        ));
                    }
                };
                let normalizer = self.map_float(n, "Normalizer", 255.0)?;
                if !(normalizer > 0.0 && normalizer.is_finite()) {
                    return Err(self.ctx.err(n, "the normalizer must be positive"));
                }
                let bitmap = Texture::Bitmap {
                    mipmapped: false,
                    path,
                    filter,
                    wrap: WrapMode::Repeat,
                    raw: true,
                    gamma: None,
                    to_uv: Mat3::IDENTITY,
                    corner_texels: true,
                };
                // Decoded texels are c / 255; the course divides c by the normalizer.
                if normalizer == 255.0 {
                    bitmap
                } else {
                    Texture::Affine {
                        texture: Box::new(bitmap),
                        scale: 255.0 / normalizer,
                        offset: Vec3::ZERO,
                    }
                }
            }
            "perlin" => {
                let conversion = match self.map_word(n, "NoiseConversion")?.as_deref() {
                    Some("linear" | "patch") | None => NoiseConversion::Linear,
                    Some("absval" | "vein") => NoiseConversion::AbsVal,
                    Some(o) => {
                        return Err(self.ctx.err(
                            n,
                            format!("unknown noise conversion '{o}' (expected linear or absval)"),
                        ));
                    }
                };
                Texture::Perlin {
                    scale: self.map_float(n, "NoiseScale", 1.0)?,
                    conversion,
                }
            }
            "checkerboard" => {
                let colour = |key: &str, d: Vec3| -> Result<Vec3> {
                    Self::map_param(n, key).map_or(Ok(d), |c| self.ctx.vec3(c))
                };
                let black = colour("BlackColor", Vec3::ZERO)?;
                let white = colour("WhiteColor", Vec3::ONE)?;
                // Colours written in 0–255 are divided by 255 like texels.
                let norm = if black.max_element() > 1.0 || white.max_element() > 1.0 {
                    255.0
                } else {
                    1.0
                };
                Texture::SolidChecker {
                    black: black / norm,
                    white: white / norm,
                    scale: self.map_float(n, "Scale", 1.0)?,
                    offset: self.map_float(n, "Offset", 0.0)?,
                }
            }
            o => {
                return Err(self.ctx.err(
                    n,
                    format!(
                        "unknown texture map type '{o}' (expected image, perlin or checkerboard)"
                    ),
                ));
            }
        };
        Ok(TextureMap {
            texture,
            decal,
            bump_factor,
            loc: self.ctx.loc(n),
        })
    }

    /// A texture's value as radiance the camera shows: 0–255 display units when the scene is
    /// in them, so that the default normalizer pastes the texels themselves.
    fn display(&self, texture: Texture) -> Texture {
        if self.display_units {
            Texture::Affine {
                texture: Box::new(texture),
                scale: 255.0,
                offset: Vec3::ZERO,
            }
        } else {
            texture
        }
    }

    /// The material of object `n`: its `Material` with the `Textures` it lists applied
    /// (homework 4: at most one shading and one normal texture per object).
    fn object_material(&mut self, n: &Node) -> Result<Option<MaterialId>> {
        let base = self.material_ref(n)?;
        let Some(tn) = n.child("Textures") else {
            return Ok(base);
        };
        let ids = self.ctx.uints(tn)?;
        if ids.is_empty() {
            return Ok(base);
        }
        let key = (base, ids.clone());
        if let Some(m) = self.textured.get(&key) {
            return Ok(*m);
        }
        let mut maps = Vec::new();
        for &id in &ids {
            let m = self
                .texture_maps
                .get(&id)
                .ok_or_else(|| self.ctx.err(tn, format!("texture map {id} is not defined")))?;
            maps.push(m.clone());
        }
        let mut desc = match base {
            Some(b) => self.desc.material(b).clone(),
            // The course's objects always name a material; without one, a grey diffuse.
            None => MaterialDesc {
                material: Material::PhongFamily {
                    model: PhongModel::OriginalBlinnPhong,
                    normalized: false,
                    kd_fresnel: false,
                    exponent: 1.0,
                    diffuse: ColorParam::constant(0.5),
                    specular: ColorParam::constant(0.0),
                    ior: 1.5,
                    absorption: 0.0,
                    ideal: None,
                },
                ambient: Vec3::ZERO,
                name: None,
                loc: self.ctx.loc(n),
            },
        };
        desc.name = Some(format!(
            "{} with texture maps {ids:?}",
            desc.name.as_deref().unwrap_or("material")
        ));
        // Shading decals change the material itself; normal decals wrap it afterwards.
        let mut unlit = None;
        for m in maps.iter() {
            let add = |b: &mut Self, texture: Texture| {
                b.desc.add_texture(TextureDesc {
                    texture,
                    name: None,
                    loc: m.loc.clone(),
                })
            };
            match m.decal {
                Decal::ReplaceKd | Decal::BlendKd | Decal::ReplaceKs => {
                    let Material::PhongFamily {
                        diffuse, specular, ..
                    } = &mut desc.material
                    else {
                        return Err(self.ctx.err(tn, "texture maps need a course material"));
                    };
                    let texture = match (m.decal, &*diffuse) {
                        (Decal::BlendKd, ColorParam::Const(kd)) => Texture::Affine {
                            texture: Box::new(m.texture.clone()),
                            scale: 0.5,
                            offset: *kd * 0.5,
                        },
                        _ => m.texture.clone(),
                    };
                    let id = ColorParam::Texture(add(self, texture));
                    if m.decal == Decal::ReplaceKs {
                        *specular = id;
                    } else {
                        *diffuse = id;
                    }
                }
                Decal::ReplaceAll => {
                    let texture = self.display(m.texture.clone());
                    unlit = Some(ColorParam::Texture(add(self, texture)));
                }
                Decal::ReplaceNormal | Decal::BumpNormal | Decal::ReplaceBackground => {}
            }
        }
        let shaded = unlit.is_none();
        if let Some(color) = unlit {
            desc.material = Material::Unlit { color };
        }
        let mut id = self.desc.add_material(desc);
        // Normals do not matter to a surface without shading.
        for m in maps.iter().filter(|_| shaded) {
            let texture = self.desc.add_texture(TextureDesc {
                texture: m.texture.clone(),
                name: None,
                loc: m.loc.clone(),
            });
            let material = match m.decal {
                Decal::ReplaceNormal => Material::NormalMap {
                    nested: id,
                    texture,
                },
                Decal::BumpNormal => Material::BumpMap {
                    nested: id,
                    texture,
                    factor: m.bump_factor,
                },
                _ => continue,
            };
            id = self.desc.add_material(MaterialDesc {
                material,
                ambient: self.desc.material(id).ambient,
                name: Some(format!("{:?} around material {}", m.decal, id.0)),
                loc: m.loc.clone(),
            });
        }
        self.textured.insert(key, Some(id));
        Ok(Some(id))
    }

    // --- materials -------------------------------------------------------------------------

    fn brdfs(&mut self, scene: &Node) -> Result<HashMap<u32, (PhongModel, bool, bool, f32)>> {
        let mut out = HashMap::new();
        for b in scene.children("BRDFs") {
            for (key, n) in b.entries() {
                let model = match key.as_str() {
                    "OriginalPhong" => PhongModel::OriginalPhong,
                    "ModifiedPhong" => PhongModel::ModifiedPhong,
                    "OriginalBlinnPhong" => PhongModel::OriginalBlinnPhong,
                    "ModifiedBlinnPhong" => PhongModel::ModifiedBlinnPhong,
                    "TorranceSparrow" => PhongModel::TorranceSparrow,
                    k if k.starts_with('_') => continue,
                    _ => {
                        self.warn(n, format!("unknown BRDF '{key}' ignored"));
                        continue;
                    }
                };
                let id = self.ctx.id(n)?;
                let normalized = self.ctx.flag(n.child("_normalized"))?;
                let kd_fresnel = self.ctx.flag(n.child("_kdfresnel"))?;
                let exponent = match n.child("Exponent") {
                    Some(e) => self.ctx.float(e)?,
                    None => 1.0,
                };
                out.insert(id, (model, normalized, kd_fresnel, exponent));
            }
        }
        Ok(out)
    }

    fn opt_vec3(&self, n: &Node, key: &str) -> Result<Option<Vec3>> {
        n.child(key).map(|c| self.ctx.vec3(c)).transpose()
    }

    fn material(
        &mut self,
        n: &Node,
        brdfs: &HashMap<u32, (PhongModel, bool, bool, f32)>,
    ) -> Result<()> {
        let id = self.ctx.id(n)?;
        let dg = self.ctx.flag(n.child("_degamma"))?;
        let col = |b: &Self, key: &str| -> Result<Rgb> {
            Ok(degamma(b.opt_vec3(n, key)?.unwrap_or(Vec3::ZERO), dg))
        };
        let ambient = col(self, "AmbientReflectance")?;
        let kd = col(self, "DiffuseReflectance")?;
        let ks = col(self, "SpecularReflectance")?;
        let mirror = col(self, "MirrorReflectance")?;
        let scalar = |b: &Self, key: &str, d: f32| -> Result<f32> {
            n.child(key).map_or(Ok(d), |c| b.ctx.float(c))
        };
        let ior = scalar(self, "RefractionIndex", 1.5)?;
        let k = scalar(self, "AbsorptionIndex", 0.0)?;
        let roughness = scalar(self, "Roughness", 0.0)?;
        let phong_exp = scalar(self, "PhongExponent", 1.0)?;
        let kind = match n.child("_type") {
            Some(t) => self.ctx.text(t)?.trim().to_ascii_lowercase(),
            None => String::new(),
        };
        let ideal_kind = match kind.as_str() {
            "" | "none" => None,
            "mirror" => Some(CourseIdealKind::Mirror),
            "conductor" => Some(CourseIdealKind::Conductor {
                eta: ior,
                k: k.max(0.0),
            }),
            "dielectric" => Some(CourseIdealKind::Dielectric {
                ior,
                absorption: self
                    .opt_vec3(n, "AbsorptionCoefficient")?
                    .filter(|a| *a != Vec3::ZERO),
            }),
            other => {
                return Err(self.ctx.err(
                    n,
                    format!(
                        "unknown material type '{other}' (expected none, mirror, conductor \
                         or dielectric)"
                    ),
                ));
            }
        };
        let ideal = ideal_kind.map(|kind| CourseIdeal {
            kind,
            reflectance: mirror,
            roughness: roughness.max(0.0),
        });
        // Every type keeps the course's ambient/diffuse/specular shading: the BRDF named by
        // `_BRDF`, or the homework's default, Lambert + Blinn-Phong in the course's convention
        // f = kd + ks cosᵖα / cos θi (no 1/π, so point-lit renders match the course's images).
        let (model, normalized, kd_fresnel, exponent) = match n.child("_BRDF") {
            Some(bn) => {
                let bid = self.ctx.uint(bn)?;
                *brdfs
                    .get(&bid)
                    .ok_or_else(|| self.ctx.err(bn, format!("BRDF {bid} is not defined")))?
            }
            None => (PhongModel::OriginalBlinnPhong, false, false, phong_exp),
        };
        let material = Material::PhongFamily {
            model,
            normalized,
            kd_fresnel,
            exponent,
            diffuse: ColorParam::Const(kd),
            specular: ColorParam::Const(ks),
            ior,
            // The complex index only bends the Torrance–Sparrow Fresnel term of BRDF-named
            // materials, as before.
            absorption: if n.child("_BRDF").is_some() {
                k.max(0.0)
            } else {
                0.0
            },
            ideal,
        };
        let mid = self.desc.add_material(MaterialDesc {
            material,
            ambient,
            name: Some(format!("material {id}")),
            loc: self.ctx.loc(n),
        });
        self.materials.insert(id, mid);
        Ok(())
    }

    fn material_ref(&self, n: &Node) -> Result<Option<MaterialId>> {
        let Some(m) = n.child("Material") else {
            return Ok(None);
        };
        let id = self.ctx.uint(m)?;
        self.materials
            .get(&id)
            .copied()
            .map(Some)
            .ok_or_else(|| self.ctx.err(m, format!("material {id} is not defined")))
    }

    // --- lights ----------------------------------------------------------------------------

    fn lights(&mut self, l: &Node) -> Result<()> {
        for (key, n) in l.entries() {
            let loc = self.ctx.loc(n);
            let emitter = match key.as_str() {
                "AmbientLight" => Emitter::Ambient {
                    radiance: self.ctx.vec3(n)?,
                },
                "PointLight" => {
                    let mut position = self.ctx.vec3(self.ctx.req(n, "Position")?)?;
                    let m = self.transform_list(n.child("Transformations"))?;
                    position = m.transform_point3(position);
                    Emitter::Point {
                        position,
                        intensity: self.ctx.vec3(self.ctx.req(n, "Intensity")?)?.into(),
                    }
                }
                "DirectionalLight" => Emitter::Directional {
                    direction: self
                        .ctx
                        .vec3(self.ctx.req(n, "Direction")?)?
                        .normalize_or_zero(),
                    irradiance: self.ctx.vec3(self.ctx.req(n, "Radiance")?)?.into(),
                },
                "SpotLight" => {
                    let pos = self.ctx.vec3(self.ctx.req(n, "Position")?)?;
                    let dn = self.ctx.req(n, "Direction")?;
                    let to_world = frame_z(pos, self.ctx.vec3(dn)?)
                        .ok_or_else(|| self.ctx.err(dn, "zero direction"))?;
                    let coverage = self.ctx.float(self.ctx.req(n, "CoverageAngle")?)?;
                    let falloff = self.ctx.float(self.ctx.req(n, "FalloffAngle")?)?;
                    // The course's angles are full cone angles; Mitsuba's are half angles.
                    Emitter::Spot {
                        to_world,
                        intensity: self.ctx.vec3(self.ctx.req(n, "Intensity")?)?.into(),
                        cutoff_angle: coverage * 0.5,
                        beam_width: falloff * 0.5,
                        falloff: SpotFalloff::Cosine4,
                    }
                }
                "AreaLight" => {
                    let pos = self.ctx.vec3(self.ctx.req(n, "Position")?)?;
                    let nn = self.ctx.req(n, "Normal")?;
                    let size = self.ctx.float(self.ctx.req(n, "Size")?)?;
                    let frame = frame_z(pos, self.ctx.vec3(nn)?)
                        .ok_or_else(|| self.ctx.err(nn, "zero normal"))?;
                    let radiance = self.ctx.vec3(self.ctx.req(n, "Radiance")?)?;
                    self.desc.shapes.push(ShapeDesc {
                        media: Default::default(),
                        motion: None,
                        shape: Shape::Rectangle,
                        to_world: frame * Mat4::from_scale(Vec3::new(size * 0.5, size * 0.5, 1.0)),
                        material: None,
                        emission: Some(AreaEmission {
                            radiance: ColorParam::Const(radiance),
                            two_sided: false,
                            directional: false,
                            loc: loc.clone(),
                        }),
                        flip_normals: false,
                        name: Some(format!("area light {}", n.path)),
                        loc,
                    });
                    continue;
                }
                "SphericalDirectionalLight" => {
                    let mapping = match n.child("_type").map(|t| self.ctx.text(t)).transpose()? {
                        Some("probe") => EnvMapping::Probe,
                        Some("latlong") | None => EnvMapping::LatLong,
                        Some(o) => {
                            return Err(self.ctx.err(n, format!("unknown environment type '{o}'")));
                        }
                    };
                    let idn = self.ctx.req(n, "ImageId")?;
                    let id = self.ctx.uint(idn)?;
                    let path =
                        self.images.get(&id).cloned().ok_or_else(|| {
                            self.ctx.err(idn, format!("image {id} is not defined"))
                        })?;
                    Emitter::EnvMap {
                        path,
                        scale: 1.0,
                        to_world: Mat4::IDENTITY,
                        mapping,
                    }
                }
                k if k.starts_with('_') => continue,
                _ => {
                    self.warn(n, format!("unknown light '{key}' ignored"));
                    continue;
                }
            };
            self.desc.emitters.push(EmitterDesc {
                name: None,
                medium: None,
                emitter,
                loc,
            });
        }
        Ok(())
    }

    // --- objects ---------------------------------------------------------------------------

    fn vertex(&self, n: &Node, id: u32) -> Result<Vec3> {
        id.checked_sub(1)
            .and_then(|i| self.vertices.get(i as usize))
            .copied()
            .ok_or_else(|| {
                self.ctx.err(
                    n,
                    format!(
                        "vertex id {id} out of range (VertexData has {} vertices, ids are 1-based)",
                        self.vertices.len()
                    ),
                )
            })
    }

    /// Build a compact mesh from 1-based vertex ids into `VertexData`.
    fn mesh_from_ids(&self, n: &Node, ids: &[u32], smooth: bool) -> Result<TriMesh> {
        self.mesh_from_ids_uv(n, ids, smooth, 0)
    }

    /// [`Self::mesh_from_ids`], with vertex id i reading its uv at `TexCoordData` id
    /// i + `uv_shift` (a mesh's `_textureOffset` differing from its `_vertexOffset`).
    fn mesh_from_ids_uv(
        &self,
        n: &Node,
        ids: &[u32],
        smooth: bool,
        uv_shift: i64,
    ) -> Result<TriMesh> {
        if !ids.len().is_multiple_of(3) {
            return Err(self.ctx.err(n, "face indices are not a multiple of 3"));
        }
        let mut remap: HashMap<u32, u32> = HashMap::new();
        let mut mesh = TriMesh::default();
        let use_uv = !self.uvs.is_empty();
        for tri in ids.chunks_exact(3) {
            let mut t = [0u32; 3];
            for (k, &id) in tri.iter().enumerate() {
                t[k] = match remap.get(&id) {
                    Some(&i) => i,
                    None => {
                        let p = self.vertex(n, id)?;
                        let i = mesh.positions.len() as u32;
                        mesh.positions.push(p);
                        if use_uv {
                            let uv = usize::try_from(i64::from(id) - 1 + uv_shift)
                                .ok()
                                .and_then(|i| self.uvs.get(i))
                                .copied()
                                .unwrap_or_default();
                            mesh.uvs.push(uv);
                        }
                        remap.insert(id, i);
                        i
                    }
                };
            }
            mesh.indices.push(t);
        }
        if smooth {
            smooth_normals(&mut mesh);
        }
        Ok(mesh)
    }

    fn shading_smooth(&self, n: &Node) -> Result<bool> {
        match n.child("_shadingMode") {
            None => Ok(false),
            Some(s) => match self.ctx.text(s)?.trim().to_ascii_lowercase().as_str() {
                "smooth" => Ok(true),
                "flat" => Ok(false),
                o => Err(self.ctx.err(s, format!("unknown shading mode '{o}'"))),
            },
        }
    }

    fn emission(&self, n: &Node, light: bool) -> Result<Option<AreaEmission>> {
        if !light {
            return Ok(None);
        }
        let r = self.ctx.vec3(self.ctx.req(n, "Radiance")?)?;
        Ok(Some(AreaEmission {
            radiance: ColorParam::Const(r),
            two_sided: false,
            directional: false,
            loc: self.ctx.loc(n),
        }))
    }

    fn objects(&mut self, o: &Node) -> Result<()> {
        for (key, n) in o.entries() {
            // The course's motion blur: a world translation over the shutter interval.
            let motion = n
                .child("MotionBlur")
                .map(|m| self.ctx.vec3(m))
                .transpose()?;
            let first = self.desc.shapes.len();
            match key.as_str() {
                "Mesh" | "LightMesh" => self.mesh(n, key == "LightMesh")?,
                "MeshInstance" => self.instance(n)?,
                "Triangle" => {
                    let ids = self.ctx.uints(self.ctx.req(n, "Indices")?)?;
                    if ids.len() != 3 {
                        return Err(self.ctx.err(n, "a triangle needs 3 vertex ids"));
                    }
                    let mesh = self.mesh_from_ids(n, &ids, false)?;
                    let to_world = self.transform_list(n.child("Transformations"))?;
                    let material = self.object_material(n)?;
                    self.push(n, Shape::Mesh(Arc::new(mesh)), to_world, material, None);
                }
                "Sphere" | "LightSphere" => {
                    let cn = self.ctx.req(n, "Center")?;
                    let center = self.vertex(cn, self.ctx.uint(cn)?)?;
                    let radius = self.ctx.float(self.ctx.req(n, "Radius")?)?;
                    if radius <= 0.0 {
                        return Err(self.ctx.err(n, "radius must be positive"));
                    }
                    let mut to_world = self.transform_list(n.child("Transformations"))?;
                    let material = self.object_material(n)?;
                    let emission = self.emission(n, key == "LightSphere")?;
                    let (mut center, mut radius) = (center, radius);
                    if n.child("Textures").is_some() {
                        // The course's sphere uv: θ = acos(y/r), φ = atan2(z, x),
                        // u = (π − φ)/2π, v = θ/π — Mitsuba's (φ about +z from +x, θ from +z)
                        // in the frame x' = −x, y' = z, z' = y.
                        let course = Mat4::from_cols(
                            glam::Vec4::new(-1.0, 0.0, 0.0, 0.0),
                            glam::Vec4::new(0.0, 0.0, 1.0, 0.0),
                            glam::Vec4::new(0.0, 1.0, 0.0, 0.0),
                            glam::Vec4::W,
                        );
                        to_world = to_world
                            * Mat4::from_translation(center)
                            * Mat4::from_scale(Vec3::splat(radius))
                            * course;
                        (center, radius) = (Vec3::ZERO, 1.0);
                    }
                    self.push(
                        n,
                        Shape::Sphere { center, radius },
                        to_world,
                        material,
                        emission,
                    );
                }
                "Plane" => {
                    let pn = self.ctx.req(n, "Point")?;
                    let point = self.vertex(pn, self.ctx.uint(pn)?)?;
                    let normal = self
                        .ctx
                        .vec3(self.ctx.req(n, "Normal")?)?
                        .normalize_or_zero();
                    if normal == Vec3::ZERO {
                        return Err(self.ctx.err(n, "zero plane normal"));
                    }
                    let to_world = self.transform_list(n.child("Transformations"))?;
                    let material = self.object_material(n)?;
                    self.push(
                        n,
                        Shape::InfinitePlane { point, normal },
                        to_world,
                        material,
                        None,
                    );
                }
                k if k.starts_with('_') => {}
                _ => self.warn(n, format!("unknown object '{key}' ignored")),
            }
            for s in &mut self.desc.shapes[first..] {
                s.motion = motion;
            }
        }
        Ok(())
    }

    fn push(
        &mut self,
        n: &Node,
        shape: Shape,
        to_world: Mat4,
        material: Option<MaterialId>,
        emission: Option<AreaEmission>,
    ) {
        self.desc.shapes.push(ShapeDesc {
            media: Default::default(),
            motion: None,
            shape,
            to_world,
            material,
            emission,
            flip_normals: false,
            name: Some(n.path.clone()),
            loc: self.ctx.loc(n),
        });
    }

    fn mesh(&mut self, n: &Node, light: bool) -> Result<()> {
        let faces = self.ctx.req(n, "Faces")?;
        let smooth = self.shading_smooth(n)?;
        let mut ply_key = None;
        let mut mesh = if let Some(ply) = faces.child("_plyFile") {
            let p = self.dir.join(self.ctx.text(ply)?.trim());
            ply_key = Some((p.clone(), smooth));
            if let Some(m) = ply_key.as_ref().and_then(|k| self.plys.get(k)) {
                let m = m.clone();
                return self.push_mesh(n, m, light);
            }
            let mut m = read_ply(&p)
                .map_err(|e| self.ctx.err(ply, format!("cannot load PLY file: {e}")))?;
            if smooth && m.normals.is_empty() {
                smooth_normals(&mut m);
            } else if !smooth {
                m.normals.clear();
            }
            m
        } else {
            let offset = |key: &str| match faces.child(key) {
                Some(o) => self.ctx.uint(o),
                None => Ok(0),
            };
            let (offset, tex_offset) = (offset("_vertexOffset")?, offset("_textureOffset")?);
            let ids: Vec<u32> = self
                .ctx
                .uints(faces)?
                .into_iter()
                .map(|i| i.saturating_add(offset)) // overflow → out of range below
                .collect();
            let uv_shift = i64::from(tex_offset) - i64::from(offset);
            self.mesh_from_ids_uv(faces, &ids, smooth, uv_shift)?
        };
        if mesh.indices.is_empty() {
            self.warn(n, "mesh has no faces");
        }
        mesh.normals.retain(|_| smooth);
        let mesh = Arc::new(mesh);
        if let Some(k) = ply_key {
            self.plys.insert(k, mesh.clone());
        }
        self.push_mesh(n, mesh, light)
    }

    /// Places a mesh object (`Mesh` / `LightMesh`) and records it for `MeshInstance`s.
    fn push_mesh(&mut self, n: &Node, mesh: Arc<TriMesh>, light: bool) -> Result<()> {
        let to_world = self.transform_list(n.child("Transformations"))?;
        let material = self.object_material(n)?;
        let emission = self.emission(n, light)?;
        if let Some(id) = n.child("_id").map(|i| self.ctx.uint(i)).transpose()? {
            self.meshes.insert(
                id,
                BaseMesh {
                    mesh: mesh.clone(),
                    to_world,
                    material,
                },
            );
        }
        self.push(n, Shape::Mesh(mesh), to_world, material, emission);
        Ok(())
    }

    fn instance(&mut self, n: &Node) -> Result<()> {
        let bn = n
            .child("_baseMeshId")
            .ok_or_else(|| self.ctx.err(n, "missing '_baseMeshId'"))?;
        let base_id = self.ctx.uint(bn)?;
        let base = self.meshes.get(&base_id).ok_or_else(|| {
            self.ctx
                .err(bn, format!("mesh {base_id} is not defined (yet)"))
        })?;
        let (mesh, base_m, base_mat) = (base.mesh.clone(), base.to_world, base.material);
        let reset = self.ctx.flag(n.child("_resetTransform"))?;
        let own = self.transform_list(n.child("Transformations"))?;
        let to_world = if reset { own } else { own * base_m };
        let material = self.material_ref(n)?.or(base_mat);
        if let Some(id) = n.child("_id").map(|i| self.ctx.uint(i)).transpose()? {
            self.meshes.insert(
                id,
                BaseMesh {
                    mesh: mesh.clone(),
                    to_world,
                    material,
                },
            );
        }
        self.push(n, Shape::Mesh(mesh), to_world, material, None);
        Ok(())
    }

    // --- cameras ---------------------------------------------------------------------------

    fn camera(&mut self, n: &Node) -> Result<()> {
        let c = &self.ctx;
        let pos = c.vec3(c.req(n, "Position")?)?;
        let up = c.vec3(c.req(n, "Up")?)?;
        let res_n = c.req(n, "ImageResolution")?;
        let res = c.uints(res_n)?;
        let [w, h] = res[..] else {
            return Err(c.err(res_n, "expected 'width height'"));
        };
        if w == 0 || h == 0 {
            return Err(c.err(res_n, "image resolution must be positive"));
        }
        let aspect = w as f32 / h as f32;
        let near = match n.child("NearDistance") {
            Some(d) => c.float(d)?,
            None => 1.0,
        };
        let is_look_at = match n.child("_type") {
            Some(t) => c.text(t)?.trim() == "lookAt",
            None => false,
        };
        if near <= 0.0 {
            return Err(c.err(n, "NearDistance must be positive"));
        }
        let thin_lens = n.child("FocusDistance").is_some() && n.child("ApertureSize").is_some();
        // `window`: the exact NearPlane window scaled to distance 1, for the pinhole.
        let (dir, fov_y, window) = if is_look_at {
            let fov = c.float(c.req(n, "FovY")?)?;
            // Some files give `Gaze` (a direction) instead of `GazePoint`.
            let dir = match n.child("GazePoint") {
                Some(g) => c.vec3(g)? - pos,
                None => c.vec3(c.req(n, "Gaze")?)?,
            };
            (dir, fov, None)
        } else {
            let gaze = c.vec3(c.req(n, "Gaze")?)?.normalize_or_zero();
            let np = c.req(n, "NearPlane")?;
            let v = c.floats(np)?;
            let [l, r, b, t] = v[..] else {
                return Err(c.err(np, "expected 'left right bottom top'"));
            };
            if r <= l || t <= b {
                return Err(c.err(np, "empty near plane window"));
            }
            let window = [l / near, r / near, b / near, t / near];
            // The course's frame: w = -gaze, u = up × w (right), v = w × u.
            let wv = -gaze;
            let u = up.cross(wv).normalize_or_zero();
            let vv = wv.cross(u);
            let (cx, cy) = ((l + r) * 0.5, (b + t) * 0.5);
            let asym = (cx.abs() > 1e-4 * (r - l)) || (cy.abs() > 1e-4 * (t - b));
            let win_aspect = (r - l) / (t - b);
            let mut msgs = Vec::new();
            // Only the thin lens approximates: the pinhole uses the window exactly.
            if thin_lens && asym {
                msgs.push(
                    "asymmetric NearPlane approximated by a symmetric frustum aimed at the \
                     window centre",
                );
            }
            if thin_lens && (win_aspect / aspect - 1.0).abs() > 1e-3 {
                msgs.push(
                    "NearPlane aspect differs from ImageResolution (non-square pixels): the \
                     vertical extent is kept",
                );
            }
            for m in msgs {
                self.warn(np, m);
            }
            if thin_lens {
                let dir = gaze * near + u * cx + vv * cy;
                let half_h = (t - b) * 0.5;
                let fov = 2.0 * (half_h / dir.length()).atan().to_degrees();
                (dir, fov, None)
            } else {
                (gaze, 0.0, Some(window))
            }
        };
        let c = &self.ctx;
        let to_world = look_at(pos, pos + dir, up)
            .ok_or_else(|| c.err(n, "gaze is zero or parallel to 'Up'"))?;
        let projection = match (n.child("FocusDistance"), n.child("ApertureSize")) {
            (Some(f), Some(a)) => Projection::ThinLens {
                fov: fov_y,
                fov_axis: FovAxis::Y,
                // The course samples a square lens of side ApertureSize; we use the disk of
                // the same width.
                aperture_radius: c.float(a)? * 0.5,
                focus_distance: c.float(f)?,
            },
            _ => match window {
                Some([left, right, bottom, top]) => Projection::Window {
                    left,
                    right,
                    bottom,
                    top,
                },
                None => Projection::Perspective {
                    fov: fov_y,
                    fov_axis: FovAxis::Y,
                },
            },
        };
        let spp = match n.child("NumSamples") {
            Some(s) => c.uint(s)?.max(1),
            None => 1,
        };
        let output = n
            .child("ImageName")
            .map(|i| c.text(i).map(|t| PathBuf::from(t.trim())))
            .transpose()?;
        // Without a Tonemap the course's radiance is in 0–255 display units (FORMATS.md §2).
        let tonemap = match n.child("Tonemap") {
            Some(t) => self.tonemap(t)?,
            None => Tonemap::DisplayUnits,
        };
        let integrator = self.renderer(n)?;
        let name = match n.child("_id") {
            Some(i) => Some(self.ctx.text(i)?.trim().to_string()),
            None => None,
        };
        let _ = aspect;
        self.desc.sensors.push(Sensor {
            medium: None,
            camera: Camera {
                projection,
                to_world,
                // The course's primary rays e + t(s − e) count hits from the image plane on
                // (t ≥ 1): a planar clip at NearDistance along the gaze.
                near_clip: near,
                far_clip: 1e30,
            },
            film: Film {
                width: w,
                height: h,
                crop: None,
                filter: FilterDesc::Box { radius: 0.5 },
                output,
                tonemap: Some(tonemap),
            },
            sampler: SamplerDesc {
                kind: SamplerKind::Independent,
                spp,
                seed: 0,
            },
            integrator: Some(integrator),
            name,
            loc: self.ctx.loc(n),
        });
        Ok(())
    }

    fn tonemap(&mut self, t: &Node) -> Result<Tonemap> {
        let c = &self.ctx;
        if let Some(tmo) = t.child("TMO") {
            let name = c.text(tmo)?.trim();
            if name != "Photographic" {
                let msg = format!("tone mapping operator '{name}' (Photographic used)");
                self.unsupported(msg);
            }
        }
        let c = &self.ctx;
        let opts = match t.child("TMOOptions") {
            Some(o) => c.floats(o)?,
            None => vec![],
        };
        let key = opts.first().copied().unwrap_or(0.18);
        let burn_percent = opts.get(1).copied().unwrap_or(0.0);
        let saturation = match t.child("Saturation") {
            Some(s) => c.float(s)?,
            None => 1.0,
        };
        let gamma = match t.child("Gamma") {
            Some(g) => {
                let s = c.text(g)?.trim();
                if s.eq_ignore_ascii_case("srgb") {
                    2.2
                } else {
                    s.parse::<f32>()
                        .ok()
                        .filter(|v| *v > 0.0)
                        .ok_or_else(|| c.err(g, format!("bad gamma '{s}'")))?
                }
            }
            None => 2.2,
        };
        Ok(Tonemap::Photographic {
            key,
            burn_percent,
            saturation,
            gamma,
        })
    }

    fn renderer(&mut self, n: &Node) -> Result<IntegratorDesc> {
        let c = &self.ctx;
        let max_depth = match n.child("MaxRecursionDepth") {
            Some(d) => c.uint(d)?,
            None => self.max_depth,
        };
        let min_depth = match n.child("MinRecursionDepth") {
            Some(d) => c.uint(d)?,
            None => 1,
        };
        let renderer = match n.child("Renderer") {
            Some(r) => c.text(r)?.trim().to_string(),
            None => return Ok(IntegratorDesc::Whitted { max_depth }),
        };
        if renderer != "PathTracing" {
            let rn = n.child("Renderer");
            if let Some(rn) = rn {
                self.warn(rn, format!("unknown renderer '{renderer}': Whitted used"));
            }
            return Ok(IntegratorDesc::Whitted { max_depth });
        }
        let params = match n.child("RendererParams") {
            Some(p) => c.text(p)?.split_whitespace().map(str::to_string).collect(),
            None => Vec::<String>::new(),
        };
        let mut d = PathDesc {
            // The course counts bounces; we count segments (the camera ray is one).
            max_depth: max_depth as i32 + 1,
            rr: RussianRoulette::Off,
            nee: false,
            directions: DirectionSampling::UniformHemisphere,
            ..PathDesc::default()
        };
        for p in &params {
            match p.as_str() {
                "NextEventEstimation" => d.nee = true,
                "ImportanceSampling" => d.directions = DirectionSampling::Bsdf,
                "RussianRoulette" => {
                    d.rr = RussianRoulette::Throughput {
                        from_depth: min_depth.max(1),
                    }
                }
                "MIS_BALANCE" => d.mis = MisHeuristic::Balance,
                "MIS_POWER" => d.mis = MisHeuristic::Power,
                other => {
                    let other = other.to_string();
                    self.unsupported(format!("renderer parameter '{other}'"));
                }
            }
        }
        if let Some(s) = n.child("SplittingFactor") {
            d.splitting = self.ctx.uint(s)?.max(1);
        }
        // Sample clamping (the "…_clamping" renders): each camera sample scaled down to this
        // largest component, as `--clamp` does.
        if let Some(c) = n.child("SampleClamp").or_else(|| n.child("Clamp")) {
            let v = self.ctx.float(c)?;
            if v.is_nan() || v <= 0.0 {
                return Err(self.ctx.err(c, "the clamp value must be positive"));
            }
            d.clamp = Some(v);
        }
        Ok(IntegratorDesc::Path(d))
    }
}

/// Put an image's texels at their centres: the background spreads texel (i, j) over the
/// pixel (i, j) of an image of the texture's size.
fn centre_texels(t: &mut Texture) {
    match t {
        Texture::Bitmap { corner_texels, .. } => *corner_texels = false,
        Texture::Affine { texture, .. } => centre_texels(texture),
        _ => {}
    }
}

/// Area-weighted vertex normals.
fn smooth_normals(mesh: &mut TriMesh) {
    let mut normals = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.indices {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    for n in &mut normals {
        *n = n.normalize_or(Vec3::Z);
    }
    mesh.normals = normals;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_and_xml_give_the_same_tree_shape() {
        let f = Arc::new(PathBuf::from("t"));
        let j = parse_json(
            r#"{"Scene":{"Objects":{"Mesh":[{"_id":"1","Faces":{"_data":"1 2 3"}},{"_id":"2"}]}}}"#,
            &f,
        )
        .unwrap();
        let x = parse_xml(
            "<Scene>\n<Objects><Mesh id=\"1\"><Faces>1 2 3</Faces></Mesh><Mesh id=\"2\"/></Objects></Scene>",
            &f,
        )
        .unwrap();
        for root in [&j, &x] {
            let o = root.child("Scene").unwrap().child("Objects").unwrap();
            let meshes: Vec<_> = o.children("Mesh").collect();
            assert_eq!(meshes.len(), 2);
            assert_eq!(meshes[0].child("Faces").unwrap().text(), Some("1 2 3"));
            assert_eq!(meshes[1].child("_id").unwrap().text(), Some("2"));
        }
        let m = j.child("Scene").unwrap().child("Objects").unwrap();
        assert_eq!(
            m.children("Mesh").nth(1).unwrap().path,
            "Scene.Objects.Mesh[1]"
        );
        let xm = x.child("Scene").unwrap().child("Objects").unwrap();
        assert_eq!(xm.line, 2);
    }

    #[test]
    fn transform_lists_apply_in_order() {
        let f = Arc::new(PathBuf::from("t"));
        let root = parse_json(
            r#"{"Scene":{"Transformations":{"Translation":{"_id":"1","_data":"1 0 0"},"Scaling":{"_id":"1","_data":"2 2 2"}}}}"#,
            &f,
        )
        .unwrap();
        let scene = root.child("Scene").unwrap();
        let mut b = Builder::new(f.clone(), scene);
        b.transformations(scene.child("Transformations").unwrap())
            .unwrap();
        let list = Node {
            path: "x".into(),
            line: 0,
            col: 0,
            value: Value::Text("t1 s1".into()),
        };
        let m = b.transform_list(Some(&list)).unwrap();
        // Translate first, then scale: (0,0,0) → (1,0,0) → (2,0,0).
        assert!((m.transform_point3(Vec3::ZERO) - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
    }
}
