//! CS184 COLLADA 1.4.1 scenes with the CGL technique: FORMATS.md §5. Issue 6.
//!
//! What is read (everything else is ignored, with a warning where it could change the image):
//! - `<asset><up_axis>`: `Y_UP` is our world; `Z_UP` maps (x, y, z) → (−x, z, y) (swap Y and
//!   Z, negate X: a proper rotation, so handedness is kept); `X_UP` maps (x, y, z) → (y, x, −z)
//!   (swap X and Y, negate Z), both as the course's parser. As there, an `<asset>` without
//!   `up_axis` is an error; a document without `<asset>` is `Y_UP` (with a warning).
//! - `<library_visual_scenes>`: the scene named by `<scene><instance_visual_scene>` (else the
//!   first), its node tree with `<matrix>` (row-major), `<translate>`, `<rotate>` (axis, degrees),
//!   `<scale>` composed in document order, and `instance_geometry` / `instance_light` /
//!   `instance_camera`. Every instance of a camera becomes a sensor, in document order.
//! - Geometry: `<mesh>` with `<triangles>`, `<polylist>` (fan-triangulated) and `<polygons>`,
//!   shared `<source>`/`<accessor>` data indexed through `<input offset>`; POSITION (through
//!   `<vertices>`), NORMAL and TEXCOORD (set 0). CGL `<sphere><radius>` geometries.
//! - Cameras: `<perspective>` with `xfov`, `yfov`, `aspect_ratio`, `znear`, `zfar`. Like the
//!   CS184 pathtracer, the *vertical* field of view is kept when the resolution changes. The
//!   film is 800 pixels wide with the camera's aspect ratio.
//! - Lights: the CGL technique overrides `technique_common`. `point` → isotropic point light of
//!   intensity `color`; `directional` → irradiance `color` along the node's −Z; `spot` → spot
//!   along −Z with half-angle `falloff_angle`/2; `ambient` → constant environment radiance;
//!   `area` → a one-sided emitting unit square [−½,½]² at the node origin in its XY plane,
//!   facing local −Z, of radiance `color` (the transform sizes it), with a black surface.
//! - Materials: an effect's CGL block with one of `emission`, `mirror`, `glass`, `refraction`,
//!   `microfacet`; otherwise Lambertian with the `phong`/`lambert`/`blinn` diffuse colour (0.5
//!   when absent or textured). Blender technique blocks are ignored.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec4;
use roxmltree::Node;

use crate::model::*;
use crate::textpos::TextIndex;
use crate::{Document, LoadError, LoadOptions, Loc, Result, Warning};

const MAX_NODES: u32 = 50_000_000;
/// Default film width; the height follows the camera's aspect ratio.
pub const DEFAULT_WIDTH: u32 = 800;

pub fn load(path: &Path, _opts: &LoadOptions) -> Result<Document> {
    let text = crate::textpos::read_text(path, &Loc::file(path))?;
    let desc = load_str(&text, path)?;
    Ok(Document::Scene(Box::new(desc)))
}

/// Parse COLLADA text; `path` names it in messages and is `SceneDesc::source`.
pub fn load_str(text: &str, path: &Path) -> Result<SceneDesc> {
    let file = Arc::new(path.to_path_buf());
    let opt = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_NODES,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(text, opt).map_err(|e| {
        let p = e.pos();
        LoadError::new(Loc::new(&file, p.row, p.col), format!("malformed XML: {e}"))
    })?;
    let mut cx = Ctx {
        doc: &doc,
        index: TextIndex::new(text),
        file,
        ids: HashMap::new(),
        desc: SceneDesc {
            source: path.to_path_buf(),
            ..SceneDesc::default()
        },
        materials: HashMap::new(),
        geometries: HashMap::new(),
        up: Mat4::IDENTITY,
        view_dirs: Vec::new(),
    };
    cx.run()?;
    Ok(cx.desc)
}

#[derive(Clone)]
enum Geometry {
    Sphere(f32),
    /// (material symbol, mesh) per primitive element.
    Meshes(Vec<(Option<String>, Arc<TriMesh>)>),
}

/// A resolved material: its id and the emitted radiance of CGL `emission` materials.
#[derive(Clone, Copy)]
struct Mat {
    id: MaterialId,
    emission: Option<Rgb>,
}

struct Ctx<'a, 'input> {
    doc: &'a roxmltree::Document<'input>,
    /// Line and column of element offsets (linear time; see `textpos`).
    index: TextIndex<'input>,
    file: Arc<PathBuf>,
    ids: HashMap<&'a str, Node<'a, 'input>>,
    desc: SceneDesc,
    /// By `<material>` id.
    materials: HashMap<String, Mat>,
    geometries: HashMap<String, Geometry>,
    /// COLLADA world → our world (up-axis conversion).
    up: Mat4,
    /// CS184's `c_dir` of every sensor (see [`place_cs184`]).
    view_dirs: Vec<Vec3>,
}

fn is(n: &Node, tag: &str) -> bool {
    n.is_element() && n.tag_name().name() == tag
}

fn child<'a, 'i>(n: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    n.children().find(|c| is(c, tag))
}

fn children<'a, 'i>(n: Node<'a, 'i>, tag: &'a str) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    n.children().filter(move |c| is(c, tag))
}

/// The `<technique profile="CGL">` of `n`'s `<extra>` blocks, if any.
fn cgl<'a, 'i>(n: Node<'a, 'i>) -> Option<Node<'a, 'i>> {
    children(n, "extra")
        .flat_map(|e| children(e, "technique"))
        .find(|t| t.attribute("profile") == Some("CGL"))
}

impl<'a, 'input> Ctx<'a, 'input> {
    fn loc(&self, n: Node) -> Loc {
        let (line, col) = self.index.pos(n.range().start);
        Loc::new(&self.file, line, col)
    }

    fn err(&self, n: Node, msg: impl Into<String>) -> LoadError {
        LoadError::new(self.loc(n), msg)
    }

    fn warn(&mut self, n: Node, msg: impl Into<String>) {
        let loc = self.loc(n);
        self.desc.warnings.push(Warning {
            loc,
            message: msg.into(),
        });
    }

    /// Resolve `#id` of the attribute `attr` of `n`.
    fn resolve(&self, n: Node<'a, 'input>, attr: &str) -> Result<Node<'a, 'input>> {
        let url = n
            .attribute(attr)
            .ok_or_else(|| self.err(n, format!("<{}> needs a '{attr}'", n.tag_name().name())))?;
        let id = url.strip_prefix('#').ok_or_else(|| {
            self.err(
                n,
                format!("'{url}': only local references ('#id') are supported"),
            )
        })?;
        self.ids.get(id).copied().ok_or_else(|| {
            self.err(
                n,
                format!("dangling reference '{url}': no element has id '{id}'"),
            )
        })
    }

    fn floats(&self, n: Node) -> Result<Vec<f32>> {
        super::common::finite_floats(n.text().unwrap_or("")).map_err(|m| self.err(n, m))
    }

    fn float(&self, n: Node) -> Result<f32> {
        let v = self.floats(n)?;
        match v.as_slice() {
            [x] => Ok(*x),
            _ => Err(self.err(n, format!("<{}> expects one number", n.tag_name().name()))),
        }
    }

    /// An RGB (or RGBA, alpha dropped) colour, or one grey value.
    fn rgb(&self, n: Node) -> Result<Rgb> {
        let v = self.floats(n)?;
        match v.as_slice() {
            [g] => Ok(Rgb::splat(*g)),
            [r, g, b] | [r, g, b, _] => Ok(Rgb::new(*r, *g, *b)),
            _ => Err(self.err(
                n,
                format!(
                    "<{}> expects 3 (or 4) numbers, found {}",
                    n.tag_name().name(),
                    v.len()
                ),
            )),
        }
    }

    fn uints(&self, n: Node) -> Result<Vec<u32>> {
        n.text()
            .unwrap_or("")
            .split_ascii_whitespace()
            .map(|t| {
                t.parse::<u32>()
                    .map_err(|_| self.err(n, format!("'{t}' is not a non-negative integer")))
            })
            .collect()
    }

    fn run(&mut self) -> Result<()> {
        let root = self.doc.root_element();
        if root.tag_name().name() != "COLLADA" {
            return Err(self.err(
                root,
                format!(
                    "expected a <COLLADA> root element, found <{}>",
                    root.tag_name().name()
                ),
            ));
        }
        for n in root.descendants().filter(|n| n.is_element()) {
            if let Some(id) = n.attribute("id")
                && self.ids.insert(id, n).is_some()
            {
                return Err(self.err(n, format!("duplicate id '{id}'")));
            }
        }
        self.up = self.up_axis(root)?;
        self.desc.integrator = IntegratorDesc::Path(cs184_path(1, 1, false));

        let scene = match child(root, "scene").and_then(|s| child(s, "instance_visual_scene")) {
            Some(ivs) => self.resolve(ivs, "url")?,
            None => root
                .descendants()
                .find(|n| is(n, "visual_scene"))
                .ok_or_else(|| self.err(root, "no <visual_scene> in the file"))?,
        };
        if !is(&scene, "visual_scene") {
            return Err(self.err(
                scene,
                "<instance_visual_scene> must refer to a <visual_scene>",
            ));
        }
        let up = self.up;
        for n in children(scene, "node") {
            self.node(n, up, 0)?;
        }
        let bbox = scene_bounds(&self.desc);
        if let Some((lo, hi)) = bbox {
            for (s, d) in self.desc.sensors.iter_mut().zip(&self.view_dirs) {
                if let Some(m) = place_cs184(lo, hi, *d) {
                    s.camera.to_world = m;
                }
            }
        }
        if self.desc.sensors.is_empty() {
            self.warn(
                scene,
                "no camera in the scene: using one at the origin looking along -Z",
            );
            let cam = self.default_camera(scene);
            self.desc.sensors.push(cam);
        }
        Ok(())
    }

    fn up_axis(&mut self, root: Node) -> Result<Mat4> {
        // As the course's parser: an <asset> without <up_axis> is an error, a document
        // without <asset> is Y_UP (with a warning here).
        let Some(asset) = child(root, "asset") else {
            self.warn(root, "no <asset>: assuming Y_UP (the COLLADA default)");
            return Ok(Mat4::IDENTITY);
        };
        let Some(ax) = child(asset, "up_axis") else {
            return Err(self.err(
                asset,
                "<asset> has no <up_axis> (expected X_UP, Y_UP or Z_UP)",
            ));
        };
        match ax.text().unwrap_or("").trim() {
            "Y_UP" => Ok(Mat4::IDENTITY),
            // (x, y, z) -> (-x, z, y)
            "Z_UP" => Ok(Mat4::from_cols(
                Vec4::new(-1.0, 0.0, 0.0, 0.0),
                Vec4::new(0.0, 0.0, 1.0, 0.0),
                Vec4::new(0.0, 1.0, 0.0, 0.0),
                Vec4::W,
            )),
            // (x, y, z) -> (y, x, -z), the course's (a proper rotation)
            "X_UP" => Ok(Mat4::from_cols(
                Vec4::new(0.0, 1.0, 0.0, 0.0),
                Vec4::new(1.0, 0.0, 0.0, 0.0),
                Vec4::new(0.0, 0.0, -1.0, 0.0),
                Vec4::W,
            )),
            other => Err(self.err(
                ax,
                format!("unknown up_axis '{other}' (expected X_UP, Y_UP or Z_UP)"),
            )),
        }
    }

    fn node_transform(&mut self, n: Node<'a, 'input>) -> Result<Mat4> {
        let mut m = Mat4::IDENTITY;
        for c in n.children().filter(|c| c.is_element()) {
            let t = match c.tag_name().name() {
                "matrix" => {
                    let mut v = self.floats(c)?;
                    if v.len() != 16 {
                        // CS184's parser reads 16 values from a stringstream: a value past
                        // the end reads as 0 (C++11) and extra values are never read.
                        self.warn(
                            c,
                            format!(
                                "<matrix> has {} numbers, 16 expected: read as the course's \
                                 parser reads it (missing entries 0, extra ones ignored; the \
                                 last row 0 0 0 1)",
                                v.len()
                            ),
                        );
                        v.resize(16, 0.0);
                        // The projective row, which an affine placement never uses, stays
                        // (0 0 0 1) so the matrix remains invertible.
                        v[12..].copy_from_slice(&[0.0, 0.0, 0.0, 1.0]);
                    }
                    // Row-major in the file; glam is column-major.
                    Mat4::from_cols_slice(&v).transpose()
                }
                "translate" => {
                    let v = self.floats(c)?;
                    let [x, y, z] = v[..] else {
                        return Err(self.err(c, "<translate> expects 3 numbers"));
                    };
                    Mat4::from_translation(Vec3::new(x, y, z))
                }
                "scale" => {
                    let v = self.floats(c)?;
                    let [x, y, z] = v[..] else {
                        return Err(self.err(c, "<scale> expects 3 numbers"));
                    };
                    Mat4::from_scale(Vec3::new(x, y, z))
                }
                "rotate" => {
                    let v = self.floats(c)?;
                    let [x, y, z, deg] = v[..] else {
                        return Err(self.err(c, "<rotate> expects 4 numbers (axis, degrees)"));
                    };
                    let axis = Vec3::new(x, y, z).normalize_or_zero();
                    if axis == Vec3::ZERO {
                        if deg != 0.0 {
                            return Err(self.err(c, "<rotate> with a zero axis"));
                        }
                        Mat4::IDENTITY
                    } else {
                        Mat4::from_axis_angle(axis, deg.to_radians())
                    }
                }
                "lookat" | "skew" => {
                    self.warn(
                        c,
                        format!("<{}> is not supported and is ignored", c.tag_name().name()),
                    );
                    Mat4::IDENTITY
                }
                _ => continue,
            };
            m *= t;
        }
        Ok(m)
    }

    fn node(&mut self, n: Node<'a, 'input>, parent: Mat4, depth: u32) -> Result<()> {
        if depth > 256 {
            return Err(self.err(n, "node hierarchy deeper than 256 levels"));
        }
        let m = parent * self.node_transform(n)?;
        if !m.is_finite() {
            return Err(self.err(n, "the node's transform is not finite"));
        }
        for c in n.children().filter(|c| c.is_element()) {
            match c.tag_name().name() {
                "node" => self.node(c, m, depth + 1)?,
                "instance_geometry" => self.instance_geometry(c, m, n)?,
                "instance_light" => {
                    let l = self.resolve(c, "url")?;
                    self.light(l, m, c)?;
                }
                "instance_camera" => {
                    let cam = self.resolve(c, "url")?;
                    let s = self.camera(cam, m, n)?;
                    self.desc.sensors.push(s);
                }
                "instance_node" | "instance_controller" => {
                    self.warn(
                        c,
                        format!("<{}> is not supported and is ignored", c.tag_name().name()),
                    );
                }
                _ => {}
            }
        }
        Ok(())
    }

    // -----------------------------------------------------------------------------------------
    // Geometry

    fn instance_geometry(&mut self, inst: Node<'a, 'input>, m: Mat4, node: Node) -> Result<()> {
        let g = self.resolve(inst, "url")?;
        if !is(&g, "geometry") {
            return Err(self.err(inst, "<instance_geometry> must refer to a <geometry>"));
        }
        let gid = g.attribute("id").unwrap_or_default().to_string();
        let geom = match self.geometries.get(&gid) {
            Some(geom) => geom.clone(),
            None => {
                let geom = self.geometry(g)?;
                self.geometries.insert(gid, geom.clone());
                geom
            }
        };
        // symbol -> material
        let mut bound: HashMap<&str, Mat> = HashMap::new();
        if let Some(tc) = child(inst, "bind_material").and_then(|b| child(b, "technique_common")) {
            for im in children(tc, "instance_material") {
                let sym = im
                    .attribute("symbol")
                    .ok_or_else(|| self.err(im, "<instance_material> needs a 'symbol'"))?;
                let target = self.resolve(im, "target")?;
                let mat = self.material(target)?;
                bound.insert(sym, mat);
            }
        }
        let name = node
            .attribute("name")
            .or(node.attribute("id"))
            .map(str::to_string);
        let loc = self.loc(inst);
        let first = bound.values().next().copied();
        let shape_for = |shape: Shape, mat: Option<Mat>| ShapeDesc {
            media: Default::default(),
            motion: None,
            shape,
            to_world: m,
            material: mat.map(|m| m.id),
            emission: mat.and_then(|m| m.emission).map(|r| AreaEmission {
                radiance: ColorParam::Const(r),
                two_sided: false,
                directional: false,
                loc: loc.clone(),
            }),
            flip_normals: false,
            name: name.clone(),
            loc: loc.clone(),
        };
        match geom {
            Geometry::Sphere(r) => {
                let s = shape_for(
                    Shape::Sphere {
                        center: Vec3::ZERO,
                        radius: r,
                    },
                    first,
                );
                self.desc.shapes.push(s);
            }
            Geometry::Meshes(meshes) => {
                let mut missing = Vec::new();
                for (sym, mesh) in meshes {
                    let mat = match &sym {
                        Some(s) => match bound.get(s.as_str()) {
                            Some(m) => Some(*m),
                            None => {
                                missing.push(s.clone());
                                None
                            }
                        },
                        None => None,
                    };
                    let s = shape_for(Shape::Mesh(mesh), mat);
                    self.desc.shapes.push(s);
                }
                for s in missing {
                    self.warn(
                        inst,
                        format!("material symbol '{s}' is not bound: using the default diffuse"),
                    );
                }
            }
        }
        Ok(())
    }

    fn geometry(&mut self, g: Node<'a, 'input>) -> Result<Geometry> {
        if let Some(t) = cgl(g)
            && let Some(s) = child(t, "sphere")
        {
            let r =
                child(s, "radius").ok_or_else(|| self.err(s, "CGL <sphere> needs a <radius>"))?;
            let r = self.float(r)?;
            if r <= 0.0 {
                return Err(self.err(s, format!("sphere radius must be positive, found {r}")));
            }
            return Ok(Geometry::Sphere(r));
        }
        let Some(mesh) = child(g, "mesh") else {
            self.warn(g, "geometry without <mesh> or CGL <sphere> ignored");
            return Ok(Geometry::Meshes(Vec::new()));
        };
        let mut out = Vec::new();
        for prim in mesh.children().filter(|c| c.is_element()) {
            let name = prim.tag_name().name();
            if !matches!(name, "triangles" | "polylist" | "polygons") {
                if matches!(name, "lines" | "linestrips" | "trifans" | "tristrips") {
                    self.warn(prim, format!("<{name}> is not supported and is ignored"));
                }
                continue;
            }
            let m = self.primitive(mesh, prim)?;
            if !m.indices.is_empty() {
                out.push((prim.attribute("material").map(str::to_string), Arc::new(m)));
            }
        }
        Ok(Geometry::Meshes(out))
    }

    /// The data of a `<source>`: (values, stride), checked against its accessor.
    fn source(&self, s: Node<'a, 'input>) -> Result<(Vec<f32>, usize)> {
        if !is(&s, "source") {
            return Err(self.err(s, "expected a reference to a <source>"));
        }
        let arr = child(s, "float_array")
            .ok_or_else(|| self.err(s, "<source> without a <float_array>"))?;
        let data = self.floats(arr)?;
        if let Some(c) = arr.attribute("count") {
            let c: usize = c
                .parse()
                .map_err(|_| self.err(arr, format!("count='{c}' is not a number")))?;
            if c != data.len() {
                return Err(self.err(
                    arr,
                    format!(
                        "<float_array> count='{c}' but it holds {} numbers",
                        data.len()
                    ),
                ));
            }
        }
        let Some(acc) = child(s, "technique_common").and_then(|t| child(t, "accessor")) else {
            return Err(self.err(s, "<source> without <technique_common><accessor>"));
        };
        let num = |a: &str, d: usize| -> Result<usize> {
            match acc.attribute(a) {
                None => Ok(d),
                Some(v) => v
                    .parse()
                    .map_err(|_| self.err(acc, format!("{a}='{v}' is not a number"))),
            }
        };
        let stride = num("stride", 1)?;
        let count = num("count", usize::MAX)?;
        let offset = num("offset", 0)?;
        if stride == 0 || count == usize::MAX {
            return Err(self.err(acc, "<accessor> needs a count and a positive stride"));
        }
        let needed = count
            .checked_mul(stride)
            .and_then(|x| x.checked_add(offset))
            .unwrap_or(usize::MAX);
        if needed > data.len() {
            return Err(self.err(
                acc,
                format!(
                    "<accessor> of {count} × {stride} (offset {offset}) needs {needed} numbers, the array holds {}",
                    data.len()
                ),
            ));
        }
        Ok((data[offset..needed].to_vec(), stride))
    }

    fn primitive(&mut self, mesh: Node<'a, 'input>, prim: Node<'a, 'input>) -> Result<TriMesh> {
        // Inputs: (offset, kind, data, stride)
        #[derive(Clone, Copy, PartialEq)]
        enum Kind {
            Pos,
            Nrm,
            Uv,
        }
        let mut inputs: Vec<(usize, Kind, Vec<f32>, usize, Loc)> = Vec::new();
        let mut max_offset = 0usize;
        for inp in children(prim, "input") {
            let off: usize = inp
                .attribute("offset")
                .ok_or_else(|| self.err(inp, "<input> of a primitive needs an 'offset'"))?
                .parse()
                .map_err(|_| self.err(inp, "offset is not a number"))?;
            max_offset = max_offset.max(off);
            let sem = inp.attribute("semantic").unwrap_or("");
            let src = self.resolve(inp, "source")?;
            match sem {
                "VERTEX" => {
                    if !is(&src, "vertices") {
                        return Err(self.err(inp, "VERTEX input must refer to <vertices>"));
                    }
                    for vi in children(src, "input") {
                        let kind = match vi.attribute("semantic") {
                            Some("POSITION") => Kind::Pos,
                            Some("NORMAL") => Kind::Nrm,
                            Some("TEXCOORD") => Kind::Uv,
                            _ => continue,
                        };
                        let s = self.resolve(vi, "source")?;
                        let (d, st) = self.source(s)?;
                        inputs.push((off, kind, d, st, self.loc(vi)));
                    }
                }
                "NORMAL" | "TEXCOORD" => {
                    if sem == "TEXCOORD" && inp.attribute("set").is_some_and(|s| s != "0") {
                        continue;
                    }
                    let (d, st) = self.source(src)?;
                    let kind = if sem == "NORMAL" { Kind::Nrm } else { Kind::Uv };
                    inputs.push((off, kind, d, st, self.loc(inp)));
                }
                _ => {}
            }
        }
        let _ = mesh;
        let pos = inputs
            .iter()
            .position(|i| i.1 == Kind::Pos)
            .ok_or_else(|| self.err(prim, "primitive without VERTEX/POSITION input"))?;
        // First of each kind wins.
        let find = |k: Kind| inputs.iter().position(|i| i.1 == k);
        let nrm = find(Kind::Nrm);
        let uv = find(Kind::Uv);
        for (i, min) in [(Some(pos), 3), (nrm, 3), (uv, 2)] {
            if let Some(i) = i
                && inputs[i].3 < min
            {
                return Err(LoadError::new(
                    inputs[i].4.clone(),
                    format!(
                        "this source has stride {} but {min} components are needed",
                        inputs[i].3
                    ),
                ));
            }
        }
        let stride = max_offset + 1;

        // Polygons: vertex counts, index lists.
        let name = prim.tag_name().name();
        let mut p: Vec<u32> = Vec::new();
        let mut vcount: Vec<u32> = Vec::new();
        match name {
            "triangles" => {
                if let Some(pn) = child(prim, "p") {
                    p = self.uints(pn)?;
                }
                if !p.len().is_multiple_of(3 * stride) {
                    return Err(self.err(
                        prim,
                        format!(
                            "<p> holds {} indices, not a multiple of 3 × {stride}",
                            p.len()
                        ),
                    ));
                }
                vcount = vec![3; p.len() / (3 * stride)];
            }
            "polylist" => {
                if let Some(v) = child(prim, "vcount") {
                    vcount = self.uints(v)?;
                }
                if let Some(pn) = child(prim, "p") {
                    p = self.uints(pn)?;
                }
                let total: u64 = vcount.iter().map(|&c| c as u64).sum();
                if total * stride as u64 != p.len() as u64 {
                    return Err(self.err(
                        prim,
                        format!(
                            "<vcount> sums to {total} vertices × {stride} inputs = {} indices, but <p> holds {}",
                            total * stride as u64,
                            p.len()
                        ),
                    ));
                }
            }
            _ => {
                // <polygons>: one <p> per polygon
                for pn in children(prim, "p") {
                    let q = self.uints(pn)?;
                    if !q.len().is_multiple_of(stride) {
                        return Err(self.err(
                            pn,
                            format!("<p> holds {} indices, not a multiple of {stride}", q.len()),
                        ));
                    }
                    vcount.push((q.len() / stride) as u32);
                    p.extend(q);
                }
                if child(prim, "ph").is_some() {
                    self.warn(
                        prim,
                        "<ph> (polygons with holes) is not supported; holes ignored",
                    );
                }
            }
        }
        if let Some(c) = prim.attribute("count")
            && c.parse::<usize>().ok() != Some(vcount.len())
        {
            return Err(self.err(
                prim,
                format!(
                    "count='{c}' but the primitive holds {} polygons",
                    vcount.len()
                ),
            ));
        }

        let mut mesh = TriMesh::default();
        let mut map: HashMap<(u32, u32, u32), u32> = HashMap::new();
        let mut corner = |k: usize, this: &Self| -> Result<u32> {
            let base = k * stride;
            let get = |slot: Option<usize>, dim: usize| -> Result<Option<(u32, usize)>> {
                let Some(s) = slot else { return Ok(None) };
                let (off, _, ref data, st, ref loc) = inputs[s];
                let idx = p[base + off];
                let start = idx as usize * st;
                if start + dim > data.len() {
                    return Err(LoadError::new(
                        this.loc(prim),
                        format!(
                            "index {idx} is out of range for the source at {loc} ({} elements)",
                            data.len() / st
                        ),
                    ));
                }
                Ok(Some((idx, start)))
            };
            let pi = get(Some(pos), 3)?.expect("position input exists");
            let ni = get(nrm, 3)?;
            let ti = get(uv, 2)?;
            let key = (
                pi.0,
                ni.map_or(u32::MAX, |x| x.0),
                ti.map_or(u32::MAX, |x| x.0),
            );
            if let Some(&v) = map.get(&key) {
                return Ok(v);
            }
            let v = mesh.positions.len() as u32;
            let d = &inputs[pos].2;
            mesh.positions
                .push(Vec3::new(d[pi.1], d[pi.1 + 1], d[pi.1 + 2]));
            if let (Some(s), Some((_, st))) = (nrm, ni) {
                let d = &inputs[s].2;
                mesh.normals.push(Vec3::new(d[st], d[st + 1], d[st + 2]));
            }
            if let (Some(s), Some((_, st))) = (uv, ti) {
                let d = &inputs[s].2;
                mesh.uvs.push(Vec2::new(d[st], d[st + 1]));
            }
            map.insert(key, v);
            Ok(v)
        };
        let mut k = 0usize;
        let mut degenerate = 0usize;
        for &c in &vcount {
            let c = c as usize;
            if c < 3 {
                degenerate += 1;
            } else {
                let v0 = corner(k, self)?;
                let mut prev = corner(k + 1, self)?;
                for j in 2..c {
                    let cur = corner(k + j, self)?;
                    mesh.indices.push([v0, prev, cur]);
                    prev = cur;
                }
            }
            k += c;
        }
        if degenerate > 0 {
            self.warn(
                prim,
                format!("{degenerate} polygon(s) with fewer than 3 vertices skipped"),
            );
        }
        // Normals with zero length would poison shading: drop them all (geometric normals).
        if mesh.normals.iter().any(|n| n.length_squared() == 0.0) {
            self.warn(prim, "zero-length normals: using geometric normals");
            mesh.normals.clear();
        }
        Ok(mesh)
    }

    // -----------------------------------------------------------------------------------------
    // Materials

    fn material(&mut self, m: Node<'a, 'input>) -> Result<Mat> {
        if !is(&m, "material") {
            return Err(self.err(m, "instance_material target must be a <material>"));
        }
        let id = m.attribute("id").unwrap_or_default().to_string();
        if let Some(r) = self.materials.get(&id) {
            return Ok(*r);
        }
        let ie = child(m, "instance_effect")
            .ok_or_else(|| self.err(m, "<material> without <instance_effect>"))?;
        let effect = self.resolve(ie, "url")?;
        if !is(&effect, "effect") {
            return Err(self.err(ie, "<instance_effect> must refer to an <effect>"));
        }
        let loc = self.loc(m);
        let (material, emission) = self.effect(effect)?;
        let mid = self.desc.add_material(MaterialDesc {
            material,
            ambient: Rgb::ZERO,
            name: m
                .attribute("name")
                .or(m.attribute("id"))
                .map(str::to_string),
            loc,
        });
        let r = Mat { id: mid, emission };
        self.materials.insert(id, r);
        Ok(r)
    }

    fn cgl_rgb(&self, n: Node, tag: &str, default: Rgb) -> Result<Rgb> {
        match child(n, tag) {
            Some(c) => self.rgb(c),
            None => Ok(default),
        }
    }

    fn cgl_float(&self, n: Node, tag: &str, default: f32) -> Result<f32> {
        match child(n, tag) {
            Some(c) => self.float(c),
            None => Ok(default),
        }
    }

    fn effect(&mut self, e: Node<'a, 'input>) -> Result<(Material, Option<Rgb>)> {
        if let Some(t) = cgl(e) {
            let kinds: Vec<Node> = t.children().filter(|c| c.is_element()).collect();
            if kinds.len() > 1 {
                return Err(self.err(t, "a CGL material block holds exactly one material"));
            }
            if let Some(&k) = kinds.first() {
                let c = ColorParam::Const;
                return Ok(match k.tag_name().name() {
                    "emission" => {
                        let r = self.cgl_rgb(k, "radiance", Rgb::ONE)?;
                        (
                            Material::Diffuse {
                                reflectance: ColorParam::constant(0.0),
                            },
                            Some(r),
                        )
                    }
                    "mirror" => (
                        Material::Mirror {
                            reflectance: c(self.cgl_rgb(k, "reflectance", Rgb::ONE)?),
                        },
                        None,
                    ),
                    "glass" | "refraction" => {
                        let rough = self.cgl_float(k, "roughness", 0.0)?;
                        if rough > 0.0 {
                            self.warn(k, "roughness of CGL glass is ignored (smooth dielectric)");
                        }
                        let ior = self.cgl_float(k, "ior", 1.5)?;
                        if ior <= 0.0 {
                            return Err(self.err(k, format!("ior must be positive, found {ior}")));
                        }
                        let refl = if k.tag_name().name() == "glass" {
                            self.cgl_rgb(k, "reflectance", Rgb::ONE)?
                        } else {
                            Rgb::ZERO
                        };
                        (
                            Material::Dielectric {
                                int_ior: ior,
                                ext_ior: 1.0,
                                dispersion: None,
                                specular_reflectance: c(refl),
                                specular_transmittance: c(self.cgl_rgb(
                                    k,
                                    "transmittance",
                                    Rgb::ONE,
                                )?),
                                absorption: None,
                            },
                            None,
                        )
                    }
                    "microfacet" => {
                        let alpha = self.cgl_float(k, "alpha", 0.5)?;
                        if alpha <= 0.0 {
                            return Err(
                                self.err(k, format!("alpha must be positive, found {alpha}"))
                            );
                        }
                        (
                            Material::RoughConductor {
                                distribution: MicrofacetDistribution::Beckmann,
                                alpha_u: FloatParam::Const(alpha),
                                alpha_v: FloatParam::Const(alpha),
                                eta: self.cgl_rgb(k, "eta", Rgb::ONE)?.into(),
                                k: self.cgl_rgb(k, "k", Rgb::ZERO)?.into(),
                                specular_reflectance: ColorParam::constant(1.0),
                            },
                            None,
                        )
                    }
                    other => {
                        return Err(self.err(k, format!(
                            "unknown CGL material '{other}' (expected emission, mirror, glass, refraction, microfacet)"
                        )));
                    }
                });
            }
        }
        // Lambertian from the common profile.
        let shader = child(e, "profile_COMMON")
            .and_then(|p| child(p, "technique"))
            .and_then(|t| {
                t.children().find(|c| {
                    c.is_element()
                        && matches!(
                            c.tag_name().name(),
                            "phong" | "lambert" | "blinn" | "constant"
                        )
                })
            });
        let mut kd = Rgb::splat(0.5);
        if let Some(s) = shader
            && let Some(d) = child(s, "diffuse")
        {
            if let Some(col) = child(d, "color") {
                kd = self.rgb(col)?;
            } else {
                self.warn(d, "textured diffuse colours are not supported: using 0.5");
            }
        }
        Ok((
            Material::Diffuse {
                reflectance: ColorParam::Const(kd),
            },
            None,
        ))
    }

    // -----------------------------------------------------------------------------------------
    // Lights and cameras

    fn light(&mut self, l: Node<'a, 'input>, m: Mat4, at: Node) -> Result<()> {
        if !is(&l, "light") {
            return Err(self.err(at, "<instance_light> must refer to a <light>"));
        }
        let block = cgl(l)
            .and_then(|t| t.children().find(|c| c.is_element()))
            .or_else(|| {
                child(l, "technique_common").and_then(|t| t.children().find(|c| c.is_element()))
            })
            .ok_or_else(|| self.err(l, "<light> without a light type"))?;
        let color = match child(block, "color") {
            Some(c) => self.rgb(c)?,
            None => Rgb::ONE,
        };
        let loc = self.loc(at);
        let origin = m.transform_point3(Vec3::ZERO);
        let emitter = match block.tag_name().name() {
            "point" => Emitter::Point {
                position: origin,
                intensity: color.into(),
            },
            "directional" => {
                let d = m.transform_vector3(-Vec3::Z).normalize_or_zero();
                if d == Vec3::ZERO {
                    return Err(self.err(at, "directional light with a degenerate transform"));
                }
                Emitter::Directional {
                    direction: d,
                    irradiance: color.into(),
                }
            }
            "spot" => {
                let falloff = match child(block, "falloff_angle") {
                    Some(f) => self.float(f)?,
                    None => 180.0,
                };
                let cutoff = (falloff * 0.5).clamp(0.01, 90.0);
                Emitter::Spot {
                    to_world: m * Mat4::from_scale(Vec3::new(1.0, -1.0, -1.0)),
                    intensity: color.into(),
                    cutoff_angle: cutoff,
                    beam_width: cutoff * 0.75,
                    falloff: SpotFalloff::Mitsuba,
                }
            }
            "ambient" => Emitter::Constant {
                radiance: color.into(),
            },
            "area" => {
                // Unit square facing local -Z: rotate Rectangle ([-1,1]², +z) by 180° about x
                // and halve it.
                let to_world = m * Mat4::from_scale(Vec3::new(0.5, -0.5, -1.0));
                if to_world.determinant().abs() < 1e-20 {
                    return Err(self.err(at, "area light with a degenerate transform"));
                }
                let black = self.desc.add_material(MaterialDesc {
                    material: Material::Diffuse {
                        reflectance: ColorParam::constant(0.0),
                    },
                    ambient: Rgb::ZERO,
                    name: Some("area light surface".into()),
                    loc: loc.clone(),
                });
                self.desc.shapes.push(ShapeDesc {
                    media: Default::default(),
                    motion: None,
                    shape: Shape::Rectangle,
                    to_world,
                    material: Some(black),
                    emission: Some(AreaEmission {
                        radiance: ColorParam::Const(color),
                        two_sided: false,
                        directional: false,
                        loc: loc.clone(),
                    }),
                    flip_normals: false,
                    name: l.attribute("name").map(str::to_string),
                    loc,
                });
                return Ok(());
            }
            other => {
                return Err(self.err(block, format!(
                    "unknown light type '{other}' (expected ambient, directional, point, spot, area)"
                )));
            }
        };
        self.desc.emitters.push(EmitterDesc {
            name: None,
            medium: None,
            emitter,
            loc,
        });
        Ok(())
    }

    fn camera(&mut self, c: Node<'a, 'input>, m: Mat4, node: Node) -> Result<Sensor> {
        if !is(&c, "camera") {
            return Err(self.err(node, "<instance_camera> must refer to a <camera>"));
        }
        let persp = child(c, "optics")
            .and_then(|o| child(o, "technique_common"))
            .and_then(|t| child(t, "perspective"));
        let Some(p) = persp else {
            return Err(self.err(c, "only <perspective> cameras are supported"));
        };
        let get =
            |tag: &str| -> Result<Option<f32>> { child(p, tag).map(|n| self.float(n)).transpose() };
        let (xfov, yfov, aspect) = (get("xfov")?, get("yfov")?, get("aspect_ratio")?);
        let t = |deg: f32| (deg.to_radians() * 0.5).tan();
        let at = |deg: f32| 2.0 * deg.atan().to_degrees();
        for v in [xfov, yfov].into_iter().flatten() {
            if !(v > 0.0 && v < 180.0) {
                return Err(self.err(
                    p,
                    format!("field of view must be in (0, 180) degrees, found {v}"),
                ));
            }
        }
        if let Some(a) = aspect
            && a <= 0.0
        {
            return Err(self.err(p, format!("aspect_ratio must be positive, found {a}")));
        }
        // (vertical fov, aspect)
        let (fov_y, aspect) = match (xfov, yfov, aspect) {
            (Some(x), Some(y), _) => (y, t(x) / t(y)),
            (Some(x), None, Some(a)) => (at(t(x) / a), a),
            (None, Some(y), Some(a)) => (y, a),
            (Some(x), None, None) => (x, 1.0),
            (None, Some(y), None) => (y, 1.0),
            (None, None, _) => {
                return Err(self.err(p, "<perspective> needs xfov or yfov"));
            }
        };
        let znear = get("znear")?.unwrap_or(0.01).max(1e-6);
        let zfar = get("zfar")?.unwrap_or(1e4).max(znear * 2.0);

        // Orthonormal frame from the node transform; ours looks along +z with +x to the left.
        let origin = m.transform_point3(Vec3::ZERO);
        // CS184: c_dir = unit(transform * (0, 0, -1, 1)) (w = 1: the translation counts).
        let view_dir = m.transform_point3(-Vec3::Z).normalize_or_zero();
        let mut fwd = m.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up0 = m.transform_vector3(Vec3::Y);
        let mut left = up0.cross(fwd).normalize_or_zero();
        if fwd == Vec3::ZERO || left == Vec3::ZERO || !left.is_finite() {
            // The course's program never builds a frame from the node's matrix: it places
            // the camera from the view direction alone (`place_cs184` below, once the
            // scene's bounds are known). So does this loader when the matrix has no frame
            // (CS184's CBgems.dae: a 15-number matrix whose third row is zero).
            if view_dir == Vec3::ZERO || !view_dir.is_finite() {
                return Err(self.err(
                    node,
                    "camera node with a degenerate transform and no view direction",
                ));
            }
            self.warn(
                node,
                "camera node with a degenerate transform: the camera is placed from its \
                 view direction alone, as the course's program places it",
            );
            fwd = view_dir;
            let hint = if fwd.y.abs() < 0.999 {
                Vec3::Y
            } else {
                Vec3::Z
            };
            left = hint.cross(fwd).normalize();
        }
        let up = fwd.cross(left);
        let to_world = Mat4::from_cols(
            left.extend(0.0),
            up.extend(0.0),
            fwd.extend(0.0),
            origin.extend(1.0),
        );
        self.view_dirs.push(if view_dir == Vec3::ZERO {
            -fwd
        } else {
            view_dir
        });
        let width = DEFAULT_WIDTH;
        let height = ((width as f32 / aspect).round() as u32).clamp(1, 1 << 16);
        Ok(Sensor {
            medium: None,
            camera: Camera {
                projection: Projection::Perspective {
                    fov: fov_y,
                    fov_axis: FovAxis::Y,
                },
                to_world,
                near_clip: znear,
                far_clip: zfar,
            },
            film: Film {
                width,
                height,
                crop: None,
                filter: FilterDesc::Box { radius: 0.5 },
                output: None,
                tonemap: None,
            },
            sampler: SamplerDesc::default(),
            integrator: None,
            name: node
                .attribute("name")
                .or(c.attribute("name"))
                .map(str::to_string),
            loc: self.loc(node),
        })
    }

    fn default_camera(&self, at: Node) -> Sensor {
        let m = self.up;
        let origin = m.transform_point3(Vec3::ZERO);
        let fwd = m.transform_vector3(-Vec3::Z);
        let left = m.transform_vector3(-Vec3::X);
        let up = fwd.cross(left);
        Sensor {
            medium: None,
            camera: Camera {
                projection: Projection::Perspective {
                    fov: 45.0,
                    fov_axis: FovAxis::Y,
                },
                to_world: Mat4::from_cols(
                    left.extend(0.0),
                    up.extend(0.0),
                    fwd.extend(0.0),
                    origin.extend(1.0),
                ),
                near_clip: 0.01,
                far_clip: 1e4,
            },
            film: Film {
                width: DEFAULT_WIDTH,
                height: DEFAULT_WIDTH * 3 / 4,
                crop: None,
                filter: FilterDesc::Box { radius: 0.5 },
                output: None,
                tonemap: None,
            },
            sampler: SamplerDesc::default(),
            integrator: None,
            name: None,
            loc: self.loc(at),
        }
    }
}

/// World-space bounds of the scene's shapes, leaving out area-light squares (CS184's
/// `Scene::get_bbox` covers objects, not lights).
pub fn scene_bounds(desc: &SceneDesc) -> Option<(Vec3, Vec3)> {
    crate::model::bounds_of(desc.shapes.iter().filter(|s| s.emission.is_none()))
}

/// The CS184 pathtracer ignores where the COLLADA camera is: `Application::load` aims it at
/// the centre of the scene's bounding box from `1.5 × |extent|` away, along `c_dir` (which
/// is `transform × (0, 0, −1, 1)` normalised, so the camera node's translation tilts it),
/// with world +Y up (−Y when `c_dir` points below the horizon... only at the poles). Returns
/// our camera-to-world (looking along +z, +x to the left).
pub fn place_cs184(lo: Vec3, hi: Vec3, c_dir: Vec3) -> Option<Mat4> {
    let target = (lo + hi) * 0.5;
    let r = (hi - lo).length() * 0.5 * 1.5 * 2.0;
    let to_cam = c_dir.normalize_or_zero();
    if to_cam == Vec3::ZERO || r <= 0.0 {
        return None;
    }
    let up = Vec3::Y;
    let right = up.cross(to_cam).normalize_or_zero();
    if right == Vec3::ZERO {
        return None;
    }
    let screen_up = to_cam.cross(right);
    let pos = target + to_cam * r;
    Some(Mat4::from_cols(
        (-right).extend(0.0),
        screen_up.extend(0.0),
        (-to_cam).extend(0.0),
        pos.extend(1.0),
    ))
}

/// The CS184 pathtracer's integrator for `-m max_depth -l light_samples`, `-H`
/// (`hemisphere`): all emitters sampled `l` times at every bounce, Russian roulette with
/// continuation 0.65 after the first bounce, `m` bounces (= `m + 1` path segments).
pub fn cs184_path(max_bounces: u32, light_samples: u32, hemisphere: bool) -> PathDesc {
    PathDesc {
        max_depth: max_bounces.saturating_add(1).min(i32::MAX as u32) as i32,
        rr: RussianRoulette::Fixed { after: 2, q: 0.35 },
        hide_emitters: false,
        nee: !hemisphere,
        directions: if hemisphere {
            DirectionSampling::UniformHemisphere
        } else {
            DirectionSampling::Bsdf
        },
        light_samples: light_samples.max(1),
        all_lights: true,
        ..PathDesc::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Z-up document with one camera, one quad (polylist with normals and UVs), a
    /// triangle list, a CGL sphere and an area light.
    const SMALL: &str = r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><up_axis>Z_UP</up_axis></asset>
  <library_lights>
    <light id="L"><technique_common><point><color>1 1 1</color></point></technique_common>
      <extra><technique profile="CGL"><area><color>2 3 4</color></area></technique></extra></light>
  </library_lights>
  <library_cameras>
    <camera id="C"><optics><technique_common><perspective>
      <xfov>60</xfov><aspect_ratio>2</aspect_ratio><znear>0.1</znear><zfar>100</zfar>
    </perspective></technique_common></optics></camera>
  </library_cameras>
  <library_effects>
    <effect id="red-fx"><profile_COMMON><technique sid="common"><phong>
      <diffuse><color>0.8 0.1 0.1 1</color></diffuse></phong></technique></profile_COMMON></effect>
    <effect id="ag-fx"><profile_COMMON/><extra><technique profile="CGL">
      <microfacet><alpha>0.2</alpha><eta>0.1 0.2 0.3</eta><k>4 3 2</k></microfacet>
    </technique></extra></effect>
    <effect id="glow-fx"><extra><technique profile="CGL"><emission><radiance>5 5 5</radiance></emission></technique></extra></effect>
  </library_effects>
  <library_materials>
    <material id="red"><instance_effect url="#red-fx"/></material>
    <material id="ag"><instance_effect url="#ag-fx"/></material>
    <material id="glow"><instance_effect url="#glow-fx"/></material>
  </library_materials>
  <library_geometries>
    <geometry id="quad"><mesh>
      <source id="q-pos"><float_array id="q-pos-a" count="12">0 0 0 1 0 0 1 1 0 0 1 0</float_array>
        <technique_common><accessor source="#q-pos-a" count="4" stride="3"/></technique_common></source>
      <source id="q-n"><float_array id="q-n-a" count="3">0 0 1</float_array>
        <technique_common><accessor source="#q-n-a" count="1" stride="3"/></technique_common></source>
      <source id="q-uv"><float_array id="q-uv-a" count="8">0 0 1 0 1 1 0 1</float_array>
        <technique_common><accessor source="#q-uv-a" count="4" stride="2"/></technique_common></source>
      <vertices id="q-v"><input semantic="POSITION" source="#q-pos"/></vertices>
      <polylist material="mat" count="1">
        <input semantic="VERTEX" source="#q-v" offset="0"/>
        <input semantic="NORMAL" source="#q-n" offset="1"/>
        <input semantic="TEXCOORD" source="#q-uv" offset="2" set="0"/>
        <vcount>4</vcount>
        <p>0 0 0 1 0 1 2 0 2 3 0 3</p>
      </polylist>
      <triangles material="mat2" count="1">
        <input semantic="VERTEX" source="#q-v" offset="0"/>
        <p>0 1 2</p>
      </triangles>
    </mesh></geometry>
    <geometry id="ball"><extra><technique profile="CGL"><sphere><radius>0.5</radius></sphere></technique></extra></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="S">
      <node id="cam"><matrix>1 0 0 0  0 0 -1 -5  0 1 0 1  0 0 0 1</matrix><instance_camera url="#C"/></node>
      <node id="group"><translate>0 0 1</translate><rotate>0 0 1 90</rotate>
        <node id="q"><scale>2 2 2</scale>
          <instance_geometry url="#quad"><bind_material><technique_common>
            <instance_material symbol="mat" target="#red"/>
            <instance_material symbol="mat2" target="#glow"/>
          </technique_common></bind_material></instance_geometry>
        </node>
      </node>
      <node id="b"><translate>1 2 3</translate>
        <instance_geometry url="#ball"><bind_material><technique_common>
          <instance_material symbol="m" target="#ag"/></technique_common></bind_material></instance_geometry>
      </node>
      <node id="light"><matrix>2 0 0 0  0 4 0 0  0 0 1 3  0 0 0 1</matrix><instance_light url="#L"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#S"/></scene>
</COLLADA>
"##;

    fn load(text: &str) -> Result<SceneDesc> {
        load_str(text, Path::new("test.dae"))
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).abs().max_element() < 1e-5
    }

    /// A `<matrix>` of 12 or 18 numbers renders as CS184's stream parser reads it (missing
    /// entries 0, extra ignored), with a warning, instead of failing.
    #[test]
    fn short_and_long_matrices_are_read_leniently() {
        let full = "2 0 0 0  0 4 0 0  0 0 1 3  0 0 0 1";
        let reference = load(SMALL).unwrap();
        let probe = |d: &SceneDesc| -> Vec<Vec3> {
            d.shapes
                .iter()
                .flat_map(|s| {
                    [Vec3::ZERO, Vec3::X, Vec3::Y].map(|p| s.to_world.transform_point3(p))
                })
                .collect()
        };
        for variant in [
            "2 0 0 0  0 4 0 0  0 0 1 3",
            "2 0 0 0  0 4 0 0  0 0 1 3  0 0 0 1  7 7",
        ] {
            let d = load(&SMALL.replace(full, variant)).unwrap();
            assert!(
                d.warnings
                    .iter()
                    .any(|w| w.message.contains("<matrix> has")),
                "{:?}",
                d.warnings
            );
            let (a, b) = (probe(&reference), probe(&d));
            assert!(a.iter().zip(&b).all(|(x, y)| close(*x, *y)), "{variant}");
        }
    }

    #[test]
    fn small_scene_geometry_and_materials() {
        let d = load(SMALL).unwrap();
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        // quad (2 triangles), triangle, sphere, area light.
        assert_eq!(d.shapes.len(), 4);
        let Shape::Mesh(q) = &d.shapes[0].shape else {
            panic!()
        };
        assert_eq!(q.indices.len(), 2);
        assert_eq!(q.positions.len(), 4);
        assert_eq!(q.normals.len(), 4);
        assert_eq!(q.uvs[2], Vec2::new(1.0, 1.0));
        // Z_UP conversion of the node chain: translate(0,0,1) rotate(z,90) scale(2):
        // local (1,0,0) → (0,2,1) in Z-up → (−0, 1, 2) in our Y-up world.
        let p = d.shapes[0].to_world.transform_point3(Vec3::X);
        assert!(close(p, Vec3::new(0.0, 1.0, 2.0)), "{p}");
        match &d.material(d.shapes[0].material.unwrap()).material {
            Material::Diffuse {
                reflectance: ColorParam::Const(c),
            } => assert!(close(*c, Vec3::new(0.8, 0.1, 0.1))),
            m => panic!("{m:?}"),
        }
        // The triangle with the emission material is an area emitter.
        let e = d.shapes[1].emission.as_ref().unwrap();
        assert_eq!(e.radiance, ColorParam::Const(Vec3::splat(5.0)));
        assert!(!e.two_sided);
        let Shape::Sphere { radius, .. } = d.shapes[2].shape else {
            panic!()
        };
        assert_eq!(radius, 0.5);
        // (1,2,3) Z-up → (−1, 3, 2).
        let c = d.shapes[2].to_world.transform_point3(Vec3::ZERO);
        assert!(close(c, Vec3::new(-1.0, 3.0, 2.0)));
        match &d.material(d.shapes[2].material.unwrap()).material {
            Material::RoughConductor {
                distribution: MicrofacetDistribution::Beckmann,
                alpha_u: FloatParam::Const(a),
                eta,
                k,
                ..
            } => {
                assert_eq!(*a, 0.2);
                assert_eq!(eta.rgb(), Vec3::new(0.1, 0.2, 0.3));
                assert_eq!(k.rgb(), Vec3::new(4.0, 3.0, 2.0));
            }
            m => panic!("{m:?}"),
        }
    }

    #[test]
    fn area_light_is_a_downward_square_of_the_node_size() {
        let d = load(SMALL).unwrap();
        let s = &d.shapes[3];
        assert!(matches!(s.shape, Shape::Rectangle));
        let e = s.emission.as_ref().unwrap();
        assert_eq!(e.radiance, ColorParam::Const(Vec3::new(2.0, 3.0, 4.0)));
        assert!(!e.two_sided);
        // The rectangle's normal (+z local) must face the node's −Z, i.e. Z-up down → −Y.
        let n = s.to_world.transform_vector3(Vec3::Z).normalize();
        assert!(close(n, -Vec3::Y), "{n}");
        // Corners (±1, ±1) map to a 2 × 4 (Z-up x × y) square centred at height 3.
        let a = s.to_world.transform_point3(Vec3::new(1.0, 1.0, 0.0));
        let b = s.to_world.transform_point3(Vec3::new(-1.0, -1.0, 0.0));
        assert!(close((a - b).abs(), Vec3::new(2.0, 0.0, 4.0)), "{a} {b}");
        assert!(close((a + b) * 0.5, Vec3::new(0.0, 3.0, 0.0)));
    }

    #[test]
    fn camera_fov_orientation_and_cs184_placement() {
        let d = load(SMALL).unwrap();
        let s = &d.sensors[0];
        assert_eq!((s.film.width, s.film.height), (800, 400));
        let Projection::Perspective { fov, fov_axis } = s.camera.projection else {
            panic!()
        };
        assert_eq!(fov_axis, FovAxis::Y);
        let expect = 2.0 * ((30f32).to_radians().tan() / 2.0).atan().to_degrees();
        assert!((fov - expect).abs() < 1e-3);
        // The Z-up camera sits at (0, −5, 1) looking along +Y (Z-up): in our world at
        // (0, 1, −5) looking along +Z, so image left (our +x) is +X. CS184 keeps only
        // c_dir = unit(M (0, 0, −1, 1)) = unit(0, −4, 1) (Z-up) = unit(0, 1, −4) (ours) and
        // places the camera at centre + 1.5 |extent| c_dir, looking back at the centre.
        let m = s.camera.to_world;
        let to_cam = Vec3::new(0.0, 1.0, -4.0).normalize();
        assert!(close(m.transform_vector3(Vec3::Z), -to_cam));
        assert!(close(m.transform_vector3(Vec3::X), Vec3::X));
        assert!(m.transform_vector3(Vec3::Y).y > 0.9);
        let (lo, hi) = scene_bounds(&d).unwrap();
        let c = (lo + hi) * 0.5;
        let pos = m.transform_point3(Vec3::ZERO);
        assert!(
            close(pos, c + to_cam * (hi - lo).length() * 1.5),
            "{pos} {c}"
        );
    }

    #[test]
    fn missing_asset_defaults_to_y_up_with_a_warning() {
        let text = SMALL.replace("<asset><up_axis>Z_UP</up_axis></asset>", "");
        let d = load(&text).unwrap();
        assert!(d.warnings.iter().any(|w| w.message.contains("Y_UP")));
        let c = d.shapes[2].to_world.transform_point3(Vec3::ZERO);
        assert!(close(c, Vec3::new(1.0, 2.0, 3.0)));
    }

    #[test]
    fn asset_without_up_axis_is_an_error_at_its_line() {
        let e = expect_err("<up_axis>Z_UP</up_axis>", "", "no <up_axis>");
        let line = SMALL.lines().position(|l| l.contains("<asset>")).unwrap() + 1;
        assert_eq!(e.loc.line as usize, line, "{e}");
    }

    #[test]
    fn x_up_is_the_courses_rotation() {
        // The course swaps X and Y and negates Z: (1, 2, 3) -> (2, 1, -3).
        let text = SMALL.replace("Z_UP", "X_UP");
        let d = load(&text).unwrap();
        let up = load(&SMALL.replace("Z_UP", "Y_UP")).unwrap();
        let (a, b) = (
            d.shapes[2].to_world.transform_point3(Vec3::ZERO),
            up.shapes[2].to_world.transform_point3(Vec3::ZERO),
        );
        assert!(close(a, Vec3::new(b.y, b.x, -b.z)), "{a} {b}");
    }

    /// Replace `from` by `to` in SMALL and expect an error mentioning `needle` at `line`.
    fn expect_err(from: &str, to: &str, needle: &str) -> LoadError {
        assert!(SMALL.contains(from), "test bug: {from}");
        let e = load(&SMALL.replacen(from, to, 1)).unwrap_err();
        assert!(e.message.contains(needle), "{e}");
        assert!(e.loc.line > 0, "{e}");
        e
    }

    #[test]
    fn malformed_documents_are_located_errors() {
        let e = expect_err("url=\"#quad\"", "url=\"#nothing\"", "dangling");
        let line = SMALL
            .lines()
            .position(|l| l.contains("url=\"#quad\""))
            .unwrap()
            + 1;
        assert_eq!(e.loc.line as usize, line);
        expect_err("count=\"12\">0 0 0", "count=\"13\">0 0 0", "holds 12");
        expect_err(
            "count=\"4\" stride=\"3\"",
            "count=\"5\" stride=\"3\"",
            "needs 15",
        );
        expect_err("<vcount>4</vcount>", "<vcount>5</vcount>", "vcount");
        expect_err("<p>0 1 2</p>", "<p>0 1 9</p>", "out of range");
        expect_err("<p>0 1 2</p>", "<p>0 1</p>", "multiple of 3");
        expect_err("<radius>0.5</radius>", "<radius>-1</radius>", "positive");
        expect_err(
            "<radius>0.5</radius>",
            "<radius>abc</radius>",
            "not a finite number",
        );
        expect_err("Z_UP", "W_UP", "up_axis");
        expect_err("<xfov>60</xfov>", "<xfov>200</xfov>", "field of view");
        expect_err(
            "<area><color>2 3 4</color></area>",
            "<laser/>",
            "unknown light type",
        );
        expect_err(
            "<microfacet><alpha>0.2</alpha><eta>0.1 0.2 0.3</eta><k>4 3 2</k></microfacet>",
            "<velvet/>",
            "unknown CGL material",
        );
        expect_err("</COLLADA>", "", "malformed XML");
        expect_err("id=\"q-n\"", "id=\"q-pos\"", "duplicate id");
        expect_err(
            "polylist material=\"mat\" count=\"1\"",
            "polylist material=\"mat\" count=\"2\"",
            "count='2'",
        );
        let e = load("<scene/>").unwrap_err();
        assert!(e.message.contains("COLLADA"));
    }

    #[test]
    fn no_panic_on_truncations() {
        // Every prefix cut at a line boundary either loads or fails cleanly.
        let lines: Vec<&str> = SMALL.lines().collect();
        for n in 0..lines.len() {
            let _ = load(&lines[..n].join("\n"));
        }
    }
}
