//! Stage 2a: the properties of one plugin element (`<float>`, `<rgb>`, `<transform>`, ...),
//! parsed and type-checked, with "was it used?" tracking for unknown-parameter warnings.

use std::cell::Cell;

use glam::{Mat4, Vec3};

use super::tree::{Attr, Elem, err};
use crate::formats::common::look_at;
use crate::{Loc, Result};

/// A colour-like value before conversion (its meaning depends on where it is used).
#[derive(Clone, Debug)]
pub enum ColorSpec {
    Rgb(Vec3),
    /// A wavelength-independent spectrum.
    Uniform(f64),
    /// `wavelength:value` pairs (nm), strictly increasing wavelengths.
    Sampled(Vec<f64>, Vec<f64>),
    /// `<spectrum type="blackbody">`: Planck's law (W·m⁻²·sr⁻¹·nm⁻¹) times `scale`.
    Blackbody {
        temperature: f64,
        scale: f64,
    },
    /// `<spectrum type="d65">`: D65 of unit luminance times `scale`.
    D65 {
        scale: f64,
    },
}

impl ColorSpec {
    /// The spectrum as sampled values at 1 nm over the visible range, for the plugins
    /// (`blackbody`, `d65`); lists as given; `None` for RGB and uniform values.
    pub fn sampled(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        let visible = || (360..=830).map(f64::from);
        match self {
            ColorSpec::Rgb(_) | ColorSpec::Uniform(_) => None,
            ColorSpec::Sampled(w, v) => Some((w.clone(), v.clone())),
            ColorSpec::Blackbody { temperature, scale } => Some((
                visible().collect(),
                visible()
                    .map(|w| crate::spectra::planck(w, *temperature) * scale)
                    .collect(),
            )),
            ColorSpec::D65 { scale } => Some((
                visible().collect(),
                visible()
                    .map(|w| crate::spectra::cie_d65(w) * scale)
                    .collect(),
            )),
        }
    }
}

#[derive(Clone, Debug)]
pub enum Value {
    Float(f64),
    Int(i64),
    Bool(bool),
    Str(String),
    /// `<point>` or `<vector>`.
    Vector(Vec3),
    Color(ColorSpec),
    Transform(Mat4),
}

impl Value {
    fn type_name(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Int(_) => "integer",
            Value::Bool(_) => "boolean",
            Value::Str(_) => "string",
            Value::Vector(_) => "point/vector",
            Value::Color(_) => "rgb/spectrum",
            Value::Transform(_) => "transform",
        }
    }
}

#[derive(Debug)]
pub struct Prop {
    pub name: String,
    pub value: Value,
    pub loc: Loc,
    pub used: Cell<bool>,
}

/// Mitsuba 0.6 / Nori camelCase names → Mitsuba 3 snake_case (`toWorld` → `to_world`,
/// `intIOR` → `int_ior`, `sampleCount` → `sample_count`); snake_case names are unchanged.
pub fn snake_case(name: &str) -> String {
    let mut out = String::with_capacity(name.len() + 4);
    let mut prev: Option<char> = None;
    for c in name.chars() {
        if c.is_ascii_uppercase() {
            if prev.is_some_and(|p| p.is_ascii_lowercase() || p.is_ascii_digit()) {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
        prev = Some(c);
    }
    out
}

/// Split a list of numbers on commas and/or whitespace.
pub fn tokens(s: &str) -> impl Iterator<Item = &str> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
}

/// Parse a finite float; the error names the text and the expectation.
pub fn parse_float(s: &str, loc: &Loc) -> Result<f64> {
    let t = s.trim();
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() <= f32::MAX as f64 => Ok(v),
        Ok(_) => Err(err(
            loc,
            format!(
                "expected a finite number, found '{t}' (NaN, infinity and values beyond ±3.4e38 are not allowed)"
            ),
        )),
        Err(_) => Err(err(loc, format!("expected a number, found '{t}'"))),
    }
}

pub fn parse_int(s: &str, loc: &Loc) -> Result<i64> {
    let t = s.trim();
    t.parse::<i64>().map_err(|e| {
        use std::num::IntErrorKind::*;
        match e.kind() {
            PosOverflow | NegOverflow => err(loc, format!("integer '{t}' is out of range")),
            _ => err(loc, format!("expected an integer, found '{t}'")),
        }
    })
}

pub fn parse_floats(s: &str, loc: &Loc) -> Result<Vec<f64>> {
    tokens(s).map(|t| parse_float(t, loc)).collect()
}

/// A 3-vector from `value="x y z"` (commas and/or spaces) or `x=`, `y=`, `z=` attributes
/// (missing components take `default`).
pub fn parse_xyz(e: &Elem, default: f64) -> Result<Vec3> {
    if let Some(a) = e.attr("value") {
        let v = parse_floats(&a.value, &a.loc)?;
        return match v.len() {
            3 => Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)),
            1 if e.tag == "scale" => Ok(Vec3::splat(v[0] as f32)),
            n => Err(err(
                &a.loc,
                format!("<{}> expects 3 numbers in 'value', found {n}", e.tag),
            )),
        };
    }
    let mut out = [default; 3];
    for (i, n) in ["x", "y", "z"].iter().enumerate() {
        if let Some(a) = e.attr(n) {
            out[i] = parse_float(&a.value, &a.loc)?;
        }
    }
    Ok(Vec3::new(out[0] as f32, out[1] as f32, out[2] as f32))
}

fn parse_vec_attr(e: &Elem, name: &str) -> Result<Vec3> {
    let a = e
        .attr(name)
        .ok_or_else(|| err(&e.loc, format!("<{}> needs a '{name}' attribute", e.tag)))?;
    let v = parse_floats(&a.value, &a.loc)?;
    if v.len() != 3 {
        return Err(err(
            &a.loc,
            format!("'{name}' expects 3 numbers, found {}", v.len()),
        ));
    }
    Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
}

fn check_attrs(e: &Elem, allowed: &[&str], warnings: &mut Vec<crate::Warning>) {
    for a in &e.attrs {
        if !allowed.contains(&a.name.as_str()) {
            warnings.push(crate::Warning {
                loc: a.loc.clone(),
                message: format!("unknown attribute '{}' on <{}> ignored", a.name, e.tag),
            });
        }
    }
}

/// Parse the children of a `<transform>`, each left-multiplied onto the accumulated matrix.
pub fn parse_transform(e: &Elem, warnings: &mut Vec<crate::Warning>) -> Result<Mat4> {
    let mut m = Mat4::IDENTITY;
    for op in &e.children {
        let t = match op.tag.as_str() {
            "translate" => {
                check_attrs(op, &["x", "y", "z", "value"], warnings);
                Mat4::from_translation(parse_xyz(op, 0.0)?)
            }
            "scale" => {
                check_attrs(op, &["x", "y", "z", "value"], warnings);
                Mat4::from_scale(parse_xyz(op, 1.0)?)
            }
            "rotate" => {
                check_attrs(op, &["x", "y", "z", "value", "angle"], warnings);
                let axis = parse_xyz(op, 0.0)?;
                let a = op
                    .attr("angle")
                    .ok_or_else(|| err(&op.loc, "<rotate> needs an 'angle' attribute (degrees)"))?;
                let angle = parse_float(&a.value, &a.loc)?;
                let axis = axis.normalize_or_zero();
                if axis == Vec3::ZERO {
                    return Err(err(&op.loc, "<rotate> needs a non-zero axis (x, y, z)"));
                }
                Mat4::from_axis_angle(axis, (angle as f32).to_radians())
            }
            "matrix" => {
                check_attrs(op, &["value"], warnings);
                let a = op
                    .attr("value")
                    .ok_or_else(|| err(&op.loc, "<matrix> needs a 'value' attribute"))?;
                let v = parse_floats(&a.value, &a.loc)?;
                let v: Vec<f32> = v.iter().map(|&x| x as f32).collect();
                match v.len() {
                    16 => Mat4::from_cols_array(&v.try_into().unwrap_or([0.0; 16])).transpose(),
                    9 => {
                        let mut m4 = Mat4::IDENTITY;
                        for r in 0..3 {
                            for c in 0..3 {
                                m4.col_mut(c)[r] = v[r * 3 + c];
                            }
                        }
                        m4
                    }
                    n => {
                        return Err(err(
                            &a.loc,
                            format!("<matrix> expects 16 (or 9) numbers, found {n}"),
                        ));
                    }
                }
            }
            "lookat" | "lookAt" => {
                check_attrs(op, &["origin", "target", "up"], warnings);
                let origin = parse_vec_attr(op, "origin")?;
                let target = parse_vec_attr(op, "target")?;
                let up = if op.attr("up").is_some() {
                    parse_vec_attr(op, "up")?
                } else {
                    Vec3::ZERO
                };
                look_at(origin, target, up).ok_or_else(|| {
                    err(
                        &op.loc,
                        "invalid <lookat>: origin equals target, or 'up' is parallel to the \
                         viewing direction",
                    )
                })?
            }
            other => {
                return Err(err(
                    &op.loc,
                    format!(
                        "unknown transform operation <{other}> (expected translate, rotate, \
                         scale, matrix or lookat)"
                    ),
                ));
            }
        };
        m = t * m;
    }
    if !m.is_finite() {
        return Err(err(&e.loc, "transform is not finite"));
    }
    Ok(m)
}

/// Parse a property element (`<float name=.. value=..>` and friends). `None` when `e` is not a
/// property tag.
pub fn parse_property(e: &Elem, warnings: &mut Vec<crate::Warning>) -> Result<Option<Prop>> {
    fn simple(e: &Elem) -> Result<((), &super::tree::Attr)> {
        let value = e
            .attr("value")
            .ok_or_else(|| err(&e.loc, format!("<{}> needs a 'value' attribute", e.tag)))?;
        Ok(((), value))
    }
    let value = match e.tag.as_str() {
        "float" => {
            check_attrs(e, &["name", "value"], warnings);
            let (_, a) = simple(e)?;
            Value::Float(parse_float(&a.value, &a.loc)?)
        }
        "integer" => {
            check_attrs(e, &["name", "value"], warnings);
            let (_, a) = simple(e)?;
            Value::Int(parse_int(&a.value, &a.loc)?)
        }
        "boolean" => {
            check_attrs(e, &["name", "value"], warnings);
            let (_, a) = simple(e)?;
            match a.value.trim().to_ascii_lowercase().as_str() {
                "true" => Value::Bool(true),
                "false" => Value::Bool(false),
                other => {
                    return Err(err(
                        &a.loc,
                        format!("expected 'true' or 'false', found '{other}'"),
                    ));
                }
            }
        }
        "string" => {
            check_attrs(e, &["name", "value"], warnings);
            let (_, a) = simple(e)?;
            Value::Str(a.value.clone())
        }
        "point" | "vector" => {
            check_attrs(e, &["name", "value", "x", "y", "z"], warnings);
            Value::Vector(parse_xyz(e, 0.0)?)
        }
        "rgb" | "color" | "srgb" => {
            check_attrs(e, &["name", "value"], warnings);
            let (_, a) = simple(e)?;
            let v = parse_floats(&a.value, &a.loc)?;
            match v.len() {
                1 => Value::Color(ColorSpec::Rgb(Vec3::splat(v[0] as f32))),
                3 => Value::Color(ColorSpec::Rgb(Vec3::new(
                    v[0] as f32,
                    v[1] as f32,
                    v[2] as f32,
                ))),
                n => {
                    return Err(err(
                        &a.loc,
                        format!("<{}> expects 1 or 3 numbers, found {n}", e.tag),
                    ));
                }
            }
        }
        "spectrum" => {
            check_attrs(e, &["name", "value", "filename", "type"], warnings);
            Value::Color(match e.attr("type") {
                Some(t) => parse_spectrum_plugin(e, t)?,
                None => parse_spectrum(e)?,
            })
        }
        "transform" => {
            check_attrs(e, &["name"], warnings);
            Value::Transform(parse_transform(e, warnings)?)
        }
        _ => return Ok(None),
    };
    let name = e
        .attr("name")
        .ok_or_else(|| err(&e.loc, format!("<{}> needs a 'name' attribute", e.tag)))?;
    Ok(Some(Prop {
        name: snake_case(&name.value),
        value,
        loc: e.loc.clone(),
        used: Cell::new(false),
    }))
}

/// Mitsuba 3's spectrum plugins `<spectrum type="d65|blackbody|uniform|regular|irregular">`
/// with their `<float>` (and, for the lists, `<string>`) parameters (Mitsuba's units:
/// `blackbody` is Planck's spectral radiance in W/(m²·sr·nm), `d65` has unit luminance).
/// `regular` (`wavelength_min`, `wavelength_max`, `values` evenly spaced between them) and
/// `irregular` (`wavelengths`, `values`) are sampled spectra like the inline
/// `wavelength:value` lists: linear in between, zero outside. The RGB conversion tabulates
/// the analytic ones at 1 nm over the visible range ([`ColorSpec::sampled`]) and treats them
/// as any sampled spectrum.
fn parse_spectrum_plugin(e: &Elem, ty: &Attr) -> Result<ColorSpec> {
    let mut params: Vec<(&str, f64, &Loc)> = Vec::new();
    let mut lists: Vec<(&str, Vec<f64>, &Loc)> = Vec::new();
    for c in &e.children {
        let (Some(name), Some(value)) = (c.attr("name"), c.attr("value")) else {
            return Err(err(
                &c.loc,
                "expected <float name=\"...\" value=\"...\"/> inside a spectrum plugin",
            ));
        };
        match c.tag.as_str() {
            "float" | "integer" => {
                params.push((&name.value, parse_float(&value.value, &value.loc)?, &c.loc))
            }
            "string" => lists.push((&name.value, parse_floats(&value.value, &value.loc)?, &c.loc)),
            other => return Err(err(&c.loc, format!("expected <float>, found <{other}>"))),
        }
    }
    let (known, known_lists): (&[&str], &[&str]) = match ty.value.as_str() {
        "d65" => (&["scale"], &[]),
        "blackbody" => (&["temperature", "scale"], &[]),
        "uniform" => (&["value"], &[]),
        "regular" => (&["wavelength_min", "wavelength_max"], &["values"]),
        "irregular" => (&[], &["wavelengths", "values"]),
        other => {
            return Err(err(
                &ty.loc,
                format!(
                    "unknown spectrum type '{other}' (d65, blackbody, uniform, regular, irregular)"
                ),
            ));
        }
    };
    if let Some((n, _, l)) = params.iter().find(|(n, _, _)| !known.contains(n)) {
        return Err(err(
            l,
            format!("unknown parameter '{n}' of spectrum '{}'", ty.value),
        ));
    }
    if let Some((n, _, l)) = lists.iter().find(|(n, _, _)| !known_lists.contains(n)) {
        return Err(err(
            l,
            format!("unknown parameter '{n}' of spectrum '{}'", ty.value),
        ));
    }
    let get = |n: &str| params.iter().find(|p| p.0 == n).map(|p| p.1);
    let list = |n: &str| {
        lists
            .iter()
            .find(|p| p.0 == n)
            .map(|p| p.1.clone())
            .ok_or_else(|| err(&e.loc, format!("a {} spectrum needs '{n}'", ty.value)))
    };
    let scale = get("scale").unwrap_or(1.0);
    match ty.value.as_str() {
        "uniform" => Ok(ColorSpec::Uniform(get("value").unwrap_or(1.0))),
        "regular" => {
            let values = list("values")?;
            let (Some(lo), Some(hi)) = (get("wavelength_min"), get("wavelength_max")) else {
                return Err(err(
                    &e.loc,
                    "a regular spectrum needs 'wavelength_min' and 'wavelength_max'",
                ));
            };
            let n = values.len();
            let wavelengths = (0..n)
                .map(|i| lo + (hi - lo) * i as f64 / (n.max(2) - 1) as f64)
                .collect();
            checked_sampled(wavelengths, values, &e.loc)
        }
        "irregular" => {
            let (wavelengths, values) = (list("wavelengths")?, list("values")?);
            if wavelengths.len() != values.len() {
                return Err(err(
                    &e.loc,
                    format!(
                        "an irregular spectrum needs as many wavelengths as values ({} and {})",
                        wavelengths.len(),
                        values.len()
                    ),
                ));
            }
            checked_sampled(wavelengths, values, &e.loc)
        }
        "d65" => Ok(ColorSpec::D65 { scale }),
        _ => {
            let t = get("temperature")
                .ok_or_else(|| err(&e.loc, "a blackbody spectrum needs a 'temperature'"))?;
            if t <= 0.0 {
                return Err(err(
                    &e.loc,
                    "blackbody temperature must be positive (kelvin)",
                ));
            }
            Ok(ColorSpec::Blackbody {
                temperature: t,
                scale,
            })
        }
    }
}

fn parse_spectrum(e: &Elem) -> Result<ColorSpec> {
    let (wavelengths, values, loc) = match (e.attr("value"), e.attr("filename")) {
        (Some(a), None) => {
            let toks: Vec<&str> = tokens(&a.value).collect();
            if toks.len() == 1 && !toks[0].contains(':') {
                return Ok(ColorSpec::Uniform(parse_float(toks[0], &a.loc)?));
            }
            let mut w = Vec::with_capacity(toks.len());
            let mut v = Vec::with_capacity(toks.len());
            for t in toks {
                let Some((l, r)) = t.split_once(':') else {
                    return Err(err(
                        &a.loc,
                        format!("expected 'wavelength:value' pairs, found '{t}'"),
                    ));
                };
                w.push(parse_float(l, &a.loc)?);
                v.push(parse_float(r, &a.loc)?);
            }
            (w, v, a.loc.clone())
        }
        (None, Some(a)) => {
            let path = super::tree::resolve_file(&a.value, &e.dir, &[])
                .ok_or_else(|| err(&a.loc, format!("spectrum file '{}' not found", a.value)))?;
            let text = super::tree::read_text(&path, &a.loc)?;
            let (mut w, mut v) = (Vec::new(), Vec::new());
            for (i, line) in text.lines().enumerate() {
                let line = line.trim();
                if line.is_empty() || line.starts_with('#') {
                    continue;
                }
                let lloc = Loc::new(&std::sync::Arc::new(path.clone()), i as u32 + 1, 1);
                let nums = parse_floats(line, &lloc)?;
                if nums.len() != 2 {
                    return Err(err(&lloc, "expected 'wavelength value' on each line"));
                }
                w.push(nums[0]);
                v.push(nums[1]);
            }
            (w, v, a.loc.clone())
        }
        _ => {
            return Err(err(
                &e.loc,
                "<spectrum> needs exactly one of 'value' or 'filename'",
            ));
        }
    };
    checked_sampled(wavelengths, values, &loc)
}

/// A sampled spectrum after the checks Mitsuba makes: two nodes or more, wavelengths
/// strictly increasing.
fn checked_sampled(wavelengths: Vec<f64>, values: Vec<f64>, loc: &Loc) -> Result<ColorSpec> {
    if wavelengths.len() < 2 {
        return Err(err(
            loc,
            "a sampled spectrum needs at least two wavelength:value pairs",
        ));
    }
    if wavelengths.windows(2).any(|w| w[1] <= w[0]) {
        return Err(err(loc, "spectrum wavelengths must be strictly increasing"));
    }
    Ok(ColorSpec::Sampled(wavelengths, values))
}

/// The properties of one plugin element, with use tracking.
pub struct Props {
    pub props: Vec<Prop>,
}

impl Props {
    pub fn get(&self, name: &str) -> Option<&Prop> {
        let p = self.props.iter().rev().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }
    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name)
    }
    fn wrong(p: &Prop, expected: &str) -> crate::LoadError {
        err(
            &p.loc,
            format!(
                "parameter '{}' should be {expected}, found {}",
                p.name,
                p.value.type_name()
            ),
        )
    }
    pub fn float_opt(&self, name: &str) -> Result<Option<f32>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Float(v) => Ok(Some(v as f32)),
                Value::Int(v) => Ok(Some(v as f32)),
                _ => Err(Self::wrong(p, "a float")),
            },
        }
    }
    pub fn float(&self, name: &str, default: f32) -> Result<f32> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }
    pub fn int_opt(&self, name: &str) -> Result<Option<(i64, Loc)>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Int(v) => Ok(Some((v, p.loc.clone()))),
                _ => Err(Self::wrong(p, "an integer")),
            },
        }
    }
    /// An integer in `[min, max]`.
    pub fn int_in(&self, name: &str, default: i64, min: i64, max: i64) -> Result<i64> {
        match self.int_opt(name)? {
            None => Ok(default),
            Some((v, loc)) if (min..=max).contains(&v) => {
                let _ = loc;
                Ok(v)
            }
            Some((v, loc)) => Err(err(
                &loc,
                format!("parameter '{name}' = {v} is out of range (expected {min}..={max})"),
            )),
        }
    }
    pub fn bool(&self, name: &str, default: bool) -> Result<bool> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Bool(v) => Ok(v),
                _ => Err(Self::wrong(p, "a boolean")),
            },
        }
    }
    pub fn string_opt(&self, name: &str) -> Result<Option<(&str, &Loc)>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::Str(s) => Ok(Some((s.as_str(), &p.loc))),
                _ => Err(Self::wrong(p, "a string")),
            },
        }
    }
    pub fn vector_opt(&self, name: &str) -> Result<Option<Vec3>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Vector(v) => Ok(Some(v)),
                _ => Err(Self::wrong(p, "a point or vector")),
            },
        }
    }
    pub fn transform(&self, name: &str) -> Result<Option<Mat4>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Transform(m) => Ok(Some(m)),
                _ => Err(Self::wrong(p, "a <transform>")),
            },
        }
    }
    /// Unused parameters (name, location).
    pub fn unused(&self) -> impl Iterator<Item = &Prop> {
        self.props.iter().filter(|p| !p.used.get())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_to_snake() {
        assert_eq!(snake_case("toWorld"), "to_world");
        assert_eq!(snake_case("intIOR"), "int_ior");
        assert_eq!(snake_case("sampleCount"), "sample_count");
        assert_eq!(snake_case("cropOffsetX"), "crop_offset_x");
        assert_eq!(snake_case("max_depth"), "max_depth");
        assert_eq!(snake_case("fovAxis"), "fov_axis");
    }

    #[test]
    fn numbers() {
        let l = Loc::default();
        assert_eq!(parse_float(" 1.5 ", &l).unwrap(), 1.5);
        assert!(parse_float("nan", &l).is_err());
        assert!(parse_float("inf", &l).is_err());
        assert!(parse_float("1e39", &l).is_err());
        assert!(parse_int("1.5", &l).is_err());
        assert!(
            parse_int("99999999999999999999", &l)
                .unwrap_err()
                .message
                .contains("range")
        );
        assert_eq!(
            tokens("1, 2 ,3\n4").collect::<Vec<_>>(),
            ["1", "2", "3", "4"]
        );
    }
}
