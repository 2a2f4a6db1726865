//! The editable values of a scene description, by stable name: what Python's
//! `scene.parameters()` lists and `scene.update({...})` sets. Each key says what its edit
//! makes stale ([`Changed`]), which [`crate::BuildCache::invalidate`] is told, so that the
//! next build rebuilds only that (the acceleration structure only when a shape moved).
//!
//! Keys are `<object>.<parameter>`, Mitsuba 3's `traverse()` names without its `.value`
//! suffix. `<object>` is the object's `id` in the scene file; an object without one is
//! named by what holds it (a shape's inline material `<shape>.bsdf`, the material a
//! `twosided` wraps `<twosided>.brdf_0` (and `.brdf_1`), the one a `normalmap`, `bumpmap`
//! or `mask` wraps `<outer>.nested_bsdf`, a `blendbsdf`'s or `mix`'s `<outer>.bsdf_0` and
//! `.bsdf_1`), else by kind and index (`shape_3`, `bsdf_2`, `emitter_0`, `sensor_0`; the
//! index counts objects of that kind in the description, in file order). A shape's area
//! light is `<shape>.emitter`. `<parameter>` is the scene file's parameter name:
//! `reflectance`, `diffuse_reflectance`, `alpha` (sets `alpha_u` and `alpha_v` together),
//! `base_color`, `roughness`, `intensity`, `radiance`, `irradiance`, `scale`, `to_world`...
//! Only constants are listed: a parameter given by a texture or a declared spectrum is not.

use std::collections::HashSet;
use std::ops::ControlFlow;

use render::math::Mat4;
use scene::{ColorParam, ColorValue, Emitter, FloatParam, Material, MaterialId, Rgb, SceneDesc};

use crate::Changed;

/// A parameter's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Float(f32),
    /// An RGB colour, or a point or a direction (a point light's `position`, a directional
    /// light's `direction`).
    Vec3([f32; 3]),
    /// A transform (column-major, as glam's).
    Matrix(Mat4),
}

impl Value {
    /// What kind of value this is, for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Float(_) => "a float",
            Value::Vec3(_) => "a 3-vector (an RGB colour, a point or a direction)",
            Value::Matrix(_) => "a 4x4 matrix",
        }
    }
}

/// One editable parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    pub key: String,
    pub value: Value,
    pub changes: Changed,
}

/// Why a parameter could not be set.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// No editable parameter has this name.
    #[error("no editable parameter '{key}'{hint}")]
    Unknown { key: String, hint: String },
    /// The value is of another kind than the parameter.
    #[error("parameter '{key}' takes {expected}, not {found}")]
    WrongType {
        key: String,
        expected: &'static str,
        found: &'static str,
    },
    /// The value is of the right kind but out of range (not finite, negative roughness).
    #[error("parameter '{key}': {message}")]
    Invalid { key: String, message: String },
}

/// Every editable parameter of `desc`, in a stable order (materials, shapes and their area
/// lights, emitters, sensors; each object's parameters in declaration order).
pub fn parameters(desc: &SceneDesc) -> Vec<Param> {
    // The visitor hands out mutable slots; listing reads them from a copy.
    let mut copy = desc.clone();
    let mut out = Vec::new();
    let _ = visit(&mut copy, &mut |key, slot, changes| {
        if let Some(value) = slot.get() {
            out.push(Param {
                key: key.to_string(),
                value,
                changes,
            });
        }
        ControlFlow::Continue(())
    });
    out
}

/// Set parameter `key` of `desc` to `value`; returns what the edit makes stale. A float
/// given for a colour sets its three channels (as a `<float>` does in a Mitsuba file).
pub fn set(desc: &mut SceneDesc, key: &str, value: Value) -> Result<Changed, ParamError> {
    let mut result = None;
    let _ = visit(desc, &mut |k, slot, changes| {
        if k != key || slot.get().is_none() {
            return ControlFlow::Continue(());
        }
        result = Some(slot.set(key, value).map(|()| changes));
        ControlFlow::Break(())
    });
    result.unwrap_or_else(|| {
        Err(ParamError::Unknown {
            key: key.to_string(),
            hint: match key.rsplit_once('.') {
                Some((object, _)) => format!(
                    " (scene.parameters() lists them; an object's parameters start with \
                     '{object}.', and only constant values can be edited, not textures or \
                     declared spectra)"
                ),
                None => " (keys are '<object>.<parameter>', see scene.parameters())".into(),
            },
        })
    })
}

/// A mutable place in a description that holds an editable value.
enum Slot<'a> {
    Float(&'a mut f32),
    /// A roughness or weight: finite and not negative.
    NonNegative(&'a mut f32),
    FloatParam(&'a mut FloatParam),
    /// `alpha` of a material with `alpha_u` and `alpha_v`: listed when both are the same
    /// constant, and sets both.
    Alpha(&'a mut FloatParam, &'a mut FloatParam),
    Color(&'a mut ColorParam),
    ColorValue(&'a mut ColorValue),
    Rgb(&'a mut Rgb),
    Matrix(&'a mut Mat4),
}

impl Slot<'_> {
    /// The value, when it is a constant.
    fn get(&self) -> Option<Value> {
        let v3 = |c: &Rgb| Value::Vec3(c.to_array());
        match self {
            Slot::Float(f) | Slot::NonNegative(f) => Some(Value::Float(**f)),
            Slot::FloatParam(FloatParam::Const(f)) => Some(Value::Float(*f)),
            Slot::FloatParam(FloatParam::Texture(_)) => None,
            Slot::Alpha(FloatParam::Const(u), FloatParam::Const(v)) if u == v => {
                Some(Value::Float(*u))
            }
            Slot::Alpha(..) => None,
            Slot::Color(ColorParam::Const(c)) => Some(v3(c)),
            Slot::Color(_) => None,
            Slot::ColorValue(ColorValue::Rgb(c)) => Some(v3(c)),
            Slot::ColorValue(ColorValue::Spectrum(_)) => None,
            Slot::Rgb(c) => Some(v3(c)),
            Slot::Matrix(m) => Some(Value::Matrix(**m)),
        }
    }

    fn set(self, key: &str, value: Value) -> Result<(), ParamError> {
        let invalid = |message: &str| ParamError::Invalid {
            key: key.to_string(),
            message: message.to_string(),
        };
        let expected = match &self {
            Slot::Float(_) | Slot::NonNegative(_) | Slot::FloatParam(_) | Slot::Alpha(..) => {
                "a float"
            }
            Slot::Color(_) | Slot::ColorValue(_) | Slot::Rgb(_) => {
                "a float or a 3-vector (an RGB colour, a point or a direction)"
            }
            Slot::Matrix(_) => "a 4x4 matrix",
        };
        let wrong = || ParamError::WrongType {
            key: key.to_string(),
            expected,
            found: value.kind(),
        };
        let float = || match value {
            Value::Float(f) if f.is_finite() => Ok(f),
            Value::Float(_) => Err(invalid("the value must be finite")),
            _ => Err(wrong()),
        };
        let non_negative = || {
            let f = float()?;
            if f >= 0.0 {
                Ok(f)
            } else {
                Err(invalid("the value must not be negative"))
            }
        };
        let rgb = || {
            let c = match value {
                Value::Float(f) => Rgb::splat(f),
                Value::Vec3(c) => Rgb::from_array(c),
                Value::Matrix(_) => return Err(wrong()),
            };
            if c.is_finite() {
                Ok(c)
            } else {
                Err(invalid("every component must be finite"))
            }
        };
        match self {
            Slot::Float(f) => *f = float()?,
            Slot::NonNegative(f) => *f = non_negative()?,
            Slot::FloatParam(p) => *p = FloatParam::Const(float()?),
            Slot::Alpha(u, v) => {
                let a = non_negative()?;
                *u = FloatParam::Const(a);
                *v = FloatParam::Const(a);
            }
            Slot::Color(c) => *c = ColorParam::Const(rgb()?),
            Slot::ColorValue(c) => *c = ColorValue::Rgb(rgb()?),
            Slot::Rgb(c) => *c = rgb()?,
            Slot::Matrix(m) => match value {
                Value::Matrix(x) if x.is_finite() => *m = x,
                Value::Matrix(_) => return Err(invalid("every element must be finite")),
                _ => return Err(wrong()),
            },
        }
        Ok(())
    }
}

type Visitor<'v> = dyn FnMut(&str, Slot<'_>, Changed) -> ControlFlow<()> + 'v;

/// Calls `f` with every editable slot of `desc`, its key and what editing it changes, until
/// `f` breaks.
fn visit(desc: &mut SceneDesc, f: &mut Visitor<'_>) -> ControlFlow<()> {
    let names = Names::new(desc);
    for (i, m) in desc.materials.iter_mut().enumerate() {
        material(&names.materials[i], &mut m.material, f)?;
    }
    for (i, s) in desc.shapes.iter_mut().enumerate() {
        let name = &names.shapes[i];
        f(
            &format!("{name}.to_world"),
            Slot::Matrix(&mut s.to_world),
            Changed::Geometry,
        )?;
        if let Some(e) = &mut s.emission {
            f(
                &format!("{name}.emitter.radiance"),
                Slot::Color(&mut e.radiance),
                Changed::Light,
            )?;
        }
    }
    for (i, e) in desc.emitters.iter_mut().enumerate() {
        emitter(&names.emitters[i], &mut e.emitter, f)?;
    }
    for (i, s) in desc.sensors.iter_mut().enumerate() {
        let name = &names.sensors[i];
        let c = Changed::Camera;
        f(
            &format!("{name}.to_world"),
            Slot::Matrix(&mut s.camera.to_world),
            c,
        )?;
        match &mut s.camera.projection {
            base::Projection::Perspective { fov, .. } | base::Projection::ThinLens { fov, .. } => {
                f(&format!("{name}.fov"), Slot::Float(fov), c)?
            }
            _ => {}
        }
    }
    ControlFlow::Continue(())
}

fn material(name: &str, m: &mut Material, f: &mut Visitor<'_>) -> ControlFlow<()> {
    let c = Changed::Material;
    let mut color = |p: &str, v: &mut ColorParam| f(&format!("{name}.{p}"), Slot::Color(v), c);
    match m {
        Material::Diffuse { reflectance } => color("reflectance", reflectance)?,
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
        } => {
            color("specular_reflectance", specular_reflectance)?;
            f(&format!("{name}.eta"), Slot::ColorValue(eta), c)?;
            f(&format!("{name}.k"), Slot::ColorValue(k), c)?;
        }
        Material::RoughConductor {
            alpha_u,
            alpha_v,
            eta,
            k,
            specular_reflectance,
            ..
        } => {
            color("specular_reflectance", specular_reflectance)?;
            f(&format!("{name}.eta"), Slot::ColorValue(eta), c)?;
            f(&format!("{name}.k"), Slot::ColorValue(k), c)?;
            alphas(name, alpha_u, alpha_v, f)?;
        }
        Material::Dielectric {
            specular_reflectance,
            specular_transmittance,
            ..
        }
        | Material::ThinDielectric {
            specular_reflectance,
            specular_transmittance,
            ..
        } => {
            color("specular_reflectance", specular_reflectance)?;
            color("specular_transmittance", specular_transmittance)?;
        }
        Material::RoughDielectric {
            alpha_u,
            alpha_v,
            specular_reflectance,
            specular_transmittance,
            ..
        } => {
            color("specular_reflectance", specular_reflectance)?;
            color("specular_transmittance", specular_transmittance)?;
            alphas(name, alpha_u, alpha_v, f)?;
        }
        // The boundary's roughness; the medium's coefficients are not editable parameters.
        Material::Subsurface { boundary, .. } => {
            if let Material::RoughDielectric {
                alpha_u, alpha_v, ..
            } = boundary.as_mut()
            {
                alphas(name, alpha_u, alpha_v, f)?;
            }
        }
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            ..
        } => {
            color("diffuse_reflectance", diffuse_reflectance)?;
            color("specular_reflectance", specular_reflectance)?;
        }
        Material::RoughPlastic {
            alpha,
            diffuse_reflectance,
            specular_reflectance,
            ..
        } => {
            color("diffuse_reflectance", diffuse_reflectance)?;
            color("specular_reflectance", specular_reflectance)?;
            f(&format!("{name}.alpha"), Slot::NonNegative(alpha), c)?;
        }
        Material::PolarizedPlastic {
            alpha_u,
            alpha_v,
            diffuse_reflectance,
            specular_reflectance,
            ..
        } => {
            color("diffuse_reflectance", diffuse_reflectance)?;
            color("specular_reflectance", specular_reflectance)?;
            f(&format!("{name}.alpha_u"), Slot::NonNegative(alpha_u), c)?;
            f(&format!("{name}.alpha_v"), Slot::NonNegative(alpha_v), c)?;
        }
        Material::Mirror { reflectance } => color("specular_reflectance", reflectance)?,
        Material::NoriMicrofacet { alpha, kd, .. } => {
            f(&format!("{name}.kd"), Slot::Rgb(kd), c)?;
            f(&format!("{name}.alpha"), Slot::NonNegative(alpha), c)?;
        }
        Material::PhongFamily {
            diffuse,
            specular,
            exponent,
            ..
        } => {
            color("diffuse", diffuse)?;
            color("specular", specular)?;
            f(&format!("{name}.exponent"), Slot::NonNegative(exponent), c)?;
        }
        Material::Unlit { color: col } => color("color", col)?,
        Material::DiffuseTransmission {
            reflectance,
            transmittance,
        } => {
            color("reflectance", reflectance)?;
            color("transmittance", transmittance)?;
        }
        Material::CoatedDiffuse {
            reflectance,
            alpha_u,
            alpha_v,
            albedo,
            ..
        } => {
            color("reflectance", reflectance)?;
            color("albedo", albedo)?;
            alphas(name, alpha_u, alpha_v, f)?;
        }
        Material::CoatedConductor { albedo, .. } => color("albedo", albedo)?,
        Material::Principled(p) => {
            color("base_color", &mut p.base_color)?;
            for (n, v) in [
                ("roughness", &mut p.roughness),
                ("anisotropic", &mut p.anisotropic),
                ("metallic", &mut p.metallic),
                ("spec_trans", &mut p.spec_trans),
                ("spec_tint", &mut p.spec_tint),
                ("sheen", &mut p.sheen),
                ("sheen_tint", &mut p.sheen_tint),
                ("flatness", &mut p.flatness),
                ("clearcoat", &mut p.clearcoat),
                ("clearcoat_gloss", &mut p.clearcoat_gloss),
            ] {
                f(&format!("{name}.{n}"), Slot::FloatParam(v), c)?;
            }
        }
        Material::PrincipledThin(p) => {
            color("base_color", &mut p.base_color)?;
            for (n, v) in [
                ("roughness", &mut p.roughness),
                ("anisotropic", &mut p.anisotropic),
                ("spec_trans", &mut p.spec_trans),
                ("spec_tint", &mut p.spec_tint),
                ("sheen", &mut p.sheen),
                ("sheen_tint", &mut p.sheen_tint),
                ("flatness", &mut p.flatness),
                ("diff_trans", &mut p.diff_trans),
            ] {
                f(&format!("{name}.{n}"), Slot::FloatParam(v), c)?;
            }
        }
        Material::Blend { weight, .. } => {
            f(&format!("{name}.weight"), Slot::FloatParam(weight), c)?
        }
        Material::Mix { amount, .. } => f(&format!("{name}.amount"), Slot::FloatParam(amount), c)?,
        Material::TwoSided { .. }
        | Material::NormalMap { .. }
        | Material::Mask { .. }
        | Material::BumpMap { .. }
        | Material::HeightBump { .. }
        | Material::Null => {}
    }
    ControlFlow::Continue(())
}

/// `alpha` (both, when they are the same constant), `alpha_u` and `alpha_v`.
fn alphas(
    name: &str,
    u: &mut FloatParam,
    v: &mut FloatParam,
    f: &mut Visitor<'_>,
) -> ControlFlow<()> {
    let c = Changed::Material;
    f(&format!("{name}.alpha"), Slot::Alpha(u, v), c)?;
    f(&format!("{name}.alpha_u"), Slot::FloatParam(u), c)?;
    f(&format!("{name}.alpha_v"), Slot::FloatParam(v), c)
}

fn emitter(name: &str, e: &mut Emitter, f: &mut Visitor<'_>) -> ControlFlow<()> {
    let c = Changed::Light;
    let key = |p: &str| format!("{name}.{p}");
    match e {
        Emitter::Point {
            position,
            intensity,
        } => {
            f(&key("intensity"), Slot::ColorValue(intensity), c)?;
            f(&key("position"), Slot::Rgb(position), c)?;
        }
        Emitter::Spot {
            to_world,
            intensity,
            cutoff_angle,
            beam_width,
            ..
        } => {
            f(&key("intensity"), Slot::ColorValue(intensity), c)?;
            f(&key("cutoff_angle"), Slot::Float(cutoff_angle), c)?;
            f(&key("beam_width"), Slot::Float(beam_width), c)?;
            f(&key("to_world"), Slot::Matrix(to_world), c)?;
        }
        Emitter::Directional {
            direction,
            irradiance,
        } => {
            f(&key("irradiance"), Slot::ColorValue(irradiance), c)?;
            f(&key("direction"), Slot::Rgb(direction), c)?;
        }
        Emitter::Constant { radiance } => f(&key("radiance"), Slot::ColorValue(radiance), c)?,
        Emitter::Projector {
            to_world,
            irradiance,
            scale,
            ..
        } => {
            f(&key("irradiance"), Slot::Color(irradiance), c)?;
            f(&key("scale"), Slot::Float(scale), c)?;
            f(&key("to_world"), Slot::Matrix(to_world), c)?;
        }
        Emitter::Ambient { radiance } => f(&key("radiance"), Slot::Rgb(radiance), c)?,
        Emitter::ImagePoint {
            to_world,
            intensity,
            ..
        } => {
            f(&key("intensity"), Slot::Rgb(intensity), c)?;
            f(&key("to_world"), Slot::Matrix(to_world), c)?;
        }
        Emitter::SunSky(s) => {
            f(&key("turbidity"), Slot::Float(&mut s.turbidity), c)?;
            f(&key("sun_scale"), Slot::Float(&mut s.sun_scale), c)?;
            f(&key("sky_scale"), Slot::Float(&mut s.sky_scale), c)?;
            f(&key("albedo"), Slot::Rgb(&mut s.albedo), c)?;
        }
        Emitter::EnvMap {
            scale, to_world, ..
        } => {
            f(&key("scale"), Slot::Float(scale), c)?;
            f(&key("to_world"), Slot::Matrix(to_world), c)?;
        }
    }
    ControlFlow::Continue(())
}

/// The name of every object of a description (see the module documentation), unique.
struct Names {
    materials: Vec<String>,
    shapes: Vec<String>,
    emitters: Vec<String>,
    sensors: Vec<String>,
}

impl Names {
    fn new(desc: &SceneDesc) -> Names {
        let mut used = HashSet::new();
        // The first object to claim a name keeps it; a later one is told apart by its index.
        let mut claim = |name: String, kind: &str, i: usize| {
            if used.insert(name.clone()) {
                name
            } else {
                let other = format!("{name}#{kind}_{i}");
                used.insert(other.clone());
                other
            }
        };
        let shapes: Vec<String> = desc
            .shapes
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let n = s.name.clone().unwrap_or_else(|| format!("shape_{i}"));
                claim(n, "shape", i)
            })
            .collect();
        let emitters = desc
            .emitters
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let n = e.name.clone().unwrap_or_else(|| format!("emitter_{i}"));
                claim(n, "emitter", i)
            })
            .collect();
        let sensors = desc
            .sensors
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let n = s.name.clone().unwrap_or_else(|| format!("sensor_{i}"));
                claim(n, "sensor", i)
            })
            .collect();
        // Materials: their ids; then the unnamed ones a shape holds; then the unnamed ones
        // a named wrapper holds, down the chains; then by index.
        let n = desc.materials.len();
        let mut names: Vec<Option<String>> =
            desc.materials.iter().map(|m| m.name.clone()).collect();
        for (s, shape) in desc.shapes.iter().zip(&shapes) {
            if let Some(MaterialId(m)) = s.material
                && let Some(slot @ None) = names.get_mut(m as usize)
            {
                *slot = Some(format!("{shape}.bsdf"));
            }
        }
        // Each pass names the children of named materials; chains are at most n long.
        for _ in 0..n {
            let mut changed = false;
            for i in 0..n {
                let Some(outer) = names[i].clone() else {
                    continue;
                };
                for (child, slot) in children(&desc.materials[i].material) {
                    if let Some(c @ None) = names.get_mut(child.0 as usize) {
                        *c = Some(format!("{outer}.{slot}"));
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        let materials = names
            .into_iter()
            .enumerate()
            .map(|(i, m)| claim(m.unwrap_or_else(|| format!("bsdf_{i}")), "bsdf", i))
            .collect();
        Names {
            materials,
            shapes,
            emitters,
            sensors,
        }
    }
}

/// The materials a material wraps, with Mitsuba 3's names of their slots.
fn children(m: &Material) -> Vec<(MaterialId, &'static str)> {
    match m {
        Material::TwoSided { front, back } => {
            let mut v = vec![(*front, "brdf_0")];
            v.extend(back.map(|b| (b, "brdf_1")));
            v
        }
        Material::NormalMap { nested, .. }
        | Material::Mask { nested, .. }
        | Material::BumpMap { nested, .. }
        | Material::HeightBump { nested, .. } => vec![(*nested, "nested_bsdf")],
        Material::Blend { materials, .. } | Material::Mix { materials, .. } => {
            vec![(materials[0], "bsdf_0"), (materials[1], "bsdf_1")]
        }
        _ => Vec::new(),
    }
}
