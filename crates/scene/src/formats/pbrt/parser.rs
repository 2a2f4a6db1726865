//! Directives: the file stack (`Include`, `Import`), the graphics state (transforms,
//! attributes, materials, media, area lights, `Attribute` defaults), named coordinate systems
//! and objects. Each directive that makes something hands its parameters to `build.rs`.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::lexer::{Kind, Lexer, Token, utf8};
use super::params::{Param, Params, Ty, Vals};
use crate::model::*;
use crate::{LoadError, LoadOptions, Loc, Result, Warning};

/// Nested `Include`/`Import` files at most.
const MAX_INCLUDE_DEPTH: usize = 15;
/// Nested `AttributeBegin`/`TransformBegin`/`ObjectBegin` at most.
const MAX_ATTRIBUTE_DEPTH: usize = 1000;
/// Parameter values (numbers, strings, booleans) in all files at most: the memory budget of
/// a parse (8 bytes each: 2 GiB).
pub(super) const MAX_VALUES: usize = 1 << 28;
/// Shapes in the scene at most (instancing multiplies them without adding text).
const MAX_SHAPES: usize = 1 << 24;
/// `Attribute` parameters of one kind at most (every directive of that kind copies them).
const MAX_ATTRIBUTES: usize = 4096;

/// Which of the two transforms (shutter open and close) the transform directives change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Active {
    Start,
    End,
    All,
}

/// The `Attribute` kinds, in `Gs::attrs` order.
pub(super) const ATTR_KINDS: [&str; 5] = ["shape", "light", "material", "medium", "texture"];

#[derive(Clone, Debug)]
pub(super) struct Gs {
    /// Current transforms at shutter open and close (object-to-world, pbrt's CTM).
    pub ctm: [Mat4; 2],
    pub active: Active,
    pub reverse: bool,
    pub material: Option<MaterialId>,
    pub area_light: Option<Rc<(String, Params)>>,
    pub inside: Option<String>,
    pub outside: Option<String>,
    pub attrs: [Vec<Param>; 5],
}

impl Default for Gs {
    fn default() -> Self {
        Gs {
            ctm: [Mat4::IDENTITY; 2],
            active: Active::All,
            reverse: false,
            material: None,
            area_light: None,
            inside: None,
            outside: None,
            attrs: Default::default(),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Frame {
    Attribute,
    Transform,
    Object,
    Import,
}

/// A resolved texture reference: a constant, or a texture of the scene.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum TexVal {
    Const(Rgb),
    Spectrum(Arc<SpectrumDesc>),
    Tex(TextureId),
}

/// Scene-wide options given before `WorldBegin`.
#[derive(Default)]
pub(super) struct Options {
    pub camera: Option<(String, Params, [Mat4; 2], Option<String>)>,
    pub film: Option<(String, Params)>,
    pub sampler: Option<(String, Params)>,
    pub filter: Option<(String, Params)>,
    pub integrator: Option<(String, Params)>,
    pub seed: Option<u64>,
    pub transform_times: (f32, f32),
}

pub(super) struct Loader {
    pub scene: SceneDesc,
    files: Vec<(Lexer, PathBuf, bool)>,
    pub gs: Gs,
    stack: Vec<(Gs, Frame, Loc)>,
    named_coords: HashMap<String, [Mat4; 2]>,
    pub world: bool,
    pub opts: Options,
    pub named_materials: HashMap<String, MaterialId>,
    pub float_textures: HashMap<String, TexVal>,
    pub spectrum_textures: HashMap<String, TexVal>,
    pub media: HashMap<String, MediumId>,
    pub objects: HashMap<String, Vec<ShapeDesc>>,
    /// The object being defined: its name and shapes.
    pub object: Option<(String, Vec<ShapeDesc>)>,
    pub meshes: HashMap<PathBuf, Arc<TriMesh>>,
    warned: HashSet<String>,
    values: usize,
}

fn err(loc: Loc, m: impl Into<String>) -> LoadError {
    LoadError::new(loc, m)
}

impl Loader {
    pub fn new(main: &Path) -> Loader {
        Loader {
            scene: SceneDesc {
                source: main.to_path_buf(),
                // pbrt-v4's default light sampler is its light BVH.
                light_selection: LightSelection::Bvh,
                integrator: IntegratorDesc::VolPath {
                    max_depth: 6,
                    rr_depth: 5,
                    hide_emitters: false,
                    equiangular: true,
                    transmittance: TransmittanceEstimator::default(),
                    sample_emission: false,
                },
                ..SceneDesc::default()
            },
            files: Vec::new(),
            gs: Gs::default(),
            stack: Vec::new(),
            named_coords: HashMap::new(),
            world: false,
            opts: Options {
                transform_times: (0.0, 1.0),
                ..Options::default()
            },
            named_materials: HashMap::new(),
            float_textures: HashMap::new(),
            spectrum_textures: HashMap::new(),
            media: HashMap::new(),
            objects: HashMap::new(),
            object: None,
            meshes: HashMap::new(),
            warned: HashSet::new(),
            values: 0,
        }
    }

    pub fn warn(&mut self, loc: &Loc, m: impl Into<String>) {
        self.scene.warnings.push(Warning {
            loc: loc.clone(),
            message: m.into(),
        });
    }

    /// A warning given once per scene for the same `key`.
    pub fn warn_once(&mut self, key: &str, loc: &Loc, m: impl Into<String>) {
        if self.warned.insert(key.to_string()) {
            self.warn(loc, m);
        }
    }

    /// Report (once per directive kind, type and parameter) the parameters nobody used.
    pub fn finish_params(&mut self, what: &str, ty: &str, p: &Params) {
        let unused: Vec<(String, Loc)> = p
            .unused()
            .map(|q| (format!("{} {}", q.ty.name(), q.name), q.loc.clone()))
            .collect();
        for (name, loc) in unused {
            self.warn_once(
                &format!("unused {what} {ty} {name}"),
                &loc,
                format!("parameter '{name}' of {what} \"{ty}\" is not used (ignored)"),
            );
        }
    }

    /// The folder of the file being read (relative file names resolve against it).
    pub fn dir(&self) -> PathBuf {
        self.files
            .last()
            .and_then(|(l, _, _)| l.file.parent().map(Path::to_path_buf))
            .unwrap_or_default()
    }

    /// A file parameter resolved against the folder of the file that names it.
    pub fn resolve(&self, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.dir().join(p)
        }
    }

    fn open(&mut self, path: &Path, at: Option<&Loc>, import: bool) -> Result<()> {
        let at_loc = || at.cloned().unwrap_or_else(|| Loc::file(path));
        if self.files.len() > MAX_INCLUDE_DEPTH {
            return Err(err(
                at_loc(),
                format!("more than {MAX_INCLUDE_DEPTH} nested Include/Import files"),
            ));
        }
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        if let Some(i) = self.files.iter().position(|(_, c, _)| *c == canonical) {
            let chain: Vec<String> = self.files[i..]
                .iter()
                .map(|(l, _, _)| l.file.display().to_string())
                .chain(std::iter::once(path.display().to_string()))
                .collect();
            return Err(err(
                at_loc(),
                format!("Include/Import cycle: {}", chain.join(" → ")),
            ));
        }
        let bytes = base::read_file(path)
            .map_err(|e| err(at_loc(), format!("cannot read '{}': {e}", path.display())))?;
        let file = Arc::new(path.to_path_buf());
        let text = utf8(bytes, &file)?;
        if import {
            let loc = at_loc();
            self.push(Frame::Import, loc)?;
        }
        self.files
            .push((Lexer::new(file, Arc::from(text)), canonical, import));
        Ok(())
    }

    fn push(&mut self, frame: Frame, loc: Loc) -> Result<()> {
        if self.stack.len() >= MAX_ATTRIBUTE_DEPTH {
            return Err(err(
                loc,
                format!("more than {MAX_ATTRIBUTE_DEPTH} nested AttributeBegin/TransformBegin"),
            ));
        }
        self.stack.push((self.gs.clone(), frame, loc));
        Ok(())
    }

    fn pop(&mut self, frame: Frame, loc: &Loc, name: &str) -> Result<()> {
        let Some((gs, f, _)) = self.stack.pop() else {
            return Err(err(loc.clone(), format!("{name} without a matching begin")));
        };
        if f != frame {
            let open = match f {
                Frame::Attribute => "AttributeBegin",
                Frame::Transform => "TransformBegin",
                Frame::Object => "ObjectBegin",
                Frame::Import => "the start of an imported file",
            };
            return Err(err(loc.clone(), format!("{name} does not match {open}")));
        }
        match frame {
            Frame::Transform => {
                self.gs.ctm = gs.ctm;
                self.gs.active = gs.active;
            }
            _ => self.gs = gs,
        }
        Ok(())
    }

    fn lex(&mut self) -> &mut Lexer {
        &mut self.files.last_mut().expect("a file is open").0
    }

    /// The next token of the current file, or an error naming what was expected.
    fn expect(&mut self, what: &str) -> Result<Token> {
        match self.lex().next()? {
            Some(t) => Ok(t),
            None => {
                let l = self.lex().here();
                Err(err(l, format!("the file ends where {what} was expected")))
            }
        }
    }

    fn string_arg(&mut self, directive: &str) -> Result<(String, Loc)> {
        let t = self.expect(&format!("the quoted name after {directive}"))?;
        let loc = self.lex().loc(&t);
        match t.kind {
            Kind::Str(s) => Ok((s, loc)),
            _ => {
                let found = describe(self.lex(), &t);
                Err(err(
                    loc,
                    format!("{directive} expects a quoted string, found {found}"),
                ))
            }
        }
    }

    fn number(&mut self, t: &Token, what: &str) -> Result<f64> {
        let lex = self.lex();
        if t.kind == Kind::Word
            && let Some(v) = parse_number(lex.text(t))
        {
            return Ok(v);
        }
        let found = describe(lex, t);
        Err(err(
            lex.loc(t),
            format!("{what}: expected a number, found {found}"),
        ))
    }

    /// `n` numbers, optionally in brackets (pbrt accepts both for `Transform`).
    fn numbers(&mut self, n: usize, directive: &str) -> Result<Vec<f64>> {
        let what = format!("{directive} ({n} numbers)");
        let first = self.expect(&what)?;
        let bracketed = first.kind == Kind::Open;
        let mut out = Vec::with_capacity(n);
        if !bracketed {
            out.push(self.number(&first, &what)?);
        }
        while out.len() < n {
            let t = self.expect(&what)?;
            if t.kind == Kind::Close && bracketed {
                let l = self.lex().loc(&t);
                return Err(err(
                    l,
                    format!("{directive}: {} numbers given, {n} expected", out.len()),
                ));
            }
            out.push(self.number(&t, &what)?);
        }
        if bracketed {
            let t = self.expect("']'")?;
            if t.kind != Kind::Close {
                let l = self.lex().loc(&t);
                return Err(err(
                    l,
                    format!("{directive}: more than {n} numbers, or a missing ']'"),
                ));
            }
        }
        Ok(out)
    }

    /// A parameter list: `"type name" value` pairs while the next token is a string.
    fn param_list(&mut self) -> Result<Vec<Param>> {
        let mut out = Vec::new();
        loop {
            match self.lex().peek()? {
                Some(Token {
                    kind: Kind::Str(_), ..
                }) => {}
                _ => return Ok(out),
            }
            let decl = self.expect("a parameter")?;
            let loc = self.lex().loc(&decl);
            let Kind::Str(d) = decl.kind else {
                unreachable!("peeked a string")
            };
            let mut words = d.split_whitespace();
            let (Some(ty), Some(name), None) = (words.next(), words.next(), words.next()) else {
                return Err(err(
                    loc,
                    format!("'{d}' is not a parameter declaration (expected \"type name\")"),
                ));
            };
            let Some((ty, v3_color)) = Ty::parse(ty) else {
                return Err(err(
                    loc,
                    format!(
                        "unknown parameter type '{ty}' (expected integer, float, point2, \
                         vector2, point3, vector3, normal, bool, string, rgb, spectrum, \
                         blackbody or texture)"
                    ),
                ));
            };
            if v3_color {
                self.warn_once(
                    "v3 color",
                    &loc,
                    "pbrt-v3's 'color' parameter type read as 'rgb'",
                );
            }
            let name = name.to_string();
            let vals = self.values(&name)?;
            self.values += vals.len();
            if self.values > MAX_VALUES {
                return Err(err(
                    loc,
                    format!("more than {MAX_VALUES} parameter values in the scene"),
                ));
            }
            out.push(Param::new(ty, name, vals, loc)?);
        }
    }

    /// The value(s) of a parameter: one token, or a bracketed list of one kind.
    fn values(&mut self, name: &str) -> Result<Vals> {
        let what = format!("the value of parameter '{name}'");
        let t = self.expect(&what)?;
        if t.kind != Kind::Open {
            return self.single(t, name).map(|v| match v {
                One::Num(x) => Vals::Nums(vec![x]),
                One::Str(s) => Vals::Strs(vec![s]),
                One::Bool(b) => Vals::Bools(vec![b]),
            });
        }
        let open = self.lex().loc(&t);
        let mut vals: Option<Vals> = None;
        loop {
            let Some(t) = self.lex().next()? else {
                return Err(err(
                    open,
                    format!("'[' of parameter '{name}' is never closed"),
                ));
            };
            if t.kind == Kind::Close {
                return Ok(vals.unwrap_or(Vals::Nums(Vec::new())));
            }
            let loc = self.lex().loc(&t);
            let v = self.single(t, name)?;
            match (&mut vals, v) {
                (None, One::Num(x)) => vals = Some(Vals::Nums(vec![x])),
                (None, One::Str(s)) => vals = Some(Vals::Strs(vec![s])),
                (None, One::Bool(b)) => vals = Some(Vals::Bools(vec![b])),
                (Some(Vals::Nums(v)), One::Num(x)) => v.push(x),
                (Some(Vals::Strs(v)), One::Str(s)) => v.push(s),
                (Some(Vals::Bools(v)), One::Bool(b)) => v.push(b),
                _ => {
                    return Err(err(
                        loc,
                        format!("parameter '{name}' mixes numbers, strings and booleans"),
                    ));
                }
            }
            if vals.as_ref().map_or(0, Vals::len) + self.values > MAX_VALUES {
                return Err(err(
                    loc,
                    format!("more than {MAX_VALUES} parameter values in the scene"),
                ));
            }
        }
    }

    fn single(&mut self, t: Token, name: &str) -> Result<One> {
        let lex = self.lex();
        match t.kind {
            Kind::Str(s) => Ok(One::Str(s)),
            Kind::Word => {
                let w = lex.text(&t);
                if let Some(v) = parse_number(w) {
                    return Ok(One::Num(v));
                }
                match w {
                    "true" => Ok(One::Bool(true)),
                    "false" => Ok(One::Bool(false)),
                    _ => {
                        let found = describe(lex, &t);
                        Err(err(
                            lex.loc(&t),
                            format!(
                                "parameter '{name}': expected a number, a quoted string, true \
                                 or false, found {found}"
                            ),
                        ))
                    }
                }
            }
            Kind::Open | Kind::Close => {
                let found = describe(lex, &t);
                Err(err(
                    lex.loc(&t),
                    format!("parameter '{name}': unexpected {found}"),
                ))
            }
        }
    }

    /// Parameters of a directive of an `Attribute` kind: that kind's defaults, then its own.
    fn params_of(&mut self, kind: Option<usize>, loc: &Loc) -> Result<Params> {
        let own = self.param_list()?;
        let mut list = match kind {
            Some(k) => self.gs.attrs[k].clone(),
            None => Vec::new(),
        };
        list.extend(own);
        Ok(Params {
            list,
            loc: loc.clone(),
        })
    }

    fn apply(&mut self, m: Mat4) {
        let a = self.gs.active;
        for (i, ctm) in self.gs.ctm.iter_mut().enumerate() {
            if a == Active::All || (a == Active::Start) == (i == 0) {
                *ctm *= m;
            }
        }
    }

    fn set(&mut self, m: [Mat4; 2]) {
        let a = self.gs.active;
        for (i, ctm) in self.gs.ctm.iter_mut().enumerate() {
            if a == Active::All || (a == Active::Start) == (i == 0) {
                *ctm = m[i];
            }
        }
    }

    fn options_only(&self, name: &str, loc: &Loc) -> Result<()> {
        if self.world {
            return Err(err(
                loc.clone(),
                format!("{name} is allowed only before WorldBegin"),
            ));
        }
        Ok(())
    }

    fn world_only(&self, name: &str, loc: &Loc) -> Result<()> {
        if !self.world {
            return Err(err(
                loc.clone(),
                format!("{name} is allowed only after WorldBegin"),
            ));
        }
        Ok(())
    }

    /// Read every directive of `path` (and the files it includes).
    pub fn run(&mut self, path: &Path) -> Result<()> {
        self.open(path, None, false)?;
        loop {
            let t = match self.lex().next()? {
                Some(t) => t,
                None => {
                    let (lex, _, import) = self.files.pop().expect("a file is open");
                    if import {
                        let here = lex.here();
                        self.pop(Frame::Import, &here, "the end of an imported file")
                            .map_err(|_| {
                                err(
                                    here,
                                    "an imported file ends inside an AttributeBegin/\
                                     TransformBegin/ObjectBegin it opened",
                                )
                            })?;
                    }
                    if self.files.is_empty() {
                        break;
                    }
                    continue;
                }
            };
            let loc = self.lex().loc(&t);
            if t.kind != Kind::Word {
                let found = describe(self.lex(), &t);
                return Err(err(loc, format!("expected a directive, found {found}")));
            }
            let name = self.lex().text(&t).to_string();
            self.directive(&name, &loc)?;
        }
        if let Some((_, f, loc)) = self.stack.last() {
            let what = match f {
                Frame::Attribute => "AttributeBegin",
                Frame::Transform => "TransformBegin",
                Frame::Object => "ObjectBegin",
                Frame::Import => "Import",
            };
            return Err(err(loc.clone(), format!("{what} is never closed")));
        }
        Ok(())
    }

    fn directive(&mut self, name: &str, loc: &Loc) -> Result<()> {
        match name {
            "Identity" => self.set([Mat4::IDENTITY; 2]),
            "Translate" => {
                let v = self.numbers(3, name)?;
                self.apply(Mat4::from_translation(v3(&v)));
            }
            "Scale" => {
                let v = self.numbers(3, name)?;
                self.apply(Mat4::from_scale(v3(&v)));
            }
            "Rotate" => {
                let v = self.numbers(4, name)?;
                let axis = v3(&v[1..]);
                if axis.length_squared() == 0.0 || !axis.is_finite() {
                    return Err(err(loc.clone(), "Rotate: the axis is zero"));
                }
                self.apply(Mat4::from_axis_angle(
                    axis.normalize(),
                    (v[0] as f32).to_radians(),
                ));
            }
            "LookAt" => {
                let v = self.numbers(9, name)?;
                let m = look_at(v3(&v[0..3]), v3(&v[3..6]), v3(&v[6..9])).ok_or_else(|| {
                    err(
                        loc.clone(),
                        "LookAt: the eye and the target coincide, or 'up' is parallel to \
                             the viewing direction",
                    )
                })?;
                self.apply(m);
            }
            "Transform" | "ConcatTransform" => {
                let v = self.numbers(16, name)?;
                let a: [f32; 16] = std::array::from_fn(|i| v[i] as f32);
                // Column-major as written: the translation is the 13th to 15th number.
                let m = Mat4::from_cols_array(&a);
                if name == "Transform" {
                    self.set([m; 2]);
                } else {
                    self.apply(m);
                }
            }
            "CoordinateSystem" => {
                let (n, _) = self.string_arg(name)?;
                self.named_coords.insert(n, self.gs.ctm);
            }
            "CoordSysTransform" => {
                let (n, l) = self.string_arg(name)?;
                match self.named_coords.get(&n) {
                    Some(m) => {
                        let m = *m;
                        self.set(m);
                    }
                    None => {
                        return Err(err(l, format!("unknown coordinate system '{n}'")));
                    }
                }
            }
            "ActiveTransform" => {
                let t = self.expect("StartTime, EndTime or All")?;
                let w = if t.kind == Kind::Word {
                    self.lex().text(&t).to_string()
                } else {
                    String::new()
                };
                self.gs.active = match w.as_str() {
                    "StartTime" => Active::Start,
                    "EndTime" => Active::End,
                    "All" => Active::All,
                    _ => {
                        let l = self.lex().loc(&t);
                        return Err(err(l, "ActiveTransform expects StartTime, EndTime or All"));
                    }
                };
            }
            "TransformTimes" => {
                let v = self.numbers(2, name)?;
                self.options_only(name, loc)?;
                self.opts.transform_times = (v[0] as f32, v[1] as f32);
            }
            "ReverseOrientation" => self.gs.reverse = !self.gs.reverse,
            "AttributeBegin" => self.push(Frame::Attribute, loc.clone())?,
            "AttributeEnd" => self.pop(Frame::Attribute, loc, name)?,
            "TransformBegin" => {
                self.warn_once(
                    "TransformBegin",
                    loc,
                    "TransformBegin/TransformEnd are deprecated in pbrt-v4 (read as a push \
                     and pop of the transform)",
                );
                self.push(Frame::Transform, loc.clone())?
            }
            "TransformEnd" => self.pop(Frame::Transform, loc, name)?,
            "Attribute" => {
                let (kind, l) = self.string_arg(name)?;
                let Some(k) = ATTR_KINDS.iter().position(|&a| a == kind) else {
                    return Err(err(
                        l,
                        format!(
                            "Attribute: unknown kind '{kind}' (expected shape, light, \
                             material, medium or texture)"
                        ),
                    ));
                };
                let list = self.param_list()?;
                self.gs.attrs[k].extend(list);
                if self.gs.attrs[k].len() > MAX_ATTRIBUTES {
                    return Err(err(
                        loc.clone(),
                        format!("more than {MAX_ATTRIBUTES} \"{kind}\" Attribute parameters"),
                    ));
                }
            }
            "Option" => {
                let p = self.param_list()?;
                self.option(p, loc);
            }
            "ColorSpace" => {
                let (cs, l) = self.string_arg(name)?;
                if cs != "srgb" {
                    self.warn(
                        &l,
                        format!(
                            "colour space '{cs}' is not supported: RGB values are read as \
                             linear sRGB"
                        ),
                    );
                }
            }
            "Camera" | "Film" | "Sampler" | "PixelFilter" | "Integrator" | "Accelerator" => {
                let (ty, _) = self.string_arg(name)?;
                let p = self.params_of(None, loc)?;
                self.options_only(name, loc)?;
                let entry = Some((ty.clone(), p.clone()));
                match name {
                    "Camera" => {
                        let ctm = self.gs.ctm;
                        self.named_coords
                            .insert("camera".to_string(), [ctm[0].inverse(), ctm[1].inverse()]);
                        self.opts.camera = Some((ty, p, ctm, self.gs.outside.clone()));
                    }
                    "Film" => self.opts.film = entry,
                    "Sampler" => self.opts.sampler = entry,
                    "PixelFilter" => self.opts.filter = entry,
                    "Integrator" => self.opts.integrator = entry,
                    _ => {
                        // The accelerator is ours whatever the file asks for.
                        for q in &p.list {
                            q.used.set(true);
                        }
                    }
                }
            }
            "WorldBegin" => {
                self.options_only(name, loc)?;
                self.world = true;
                self.gs.ctm = [Mat4::IDENTITY; 2];
                self.gs.active = Active::All;
                self.named_coords
                    .insert("world".to_string(), [Mat4::IDENTITY; 2]);
            }
            "WorldEnd" => {
                self.warn_once("WorldEnd", loc, "pbrt-v3's WorldEnd ignored");
            }
            "MakeNamedMedium" => {
                let (n, _) = self.string_arg(name)?;
                let p = self.params_of(Some(3), loc)?;
                self.make_medium(n, p, loc)?;
            }
            "MediumInterface" => {
                let (inside, _) = self.string_arg(name)?;
                let outside = match self.lex().peek()? {
                    Some(Token {
                        kind: Kind::Str(_), ..
                    }) => self.string_arg(name)?.0,
                    _ => inside.clone(),
                };
                let none = |s: String| (!s.is_empty()).then_some(s);
                self.gs.inside = none(inside);
                self.gs.outside = none(outside);
            }
            "Texture" => {
                let (n, _) = self.string_arg(name)?;
                let (kind, kl) = self.string_arg(name)?;
                let (class, _) = self.string_arg(name)?;
                let p = self.params_of(Some(4), loc)?;
                self.world_only(name, loc)?;
                let spectrum = match kind.as_str() {
                    "spectrum" => true,
                    "float" => false,
                    "color" | "rgb" => {
                        self.warn_once(
                            "v3 color texture",
                            &kl,
                            "pbrt-v3's 'color' texture type read as 'spectrum'",
                        );
                        true
                    }
                    _ => {
                        return Err(err(
                            kl,
                            format!("texture type '{kind}' (expected \"float\" or \"spectrum\")"),
                        ));
                    }
                };
                self.make_texture(n, spectrum, &class, p, loc)?;
            }
            "Material" => {
                let (ty, _) = self.string_arg(name)?;
                let p = self.params_of(Some(2), loc)?;
                self.world_only(name, loc)?;
                self.gs.material = Some(self.make_material(&ty, &p, loc, None)?);
            }
            "MakeNamedMaterial" => {
                let (n, _) = self.string_arg(name)?;
                let p = self.params_of(Some(2), loc)?;
                self.world_only(name, loc)?;
                let ty = p.string_opt("type")?.map(|(s, _)| s.to_string());
                let Some(ty) = ty else {
                    return Err(err(
                        loc.clone(),
                        format!("MakeNamedMaterial \"{n}\" needs a \"string type\" parameter"),
                    ));
                };
                if self.named_materials.contains_key(&n) {
                    self.warn(loc, format!("named material '{n}' redefined"));
                }
                let id = self.make_material(&ty, &p, loc, Some(n.clone()))?;
                self.named_materials.insert(n, id);
            }
            "NamedMaterial" => {
                let (n, l) = self.string_arg(name)?;
                self.world_only(name, loc)?;
                match self.named_materials.get(&n) {
                    Some(&id) => self.gs.material = Some(id),
                    None => return Err(err(l, format!("unknown named material '{n}'"))),
                }
            }
            "LightSource" => {
                let (ty, _) = self.string_arg(name)?;
                let p = self.params_of(Some(1), loc)?;
                self.world_only(name, loc)?;
                self.make_light(&ty, &p, loc)?;
            }
            "AreaLightSource" => {
                let (ty, _) = self.string_arg(name)?;
                let p = self.params_of(Some(1), loc)?;
                self.world_only(name, loc)?;
                if ty == "area" {
                    self.warn_once(
                        "v3 area light",
                        loc,
                        "pbrt-v3's area light \"area\" read as \"diffuse\"",
                    );
                } else if ty != "diffuse" {
                    return Err(err(
                        loc.clone(),
                        format!("unknown area light \"{ty}\" (pbrt-v4 has \"diffuse\")"),
                    ));
                }
                self.gs.area_light = Some(Rc::new((ty, p)));
            }
            "Shape" => {
                let (ty, _) = self.string_arg(name)?;
                let p = self.params_of(Some(0), loc)?;
                self.world_only(name, loc)?;
                self.make_shape(&ty, &p, loc)?;
            }
            "ObjectBegin" => {
                let (n, _) = self.string_arg(name)?;
                self.world_only(name, loc)?;
                if self.object.is_some() {
                    return Err(err(loc.clone(), "ObjectBegin inside another ObjectBegin"));
                }
                self.push(Frame::Object, loc.clone())?;
                self.object = Some((n, Vec::new()));
            }
            "ObjectEnd" => {
                let Some((n, shapes)) = self.object.take() else {
                    return Err(err(loc.clone(), "ObjectEnd without ObjectBegin"));
                };
                self.pop(Frame::Object, loc, name)?;
                if self.objects.insert(n.clone(), shapes).is_some() {
                    self.warn(loc, format!("object '{n}' redefined"));
                }
            }
            "ObjectInstance" => {
                let (n, l) = self.string_arg(name)?;
                self.world_only(name, loc)?;
                if self.object.is_some() {
                    return Err(err(loc.clone(), "ObjectInstance inside ObjectBegin"));
                }
                let Some(shapes) = self.objects.get(&n) else {
                    return Err(err(l, format!("unknown object '{n}'")));
                };
                if self.scene.shapes.len() + shapes.len() > MAX_SHAPES {
                    return Err(err(
                        loc.clone(),
                        format!("more than {MAX_SHAPES} shapes (instances included)"),
                    ));
                }
                let [m0, m1] = self.gs.ctm;
                let motion = motion_of(&m0, &m1);
                let mut out = Vec::with_capacity(shapes.len());
                for s in shapes {
                    let mut s = s.clone();
                    s.to_world = m0 * s.to_world;
                    s.motion = motion.or(s.motion);
                    s.loc = loc.clone();
                    out.push(s);
                }
                if m0 != m1 && motion.is_none() {
                    self.warn_once(
                        "instance motion",
                        loc,
                        "only translating motion is supported: instances use their \
                         shutter-open transform",
                    );
                }
                self.scene.shapes.extend(out);
            }
            "Include" | "Import" => {
                let (f, l) = self.string_arg(name)?;
                let path = self.resolve(&f);
                if !path.is_file() {
                    return Err(err(
                        l,
                        format!("{name}: file '{}' not found", path.display()),
                    ));
                }
                self.open(&path, Some(&l), name == "Import")?;
            }
            "MakeNamedTexture" | "Volume" | "ShapeSet" => {
                return Err(err(loc.clone(), format!("unknown directive '{name}'")));
            }
            _ => {
                let shown: String = name.chars().take(40).collect();
                return Err(err(
                    loc.clone(),
                    format!(
                        "unknown directive '{shown}' (pbrt-v4 directives start with a capital \
                         letter, e.g. Shape, Material, LightSource)"
                    ),
                ));
            }
        }
        Ok(())
    }

    fn option(&mut self, p: Vec<Param>, loc: &Loc) {
        for q in p {
            match (q.name.as_str(), &q.vals) {
                ("seed", Vals::Nums(v)) if v.len() == 1 => {
                    self.opts.seed = Some(v[0].max(0.0) as u64);
                }
                _ => self.warn(
                    loc,
                    format!(
                        "Option \"{} {}\" is not used (ignored)",
                        q.ty.name(),
                        q.name
                    ),
                ),
            }
        }
    }
}

enum One {
    Num(f64),
    Str(String),
    Bool(bool),
}

fn v3(v: &[f64]) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// A finite number in pbrt's syntax (Rust's float syntax minus `inf`/`nan`).
pub(super) fn parse_number(w: &str) -> Option<f64> {
    let first = *w.as_bytes().first()?;
    if !(first.is_ascii_digit() || matches!(first, b'-' | b'+' | b'.')) {
        return None;
    }
    w.parse::<f64>().ok().filter(|v| v.is_finite())
}

fn describe(lex: &Lexer, t: &Token) -> String {
    match &t.kind {
        Kind::Word => {
            let w: String = lex.text(t).chars().take(40).collect();
            format!("'{w}'")
        }
        Kind::Str(s) => {
            let s: String = s.chars().take(40).collect();
            format!("\"{s}\"")
        }
        Kind::Open => "'['".to_string(),
        Kind::Close => "']'".to_string(),
    }
}

/// pbrt's `LookAt`: camera-from-world (the inverse of the frame with columns right = up × dir,
/// up' = dir × right, dir, eye).
pub(super) fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - eye).normalize_or_zero();
    if dir == Vec3::ZERO || !eye.is_finite() {
        return None;
    }
    let right = up.normalize_or_zero().cross(dir);
    if right.length_squared() == 0.0 || !right.is_finite() {
        return None;
    }
    let right = right.normalize();
    let new_up = dir.cross(right);
    let world_from_camera = Mat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    );
    Some(world_from_camera.inverse())
}

/// The world-space translation a shape moves by over the shutter, when the two transforms
/// differ only by one (the motion our model has).
pub(super) fn motion_of(m0: &Mat4, m1: &Mat4) -> Option<Vec3> {
    if m0 == m1 {
        return None;
    }
    let same_linear = (0..3).all(|c| m0.col(c).abs_diff_eq(m1.col(c), 1e-6));
    same_linear.then(|| (m1.w_axis - m0.w_axis).truncate())
}

/// Load a pbrt-v4 file into a scene description.
pub(super) fn load(path: &Path, _opts: &LoadOptions) -> Result<SceneDesc> {
    let mut l = Loader::new(path);
    l.run(path)?;
    l.finish()
}
