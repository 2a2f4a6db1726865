//! Stage 3: plugins → the scene model. Defaults are Mitsuba 3's for Mitsuba tags (`sensor`,
//! `shape`...) and Nori's for Nori tags (`camera`, `mesh`) and Nori-only plugins.

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;
use std::sync::Arc;

use glam::{Mat3, Mat4, Vec3};

mod emitters;
mod legacy;
mod principled;

use super::ior;
use super::plugin::{Child, Plugin};
use super::props::{ColorSpec, Value, parse_floats};
use super::tree::{Elem, Source, err, resolve_file};
use crate::model::*;
use crate::spectra::{self, SpectrumUse};
use crate::{LoadError, Loc, Result, Warning};
use base::dispersion::Dispersion;

/// Largest accepted film side and pixel count (a bigger film would not fit in memory).
const MAX_FILM_SIDE: i64 = 1 << 16;
const MAX_FILM_PIXELS: i64 = 1 << 28;

/// Which renderer's conventions a file follows (decides defaults that differ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dialect {
    /// Mitsuba 2/3 (`<scene version="2.x/3.x">`).
    Mitsuba3,
    /// Mitsuba 0.x or Nori (no version, or version 0.x).
    Legacy,
}

/// State shared by every scene of one document.
pub struct Ctx<'s> {
    pub src: &'s Source,
    pub ids: HashMap<String, &'s Elem>,
    pub main_file: PathBuf,
    pub dialect: Dialect,
    meshes: HashMap<PathBuf, Arc<TriMesh>>,
    warned: HashSet<(String, String, String)>,
    pub warnings: Vec<Warning>,
}

impl<'s> Ctx<'s> {
    pub fn new(src: &'s Source, main_file: PathBuf, dialect: Dialect) -> Result<Self> {
        let mut ids = HashMap::new();
        collect_ids(&src.root, &mut ids)?;
        Ok(Ctx {
            src,
            ids,
            main_file,
            dialect,
            meshes: HashMap::new(),
            warned: HashSet::new(),
            warnings: src.warnings.clone(),
        })
    }

    pub fn plugin(&mut self, elem: &'s Elem) -> Result<Plugin<'s>> {
        Plugin::new(elem, &self.ids, &mut self.warnings)
    }

    pub fn warn(&mut self, loc: &Loc, message: impl Into<String>) {
        self.warnings.push(Warning {
            loc: loc.clone(),
            message: message.into(),
        });
    }

    /// Warn (once per tag, type and name) about parameters the plugin did not use.
    pub fn finish(&mut self, pl: &Plugin<'_>) {
        for p in pl.props.unused() {
            let key = (pl.elem.tag.clone(), pl.ty.clone(), p.name.clone());
            if self.warned.insert(key) {
                let what = if pl.ty.is_empty() {
                    format!("<{}>", pl.elem.tag)
                } else {
                    format!("{} '{}'", pl.elem.tag, pl.ty)
                };
                self.warnings.push(Warning {
                    loc: p.loc.clone(),
                    message: format!("unknown parameter '{}' of {what} ignored", p.name),
                });
            }
        }
    }

    fn resolve(&self, name: &str, elem: &Elem) -> Option<PathBuf> {
        resolve_file(name, &elem.dir, &self.src.search_dirs)
    }

    /// A file parameter (`filename`), resolved and checked to exist.
    fn file_param(&self, pl: &Plugin<'_>, what: &str) -> Result<PathBuf> {
        let (name, loc) = pl.props.string_opt("filename")?.ok_or_else(|| {
            err(
                pl.loc(),
                format!("{what} needs a 'filename' string parameter"),
            )
        })?;
        self.resolve(name, pl.elem).ok_or_else(|| {
            let mut dirs: Vec<String> = Vec::new();
            for d in std::iter::once(pl.elem.dir.as_path())
                .chain(self.src.search_dirs.iter().map(PathBuf::as_path))
            {
                let d = d.display().to_string();
                if !dirs.contains(&d) {
                    dirs.push(d);
                }
            }
            err(
                loc,
                format!(
                    "{what} file '{name}' not found (looked in {})",
                    dirs.join(", ")
                ),
            )
        })
    }

    fn mesh(&mut self, path: PathBuf, ty: &str) -> Result<Arc<TriMesh>> {
        if let Some(m) = self.meshes.get(&path) {
            return Ok(m.clone());
        }
        let mesh = match ty {
            "ply" => crate::formats::ply::read_ply(&path)?,
            _ => crate::formats::obj::read_obj(&path)?,
        };
        let mesh = Arc::new(mesh);
        self.meshes.insert(path, mesh.clone());
        Ok(mesh)
    }
}

fn collect_ids<'s>(e: &'s Elem, ids: &mut HashMap<String, &'s Elem>) -> Result<()> {
    for c in &e.children {
        if c.tag != "ref"
            && let Some(a) = c.attr("id")
            && ids.insert(a.value.clone(), c).is_some()
        {
            return Err(err(&a.loc, format!("duplicate id '{}'", a.value)));
        }
        collect_ids(c, ids)?;
    }
    Ok(())
}

fn unknown_type(pl: &Plugin<'_>, expected: &str) -> LoadError {
    err(
        pl.loc(),
        format!(
            "unknown {} type '{}' (supported: {expected})",
            pl.elem.tag, pl.ty
        ),
    )
}

/// Turn a 4×4 `to_uv` transform into the 2D homogeneous matrix Mitsuba uses (rows and
/// columns 0, 1, 3).
fn extract_uv(m: Mat4) -> Mat3 {
    let pick = |c: usize| Vec3::new(m.col(c)[0], m.col(c)[1], m.col(c)[3]);
    Mat3::from_cols(pick(0), pick(1), pick(3))
}

fn spec_to_rgb(spec: &ColorSpec, usage: SpectrumUse, loc: &Loc) -> Result<Rgb> {
    match spec {
        ColorSpec::Rgb(v) => Ok(*v),
        ColorSpec::Uniform(v) => Ok(spectra::uniform_to_rgb(*v, usage)),
        ColorSpec::Sampled(w, v) => {
            spectra::sampled_to_rgb(w, v, usage).map_err(|e| err(loc, e.to_string()))
        }
        ColorSpec::Blackbody { .. } | ColorSpec::D65 { .. } => {
            let (w, v) = spec.sampled().expect("a plugin spectrum tabulates");
            spectra::sampled_to_rgb(&w, &v, usage).map_err(|e| err(loc, e.to_string()))
        }
    }
}

/// A colour value as declared: RGB as given, a spectrum with the RGB `spec_to_rgb` makes of
/// it for RGB mode beside its declaration for spectral mode.
fn spec_to_value(spec: &ColorSpec, usage: SpectrumUse, loc: &Loc) -> Result<ColorValue> {
    let rgb = spec_to_rgb(spec, usage, loc)?;
    let (kind, scale) = match spec {
        ColorSpec::Rgb(_) => return Ok(ColorValue::Rgb(rgb)),
        ColorSpec::Uniform(v) => (SpectrumKind::Uniform(*v), 1.0),
        ColorSpec::Sampled(w, v) => (
            SpectrumKind::Tabulated {
                wavelengths: w.clone(),
                values: v.clone(),
            },
            1.0,
        ),
        ColorSpec::Blackbody { temperature, scale } => (
            SpectrumKind::Blackbody {
                temperature: *temperature,
            },
            *scale,
        ),
        ColorSpec::D65 { scale } => (SpectrumKind::D65, *scale),
    };
    Ok(ColorValue::Spectrum(Arc::new(SpectrumDesc {
        rgb,
        kind,
        scale,
    })))
}

fn usage_for(name: &str, emitter: bool) -> SpectrumUse {
    if emitter {
        SpectrumUse::Emission
    } else if matches!(
        name,
        "eta" | "k" | "int_ior" | "ext_ior" | "sigma_t" | "sigma_a" | "sigma_s"
    ) {
        SpectrumUse::Unbounded
    } else {
        SpectrumUse::Reflectance
    }
}

/// A grid file's format by its extension: OpenVDB (`.vdb`, with the plugin's `grid_name`,
/// default `density`) or Mitsuba's `.vol`.
/// The format of a grid file; `own_map` as [`VolumeFormat::Vdb`] says.
fn grid_format(pl: &Plugin<'_>, path: &std::path::Path, own_map: bool) -> Result<VolumeFormat> {
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vdb"))
    {
        return Ok(VolumeFormat::MitsubaVol);
    }
    let name = pl
        .props
        .string_opt("grid_name")?
        .map_or("density", |(n, _)| n)
        .to_string();
    Ok(VolumeFormat::Vdb {
        grid_name: name,
        own_map,
    })
}

/// Builds one `SceneDesc` (a document holds one, or several for Nori t-tests).
pub struct SceneBuilder<'c, 's> {
    pub ctx: &'c mut Ctx<'s>,
    pub scene: SceneDesc,
    materials: HashMap<String, MaterialId>,
    textures: HashMap<String, TextureId>,
    media: HashMap<String, MediumId>,
    /// A sampler given at scene level (Nori), applied to every sensor without its own.
    top_sampler: Option<SamplerDesc>,
    sensor_has_sampler: Vec<bool>,
    has_integrator: bool,
    /// The shapes of each `shapegroup` met so far (by element), in the group's space.
    groups: HashMap<*const Elem, Vec<ShapeDesc>>,
    /// Inside a `shapegroup`: nested groups and instances are refused, as in Mitsuba 3.
    in_group: bool,
}

impl<'c, 's> SceneBuilder<'c, 's> {
    pub fn new(ctx: &'c mut Ctx<'s>) -> Self {
        let source = ctx.main_file.clone();
        SceneBuilder {
            ctx,
            scene: SceneDesc {
                source,
                ..Default::default()
            },
            materials: HashMap::new(),
            textures: HashMap::new(),
            media: HashMap::new(),
            top_sampler: None,
            sensor_has_sampler: Vec::new(),
            has_integrator: false,
            groups: HashMap::new(),
            in_group: false,
        }
    }

    // -----------------------------------------------------------------------------------------
    // Parameters

    /// A colour parameter: a texture child, an `<rgb>`/`<spectrum>`/`<float>`, or `default`.
    fn color(
        &mut self,
        pl: &Plugin<'s>,
        name: &str,
        default: f32,
        emitter: bool,
    ) -> Result<ColorParam> {
        Ok(self
            .color_opt(pl, name, emitter)?
            .unwrap_or(ColorParam::constant(default)))
    }

    fn color_opt(
        &mut self,
        pl: &Plugin<'s>,
        name: &str,
        emitter: bool,
    ) -> Result<Option<ColorParam>> {
        if let Some(c) = pl.named_child(name) {
            if c.elem.tag != "texture" {
                return Err(err(
                    &c.loc,
                    format!(
                        "parameter '{name}' expects a texture, found <{}>",
                        c.elem.tag
                    ),
                ));
            }
            return Ok(Some(ColorParam::Texture(self.texture(c)?)));
        }
        let Some(p) = pl.props.get(name) else {
            return Ok(None);
        };
        let usage = usage_for(name, emitter);
        let value = match &p.value {
            Value::Color(spec) => match self.legacy_color(spec) {
                Some(v) => v,
                None => spec_to_value(spec, usage, &p.loc)?,
            },
            Value::Float(v) => ColorValue::Rgb(Vec3::splat(*v as f32)),
            Value::Int(v) => ColorValue::Rgb(Vec3::splat(*v as f32)),
            other => {
                return Err(err(
                    &p.loc,
                    format!(
                        "parameter '{name}' should be a colour (rgb, spectrum, float or \
                         texture), found {other:?}"
                    ),
                ));
            }
        };
        Ok(Some(value.into()))
    }

    /// A constant colour (no textures allowed) as RGB, declared spectra converted.
    fn rgb(&mut self, pl: &Plugin<'s>, name: &str, default: Rgb, emitter: bool) -> Result<Rgb> {
        Ok(self.color_value(pl, name, default, emitter)?.rgb())
    }

    /// A constant colour (no textures allowed), declared spectra kept.
    fn color_value(
        &mut self,
        pl: &Plugin<'s>,
        name: &str,
        default: Rgb,
        emitter: bool,
    ) -> Result<ColorValue> {
        match self.color_opt(pl, name, emitter)? {
            None => Ok(ColorValue::Rgb(default)),
            Some(ColorParam::Const(v)) => Ok(ColorValue::Rgb(v)),
            Some(ColorParam::Spectrum(s)) => Ok(ColorValue::Spectrum(s)),
            Some(ColorParam::Texture(_)) => Err(err(
                pl.named_child(name).map_or(pl.loc(), |c| &c.loc),
                format!(
                    "parameter '{name}' of {} '{}' cannot be a texture",
                    pl.elem.tag, pl.ty
                ),
            )),
        }
    }

    /// A scalar parameter: a float or a texture.
    fn float_param(&mut self, pl: &Plugin<'s>, name: &str, default: f32) -> Result<FloatParam> {
        if let Some(c) = pl.named_child(name)
            && c.elem.tag == "texture"
        {
            return Ok(FloatParam::Texture(self.texture(c)?));
        }
        Ok(FloatParam::Const(pl.props.float(name, default)?))
    }

    /// An index of refraction: a number, one of Mitsuba's names (`bk7`, `water`...), or a
    /// dispersive glass by pbrt-v4's name (`glass-BK7`...; see [`Dispersion::named`]), whose
    /// index at the d line an RGB render uses.
    fn ior(&self, pl: &Plugin<'s>, name: &str, default: f32) -> Result<f32> {
        Ok(self.ior_dispersive(pl, name, default)?.0)
    }

    /// [`Self::ior`], with the dispersion of a named dispersive glass.
    fn ior_dispersive(
        &self,
        pl: &Plugin<'s>,
        name: &str,
        default: f32,
    ) -> Result<(f32, Option<Dispersion>)> {
        let Some(p) = pl.props.get(name) else {
            return Ok((default, None));
        };
        let mut dispersion = None;
        let v = match &p.value {
            Value::Float(v) => *v as f32,
            Value::Int(v) => *v as f32,
            Value::Str(s) => ior::dielectric(s)
                .or_else(|| {
                    dispersion = Dispersion::named(s.trim());
                    dispersion.map(|d| d.ior_rgb() as f32)
                })
                .ok_or_else(|| {
                    err(
                        &p.loc,
                        format!(
                            "unknown IOR name '{s}' (known: {}; dispersive: {})",
                            ior::dielectric_names(),
                            Dispersion::names().collect::<Vec<_>>().join(", ")
                        ),
                    )
                })?,
            Value::Color(spec) => spec_to_rgb(spec, SpectrumUse::Unbounded, &p.loc)?.x,
            _ => {
                return Err(err(
                    &p.loc,
                    format!("'{name}' should be a number or a name"),
                ));
            }
        };
        if v <= 0.0 {
            return Err(err(&p.loc, format!("'{name}' must be positive, found {v}")));
        }
        Ok((v, dispersion))
    }

    /// A dielectric's interior index and its dispersion (docs/formats.md, "Dispersion"):
    /// `int_ior` as in [`Self::ior_dispersive`], or Cauchy's `cauchy_a`, `cauchy_b` (µm²), or
    /// Sellmeier's `sellmeier_b1`..`sellmeier_b3`, `sellmeier_c1`..`sellmeier_c3` (µm²;
    /// missing terms are 0). The RGB index of a dispersive one is its value at the d line.
    fn int_ior(&self, pl: &Plugin<'s>) -> Result<(f32, Option<Dispersion>)> {
        const CAUCHY: [&str; 2] = ["cauchy_a", "cauchy_b"];
        const SELLMEIER: [&str; 6] = [
            "sellmeier_b1",
            "sellmeier_b2",
            "sellmeier_b3",
            "sellmeier_c1",
            "sellmeier_c2",
            "sellmeier_c3",
        ];
        let given = |names: &[&str]| names.iter().any(|n| pl.props.has(n));
        let (cauchy, sellmeier) = (given(&CAUCHY), given(&SELLMEIER));
        if !cauchy && !sellmeier {
            return self.ior_dispersive(pl, "int_ior", ior::BK7);
        }
        let loc = pl.loc();
        if cauchy && sellmeier {
            return Err(err(
                loc,
                format!(
                    "{} '{}' has both Cauchy and Sellmeier coefficients",
                    pl.elem.tag, pl.ty
                ),
            ));
        }
        if pl.props.has("int_ior") {
            return Err(err(
                loc,
                format!(
                    "{} '{}' has both 'int_ior' and dispersion coefficients",
                    pl.elem.tag, pl.ty
                ),
            ));
        }
        let d = if cauchy {
            let a = pl.props.float_opt("cauchy_a")?;
            let b = pl.props.float_opt("cauchy_b")?;
            let (Some(a), Some(b)) = (a, b) else {
                return Err(err(
                    loc,
                    "Cauchy dispersion needs both 'cauchy_a' and 'cauchy_b'",
                ));
            };
            Dispersion::Cauchy {
                a: f64::from(a),
                b: f64::from(b),
            }
        } else {
            let mut v = [0.0f64; 6];
            for (v, n) in v.iter_mut().zip(SELLMEIER) {
                *v = f64::from(pl.props.float(n, 0.0)?);
            }
            Dispersion::Sellmeier {
                b: [v[0], v[1], v[2]],
                c: [v[3], v[4], v[5]],
            }
        };
        if !d.is_valid_visible() {
            return Err(err(
                loc,
                format!(
                    "the dispersion of {} '{}' is not a valid index (finite, ≥ 1, no Sellmeier \
                     pole) over 360–830 nm",
                    pl.elem.tag, pl.ty
                ),
            ));
        }
        Ok((d.ior_rgb() as f32, Some(d)))
    }

    fn dispersion_sampling(&self, pl: &Plugin<'s>) -> Result<DispersionSampling> {
        match pl.props.string_opt("dispersion_sampling")? {
            None => Ok(DispersionSampling::default()),
            Some((s, loc)) => DispersionSampling::parse(s).ok_or_else(|| {
                err(
                    loc,
                    format!("unknown dispersion_sampling '{s}' (mis, terminate)"),
                )
            }),
        }
    }

    fn distribution(&self, pl: &Plugin<'s>) -> Result<MicrofacetDistribution> {
        match pl.props.string_opt("distribution")? {
            None => Ok(MicrofacetDistribution::Beckmann),
            Some((s, loc)) => match s.to_ascii_lowercase().as_str() {
                "beckmann" => Ok(MicrofacetDistribution::Beckmann),
                "ggx" => Ok(MicrofacetDistribution::Ggx),
                "phong" | "as" => Err(err(
                    loc,
                    format!("microfacet distribution '{s}' is not supported (beckmann, ggx)"),
                )),
                _ => Err(err(
                    loc,
                    format!("unknown microfacet distribution '{s}' (beckmann, ggx)"),
                )),
            },
        }
    }

    /// Our extension `<bsdf type="subsurface">`: a dielectric boundary (`int_ior`,
    /// `ext_ior`, smooth unless `alpha` or `alpha_u`/`alpha_v` is given, then rough with
    /// `distribution`) around a homogeneous medium given by `sigma_a` and `sigma_s`, or `mfp`
    /// and `albedo` (the multiple-scattering albedo), or `material` (a name of Jensen et al.
    /// 2001's table, in mm⁻¹), each times `scale`; `g` the Henyey–Greenstein asymmetry.
    fn subsurface(&mut self, pl: &Plugin<'s>) -> Result<Material> {
        // Water's index unless an index or dispersion coefficients are given.
        let declared = ["int_ior", "cauchy_a", "cauchy_b"]
            .iter()
            .any(|n| pl.props.has(n))
            || (1..=3).any(|i| {
                pl.props.has(&format!("sellmeier_b{i}")) || pl.props.has(&format!("sellmeier_c{i}"))
            });
        let (int_ior, dispersion) = if declared {
            self.int_ior(pl)?
        } else {
            (1.33, None)
        };
        let ext_ior = self.ior(pl, "ext_ior", ior::AIR)?;
        let one = || ColorParam::constant(1.0);
        let boundary = if ["alpha", "alpha_u", "alpha_v"]
            .iter()
            .any(|n| pl.props.has(n))
        {
            let (alpha_u, alpha_v) = self.alphas(pl)?;
            Material::RoughDielectric {
                distribution: self.distribution(pl)?,
                alpha_u,
                alpha_v,
                int_ior,
                ext_ior,
                dispersion,
                dispersion_sampling: self.dispersion_sampling(pl)?,
                specular_reflectance: one(),
                specular_transmittance: one(),
            }
        } else {
            Material::Dielectric {
                int_ior,
                ext_ior,
                dispersion,
                specular_reflectance: one(),
                specular_transmittance: one(),
                absorption: None,
            }
        };
        let mut rgb = |name: &str, default: f32| -> Result<Option<Rgb>> {
            if !pl.props.has(name) {
                return Ok(None);
            }
            match self.color(pl, name, default, false)?.const_rgb() {
                Some(c) => Ok(Some(c)),
                None => Err(err(
                    pl.loc(),
                    format!("subsurface: '{name}' must be a constant colour, not a texture"),
                )),
            }
        };
        let sigma_a = rgb("sigma_a", 0.0)?;
        let sigma_s = rgb("sigma_s", 0.0)?;
        let mfp = rgb("mfp", 1.0)?;
        let albedo = rgb("albedo", 0.8)?;
        let name = pl.props.string_opt("material")?;
        let coefficients = match (sigma_a.or(sigma_s), mfp.or(albedo), name) {
            (Some(_), None, None) => SubsurfaceCoefficients::Sigma {
                sigma_a: sigma_a.unwrap_or(Rgb::ZERO),
                sigma_s: sigma_s.unwrap_or(Rgb::ZERO),
            },
            (None, _, None) => SubsurfaceCoefficients::MeanFreePath {
                mfp: mfp.unwrap_or(Rgb::ONE),
                albedo: albedo.unwrap_or(Rgb::splat(0.8)),
            },
            (None, None, Some((n, loc))) => SubsurfaceCoefficients::Measured(
                base::subsurface::measured(n).ok_or_else(|| {
                    err(
                        loc,
                        format!(
                            "subsurface: unknown measured material \"{n}\" (known: {})",
                            base::subsurface::MEASURED.map(|m| m.name).join(", ")
                        ),
                    )
                })?,
            ),
            _ => {
                return Err(err(
                    pl.loc(),
                    "subsurface: give one of sigma_a/sigma_s, mfp/albedo or material",
                ));
            }
        };
        if let SubsurfaceCoefficients::MeanFreePath { mfp, albedo } = &coefficients
            && (mfp.min_element() <= 0.0
                || albedo.min_element() < 0.0
                || albedo.max_element() > 1.0)
        {
            return Err(err(
                pl.loc(),
                "subsurface: 'mfp' must be > 0 and 'albedo' within [0, 1]",
            ));
        }
        let g = pl.props.float("g", 0.0)?;
        if !(g > -1.0 && g < 1.0) {
            return Err(err(pl.loc(), "subsurface: 'g' must lie in (-1, 1)"));
        }
        Ok(Material::Subsurface {
            boundary: Box::new(boundary),
            medium: SubsurfaceMedium {
                coefficients,
                scale: pl.props.float("scale", 1.0)?,
                g,
            },
        })
    }

    fn alphas(&mut self, pl: &Plugin<'s>) -> Result<(FloatParam, FloatParam)> {
        if pl.props.has("alpha_u") || pl.props.has("alpha_v") {
            if pl.props.has("alpha") {
                return Err(err(
                    pl.loc(),
                    "give either 'alpha' or 'alpha_u'/'alpha_v', not both",
                ));
            }
            let u = self.float_param(pl, "alpha_u", 0.1)?;
            let v = self.float_param(pl, "alpha_v", 0.1)?;
            return Ok((u, v));
        }
        let a = self.float_param(pl, "alpha", 0.1)?;
        Ok((a.clone(), a))
    }

    // -----------------------------------------------------------------------------------------
    // Textures

    fn texture(&mut self, c: &Child<'s>) -> Result<TextureId> {
        if let Some(id) = c.id()
            && let Some(&t) = self.textures.get(id)
        {
            return Ok(t);
        }
        let pl = self.ctx.plugin(c.elem)?;
        let to_uv = match pl.props.transform("to_uv")? {
            Some(m) => extract_uv(m),
            None => self.legacy_uv_transform(&pl)?.unwrap_or(Mat3::IDENTITY),
        };
        let texture = match pl.ty.as_str() {
            "bitmap" => {
                let path = self.ctx.file_param(&pl, "bitmap texture")?;
                let filter = match pl.props.string_opt("filter_type")? {
                    None => TextureFilter::Bilinear,
                    Some((s, loc)) => match s {
                        "bilinear" => TextureFilter::Bilinear,
                        "nearest" => TextureFilter::Nearest,
                        "ewa" | "trilinear" => {
                            self.ctx
                                .warn(loc, format!("filter_type '{s}' approximated by bilinear"));
                            TextureFilter::Bilinear
                        }
                        _ => {
                            return Err(err(
                                loc,
                                format!("unknown filter_type '{s}' (bilinear, nearest)"),
                            ));
                        }
                    },
                };
                let wrap = match pl.props.string_opt("wrap_mode")? {
                    None => WrapMode::Repeat,
                    Some((s, loc)) => match s {
                        "repeat" => WrapMode::Repeat,
                        "mirror" => WrapMode::Mirror,
                        "clamp" => WrapMode::Clamp,
                        _ => {
                            return Err(err(
                                loc,
                                format!("unknown wrap_mode '{s}' (repeat, mirror, clamp)"),
                            ));
                        }
                    },
                };
                let raw = pl.props.bool("raw", false)?;
                Texture::Bitmap {
                    mipmapped: false,
                    path,
                    filter,
                    wrap,
                    raw,
                    gamma: None,
                    to_uv,
                    corner_texels: false,
                }
            }
            "checkerboard" => Texture::Checkerboard {
                color0: self.rgb(&pl, "color0", Vec3::splat(0.4), false)?,
                color1: self.rgb(&pl, "color1", Vec3::splat(0.2), false)?,
                to_uv,
            },
            _ => return Err(unknown_type(&pl, "bitmap, checkerboard")),
        };
        self.ctx.finish(&pl);
        let id = self.scene.add_texture(TextureDesc {
            texture,
            name: c.id().map(str::to_string),
            loc: pl.loc().clone(),
        });
        if let Some(key) = c.id() {
            self.textures.insert(key.to_string(), id);
        }
        Ok(id)
    }

    // -----------------------------------------------------------------------------------------
    // Materials

    pub fn material(&mut self, c: &Child<'s>) -> Result<MaterialId> {
        if let Some(id) = c.id()
            && let Some(&m) = self.materials.get(id)
        {
            return Ok(m);
        }
        let pl = self.ctx.plugin(c.elem)?;
        let material = self.material_of(&pl)?;
        self.ctx.finish(&pl);
        let id = match material {
            // Wrappers we do not model resolve to their nested material.
            Err(nested) => nested,
            Ok(material) => self.scene.add_material(MaterialDesc {
                material,
                ambient: Default::default(),
                name: c.id().map(str::to_string),
                loc: pl.loc().clone(),
            }),
        };
        if let Some(key) = c.id() {
            self.materials.insert(key.to_string(), id);
        }
        Ok(id)
    }

    // -----------------------------------------------------------------------------------------
    // Participating media

    /// A medium, instantiated once per id.
    pub fn medium(&mut self, c: &Child<'s>) -> Result<MediumId> {
        if let Some(id) = c.id()
            && let Some(&m) = self.media.get(id)
        {
            return Ok(m);
        }
        let pl = self.ctx.plugin(c.elem)?;
        let mut phase = PhaseDesc::Isotropic;
        let mut grids: [Option<VolumeParam>; 2] = [None, None];
        let mut emission = None;
        for ch in &pl.children {
            match (ch.elem.tag.as_str(), ch.name.as_deref()) {
                ("phase", _) => phase = self.phase(ch)?,
                ("volume", Some("sigma_t")) => grids[0] = Some(self.volume(ch)?),
                ("volume", Some("albedo")) => grids[1] = Some(self.volume(ch)?),
                ("volume", Some("radiance")) => {
                    emission = Some(MediumEmission::Radiance(self.volume(ch)?));
                }
                ("volume", Some("temperature")) => match self.volume(ch)? {
                    VolumeParam::Grid(grid) | VolumeParam::SigmaSGrid(grid) => {
                        let scale = pl.props.float("emission_scale", 1.0)?;
                        emission = Some(MediumEmission::Temperature { grid, scale });
                    }
                    VolumeParam::Const(_) => {
                        return Err(err(&ch.loc, "a temperature must be a gridvolume"));
                    }
                },
                ("volume", _) => {
                    return Err(err(
                        &ch.loc,
                        "a volume in a medium needs name=\"sigma_t\", \"albedo\", \"radiance\" or \"temperature\"",
                    ));
                }
                (other, _) => {
                    return Err(err(
                        &ch.loc,
                        format!("<{other}> cannot be nested in a medium"),
                    ));
                }
            }
        }
        let scale = pl.props.float("scale", 1.0)?;
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(err(pl.loc(), "medium 'scale' must be a finite number ≥ 0"));
        }
        let [sigma_t_grid, albedo_grid] = grids;
        let medium = match pl.ty.as_str() {
            "homogeneous" => {
                let (sigma_t, albedo) = if pl.props.has("sigma_a") || pl.props.has("sigma_s") {
                    // Mitsuba 0.6: absorption and scattering coefficients.
                    let a = self.medium_rgb(&pl, "sigma_a", Vec3::ZERO)?;
                    let s = self.medium_rgb(&pl, "sigma_s", Vec3::ZERO)?;
                    let t = a + s;
                    let albedo = Vec3::select(t.cmpgt(Vec3::ZERO), s / t, Vec3::ZERO);
                    (t, albedo)
                } else {
                    let t = match sigma_t_grid {
                        Some(VolumeParam::Const(v)) => v,
                        Some(VolumeParam::Grid(_) | VolumeParam::SigmaSGrid(_)) => {
                            return Err(err(
                                pl.loc(),
                                "a homogeneous medium takes constant coefficients; use type \"heterogeneous\" for a grid",
                            ));
                        }
                        None => self.medium_rgb(&pl, "sigma_t", Vec3::ONE)?,
                    };
                    let albedo = match albedo_grid {
                        Some(VolumeParam::Const(v)) => v,
                        Some(VolumeParam::Grid(_) | VolumeParam::SigmaSGrid(_)) => {
                            return Err(err(
                                pl.loc(),
                                "a homogeneous medium takes a constant albedo",
                            ));
                        }
                        None => self.medium_rgb(&pl, "albedo", Vec3::splat(0.75))?,
                    };
                    (t, albedo)
                };
                Medium::Homogeneous {
                    sigma_t,
                    albedo,
                    scale,
                }
            }
            "heterogeneous" => {
                let sigma_t = match sigma_t_grid {
                    Some(VolumeParam::Grid(g)) => g,
                    // Nori's dialect: the grid file on the medium itself, placed by the box
                    // `bbox_min`..`bbox_max` (the grid's [0,1]³ stretched over it).
                    None if pl.props.has("filename") => self.nori_grid(&pl)?,
                    _ => {
                        return Err(err(
                            pl.loc(),
                            "a heterogeneous medium needs <volume type=\"gridvolume\" name=\"sigma_t\">",
                        ));
                    }
                };
                let albedo = match albedo_grid {
                    Some(v) => v,
                    None => {
                        VolumeParam::Const(self.medium_rgb(&pl, "albedo", Vec3::splat(0.75))?)
                    }
                };
                Medium::Heterogeneous {
                    sigma_t,
                    albedo,
                    scale,
                }
            }
            _ => return Err(unknown_type(&pl, "homogeneous, heterogeneous")),
        };
        if emission.is_none() && pl.props.has("radiance") {
            let le = self.rgb(&pl, "radiance", Vec3::ZERO, true)?;
            if !(le.is_finite() && le.cmpge(Vec3::ZERO).all()) {
                return Err(err(pl.loc(), "medium 'radiance' must be finite and ≥ 0"));
            }
            emission = Some(MediumEmission::Radiance(VolumeParam::Const(le)));
        }
        // Mitsuba's `sample_emitters` (next-event estimation from medium vertices) is always on.
        pl.props.bool("sample_emitters", true)?;
        self.ctx.finish(&pl);
        let id = self.scene.add_medium(MediumDesc {
            medium,
            phase,
            emission,
            name: c.id().map(str::to_string),
            loc: pl.loc().clone(),
        });
        if let Some(key) = c.id() {
            self.media.insert(key.to_string(), id);
        }
        Ok(id)
    }

    /// A heterogeneous medium's grid given Nori's way: `filename` (`.vol`, or `.vdb` with
    /// `grid_name`) on the medium, placed by `bbox_min`/`bbox_max` (default the unit cube).
    fn nori_grid(&mut self, pl: &Plugin<'s>) -> Result<Box<VolumeDesc>> {
        let path = self.ctx.file_param(pl, "heterogeneous medium")?;
        let lo = pl.props.vector_opt("bbox_min")?.unwrap_or(Vec3::ZERO);
        let hi = pl.props.vector_opt("bbox_max")?.unwrap_or(Vec3::ONE);
        if !(lo.is_finite() && hi.is_finite() && hi.cmpgt(lo).all()) {
            return Err(err(
                pl.loc(),
                format!("bbox_min {lo} must be below bbox_max {hi} on every axis"),
            ));
        }
        // The box holds the grid's active voxels, whatever the file's own placement.
        let format = grid_format(pl, &path, false)?;
        Ok(Box::new(VolumeDesc {
            path,
            format,
            to_world: Mat4::from_translation(lo) * Mat4::from_scale(hi - lo),
            trilinear: true,
            loc: pl.loc().clone(),
        }))
    }

    /// A non-negative, finite constant colour parameter of a medium.
    fn medium_rgb(&mut self, pl: &Plugin<'s>, name: &str, default: Rgb) -> Result<Rgb> {
        let v = self.rgb(pl, name, default, false)?;
        if !(v.is_finite() && v.cmpge(Vec3::ZERO).all()) {
            let loc = pl.props.get(name).map_or(pl.loc(), |p| &p.loc);
            return Err(err(
                loc,
                format!("medium parameter '{name}' must be finite and ≥ 0, found {v}"),
            ));
        }
        Ok(v)
    }

    fn phase(&mut self, c: &Child<'s>) -> Result<PhaseDesc> {
        let pl = self.ctx.plugin(c.elem)?;
        let phase = match pl.ty.as_str() {
            "isotropic" => PhaseDesc::Isotropic,
            "hg" => {
                let g = pl.props.float("g", 0.8)?;
                if !(g > -1.0 && g < 1.0) {
                    return Err(err(pl.loc(), "phase 'hg' needs -1 < g < 1"));
                }
                PhaseDesc::HenyeyGreenstein { g }
            }
            "rayleigh" => PhaseDesc::Rayleigh,
            "tabphase" => {
                let values = float_list(&pl, "values")?;
                if values.len() < 2
                    || values.iter().any(|v| !(v.is_finite() && *v >= 0.0))
                    || !values.iter().any(|&v| v > 0.0)
                {
                    return Err(err(
                        pl.loc(),
                        "phase 'tabphase' needs 'values': at least two non-negative numbers, not \
                         all zero",
                    ));
                }
                PhaseDesc::Tabulated { values }
            }
            "blendphase" => {
                // Mitsuba 3.9.1 takes the nested phase functions in document order.
                let nested: Vec<&Child<'s>> = pl.children_with(&["phase"]).collect();
                let [first, second] = nested[..] else {
                    return Err(err(
                        pl.loc(),
                        format!(
                            "blendphase needs two nested phase functions, found {}",
                            nested.len()
                        ),
                    ));
                };
                if pl.named_child("weight").is_some() {
                    return Err(err(
                        pl.loc(),
                        "blendphase: only a constant 'weight' is supported, not a volume",
                    ));
                }
                let weight = pl.props.float("weight", 0.5)?.clamp(0.0, 1.0);
                let phases = Box::new([self.phase(first)?, self.phase(second)?]);
                PhaseDesc::Blend { weight, phases }
            }
            "sggx" => {
                let Some(c) = pl.named_child("s") else {
                    return Err(err(
                        pl.loc(),
                        "phase 'sggx' needs its S matrix: <volume name=\"S\" type=\"gridvolume\"> \
                         of 6 channels (S_xx, S_yy, S_zz, S_xy, S_xz, S_yz)",
                    ));
                };
                match self.volume(c)? {
                    VolumeParam::Grid(v) if matches!(v.format, VolumeFormat::MitsubaVol) => {
                        PhaseDesc::Sggx { s_grid: v.path }
                    }
                    _ => {
                        // Mitsuba's constvolume has no 6-channel value (eval_6).
                        return Err(err(
                            &c.loc,
                            "phase 'sggx': S must be a 6-channel gridvolume (.vol file)",
                        ));
                    }
                }
            }
            _ => {
                return Err(unknown_type(
                    &pl,
                    "isotropic, hg, rayleigh, tabphase, blendphase, sggx",
                ));
            }
        };
        self.ctx.finish(&pl);
        Ok(phase)
    }

    /// A medium parameter given as a volume: `constvolume` or `gridvolume` (a Mitsuba `.vol`
    /// file, or an OpenVDB `.vdb` file with its `grid_name`, default `density`).
    fn volume(&mut self, c: &Child<'s>) -> Result<VolumeParam> {
        let pl = self.ctx.plugin(c.elem)?;
        let v = match pl.ty.as_str() {
            "constvolume" => VolumeParam::Const(self.medium_rgb(&pl, "value", Vec3::ONE)?),
            "gridvolume" => {
                let path = self.ctx.file_param(&pl, "gridvolume")?;
                let format = grid_format(&pl, &path, true)?;
                let trilinear = match pl.props.string_opt("filter_type")? {
                    None | Some(("trilinear", _)) => true,
                    Some(("nearest", _)) => false,
                    Some((other, loc)) => {
                        return Err(err(
                            loc,
                            format!("filter_type '{other}': expected trilinear or nearest"),
                        ));
                    }
                };
                VolumeParam::Grid(Box::new(VolumeDesc {
                    path,
                    format,
                    to_world: pl.props.transform("to_world")?.unwrap_or(Mat4::IDENTITY),
                    trilinear,
                    loc: pl.loc().clone(),
                }))
            }
            _ => return Err(unknown_type(&pl, "constvolume, gridvolume")),
        };
        self.ctx.finish(&pl);
        Ok(v)
    }

    /// The single nested bsdf of a wrapper (`normalmap`, `mask`), or an error naming it.
    fn one_nested_bsdf(&mut self, pl: &Plugin<'s>) -> Result<MaterialId> {
        let nested = self.nested_bsdfs(pl)?;
        match nested[..] {
            [one] => Ok(one),
            _ => Err(err(
                pl.loc(),
                format!("{} needs one nested bsdf, found {}", pl.ty, nested.len()),
            )),
        }
    }

    fn nested_bsdfs(&mut self, pl: &Plugin<'s>) -> Result<Vec<MaterialId>> {
        let children: Vec<&Child<'s>> = pl.children_with(&["bsdf"]).collect();
        let mut out = Vec::with_capacity(children.len());
        for c in children {
            out.push(self.material(c)?);
        }
        Ok(out)
    }

    /// `Ok(Err(id))`: the plugin is a wrapper resolved to the nested material `id`.
    fn material_of(
        &mut self,
        pl: &Plugin<'s>,
    ) -> Result<std::result::Result<Material, MaterialId>> {
        let m = match pl.ty.as_str() {
            "diffuse" => {
                let name = if pl.props.has("albedo") || pl.named_child("albedo").is_some() {
                    "albedo"
                } else {
                    "reflectance"
                };
                Material::Diffuse {
                    reflectance: self.color(pl, name, 0.5, false)?,
                }
            }
            "conductor" | "roughconductor" => {
                let (eta, k) = self.conductor_ior(pl)?;
                let specular_reflectance = self.color(pl, "specular_reflectance", 1.0, false)?;
                if pl.ty == "conductor" {
                    match (eta, k) {
                        (None, _) => Material::Mirror {
                            reflectance: specular_reflectance,
                        },
                        (Some(eta), k) => Material::Conductor {
                            eta,
                            k,
                            specular_reflectance,
                        },
                    }
                } else {
                    let (alpha_u, alpha_v) = self.alphas(pl)?;
                    let (eta, k) = eta.map_or((Vec3::ZERO.into(), Vec3::ONE.into()), |e| (e, k));
                    Material::RoughConductor {
                        distribution: self.distribution(pl)?,
                        alpha_u,
                        alpha_v,
                        eta,
                        k,
                        specular_reflectance,
                    }
                }
            }
            "dielectric" => {
                let (int_ior, dispersion) = self.int_ior(pl)?;
                Material::Dielectric {
                    int_ior,
                    ext_ior: self.ior(pl, "ext_ior", ior::AIR)?,
                    dispersion,
                    specular_reflectance: self.color(pl, "specular_reflectance", 1.0, false)?,
                    specular_transmittance: self.color(pl, "specular_transmittance", 1.0, false)?,
                    absorption: None,
                }
            }
            "thindielectric" => {
                let (int_ior, dispersion) = self.int_ior(pl)?;
                Material::ThinDielectric {
                    int_ior,
                    ext_ior: self.ior(pl, "ext_ior", ior::AIR)?,
                    dispersion,
                    specular_reflectance: self.color(pl, "specular_reflectance", 1.0, false)?,
                    specular_transmittance: self.color(pl, "specular_transmittance", 1.0, false)?,
                }
            }
            "roughdielectric" => {
                let (alpha_u, alpha_v) = self.alphas(pl)?;
                let (int_ior, dispersion) = self.int_ior(pl)?;
                Material::RoughDielectric {
                    distribution: self.distribution(pl)?,
                    alpha_u,
                    alpha_v,
                    int_ior,
                    ext_ior: self.ior(pl, "ext_ior", ior::AIR)?,
                    dispersion,
                    dispersion_sampling: self.dispersion_sampling(pl)?,
                    specular_reflectance: self.color(pl, "specular_reflectance", 1.0, false)?,
                    specular_transmittance: self.color(pl, "specular_transmittance", 1.0, false)?,
                }
            }
            "subsurface" => self.subsurface(pl)?,
            "plastic" => Material::Plastic {
                diffuse_reflectance: self.color(pl, "diffuse_reflectance", 0.5, false)?,
                specular_reflectance: self.color(pl, "specular_reflectance", 1.0, false)?,
                int_ior: self.ior(pl, "int_ior", ior::POLYPROPYLENE)?,
                ext_ior: self.ior(pl, "ext_ior", ior::AIR)?,
                nonlinear: pl.props.bool("nonlinear", false)?,
            },
            "roughplastic" => Material::RoughPlastic {
                distribution: self.distribution(pl)?,
                alpha: pl.props.float("alpha", 0.1)?,
                diffuse_reflectance: self.color(pl, "diffuse_reflectance", 0.5, false)?,
                specular_reflectance: self.color(pl, "specular_reflectance", 1.0, false)?,
                int_ior: self.ior(pl, "int_ior", ior::POLYPROPYLENE)?,
                ext_ior: self.ior(pl, "ext_ior", ior::AIR)?,
                nonlinear: pl.props.bool("nonlinear", false)?,
            },
            "twosided" => {
                let nested = self.nested_bsdfs(pl)?;
                match nested[..] {
                    [front] => Material::TwoSided { front, back: None },
                    [front, back] => Material::TwoSided {
                        front,
                        back: Some(back),
                    },
                    _ => {
                        return Err(err(
                            pl.loc(),
                            format!(
                                "twosided needs one or two nested bsdfs, found {}",
                                nested.len()
                            ),
                        ));
                    }
                }
            }
            "normalmap" => {
                let nested = self.one_nested_bsdf(pl)?;
                let Some(c) = pl
                    .named_child("normalmap")
                    .filter(|c| c.elem.tag == "texture")
                else {
                    return Err(err(
                        pl.loc(),
                        "normalmap needs a <texture name=\"normalmap\"> (a raw bitmap)",
                    ));
                };
                let texture = self.texture(c)?;
                Material::NormalMap { nested, texture }
            }
            "mask" => {
                let nested = self.one_nested_bsdf(pl)?;
                let opacity = self.float_param(pl, "opacity", 0.5)?;
                Material::Mask { nested, opacity }
            }
            "null" => Material::Null,
            "principled" => self.principled(pl)?,
            "principledthin" => self.principledthin(pl)?,
            "blendbsdf" => self.blendbsdf(pl)?,
            "pplastic" => self.pplastic(pl)?,
            // Nori
            "mirror" => Material::Mirror {
                reflectance: ColorParam::constant(1.0),
            },
            "microfacet" => Material::NoriMicrofacet {
                alpha: pl.props.float("alpha", 0.1)?,
                int_ior: self.ior(pl, "int_ior", ior::BK7)?,
                ext_ior: self.ior(pl, "ext_ior", ior::AIR)?,
                kd: self.rgb(pl, "kd", Vec3::splat(0.5), false)?,
            },
            "bumpmap" => self.bumpmap(pl)?,
            _ => {
                return Err(unknown_type(
                    pl,
                    "diffuse, conductor, roughconductor, dielectric, thindielectric, \
                     roughdielectric, plastic, roughplastic, twosided, null, principled, principledthin, blendbsdf, bumpmap, pplastic, \
                     mirror, \
                     microfacet",
                ));
            }
        };
        Ok(Ok(m))
    }

    /// (η, k) of a conductor; `None` η means Mitsuba's default "none" (a perfect mirror).
    /// A named material keeps its measured spectra beside their RGB values.
    fn conductor_ior(&mut self, pl: &Plugin<'s>) -> Result<(Option<ColorValue>, ColorValue)> {
        let material = pl
            .props
            .string_opt("material")?
            .map(|(s, l)| (s.to_string(), l.clone()));
        let has_eta = pl.props.has("eta") || pl.props.has("k");
        match material {
            Some((m, loc)) if m != "none" => {
                if has_eta {
                    return Err(err(&loc, "give either 'material' or 'eta'/'k', not both"));
                }
                let (eta, k) = ior::conductor(&m).ok_or_else(|| {
                    err(
                        &loc,
                        format!(
                            "unknown conductor material '{m}' (known: {})",
                            ior::conductor_names()
                        ),
                    )
                })?;
                let ext = self.ior(pl, "ext_eta", 1.0)?;
                let measured = |rgb: Rgb, eta: bool| {
                    ColorValue::Spectrum(Arc::new(SpectrumDesc {
                        rgb: rgb / ext,
                        kind: SpectrumKind::Conductor {
                            material: m.clone(),
                            eta,
                        },
                        scale: 1.0 / ext as f64,
                    }))
                };
                Ok((Some(measured(eta, true)), measured(k, false)))
            }
            _ if has_eta => {
                let eta = self.color_value(pl, "eta", Vec3::ZERO, false)?;
                let k = self.color_value(pl, "k", Vec3::ONE, false)?;
                Ok((Some(eta), k))
            }
            _ => Ok((None, Vec3::ONE.into())),
        }
    }

    // -----------------------------------------------------------------------------------------
    // Emitters

    fn area_emission(&mut self, c: &Child<'s>) -> Result<AreaEmission> {
        let pl = self.ctx.plugin(c.elem)?;
        if pl.ty != "area" && pl.ty != "directionalarea" {
            return Err(err(
                &c.loc,
                format!(
                    "a shape can only carry an 'area' or 'directionalarea' emitter, found '{}'",
                    pl.ty
                ),
            ));
        }
        if pl.ty == "directionalarea" && pl.props.has("to_world") {
            // As Mitsuba: the emitter inherits its shape's placement.
            return Err(err(
                pl.loc(),
                "a directionalarea emitter cannot have a to_world (it inherits its shape's)",
            ));
        }
        let radiance = self.color(&pl, "radiance", 1.0, true)?;
        self.ctx.finish(&pl);
        Ok(AreaEmission {
            radiance,
            two_sided: false,
            directional: pl.ty == "directionalarea",
            loc: pl.loc().clone(),
        })
    }

    fn emitter(&mut self, pl: &Plugin<'s>) -> Result<Option<Emitter>> {
        let to_world = pl.props.transform("to_world")?;
        let e = match pl.ty.as_str() {
            "area" | "directionalarea" => {
                if pl.elem.attr("id").is_none() {
                    return Err(err(
                        pl.loc(),
                        "an area emitter must be nested in a shape (or given an id and \
                         referenced from one)",
                    ));
                }
                // A template referenced by shapes: instantiated (and checked) there.
                for p in &pl.props.props {
                    p.used.set(true);
                }
                return Ok(None);
            }
            "point" => {
                let position = match pl.props.vector_opt("position")? {
                    Some(p) => p,
                    None => to_world.map_or(Vec3::ZERO, |m| m.w_axis.truncate()),
                };
                let intensity = if pl.props.has("power") {
                    // Nori: isotropic point light of total power Φ → I = Φ / 4π.
                    self.color_value(pl, "power", Vec3::ONE, true)?
                        .divided(4.0 * std::f32::consts::PI)
                } else {
                    self.color_value(pl, "intensity", Vec3::ONE, true)?
                };
                Emitter::Point {
                    position,
                    intensity,
                }
            }
            "spot" => {
                let cutoff_angle = pl.props.float("cutoff_angle", 20.0)?;
                let beam_width = pl.props.float("beam_width", cutoff_angle * 0.75)?;
                if !(cutoff_angle > 0.0 && cutoff_angle <= 180.0) {
                    return Err(err(pl.loc(), "spot: cutoff_angle must be in (0, 180]"));
                }
                Emitter::Spot {
                    to_world: to_world.unwrap_or(Mat4::IDENTITY),
                    intensity: self.color_value(pl, "intensity", Vec3::ONE, true)?,
                    cutoff_angle,
                    beam_width: beam_width.min(cutoff_angle),
                    falloff: SpotFalloff::Mitsuba,
                }
            }
            "directional" => {
                let direction = match pl.props.vector_opt("direction")? {
                    Some(d) => d,
                    None => to_world.map_or(Vec3::Z, |m| m.transform_vector3(Vec3::Z)),
                };
                let direction = direction.normalize_or_zero();
                if direction == Vec3::ZERO {
                    return Err(err(pl.loc(), "directional: direction must be non-zero"));
                }
                Emitter::Directional {
                    direction,
                    irradiance: self.color_value(pl, "irradiance", Vec3::ONE, true)?,
                }
            }
            "constant" => Emitter::Constant {
                radiance: self.color_value(pl, "radiance", Vec3::ONE, true)?,
            },
            "projector" => {
                let Some(irradiance) = self.color_opt(pl, "irradiance", true)? else {
                    return Err(err(pl.loc(), "projector: 'irradiance' is required"));
                };
                let (fov, fov_axis) = self.fov(pl, false)?;
                Emitter::Projector {
                    to_world: to_world.unwrap_or(Mat4::IDENTITY),
                    irradiance,
                    scale: pl.props.float("scale", 1.0)?,
                    fov,
                    fov_axis,
                }
            }
            "envmap" => {
                let path = self.ctx.file_param(pl, "envmap")?;
                Emitter::EnvMap {
                    path,
                    scale: pl.props.float("scale", 1.0)?,
                    to_world: to_world.unwrap_or(Mat4::IDENTITY),
                    mapping: EnvMapping::LatLong,
                }
            }
            _ => match self.extra_emitter(pl, to_world)? {
                Some(e) => e,
                None => {
                    return Err(unknown_type(
                        pl,
                        &format!(
                            "area, point, spot, directional, constant, envmap, {}",
                            emitters::TYPES.join(", ")
                        ),
                    ));
                }
            },
        };
        Ok(Some(e))
    }

    // -----------------------------------------------------------------------------------------
    // Shapes

    /// The shapes of the `shapegroup` `pl` (built on first use; a group declared in the scene
    /// adds nothing by itself).
    fn shape_group(&mut self, pl: &Plugin<'s>) -> Result<&[ShapeDesc]> {
        let key: *const Elem = pl.elem;
        if !self.groups.contains_key(&key) {
            if self.in_group {
                return Err(err(
                    pl.loc(),
                    "a shapegroup cannot contain another shapegroup",
                ));
            }
            let first = self.scene.shapes.len();
            self.in_group = true;
            let built = (|| {
                for c in &pl.children {
                    match c.elem.tag.as_str() {
                        "shape" | "mesh" => {
                            let cp = self.ctx.plugin(c.elem)?;
                            self.shape(&cp)?;
                        }
                        other => {
                            return Err(err(
                                &c.loc,
                                format!("<{other}> cannot be nested in a shapegroup"),
                            ));
                        }
                    }
                }
                Ok(())
            })();
            self.in_group = false;
            built?;
            let shapes = self.scene.shapes.split_off(first);
            self.ctx.finish(pl);
            self.groups.insert(key, shapes);
        }
        Ok(&self.groups[&key])
    }

    /// A Mitsuba `instance`: every shape of the referenced `shapegroup` placed by the
    /// instance's `to_world` (their meshes stay shared: the renderer instances them).
    fn instance(&mut self, pl: &Plugin<'s>) -> Result<()> {
        if self.in_group {
            return Err(err(pl.loc(), "a shapegroup cannot contain an instance"));
        }
        let to_world = pl.props.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let to_world = if to_world.is_finite() {
            to_world
        } else {
            Mat4::IDENTITY
        };
        let mut groups = pl
            .children
            .iter()
            .filter(|c| c.elem.tag == "shape" && c.elem.value("type") == Some("shapegroup"));
        let (Some(group), None) = (groups.next(), groups.next()) else {
            return Err(err(
                pl.loc(),
                "an instance needs exactly one shapegroup (<ref id=\"...\"/>)",
            ));
        };
        if let Some(other) = pl
            .children
            .iter()
            .find(|c| !(c.elem.tag == "shape" && c.elem.value("type") == Some("shapegroup")))
        {
            return Err(err(
                &other.loc,
                format!("<{}> cannot be nested in an instance", other.elem.tag),
            ));
        }
        let gp = self.ctx.plugin(group.elem)?;
        let name = pl.elem.value("id").map(str::to_string);
        let loc = pl.loc().clone();
        let placed: Vec<ShapeDesc> = self
            .shape_group(&gp)?
            .iter()
            .map(|s| ShapeDesc {
                to_world: to_world * s.to_world,
                name: name.clone().or_else(|| s.name.clone()),
                loc: loc.clone(),
                ..s.clone()
            })
            .collect();
        self.scene.shapes.extend(placed);
        self.ctx.finish(pl);
        Ok(())
    }

    fn shape(&mut self, pl: &Plugin<'s>) -> Result<()> {
        match pl.ty.as_str() {
            "shapegroup" => return self.shape_group(pl).map(|_| ()),
            "instance" => return self.instance(pl),
            _ => {}
        }
        let mut to_world = pl.props.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let mut cylinder_flip = false;
        let shape = match pl.ty.as_str() {
            "obj" | "ply" => {
                let path = self.ctx.file_param(pl, "mesh")?;
                let mut mesh = self.ctx.mesh(path, &pl.ty)?;
                if pl.props.bool("face_normals", false)? && !mesh.normals.is_empty() {
                    let mut m = (*mesh).clone();
                    m.normals.clear();
                    mesh = Arc::new(m);
                }
                // Mitsuba flips v of OBJ texture coordinates by default, so that v = 0 is
                // the top row of a bitmap (textures are indexed top-down).
                if pl.ty == "obj" && pl.props.bool("flip_tex_coords", true)? && !mesh.uvs.is_empty()
                {
                    let mut m = (*mesh).clone();
                    m.uvs.iter_mut().for_each(|uv| uv.y = 1.0 - uv.y);
                    mesh = Arc::new(m);
                }
                Shape::Mesh(mesh)
            }
            "sphere" => {
                let center = pl.props.vector_opt("center")?.unwrap_or(Vec3::ZERO);
                let radius = pl.props.float("radius", 1.0)?;
                Shape::Sphere { center, radius }
            }
            "rectangle" => Shape::Rectangle,
            "disk" => Shape::Disk,
            "cube" => Shape::Cube,
            "cylinder" => {
                // Mitsuba folds the centre line and radius into to_world: translate(p0) ·
                // to_frame(coordinate_system(d)) · scale(r, r, |d|); a negative radius flips
                // the normals.
                let p0 = pl.props.vector_opt("p0")?.unwrap_or(Vec3::ZERO);
                let p1 = pl.props.vector_opt("p1")?.unwrap_or(Vec3::Z);
                let radius = pl.props.float("radius", 1.0)?;
                let d = p1 - p0;
                let length = d.length();
                if !(length > 0.0 && radius != 0.0) {
                    return Err(err(
                        pl.loc(),
                        "cylinder with p0 = p1 or a zero radius (an empty surface)",
                    ));
                }
                let (s, t) = coordinate_system(d / length);
                let frame = Mat4::from_cols(
                    s.extend(0.0),
                    t.extend(0.0),
                    (d / length).extend(0.0),
                    p0.extend(1.0),
                );
                to_world = to_world
                    * frame
                    * Mat4::from_scale(Vec3::new(radius.abs(), radius.abs(), length));
                cylinder_flip = radius < 0.0;
                let l = Mat3::from_mat4(to_world);
                let (cx, cy) = (l.x_axis, l.y_axis);
                let tol = 1e-4 * cx.length_squared().max(cy.length_squared());
                if (cx.length_squared() - cy.length_squared()).abs() > tol
                    || cx.dot(cy).abs() > tol
                    || cx.dot(l.z_axis).abs() > 1e-4 * cx.length() * l.z_axis.length()
                    || cy.dot(l.z_axis).abs() > 1e-4 * cy.length() * l.z_axis.length()
                {
                    self.ctx.warn(
                        pl.loc(),
                        "cylinder with a shear or a non-uniform scale across its axis in \
                         to_world (Mitsuba 3 warns and ignores them): rendered as the \
                         elliptic or slanted cylinder it describes",
                    );
                }
                Shape::Cylinder
            }
            "serialized" => {
                return Err(err(
                    pl.loc(),
                    format!("{} '{}' is not supported", pl.elem.tag, pl.ty),
                ));
            }
            _ => {
                return Err(unknown_type(
                    pl,
                    "obj, ply, sphere, rectangle, disk, cube, cylinder, shapegroup, instance",
                ));
            }
        };
        if !to_world.is_finite() {
            to_world = Mat4::IDENTITY;
        }
        if matches!(shape, Shape::Sphere { .. }) && !crate::model::is_similarity(&to_world) {
            self.ctx.warn(
                pl.loc(),
                "sphere with a non-uniform scale or shear in to_world (Mitsuba 3 rejects it): \
                 rendered as the ellipsoid it describes",
            );
        }
        let flip_normals = pl.props.bool("flip_normals", false)? != cylinder_flip;
        let mut material = None;
        let mut emission = None;
        let mut sensor = None;
        let mut media = MediumInterface::default();
        for c in &pl.children {
            match c.elem.tag.as_str() {
                "sensor" => {
                    // Mitsuba 3's irradiancemeter sits on a shape; read after the shape is in.
                    if sensor.is_some() {
                        return Err(err(&c.loc, "a shape can have only one sensor"));
                    }
                    sensor = Some(c);
                }
                "bsdf" => {
                    if material.is_some() {
                        return Err(err(&c.loc, "a shape can have only one bsdf"));
                    }
                    material = Some(self.material(c)?);
                }
                "emitter" => {
                    if emission.is_some() {
                        return Err(err(&c.loc, "a shape can have only one emitter"));
                    }
                    emission = Some(self.area_emission(c)?);
                }
                "medium" => {
                    let m = Some(self.medium(c)?);
                    match c.name.as_deref() {
                        // Nori's dialect: a medium without a name fills the mesh.
                        Some("interior") | None => media.interior = m,
                        Some("exterior") => media.exterior = m,
                        Some(other) => {
                            return Err(err(
                                &c.loc,
                                format!(
                                    "medium name '{other}': a medium in a shape is its \"interior\" or \"exterior\""
                                ),
                            ));
                        }
                    }
                }
                other => {
                    return Err(err(
                        &c.loc,
                        format!("<{other}> cannot be nested in a shape"),
                    ));
                }
            }
        }
        self.ctx.finish(pl);
        let name = pl
            .elem
            .value("id")
            .or_else(|| pl.elem.value("name"))
            .map(str::to_string);
        self.scene.shapes.push(ShapeDesc {
            media,
            motion: None,
            shape,
            to_world,
            material,
            emission,
            flip_normals,
            name,
            loc: pl.loc().clone(),
        });
        if let Some(c) = sensor {
            let cp = self.ctx.plugin(c.elem)?;
            self.sensor(&cp, Some(self.scene.shapes.len() - 1))?;
        }
        Ok(())
    }

    // -----------------------------------------------------------------------------------------
    // Sensors, films, filters, samplers

    fn sampler(&mut self, pl: &Plugin<'s>) -> Result<SamplerDesc> {
        let kind = match pl.ty.as_str() {
            "independent" => SamplerKind::Independent,
            "stratified" => SamplerKind::Stratified,
            "halton" => SamplerKind::Halton,
            "sobol" => SamplerKind::Sobol,
            "multijitter" => SamplerKind::MultiJitter {
                jitter: pl.props.bool("jitter", true)?,
            },
            "orthogonal" => {
                self.ctx.warn(
                    pl.loc(),
                    "sampler 'orthogonal' approximated by multijitter (each 2D draw \
                     stratified alike; not an orthogonal array across all dimensions)",
                );
                SamplerKind::MultiJitter {
                    jitter: pl.props.bool("jitter", true)?,
                }
            }
            // Mitsuba 0.6's low-discrepancy sampler: padded (0,2)-sequences for 2D draws and
            // van der Corput for 1D ones, scrambled per pixel and dimension; our `sobol` is
            // that construction (its first two dimensions are the (0,2)-sequence), with Owen
            // scrambling for 0.6's random digit scrambling.
            "ldsampler" => SamplerKind::Sobol,
            "hammersley" => {
                self.ctx
                    .warn(pl.loc(), "sampler 'hammersley' approximated by halton");
                SamplerKind::Halton
            }
            _ => {
                return Err(unknown_type(
                    pl,
                    "independent, stratified, multijitter, orthogonal, ldsampler, halton, \
                     hammersley, sobol",
                ));
            }
        };
        let default_spp = match self.ctx.dialect {
            Dialect::Mitsuba3 => 4,
            Dialect::Legacy => 1,
        };
        let spp = pl
            .props
            .int_in("sample_count", default_spp, 1, u32::MAX as i64)? as u32;
        let seed = pl.props.int_in("seed", 0, 0, i64::MAX)? as u64;
        // Options of Mitsuba's samplers that do not change what is estimated.
        let _ = pl.props.bool("jitter", true)?;
        let _ = pl.props.int_opt("dimension")?;
        let _ = pl.props.bool("scramble", true);
        Ok(SamplerDesc { kind, spp, seed })
    }

    fn default_sampler(&self) -> SamplerDesc {
        SamplerDesc {
            kind: SamplerKind::Independent,
            spp: match self.ctx.dialect {
                Dialect::Mitsuba3 => 4,
                Dialect::Legacy => 1,
            },
            seed: 0,
        }
    }

    fn rfilter(&mut self, pl: &Plugin<'s>) -> Result<FilterDesc> {
        let positive = |v: f32, what: &str| -> Result<f32> {
            if v > 0.0 {
                Ok(v)
            } else {
                Err(err(
                    pl.loc(),
                    format!("rfilter '{}': {what} must be positive", pl.ty),
                ))
            }
        };
        let f = match pl.ty.as_str() {
            "box" => FilterDesc::Box {
                radius: positive(pl.props.float("radius", 0.5)?, "radius")?,
            },
            "tent" => FilterDesc::Tent {
                radius: positive(pl.props.float("radius", 1.0)?, "radius")?,
            },
            "gaussian" => {
                let stddev = positive(pl.props.float("stddev", 0.5)?, "stddev")?;
                // Mitsuba 3 truncates at 4σ; Nori has an explicit radius (default 2).
                let radius = positive(pl.props.float("radius", 4.0 * stddev)?, "radius")?;
                FilterDesc::Gaussian { stddev, radius }
            }
            "mitchell" => FilterDesc::Mitchell {
                b: pl.props.float("b", 1.0 / 3.0)?,
                c: pl.props.float("c", 1.0 / 3.0)?,
                radius: positive(pl.props.float("radius", 2.0)?, "radius")?,
            },
            "catmullrom" => FilterDesc::Mitchell {
                b: 0.0,
                c: 0.5,
                radius: 2.0,
            },
            "lanczos" => {
                let lobes = pl.props.int_in("lobes", 3, 1, 16)?;
                FilterDesc::Lanczos {
                    radius: lobes as f32,
                    tau: lobes as f32,
                }
            }
            _ => {
                return Err(unknown_type(
                    pl,
                    "box, tent, gaussian, mitchell, catmullrom, lanczos",
                ));
            }
        };
        Ok(f)
    }

    fn resolution(&self, pl: &Plugin<'s>, dw: i64, dh: i64) -> Result<(u32, u32)> {
        let w = pl.props.int_in("width", dw, 1, MAX_FILM_SIDE)?;
        let h = pl.props.int_in("height", dh, 1, MAX_FILM_SIDE)?;
        if w * h > MAX_FILM_PIXELS {
            return Err(err(
                pl.loc(),
                format!("film of {w}×{h} pixels is too large (at most {MAX_FILM_PIXELS} pixels)"),
            ));
        }
        Ok((w as u32, h as u32))
    }

    fn film(&mut self, pl: &Plugin<'s>) -> Result<Film> {
        if !matches!(pl.ty.as_str(), "hdrfilm" | "ldrfilm" | "specfilm" | "mfilm") {
            return Err(unknown_type(pl, "hdrfilm (ldrfilm, specfilm accepted)"));
        }
        let (width, height) = self.resolution(pl, 768, 576)?;
        let crop = if [
            "crop_offset_x",
            "crop_offset_y",
            "crop_width",
            "crop_height",
        ]
        .iter()
        .any(|n| pl.props.has(n))
        {
            let ox = pl.props.int_in("crop_offset_x", 0, 0, width as i64 - 1)?;
            let oy = pl.props.int_in("crop_offset_y", 0, 0, height as i64 - 1)?;
            let cw = pl
                .props
                .int_in("crop_width", width as i64 - ox, 1, width as i64 - ox)?;
            let ch = pl
                .props
                .int_in("crop_height", height as i64 - oy, 1, height as i64 - oy)?;
            Some(CropWindow {
                offset_x: ox as u32,
                offset_y: oy as u32,
                width: cw as u32,
                height: ch as u32,
            })
        } else {
            None
        };
        // Output-format options: they do not change the image we compute.
        for n in [
            "pixel_format",
            "component_format",
            "file_format",
            "banner",
            "high_quality_edges",
            "sample_border",
            "compensate",
            "tonemap_method",
            "gamma",
            "exposure",
        ] {
            let _ = pl.props.get(n);
        }
        let mut filter = FilterDesc::Gaussian {
            stddev: 0.5,
            radius: 2.0,
        };
        for c in &pl.children {
            if c.elem.tag != "rfilter" {
                return Err(err(
                    &c.loc,
                    format!("<{}> cannot be nested in a film", c.elem.tag),
                ));
            }
            let fp = self.ctx.plugin(c.elem)?;
            filter = self.rfilter(&fp)?;
            self.ctx.finish(&fp);
        }
        Ok(Film {
            width,
            height,
            crop,
            filter,
            output: None,
            tonemap: None,
        })
    }

    fn fov(&mut self, pl: &Plugin<'s>, nori: bool) -> Result<(f32, FovAxis)> {
        let axis = match pl.props.string_opt("fov_axis")? {
            None => FovAxis::X,
            Some((s, loc)) => match s.to_ascii_lowercase().as_str() {
                "x" => FovAxis::X,
                "y" => FovAxis::Y,
                "diagonal" => FovAxis::Diagonal,
                "smaller" => FovAxis::Smaller,
                "larger" => FovAxis::Larger,
                _ => {
                    return Err(err(
                        loc,
                        format!("unknown fov_axis '{s}' (x, y, diagonal, smaller, larger)"),
                    ));
                }
            },
        };
        if let Some(fov) = pl.props.float_opt("fov")? {
            if pl.props.has("focal_length") {
                return Err(err(
                    pl.loc(),
                    "give either 'fov' or 'focal_length', not both",
                ));
            }
            if !(fov > 0.0 && fov < 180.0) {
                return Err(err(
                    &pl.props
                        .get("fov")
                        .map_or(pl.loc().clone(), |p| p.loc.clone()),
                    format!("fov must be in (0, 180) degrees, found {fov}"),
                ));
            }
            return Ok((fov, axis));
        }
        if nori {
            return Ok((30.0, FovAxis::X));
        }
        // Mitsuba: 35 mm-equivalent focal length (default 50mm) → diagonal field of view.
        let f = match pl.props.get("focal_length") {
            None => 50.0,
            Some(p) => {
                let v = match &p.value {
                    Value::Str(s) => {
                        let t = s.trim().trim_end_matches("mm");
                        super::props::parse_float(t, &p.loc)?
                    }
                    Value::Float(v) => *v,
                    Value::Int(v) => *v as f64,
                    _ => return Err(err(&p.loc, "focal_length should be like \"50mm\"")),
                };
                if v <= 0.0 {
                    return Err(err(&p.loc, "focal_length must be positive"));
                }
                v as f32
            }
        };
        let diag = (36.0f32 * 36.0 + 24.0 * 24.0).sqrt();
        Ok((
            2.0 * (diag / (2.0 * f)).atan().to_degrees(),
            FovAxis::Diagonal,
        ))
    }

    /// A sensor; `on_shape` is the index of the shape it is nested in (an irradiance meter).
    fn sensor(&mut self, pl: &Plugin<'s>, on_shape: Option<usize>) -> Result<()> {
        let nori = pl.elem.tag == "camera";
        let mut to_world = pl.props.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let (near_default, far_default) = if nori { (1e-4, 1e4) } else { (1e-2, 1e4) };
        let near_clip = pl.props.float("near_clip", near_default)?;
        let far_clip = pl.props.float("far_clip", far_default)?;
        if !(near_clip > 0.0 && far_clip > near_clip) {
            return Err(err(
                pl.loc(),
                format!("need 0 < near_clip < far_clip, found {near_clip} and {far_clip}"),
            ));
        }
        if on_shape.is_some() != (pl.ty == "irradiancemeter") {
            return Err(err(
                pl.loc(),
                if on_shape.is_some() {
                    format!("a '{}' sensor cannot be nested in a shape", pl.ty)
                } else {
                    "an irradiancemeter is nested in the shape it measures".to_string()
                },
            ));
        }
        let projection = match pl.ty.as_str() {
            "irradiancemeter" => {
                if pl.props.has("to_world") {
                    // Mitsuba: "Found a 'to_world' transformation -- this is not allowed".
                    return Err(err(
                        pl.loc(),
                        "an irradiancemeter takes its place from its shape, not a to_world",
                    ));
                }
                Projection::IrradianceMeter {
                    shape: on_shape.unwrap_or_default(),
                }
            }
            "perspective" => {
                let (fov, fov_axis) = self.fov(pl, nori)?;
                if !nori {
                    // Used only by thinlens; Mitsuba's perspective accepts and ignores it.
                    let _ = pl.props.float_opt("focus_distance")?;
                }
                Projection::Perspective { fov, fov_axis }
            }
            "thinlens" => {
                let (fov, fov_axis) = self.fov(pl, nori)?;
                Projection::ThinLens {
                    fov,
                    fov_axis,
                    aperture_radius: pl.props.float("aperture_radius", 1.0)?,
                    focus_distance: pl.props.float("focus_distance", 0.0)?,
                }
            }
            "orthographic" => Projection::Orthographic,
            "radiancemeter" => {
                // Mitsuba: `origin` and `direction`, or a to_world (not both).
                let origin = pl.props.vector_opt("origin")?;
                let direction = pl.props.vector_opt("direction")?;
                if origin.is_some() || direction.is_some() {
                    if pl.props.has("to_world") {
                        return Err(err(
                            pl.loc(),
                            "radiancemeter: give either to_world or origin and direction",
                        ));
                    }
                    let (Some(o), Some(d)) = (origin, direction) else {
                        return Err(err(
                            pl.loc(),
                            "radiancemeter: 'origin' and 'direction' go together",
                        ));
                    };
                    let d = d.normalize_or_zero();
                    if d == Vec3::ZERO {
                        return Err(err(pl.loc(), "radiancemeter: direction must be non-zero"));
                    }
                    let (s, t) = coordinate_system(d);
                    to_world =
                        Mat4::from_cols(s.extend(0.0), t.extend(0.0), d.extend(0.0), o.extend(1.0));
                }
                Projection::RadianceMeter
            }
            _ => {
                return Err(unknown_type(
                    pl,
                    "perspective, thinlens, orthographic, radiancemeter, irradiancemeter",
                ));
            }
        };
        let mut film = None;
        let mut sampler = None;
        let mut filter = None;
        let mut medium = None;
        for c in &pl.children {
            if c.elem.tag == "medium" {
                medium = Some(self.medium(c)?);
                continue;
            }
            let cp = self.ctx.plugin(c.elem)?;
            match c.elem.tag.as_str() {
                "film" => film = Some(self.film(&cp)?),
                "sampler" => sampler = Some(self.sampler(&cp)?),
                "rfilter" => filter = Some(self.rfilter(&cp)?),
                other => {
                    return Err(err(
                        &c.loc,
                        format!("<{other}> cannot be nested in a sensor"),
                    ));
                }
            }
            self.ctx.finish(&cp);
        }
        let film = match film {
            Some(f) => f,
            None if nori => {
                let (width, height) = self.resolution(pl, 1280, 720)?;
                Film {
                    width,
                    height,
                    crop: None,
                    filter: filter.unwrap_or(FilterDesc::Gaussian {
                        stddev: 0.5,
                        radius: 2.0,
                    }),
                    output: None,
                    tonemap: None,
                }
            }
            None => Film {
                width: 768,
                height: 576,
                crop: None,
                filter: filter.unwrap_or(FilterDesc::Gaussian {
                    stddev: 0.5,
                    radius: 2.0,
                }),
                output: None,
                tonemap: None,
            },
        };
        if matches!(
            projection,
            Projection::RadianceMeter | Projection::IrradianceMeter { .. }
        ) && (film.width, film.height) != (1, 1)
        {
            // As Mitsuba: "This sensor only supports films of size 1x1 Pixels!".
            return Err(err(
                pl.loc(),
                format!(
                    "a {} takes a 1×1 film, found {}×{}",
                    pl.ty, film.width, film.height
                ),
            ));
        }
        self.ctx.finish(pl);
        self.sensor_has_sampler.push(sampler.is_some());
        self.scene.sensors.push(Sensor {
            medium,
            camera: Camera {
                projection,
                to_world,
                near_clip,
                far_clip,
            },
            film,
            sampler: sampler.unwrap_or_else(|| self.default_sampler()),
            integrator: None,
            name: pl
                .elem
                .value("id")
                .or_else(|| pl.elem.value("name"))
                .map(str::to_string),
            loc: pl.loc().clone(),
        });
        Ok(())
    }

    // -----------------------------------------------------------------------------------------
    // Integrators

    fn integrator(&mut self, pl: &Plugin<'s>) -> Result<IntegratorDesc> {
        let i = match pl.ty.as_str() {
            // Mitsuba 3's `prb`/`prbvolpath` render (forward) what `path`/`volpath` render.
            "volpath" | "volpathmis" | "prbvolpath" => IntegratorDesc::VolPath {
                max_depth: pl.props.int_in("max_depth", -1, -1, i32::MAX as i64)? as i32,
                rr_depth: pl.props.int_in("rr_depth", 5, 0, u32::MAX as i64)? as u32,
                hide_emitters: pl.props.bool("hide_emitters", false)?,
                equiangular: pl.props.bool("equiangular", true)?,
                sample_emission: pl.props.bool("sample_emission", false)?,
                transmittance: match pl.props.string_opt("transmittance")? {
                    None => TransmittanceEstimator::default(),
                    Some((name, loc)) => {
                        TransmittanceEstimator::from_name(name).ok_or_else(|| {
                            err(
                                loc,
                                format!(
                                    "transmittance '{name}': expected one of {}",
                                    TransmittanceEstimator::ALL.map(|e| e.name()).join(", ")
                                ),
                            )
                        })?
                    }
                },
            },
            "path" | "prb" => IntegratorDesc::Path(PathDesc {
                max_depth: pl.props.int_in("max_depth", -1, -1, i32::MAX as i64)? as i32,
                rr: RussianRoulette::Throughput {
                    from_depth: pl.props.int_in("rr_depth", 5, 0, u32::MAX as i64)? as u32,
                },
                hide_emitters: pl.props.bool("hide_emitters", false)?,
                // Our extension: path guiding (`docs/formats.md`).
                guiding: pl.props.bool("guiding", false)?,
                ..PathDesc::default()
            }),
            "direct" => {
                let shading = pl.props.int_in("shading_samples", 1, 0, 1 << 20)?;
                IntegratorDesc::Direct {
                    emitter_samples: pl.props.int_in("emitter_samples", shading, 0, 1 << 20)?
                        as u32,
                    bsdf_samples: pl.props.int_in("bsdf_samples", shading, 0, 1 << 20)? as u32,
                }
            }
            // Mitsuba 0.6's parameters and defaults (camelCase arrives as snake_case):
            // photonCount per pass (250 000), initialRadius (0: guess), alpha (0.7),
            // maxDepth (−1), rrDepth (3), maxPasses (−1: until stopped; here the sensor's
            // sample count, as `--spp`), granularity (the size of its scheduler's work units;
            // read and ignored: our photon chunks are fixed so that the image does not
            // depend on the thread count); `ppm` also takes our `eye_samples` (visible
            // points per pixel, 4).
            "sppm" | "ppm" => {
                pl.props.int_in("granularity", 0, -1, i32::MAX as i64)?;
                let passes = match pl.props.int_in("max_passes", -1, -1, u32::MAX as i64)? {
                    n if n > 0 => Some(n as u32),
                    _ => None,
                };
                let initial_radius = match pl.props.float_opt("initial_radius")? {
                    Some(r) if r > 0.0 && r.is_finite() => Some(r),
                    Some(0.0) | None => None,
                    Some(r) => {
                        return Err(err(
                            pl.loc(),
                            format!("{}: initialRadius = {r} must be ≥ 0 (0: guess one)", pl.ty),
                        ));
                    }
                };
                let alpha = match pl.props.float("alpha", 0.7)? {
                    a if a > 0.0 && a <= 1.0 => a,
                    a => {
                        return Err(err(
                            pl.loc(),
                            format!("{}: alpha = {a} must lie in (0, 1]", pl.ty),
                        ));
                    }
                };
                IntegratorDesc::Sppm(SppmDesc {
                    max_depth: pl.props.int_in("max_depth", -1, -1, i32::MAX as i64)? as i32,
                    rr_depth: pl.props.int_in("rr_depth", 3, 0, u32::MAX as i64)? as u32,
                    photons: Some(pl.props.int_in("photon_count", 250_000, 1, 1 << 40)? as u64),
                    initial_radius,
                    alpha,
                    fixed_eye_samples: (pl.ty == "ppm")
                        .then(|| pl.props.int_in("eye_samples", 4, 1, 1 << 16))
                        .transpose()?
                        .map(|n| n as u32),
                    passes,
                })
            }
            "photonmapper" => IntegratorDesc::Photon(self.photon_mapper(pl)?),
            // Mitsuba 3's particle tracer (max_depth, hide_emitters; rr_depth and
            // samples_per_pass read: the photon tracer's roulette and one light path per
            // pixel and pass are ours) and Mitsuba 0.6's (maxDepth, rrDepth, granularity,
            // bruteForce read likewise).
            // Mitsuba 0.6's bdpt: maxDepth; rrDepth, lightImage and sampleDirect read (our
            // roulette starts at 5 vertices; light tracing and light sampling are always on);
            // pbrt-v4's visualizeStrategies / visualizeWeights (per-strategy images).
            "bdpt" => {
                pl.props.int_in("rr_depth", 5, 0, u32::MAX as i64)?;
                pl.props.bool("light_image", true)?;
                pl.props.bool("sample_direct", true)?;
                IntegratorDesc::Bdpt {
                    max_depth: pl.props.int_in("max_depth", -1, -1, i32::MAX as i64)? as i32,
                    visualize_strategies: pl.props.bool("visualize_strategies", false)?,
                    visualize_weights: pl.props.bool("visualize_weights", false)?,
                }
            }
            // Mitsuba 0.6's pssmlt/mlt (maxDepth, pLarge, luminanceSamples as the bootstrap,
            // directSamples, chains as ours; its other mutation settings are read and do not apply: ours
            // are primary-sample-space mutations of every strategy) and pbrt-v3's names.
            // `multiplexed` (ours): true, the default, multiplexes the chains over BDPT's
            // strategies (pbrt-v3's MLTIntegrator); false makes a state a whole BDPT sample
            // (Kelemen 2002), which is what Mitsuba 0.6's own pssmlt does.
            "pssmlt" | "mlt" => {
                pl.props.int_in("rr_depth", 5, 0, u32::MAX as i64)?;
                pl.props.bool("bidirectional", true)?;
                pl.props.bool("two_stage", false)?;
                IntegratorDesc::Mlt {
                    direct_samples: pl.props.int_in("direct_samples", 16, -1, 1 << 20)? as i32,
                    max_depth: pl.props.int_in("max_depth", -1, -1, i32::MAX as i64)? as i32,
                    bootstrap: pl.props.int_in("luminance_samples", 100_000, 1, 1 << 30)? as u32,
                    chains: pl.props.int_in("chains", 1000, 1, 1 << 24)? as u32,
                    large_step: pl.props.float("p_large", 0.3)?.clamp(0.0, 1.0),
                    sigma: pl.props.float("sigma", 0.01)?.max(1e-6),
                    multiplexed: pl.props.bool("multiplexed", true)?,
                }
            }
            "ptracer" => {
                pl.props.int_in("rr_depth", 5, 0, u32::MAX as i64)?;
                pl.props
                    .int_in("samples_per_pass", -1, -1, i32::MAX as i64)?;
                pl.props.int_in("granularity", 0, -1, i32::MAX as i64)?;
                pl.props.bool("brute_force", false)?;
                IntegratorDesc::Ptracer {
                    max_depth: pl.props.int_in("max_depth", -1, -1, i32::MAX as i64)? as i32,
                    hide_emitters: pl.props.bool("hide_emitters", false)?,
                }
            }
            "whitted" => IntegratorDesc::Whitted {
                // Nori's whitted has no depth limit (specular chains end by Russian roulette).
                max_depth: pl
                    .props
                    .int_in("max_depth", u32::MAX as i64, 0, u32::MAX as i64)?
                    as u32,
            },
            "normals" => IntegratorDesc::Normals,
            "albedo" => IntegratorDesc::Albedo,
            "depth" => IntegratorDesc::Depth,
            "ao" => IntegratorDesc::AmbientOcclusion {
                samples: pl.props.int_in("shading_samples", 1, 1, 1 << 20)? as u32,
                length: pl.props.float_opt("length")?,
            },
            "aov" => {
                let (aovs, loc) = pl
                    .props
                    .string_opt("aovs")?
                    .map(|(s, l)| (s.to_string(), l.clone()))
                    .unwrap_or_default();
                let kinds: Vec<&str> = aovs
                    .split(',')
                    .filter_map(|t| t.split(':').nth(1))
                    .map(str::trim)
                    .collect();
                match kinds[..] {
                    ["sh_normal"] | ["geo_normal"] => IntegratorDesc::Normals,
                    ["albedo"] => IntegratorDesc::Albedo,
                    ["depth"] => IntegratorDesc::Depth,
                    _ => {
                        return Err(err(
                            &loc,
                            format!(
                                "aov integrator: only one of sh_normal, geo_normal, albedo, \
                                 depth is supported, found '{aovs}'"
                            ),
                        ));
                    }
                }
            }
            "simple" => IntegratorDesc::NoriSimple,
            "direct_ems" => IntegratorDesc::Nori(NoriIntegrator::DirectEms),
            "direct_mats" => IntegratorDesc::Nori(NoriIntegrator::DirectMats),
            "direct_mis" => IntegratorDesc::Nori(NoriIntegrator::DirectMis),
            "path_mats" => IntegratorDesc::Nori(NoriIntegrator::PathMats),
            "path_ems" => IntegratorDesc::Nori(NoriIntegrator::PathEms),
            "path_mis" => IntegratorDesc::Nori(NoriIntegrator::PathMis),
            _ => {
                return Err(unknown_type(
                    pl,
                    "path, direct, photonmapper, sppm, ppm, ptracer, bdpt, pssmlt, mlt, normals, albedo, depth, aov, ao, whitted, simple, \
                     direct_ems, direct_mats, direct_mis, path_mats, path_ems, path_mis",
                ));
            }
        };
        Ok(i)
    }

    /// `photonmapper`: Nori's (`photonCount`, `photonRadius`: every photon within the radius,
    /// default 1/500 of the scene's bounding-box diagonal, read directly — no final
    /// gathering) when either of its parameters is given, else Mitsuba 0.6's
    /// (`globalPhotons` emitted, `lookupSize` nearest photons within `globalLookupRadius` /
    /// `causticLookupRadius` of the scene's size, `directSamples`, `maxDepth`; its maps are
    /// read directly too; `volumeLookupSize`, see [`PhotonLookupDesc::calibrated`]). Our
    /// own: `final_gather` rays, `kernel` (box, cone, epanechnikov).
    fn photon_mapper(&self, pl: &Plugin<'s>) -> Result<PhotonDesc> {
        let p = &pl.props;
        let nori = p.has("photon_count") || p.has("photon_radius");
        let kernel = match p.string_opt("kernel")? {
            None => PhotonKernel::Box,
            Some((name, loc)) => PhotonKernel::from_name(name).ok_or_else(|| {
                err(
                    loc,
                    format!("kernel '{name}': expected box, cone or epanechnikov"),
                )
            })?,
        };
        let positive = |name: &str, default: f32| -> Result<f32> {
            let v = p.float(name, default)?;
            if v > 0.0 && v.is_finite() {
                Ok(v)
            } else {
                Err(err(
                    pl.loc(),
                    format!("{}: {name} = {v} must be > 0", pl.ty),
                ))
            }
        };
        let final_gather = p.int_in("final_gather", 0, 0, 1 << 16)? as u32;
        let max_depth = p.int_in("max_depth", -1, -1, i32::MAX as i64)? as i32;
        if nori {
            // Nori: 0 means "the bounding-box diagonal / 500" = the bounding radius / 250.
            let radius = p.float("photon_radius", 0.0)?;
            let lookup = if radius > 0.0 && radius.is_finite() {
                PhotonLookupDesc {
                    k: None,
                    radius: Some(radius),
                    relative: false,
                    calibrated: false,
                }
            } else if radius == 0.0 {
                PhotonLookupDesc {
                    k: None,
                    radius: Some(1.0 / 250.0),
                    relative: true,
                    calibrated: false,
                }
            } else {
                return Err(err(
                    pl.loc(),
                    format!("photonmapper: photonRadius = {radius} must be ≥ 0"),
                ));
            };
            return Ok(PhotonDesc {
                max_depth,
                photons: p.int_in("photon_count", 1_000_000, 1, 1 << 40)? as u64,
                global: lookup,
                caustic: lookup,
                volume: lookup,
                kernel,
                final_gather,
                direct_samples: 1,
            });
        }
        let k = p.int_in("lookup_size", 120, 1, 1 << 20)? as u32;
        Ok(PhotonDesc {
            max_depth,
            photons: p.int_in("global_photons", 250_000, 1, 1 << 40)? as u64,
            global: PhotonLookupDesc {
                k: Some(k),
                radius: Some(positive("global_lookup_radius", 0.05)?),
                relative: true,
                calibrated: false,
            },
            caustic: PhotonLookupDesc {
                k: Some(k),
                radius: Some(positive("caustic_lookup_radius", 0.0125)?),
                relative: true,
                calibrated: false,
            },
            // Mitsuba 0.6 reads `volumeLookupSize` nearest photons; ours are capped (see
            // `PhotonLookupDesc::calibrated`).
            volume: PhotonLookupDesc {
                k: Some(p.int_in("volume_lookup_size", 120, 1, 1 << 20)? as u32),
                radius: None,
                relative: false,
                calibrated: true,
            },
            kernel,
            final_gather,
            direct_samples: p.int_in("direct_samples", 1, 1, 1 << 16)? as u32,
        })
    }

    // -----------------------------------------------------------------------------------------
    // Scene

    /// Add every object of a `<scene>` element.
    pub fn scene_children(&mut self, scene: &'s Elem) -> Result<()> {
        let pl = self.ctx.plugin(scene)?;
        for c in &pl.children {
            match c.elem.tag.as_str() {
                "shape" | "mesh" => {
                    let cp = self.ctx.plugin(c.elem)?;
                    self.shape(&cp)?;
                }
                // Declarations (usually with an id): instantiated once, used through <ref>.
                "bsdf" => {
                    self.material(c)?;
                }
                "texture" => {
                    self.texture(c)?;
                }
                "emitter" => {
                    let cp = self.ctx.plugin(c.elem)?;
                    if let Some(e) = self.emitter(&cp)? {
                        let mut medium = None;
                        for m in cp.children.iter().filter(|m| m.elem.tag == "medium") {
                            medium = Some(self.medium(m)?);
                        }
                        self.scene.emitters.push(EmitterDesc {
                            medium,
                            name: c.id().map(str::to_string),
                            emitter: e,
                            loc: cp.loc().clone(),
                        });
                    }
                    self.ctx.finish(&cp);
                }
                "sensor" | "camera" => {
                    let cp = self.ctx.plugin(c.elem)?;
                    self.sensor(&cp, None)?;
                }
                "integrator" => {
                    if self.has_integrator {
                        return Err(err(&c.loc, "more than one <integrator>"));
                    }
                    let cp = self.ctx.plugin(c.elem)?;
                    self.scene.integrator = self.integrator(&cp)?;
                    self.has_integrator = true;
                    self.ctx.finish(&cp);
                }
                "sampler" => {
                    let cp = self.ctx.plugin(c.elem)?;
                    self.top_sampler = Some(self.sampler(&cp)?);
                    self.ctx.finish(&cp);
                }
                // Declared media are instantiated (and checked) once, used through <ref>.
                "medium" => {
                    self.medium(c)?;
                }
                "phase" | "volume" => {
                    let cp = self.ctx.plugin(c.elem)?;
                    self.ctx.finish(&cp);
                }
                other => {
                    return Err(err(&c.loc, format!("<{other}> cannot appear in a <scene>")));
                }
            }
        }
        self.ctx.finish(&pl);
        Ok(())
    }

    /// Apply scene-level defaults and return the scene.
    pub fn finish(mut self, loc: &Loc) -> SceneDesc {
        if let Some(s) = &self.top_sampler {
            for (sensor, own) in self.scene.sensors.iter_mut().zip(&self.sensor_has_sampler) {
                if !own {
                    sensor.sampler = s.clone();
                }
            }
        }
        let uses_media = self.scene.shapes.iter().any(|s| s.media.is_transition())
            || self.scene.sensors.iter().any(|s| s.medium.is_some());
        if !self.has_integrator && uses_media {
            // Media need the volumetric path tracer; with its defaults.
            self.scene.integrator = IntegratorDesc::VolPath {
                max_depth: -1,
                rr_depth: 5,
                hide_emitters: false,
                equiangular: true,
                transmittance: TransmittanceEstimator::default(),
                sample_emission: false,
            };
        } else if !self.has_integrator && self.ctx.dialect == Dialect::Legacy {
            self.ctx.warn(
                loc,
                "no <integrator> given: using 'path' (Mitsuba's default)",
            );
        }
        if self.scene.sensors.is_empty() {
            let sensor = default_sensor(&self.scene, loc);
            let mut sensor = sensor;
            if let Some(s) = &self.top_sampler {
                sensor.sampler = s.clone();
            } else {
                sensor.sampler = self.default_sampler();
            }
            self.ctx.warn(
                loc,
                "no sensor given: using a 45° perspective camera framing the scene from −z \
                 (Mitsuba's default)",
            );
            self.scene.sensors.push(sensor);
        }
        self.scene
    }
}

/// Mitsuba's fallback camera: 45° field of view, looking along +z at the scene's bounding box
/// from `distance` in front of its near face.
fn default_sensor(scene: &SceneDesc, loc: &Loc) -> Sensor {
    let fov = 45.0f32;
    let (to_world, near_clip, far_clip) = match scene.bounds() {
        Some((lo, hi)) => {
            let center = (lo + hi) * 0.5;
            let extents = hi - lo;
            let max_ext = extents.max_element().max(1e-6);
            let distance = max_ext / (2.0 * (0.5 * fov).to_radians().tan());
            (
                Mat4::from_translation(Vec3::new(center.x, center.y, lo.z - distance)),
                distance / 100.0,
                max_ext * 5.0 + distance,
            )
        }
        None => (Mat4::IDENTITY, 1e-2, 1e4),
    };
    Sensor {
        medium: None,
        camera: Camera {
            projection: Projection::Perspective {
                fov,
                fov_axis: FovAxis::X,
            },
            to_world,
            near_clip,
            far_clip,
        },
        film: Film {
            width: 768,
            height: 576,
            crop: None,
            filter: FilterDesc::Gaussian {
                stddev: 0.5,
                radius: 2.0,
            },
            output: None,
            tonemap: None,
        },
        sampler: SamplerDesc::default(),
        integrator: None,
        name: None,
        loc: loc.clone(),
    }
}

/// Parse a Nori list parameter (`references`, `angles`): numbers separated by commas/spaces.
pub fn float_list(pl: &Plugin<'_>, name: &str) -> Result<Vec<f32>> {
    match pl.props.get(name) {
        None => Ok(Vec::new()),
        Some(p) => match &p.value {
            Value::Str(s) => Ok(parse_floats(s, &p.loc)?
                .into_iter()
                .map(|v| v as f32)
                .collect()),
            Value::Float(v) => Ok(vec![*v as f32]),
            Value::Int(v) => Ok(vec![*v as f32]),
            _ => Err(err(&p.loc, format!("'{name}' should be a list of numbers"))),
        },
    }
}

/// Mitsuba's `coordinate_system(n)` (Duff et al. 2017): the tangents `s`, `t` of its
/// `Frame3f(n)`, which fix where a cylinder's φ = 0 lies.
fn coordinate_system(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}
