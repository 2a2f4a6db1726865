//! Parameter lists (`"type name" value`): their types, typed access with pbrt-v4's defaults,
//! and the record of which were used, so that the loader can report the ones it ignored.

use std::cell::Cell;

use crate::{LoadError, Loc, Result};

/// The values of one parameter, as written.
#[derive(Clone, Debug)]
pub enum Vals {
    Nums(Vec<f64>),
    Strs(Vec<String>),
    Bools(Vec<bool>),
}

impl Vals {
    pub fn len(&self) -> usize {
        match self {
            Vals::Nums(v) => v.len(),
            Vals::Strs(v) => v.len(),
            Vals::Bools(v) => v.len(),
        }
    }
}

/// Parameter types (pbrt-v4's names; `point`, `vector`, `normal` and `color` are spellings of
/// `point3`, `vector3`, `normal3` and `rgb`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ty {
    Integer,
    Float,
    Point2,
    Vector2,
    Point3,
    Vector3,
    Normal,
    Bool,
    Str,
    Rgb,
    Spectrum,
    Blackbody,
    Texture,
}

impl Ty {
    /// The type of a declaration word, and whether it was pbrt-v3's `color`.
    pub fn parse(s: &str) -> Option<(Ty, bool)> {
        Some(match s {
            "integer" => (Ty::Integer, false),
            "float" => (Ty::Float, false),
            "point2" => (Ty::Point2, false),
            "vector2" => (Ty::Vector2, false),
            "point3" | "point" => (Ty::Point3, false),
            "vector3" | "vector" => (Ty::Vector3, false),
            "normal" | "normal3" => (Ty::Normal, false),
            "bool" => (Ty::Bool, false),
            "string" => (Ty::Str, false),
            "rgb" => (Ty::Rgb, false),
            "color" => (Ty::Rgb, true),
            "spectrum" => (Ty::Spectrum, false),
            "blackbody" => (Ty::Blackbody, false),
            "texture" => (Ty::Texture, false),
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            Ty::Integer => "integer",
            Ty::Float => "float",
            Ty::Point2 => "point2",
            Ty::Vector2 => "vector2",
            Ty::Point3 => "point3",
            Ty::Vector3 => "vector3",
            Ty::Normal => "normal",
            Ty::Bool => "bool",
            Ty::Str => "string",
            Ty::Rgb => "rgb",
            Ty::Spectrum => "spectrum",
            Ty::Blackbody => "blackbody",
            Ty::Texture => "texture",
        }
    }

    /// Values per element (3 for points, 2 for point2...), for the count check.
    fn arity(self) -> usize {
        match self {
            Ty::Point2 | Ty::Vector2 => 2,
            Ty::Point3 | Ty::Vector3 | Ty::Normal | Ty::Rgb => 3,
            _ => 1,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Param {
    pub ty: Ty,
    pub name: String,
    pub vals: Vals,
    pub loc: Loc,
    pub used: Cell<bool>,
}

impl Param {
    /// Check that the values suit the type (kind and count).
    pub fn new(ty: Ty, name: String, vals: Vals, loc: Loc) -> Result<Param> {
        let what = |m: &str| {
            LoadError::new(
                loc.clone(),
                format!("parameter '{} {name}': {m}", ty.name()),
            )
        };
        match (&vals, ty) {
            (Vals::Nums(v), Ty::Integer) => {
                if let Some(x) = v
                    .iter()
                    .find(|x| x.fract() != 0.0 || x.abs() > i32::MAX as f64)
                {
                    return Err(what(&format!("'{x}' is not an integer")));
                }
            }
            (
                Vals::Nums(v),
                Ty::Float
                | Ty::Point2
                | Ty::Vector2
                | Ty::Point3
                | Ty::Vector3
                | Ty::Normal
                | Ty::Rgb,
            ) => {
                if v.len() % ty.arity() != 0 {
                    return Err(what(&format!(
                        "{} values are not a whole number of {}-tuples",
                        v.len(),
                        ty.arity()
                    )));
                }
            }
            (Vals::Nums(v), Ty::Spectrum) => {
                if v.len() < 4 || v.len() % 2 != 0 {
                    return Err(what(
                        "a tabulated spectrum needs pairs of wavelength and value (two pairs or \
                         more)",
                    ));
                }
            }
            (Vals::Strs(v), Ty::Spectrum) if v.len() == 1 => {}
            (Vals::Nums(v), Ty::Blackbody) => {
                if v.is_empty() || v.len() > 2 {
                    return Err(what("expected a temperature in kelvin"));
                }
            }
            (Vals::Strs(_), Ty::Str | Ty::Texture) | (Vals::Bools(_), Ty::Bool) => {}
            (Vals::Strs(v), Ty::Bool) => {
                // pbrt accepts quoted "true" / "false".
                if v.iter().any(|s| s != "true" && s != "false") {
                    return Err(what("expected true or false"));
                }
                let b = v.iter().map(|s| s == "true").collect();
                return Ok(Param {
                    ty,
                    name,
                    vals: Vals::Bools(b),
                    loc,
                    used: Cell::new(false),
                });
            }
            (Vals::Nums(_), _) => return Err(what("expected strings, found numbers")),
            (Vals::Strs(_), _) => return Err(what("expected numbers, found strings")),
            (Vals::Bools(_), _) => return Err(what("expected numbers, found true/false")),
        }
        if vals.len() == 0 {
            return Err(what("no values"));
        }
        Ok(Param {
            ty,
            name,
            vals,
            loc,
            used: Cell::new(false),
        })
    }

    pub fn nums(&self) -> &[f64] {
        match &self.vals {
            Vals::Nums(v) => v,
            _ => &[],
        }
    }

    pub fn strs(&self) -> &[String] {
        match &self.vals {
            Vals::Strs(v) => v,
            _ => &[],
        }
    }

    pub fn err(&self, m: impl std::fmt::Display) -> LoadError {
        LoadError::new(
            self.loc.clone(),
            format!("parameter '{} {}': {m}", self.ty.name(), self.name),
        )
    }
}

/// A directive's parameters, after the `Attribute` defaults of its kind.
#[derive(Clone, Debug, Default)]
pub struct Params {
    pub list: Vec<Param>,
    /// Where the directive is (for errors about missing parameters).
    pub loc: Loc,
}

impl Params {
    /// The parameter called `name`, marked used; an error when its type is none of `tys`.
    pub fn get(&self, name: &str, tys: &[Ty]) -> Result<Option<&Param>> {
        // A later declaration of the same name wins (the directive's own over Attribute's);
        // the earlier ones count as used too, so they are not reported as ignored.
        for p in self.list.iter().filter(|p| p.name == name) {
            p.used.set(true);
        }
        let Some(p) = self.list.iter().rev().find(|p| p.name == name) else {
            return Ok(None);
        };
        if !tys.contains(&p.ty) {
            let want: Vec<&str> = tys.iter().map(|t| t.name()).collect();
            return Err(p.err(format!("wrong type: expected {}", want.join(" or "))));
        }
        Ok(Some(p))
    }

    pub fn has(&self, name: &str) -> bool {
        self.list.iter().any(|p| p.name == name)
    }

    fn one(&self, name: &str, ty: Ty) -> Result<Option<(&Param, f64)>> {
        let Some(p) = self.get(name, &[ty])? else {
            return Ok(None);
        };
        match p.nums() {
            [v] => Ok(Some((p, *v))),
            v => Err(p.err(format!("expected one value, found {}", v.len()))),
        }
    }

    pub fn float(&self, name: &str, default: f32) -> Result<f32> {
        Ok(self
            .one(name, Ty::Float)?
            .map_or(default, |(_, v)| v as f32))
    }

    pub fn float_opt(&self, name: &str) -> Result<Option<f32>> {
        Ok(self.one(name, Ty::Float)?.map(|(_, v)| v as f32))
    }

    pub fn int(&self, name: &str, default: i64) -> Result<i64> {
        Ok(self
            .one(name, Ty::Integer)?
            .map_or(default, |(_, v)| v as i64))
    }

    /// An integer within [lo, hi].
    pub fn int_in(&self, name: &str, default: i64, lo: i64, hi: i64) -> Result<i64> {
        match self.one(name, Ty::Integer)? {
            None => Ok(default),
            Some((p, v)) => {
                let v = v as i64;
                if v < lo || v > hi {
                    return Err(p.err(format!("{v} is outside [{lo}, {hi}]")));
                }
                Ok(v)
            }
        }
    }

    pub fn bool(&self, name: &str, default: bool) -> Result<bool> {
        let Some(p) = self.get(name, &[Ty::Bool])? else {
            return Ok(default);
        };
        match &p.vals {
            Vals::Bools(b) if b.len() == 1 => Ok(b[0]),
            v => Err(p.err(format!("expected one value, found {}", v.len()))),
        }
    }

    pub fn string_opt(&self, name: &str) -> Result<Option<(&str, &Param)>> {
        let Some(p) = self.get(name, &[Ty::Str])? else {
            return Ok(None);
        };
        match p.strs() {
            [s] => Ok(Some((s.as_str(), p))),
            v => Err(p.err(format!("expected one string, found {}", v.len()))),
        }
    }

    pub fn string<'a>(&'a self, name: &str, default: &'a str) -> Result<&'a str> {
        Ok(self.string_opt(name)?.map_or(default, |(s, _)| s))
    }

    /// A list of numbers of type `ty` (empty when absent).
    pub fn nums(&self, name: &str, ty: Ty) -> Result<Option<&Param>> {
        self.get(name, &[ty])
    }

    /// A point3 / vector3 / normal given once, or the default.
    pub fn vec3(&self, name: &str, ty: Ty, default: [f32; 3]) -> Result<[f32; 3]> {
        let Some(p) = self.get(name, &[ty])? else {
            return Ok(default);
        };
        match p.nums() {
            [a, b, c] => Ok([*a as f32, *b as f32, *c as f32]),
            v => Err(p.err(format!("expected 3 values, found {}", v.len()))),
        }
    }

    /// The parameters nobody asked for.
    pub fn unused(&self) -> impl Iterator<Item = &Param> {
        self.list.iter().filter(|p| !p.used.get())
    }
}
