//! pbrt-v4 entities → the scene model: spectra, textures, materials, media, lights, and the
//! options (camera, film, sampler, filter, integrator) at the end. pbrt-v4's defaults
//! throughout; what has no exact counterpart is warned about or refused here.

use std::sync::Arc;

use glam::{Mat3, Mat4, Vec3};

use super::params::{Param, Params, Ty, Vals};
use super::parser::{Loader, TexVal};
use crate::formats::mitsuba::ior;
use crate::model::*;
use crate::spectra::{self, SpectrumUse};
use crate::{LoadError, Loc, Result};
use base::dispersion::{D_LINE_NM, Dispersion};

/// Largest accepted film side and pixel count (as the other loaders).
const MAX_FILM_SIDE: i64 = 1 << 16;
const MAX_FILM_PIXELS: i64 = 1 << 28;

/// pbrt-v4 treats a microfacet distribution as a perfect specular one below this α.
const SMOOTH_ALPHA: f32 = 1e-3;

/// How a spectrum parameter is used: pbrt-v4's `SpectrumType`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Usage {
    Albedo,
    Unbounded,
    Illuminant,
}

impl Usage {
    fn spectrum_use(self) -> SpectrumUse {
        match self {
            Usage::Albedo => SpectrumUse::Reflectance,
            Usage::Unbounded => SpectrumUse::Unbounded,
            Usage::Illuminant => SpectrumUse::Emission,
        }
    }
}

fn err(loc: &Loc, m: impl Into<String>) -> LoadError {
    LoadError::new(loc.clone(), m)
}

/// The nodes of a spectrum kind over the visible range (1 nm), for conversions.
fn nodes(kind: &SpectrumKind) -> (Vec<f64>, Vec<f64>) {
    if let Some((w, v)) = kind.table() {
        return (w.into_owned(), v.into_owned());
    }
    let w: Vec<f64> = (360..=830).map(f64::from).collect();
    let v = w
        .iter()
        .map(|&l| match kind {
            SpectrumKind::Uniform(u) => *u,
            SpectrumKind::Blackbody { temperature } => spectra::planck(l, *temperature),
            _ => 0.0,
        })
        .collect();
    (w, v)
}

/// Luminance of a spectrum in the model's units (a flat unit spectrum has 1).
fn luminance(kind: &SpectrumKind) -> f64 {
    let mut y = 0.0;
    let mut norm = 0.0;
    let desc = SpectrumDesc {
        rgb: Rgb::ZERO,
        kind: kind.clone(),
        scale: 1.0,
    };
    for l in 360..=830 {
        let l = f64::from(l);
        let ybar = spectra::cie1931_xyz(l)[1];
        y += ybar * desc.eval(l);
        norm += ybar;
    }
    y / norm
}

/// A declared spectrum with pbrt-v4's normalisation: illuminants to unit luminance (pbrt-v4
/// divides every light's spectrum by its photometric integral), black bodies elsewhere to a
/// peak of 1 (pbrt-v4's `BlackbodySpectrum`).
fn declared(kind: SpectrumKind, usage: Usage, loc: &Loc) -> Result<ColorValue> {
    let scale = match (&kind, usage) {
        (_, Usage::Illuminant) => {
            let y = luminance(&kind);
            if !(y > 0.0 && y.is_finite()) {
                return Err(err(loc, "an emission spectrum with no luminance"));
            }
            1.0 / y
        }
        (SpectrumKind::Blackbody { temperature }, _) => {
            let peak = 2.897_772_1e6 / temperature;
            1.0 / spectra::planck(peak, *temperature)
        }
        _ => 1.0,
    };
    let rgb = match &kind {
        SpectrumKind::Conductor { material, eta } => {
            let (e, k) = ior::conductor(material).expect("a known conductor");
            if *eta { e } else { k }
        }
        _ => {
            let (w, v) = nodes(&kind);
            spectra::sampled_to_rgb(&w, &v, usage.spectrum_use())
                .map_err(|e| err(loc, e.to_string()))?
                * scale as f32
        }
    };
    Ok(ColorValue::Spectrum(Arc::new(SpectrumDesc {
        rgb,
        kind,
        scale,
    })))
}

/// pbrt-v4's named metals (`metal-Cu-eta`...) that Mitsuba's measured tables hold.
fn named_metal(name: &str) -> Option<SpectrumKind> {
    let rest = name.strip_prefix("metal-")?;
    let (metal, part) = rest.rsplit_once('-')?;
    let eta = match part {
        "eta" => true,
        "k" => false,
        _ => return None,
    };
    ior::measured(metal)?;
    Some(SpectrumKind::Conductor {
        material: metal.to_string(),
        eta,
    })
}

/// pbrt-v4's spellings of its named glasses, as `Dispersion::named` knows them.
fn named_glass(name: &str) -> Option<Dispersion> {
    name.starts_with("glass-")
        .then(|| Dispersion::named(&name.to_ascii_lowercase()))
        .flatten()
}

impl Loader {
    /// A spectrum file: pairs of wavelength (nm) and value, `#` comments.
    fn spectrum_file(&self, name: &str, p: &Param) -> Result<SpectrumKind> {
        let path = self.resolve(name);
        let bytes = base::read_file(&path).map_err(|e| {
            p.err(format!(
                "'{name}' is neither a named spectrum nor a readable file ({}: {e})",
                path.display()
            ))
        })?;
        let text = String::from_utf8_lossy(&bytes);
        let mut nums = Vec::new();
        for line in text.lines() {
            let line = line.split('#').next().unwrap_or("");
            for w in line.split_whitespace() {
                let v = super::parser::parse_number(w).ok_or_else(|| {
                    p.err(format!(
                        "spectrum file {}: '{w}' is not a number",
                        path.display()
                    ))
                })?;
                nums.push(v);
            }
        }
        tabulated(&nums, p)
    }

    /// The colour value of an `rgb`, `spectrum` or `blackbody` parameter.
    pub(super) fn spectrum_value(&self, p: &Param, usage: Usage) -> Result<ColorValue> {
        match p.ty {
            Ty::Rgb => {
                // Lists of several colours are read where they are meant (grid media).
                let v = p.nums();
                if v.len() != 3 {
                    return Err(p.err(format!("expected 3 values, found {}", v.len())));
                }
                let c = Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32);
                if usage != Usage::Illuminant && c.min_element() < 0.0 {
                    return Err(p.err("negative RGB component"));
                }
                Ok(ColorValue::Rgb(c))
            }
            Ty::Blackbody => {
                let t = p.nums()[0];
                if t <= 0.0 {
                    return Err(p.err("the temperature must be positive"));
                }
                let v = declared(SpectrumKind::Blackbody { temperature: t }, usage, &p.loc)?;
                // pbrt-v3's second value was a scale.
                Ok(match p.nums().get(1) {
                    Some(&s) => v.divided(1.0 / s as f32),
                    None => v,
                })
            }
            Ty::Spectrum => {
                let kind = match &p.vals {
                    Vals::Nums(v) => tabulated(v, p)?,
                    Vals::Strs(s) => {
                        let name = s[0].as_str();
                        if let Some(k) = named_metal(name) {
                            k
                        } else if name == "stdillum-D65" {
                            SpectrumKind::D65
                        } else if name == "stdillum-A" {
                            // CIE illuminant A is Planck's law at 2856 K.
                            SpectrumKind::Blackbody {
                                temperature: 2856.0,
                            }
                        } else if name.starts_with("glass-") {
                            return Err(p.err(format!(
                                "'{name}' is an index of refraction: only a dielectric's \
                                 'eta' takes it"
                            )));
                        } else if name.starts_with("metal-")
                            || name.starts_with("stdillum-")
                            || name.starts_with("illum-")
                            || name.starts_with("canon_")
                            || name.starts_with("nikon_")
                            || name.starts_with("sony_")
                        {
                            return Err(p.err(format!(
                                "named spectrum '{name}' is not available (we have metal-X-eta \
                                 and metal-X-k for Ag, Al, Au, Cu, MgO, TiO2, the glass-* \
                                 indices, stdillum-D65 and stdillum-A)"
                            )));
                        } else {
                            self.spectrum_file(name, p)?
                        }
                    }
                    Vals::Bools(_) => unreachable!("checked at parse time"),
                };
                declared(kind, usage, &p.loc)
            }
            _ => Err(p.err("not a colour")),
        }
    }

    /// A spectrum-valued parameter that may be a texture (`texture`), a colour or, where pbrt
    /// allows it, a float.
    pub(super) fn tex_param(
        &mut self,
        p: &Params,
        name: &str,
        spectrum: bool,
        usage: Usage,
    ) -> Result<Option<TexVal>> {
        let tys: &[Ty] = if spectrum {
            &[Ty::Rgb, Ty::Spectrum, Ty::Blackbody, Ty::Texture, Ty::Float]
        } else {
            &[Ty::Float, Ty::Texture]
        };
        let Some(q) = p.get(name, tys)? else {
            return Ok(None);
        };
        Ok(Some(match q.ty {
            Ty::Texture => {
                let [n] = q.strs() else {
                    return Err(q.err("expected one texture name"));
                };
                let (map, other) = if spectrum {
                    (&self.spectrum_textures, &self.float_textures)
                } else {
                    (&self.float_textures, &self.spectrum_textures)
                };
                match map.get(n) {
                    Some(t) => t.clone(),
                    None if other.contains_key(n) => {
                        return Err(q.err(format!(
                            "'{n}' is a {} texture; this parameter needs a {} one",
                            if spectrum { "float" } else { "spectrum" },
                            if spectrum { "spectrum" } else { "float" },
                        )));
                    }
                    None => return Err(q.err(format!("unknown texture '{n}'"))),
                }
            }
            Ty::Float => {
                let [v] = q.nums() else {
                    return Err(q.err("expected one value"));
                };
                TexVal::Const(Rgb::splat(*v as f32))
            }
            _ => match self.spectrum_value(q, usage)? {
                ColorValue::Rgb(c) => TexVal::Const(c),
                ColorValue::Spectrum(s) => TexVal::Spectrum(s),
            },
        }))
    }

    pub(super) fn color(
        &mut self,
        p: &Params,
        name: &str,
        default: f32,
        usage: Usage,
    ) -> Result<ColorParam> {
        Ok(match self.tex_param(p, name, true, usage)? {
            None => ColorParam::constant(default),
            Some(t) => color_of(t),
        })
    }

    pub(super) fn float(&mut self, p: &Params, name: &str, default: f32) -> Result<FloatParam> {
        Ok(match self.tex_param(p, name, false, Usage::Unbounded)? {
            None => FloatParam::Const(default),
            Some(TexVal::Tex(t)) => FloatParam::Texture(t),
            Some(TexVal::Const(c)) => FloatParam::Const(c.x),
            Some(TexVal::Spectrum(s)) => FloatParam::Const(s.rgb.x),
        })
    }

    /// A constant colour (no texture): conductor indices, light spectra.
    fn value(&mut self, p: &Params, name: &str, usage: Usage) -> Result<Option<ColorValue>> {
        let Some(q) = p.get(
            name,
            &[Ty::Rgb, Ty::Spectrum, Ty::Blackbody, Ty::Float, Ty::Texture],
        )?
        else {
            return Ok(None);
        };
        match q.ty {
            Ty::Texture => Err(q.err("a texture is not supported here (a constant is needed)")),
            Ty::Float => match q.nums() {
                [v] => Ok(Some(ColorValue::Rgb(Rgb::splat(*v as f32)))),
                _ => Err(q.err("expected one value")),
            },
            _ => self.spectrum_value(q, usage).map(Some),
        }
    }

    // -----------------------------------------------------------------------------------------
    // Textures

    pub(super) fn make_texture(
        &mut self,
        name: String,
        spectrum: bool,
        class: &str,
        p: Params,
        loc: &Loc,
    ) -> Result<()> {
        let usage = Usage::Albedo;
        let what = if spectrum { "spectrum" } else { "float" };
        let val = match class {
            "constant" => self
                .tex_param(&p, "value", spectrum, usage)?
                .unwrap_or(TexVal::Const(Rgb::ONE)),
            "scale" => {
                let t = self
                    .tex_param(&p, "tex", spectrum, usage)?
                    .unwrap_or(TexVal::Const(Rgb::ONE));
                let s = self
                    .tex_param(&p, "scale", false, usage)?
                    .unwrap_or(TexVal::Const(Rgb::ONE));
                match (t, s) {
                    (TexVal::Tex(t), TexVal::Const(s)) | (TexVal::Const(s), TexVal::Tex(t))
                        if s.x == s.y && s.y == s.z =>
                    {
                        self.affine(t, s.x, Rgb::ZERO, &name, loc)
                    }
                    (a, b) => match (const_of(&a), const_of(&b)) {
                        (Some(a), Some(b)) => TexVal::Const(a * b),
                        _ => {
                            let product = Texture::Product {
                                a: Box::new(self.inline(&a)),
                                b: Box::new(self.inline(&b)),
                            };
                            self.add_tex(product, &name, loc)
                        }
                    },
                }
            }
            "mix" => {
                let t1 = self
                    .tex_param(&p, "tex1", spectrum, usage)?
                    .unwrap_or(TexVal::Const(Rgb::ZERO));
                let t2 = self
                    .tex_param(&p, "tex2", spectrum, usage)?
                    .unwrap_or(TexVal::Const(Rgb::ONE));
                let a = self
                    .tex_param(&p, "amount", false, usage)?
                    .unwrap_or(TexVal::Const(Rgb::splat(0.5)));
                match (const_of(&t1), const_of(&t2), const_of(&a)) {
                    (Some(x), Some(y), Some(a)) => TexVal::Const(x.lerp(y, a.x)),
                    (None, Some(y), Some(a)) => {
                        let TexVal::Tex(t) = t1 else { unreachable!() };
                        self.affine(t, 1.0 - a.x, y * a.x, &name, loc)
                    }
                    (Some(x), None, Some(a)) => {
                        let TexVal::Tex(t) = t2 else { unreachable!() };
                        self.affine(t, a.x, x * (1.0 - a.x), &name, loc)
                    }
                    _ => {
                        let mix = Texture::Mix {
                            a: Box::new(self.inline(&t1)),
                            b: Box::new(self.inline(&t2)),
                            amount: Box::new(self.inline(&a)),
                        };
                        self.add_tex(mix, &name, loc)
                    }
                }
            }
            "imagemap" => self.imagemap(&name, &p, loc)?,
            "checkerboard" => self.checkerboard(&name, &p, loc)?,
            "bilerp" => {
                let to_uv = self.uv_mapping(&p, &name, loc)?;
                let mut v = [Rgb::ZERO; 4];
                for (i, (key, default)) in [("v00", 0.0), ("v01", 1.0), ("v10", 0.0), ("v11", 1.0)]
                    .iter()
                    .enumerate()
                {
                    let t = self.tex_param(&p, key, spectrum, usage)?;
                    v[i] = match t {
                        None => Rgb::splat(*default),
                        Some(t) => match const_of(&t) {
                            Some(c) => c,
                            None => {
                                return Err(err(
                                    loc,
                                    format!("bilerp '{name}': '{key}' must be a constant"),
                                ));
                            }
                        },
                    };
                }
                let bilerp = Texture::Bilerp {
                    v00: v[0],
                    v01: v[1],
                    v10: v[2],
                    v11: v[3],
                    to_uv,
                };
                self.add_tex(bilerp, &name, loc)
            }
            "fbm" | "wrinkled" | "windy" | "marble" => {
                let octaves = p.int_in("octaves", 8, 1, 64)? as u32;
                let omega = p.float("roughness", 0.5)?;
                let kind = match class {
                    "fbm" => NoiseKind::Fbm { octaves, omega },
                    "wrinkled" => NoiseKind::Wrinkled { octaves, omega },
                    "windy" => NoiseKind::Windy,
                    _ => NoiseKind::Marble {
                        octaves,
                        omega,
                        scale: p.float("scale", 1.0)?,
                        variation: p.float("variation", 0.2)?,
                    },
                };
                let noise = Texture::Noise {
                    kind,
                    to_texture: self.texture_space(),
                };
                self.add_tex(noise, &name, loc)
            }
            "dots" => {
                let to_uv = self.uv_mapping(&p, &name, loc)?;
                let inside = self
                    .tex_param(&p, "inside", spectrum, usage)?
                    .unwrap_or(TexVal::Const(Rgb::ONE));
                let outside = self
                    .tex_param(&p, "outside", spectrum, usage)?
                    .unwrap_or(TexVal::Const(Rgb::ZERO));
                let dots = Texture::Dots {
                    inside: Box::new(self.inline(&inside)),
                    outside: Box::new(self.inline(&outside)),
                    to_uv,
                };
                self.add_tex(dots, &name, loc)
            }
            "directionmix" | "ptex" => {
                self.warn(
                    loc,
                    format!(
                        "{what} texture '{name}': class \"{class}\" is not supported; a constant \
                         0.5 is used"
                    ),
                );
                for q in &p.list {
                    q.used.set(true);
                }
                TexVal::Const(Rgb::splat(0.5))
            }
            _ => {
                return Err(err(
                    loc,
                    format!(
                        "unknown texture class \"{class}\" (pbrt-v4 has constant, scale, mix, \
                         imagemap, checkerboard, bilerp, directionmix, dots, fbm, marble, ptex, \
                         windy, wrinkled)"
                    ),
                ));
            }
        };
        self.finish_params("Texture", class, &p);
        let map = if spectrum {
            &mut self.spectrum_textures
        } else {
            &mut self.float_textures
        };
        map.insert(name, val);
        Ok(())
    }

    /// `t` as an inline model texture (a constant, or a copy of the texture it names).
    fn inline(&self, t: &TexVal) -> Texture {
        match t {
            TexVal::Tex(id) => self.scene.texture(*id).texture.clone(),
            other => Texture::Constant(const_of(other).unwrap_or(Rgb::ZERO)),
        }
    }

    fn add_tex(&mut self, texture: Texture, name: &str, loc: &Loc) -> TexVal {
        TexVal::Tex(self.scene.add_texture(TextureDesc {
            texture,
            name: Some(name.to_string()),
            loc: loc.clone(),
        }))
    }

    /// The world-to-texture transform of a 3D texture: the inverse of the CTM at its
    /// definition (pbrt-v4's `PointTransformMapping`).
    fn texture_space(&self) -> Mat4 {
        let inv = self.gs.ctm[0].inverse();
        if inv.is_finite() { inv } else { Mat4::IDENTITY }
    }

    fn affine(&mut self, t: TextureId, scale: f32, offset: Rgb, name: &str, loc: &Loc) -> TexVal {
        let inner = self.scene.texture(t).texture.clone();
        TexVal::Tex(self.scene.add_texture(TextureDesc {
            texture: Texture::Affine {
                texture: Box::new(inner),
                scale,
                offset,
            },
            name: Some(name.to_string()),
            loc: loc.clone(),
        }))
    }

    /// pbrt-v4's (u, v) mapping as a 2D matrix: s = su·u + du, t = sv·v + dv.
    fn uv_mapping(&mut self, p: &Params, name: &str, loc: &Loc) -> Result<Mat3> {
        let mapping = p.string("mapping", "uv")?;
        if mapping != "uv" {
            self.warn(
                loc,
                format!("texture '{name}': mapping \"{mapping}\" is not supported; uv is used"),
            );
            for n in ["v1", "v2"] {
                let _ = p.get(n, &[Ty::Vector3]);
            }
        }
        let su = p.float("uscale", 1.0)?;
        let sv = p.float("vscale", 1.0)?;
        let du = p.float("udelta", 0.0)?;
        let dv = p.float("vdelta", 0.0)?;
        Ok(Mat3::from_cols(
            Vec3::new(su, 0.0, 0.0),
            Vec3::new(0.0, sv, 0.0),
            Vec3::new(du, dv, 1.0),
        ))
    }

    fn imagemap(&mut self, name: &str, p: &Params, loc: &Loc) -> Result<TexVal> {
        let Some((file, fp)) = p.string_opt("filename")? else {
            return Err(err(
                loc,
                format!("imagemap '{name}' needs a \"string filename\""),
            ));
        };
        let path = self.resolve(file);
        if !path.is_file() {
            return Err(fp.err(format!("image '{}' not found", path.display())));
        }
        let m = self.uv_mapping(p, name, loc)?;
        // pbrt-v4 looks images up at t' = 1 − t with (0, 0) the top-left pixel.
        let flip = Mat3::from_cols(Vec3::X, Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 1.0));
        let filter = match p.string("filter", "bilinear")? {
            "point" => TextureFilter::Nearest,
            "bilinear" => TextureFilter::Bilinear,
            "trilinear" => TextureFilter::Trilinear,
            "ewa" | "EWA" => TextureFilter::Ewa,
            f => {
                return Err(err(
                    loc,
                    format!("imagemap '{name}': unknown filter \"{f}\""),
                ));
            }
        };
        let _ = p.float("maxanisotropy", 8.0)?;
        let wrap = match p.string("wrap", "repeat")? {
            "repeat" => WrapMode::Repeat,
            "clamp" => WrapMode::Clamp,
            "black" => {
                self.warn(
                    loc,
                    format!("imagemap '{name}': wrap \"black\" is not supported; clamp is used"),
                );
                WrapMode::Clamp
            }
            "octahedralsphere" => {
                self.warn(
                    loc,
                    format!(
                        "imagemap '{name}': wrap \"octahedralsphere\" is not supported; repeat \
                         is used"
                    ),
                );
                WrapMode::Repeat
            }
            w => return Err(err(loc, format!("imagemap '{name}': unknown wrap \"{w}\""))),
        };
        // pbrt-v3: `bool gamma` (sRGB or linear) and `bool trilinear`.
        let v3_encoding = match p.get("gamma", &[Ty::Bool])? {
            Some(_) => Some(if p.bool("gamma", false)? {
                "sRGB"
            } else {
                "linear"
            }),
            None => None,
        };
        let v3_trilinear = p.bool("trilinear", false)?;
        // pbrt-v3 filtered with EWA unless `trilinear` was set.
        let filter = if p.has("trilinear") && !p.has("filter") {
            if v3_trilinear {
                TextureFilter::Trilinear
            } else {
                TextureFilter::Ewa
            }
        } else {
            filter
        };
        let encoding = match v3_encoding {
            Some(e) if !p.has("encoding") => e,
            _ => p.string("encoding", "sRGB")?,
        };
        let (raw, gamma) = match encoding {
            "sRGB" | "srgb" => (false, None),
            "linear" => (true, None),
            e => match e
                .strip_prefix("gamma ")
                .and_then(|g| g.trim().parse::<f32>().ok())
            {
                Some(g) if g > 0.0 && g.is_finite() => (false, Some(g)),
                _ => {
                    return Err(err(
                        loc,
                        format!(
                            "imagemap '{name}': unknown encoding \"{e}\" (sRGB, linear or \
                             \"gamma g\")"
                        ),
                    ));
                }
            },
        };
        let scale = p.float("scale", 1.0)?;
        let invert = p.bool("invert", false)?;
        let bitmap = Texture::Bitmap {
            mipmapped: true,
            path,
            filter,
            wrap,
            raw,
            gamma,
            to_uv: flip * m,
            corner_texels: false,
        };
        let texture = if invert {
            Texture::Affine {
                texture: Box::new(bitmap),
                scale: -scale,
                offset: Rgb::ONE,
            }
        } else if scale != 1.0 {
            Texture::Affine {
                texture: Box::new(bitmap),
                scale,
                offset: Rgb::ZERO,
            }
        } else {
            bitmap
        };
        Ok(TexVal::Tex(self.scene.add_texture(TextureDesc {
            texture,
            name: Some(name.to_string()),
            loc: loc.clone(),
        })))
    }

    fn checkerboard(&mut self, name: &str, p: &Params, loc: &Loc) -> Result<TexVal> {
        let dim = p.int("dimension", 2)?;
        let t1 = self
            .tex_param(p, "tex1", true, Usage::Albedo)?
            .unwrap_or(TexVal::Const(Rgb::ONE));
        let t2 = self
            .tex_param(p, "tex2", true, Usage::Albedo)?
            .unwrap_or(TexVal::Const(Rgb::ZERO));
        let texture = match dim {
            2 => {
                let m = self.uv_mapping(p, name, loc)?;
                // Our checkerboard has two cells per unit of uv, pbrt's one.
                let to_uv = Mat3::from_diagonal(Vec3::new(0.5, 0.5, 1.0)) * m;
                match (const_of(&t1), const_of(&t2)) {
                    (Some(c1), Some(c2)) => Texture::Checkerboard {
                        color0: c1,
                        color1: c2,
                        to_uv,
                    },
                    // Textured cells: the two textures mixed by a 0/1 checkerboard.
                    _ => Texture::Mix {
                        a: Box::new(self.inline(&t1)),
                        b: Box::new(self.inline(&t2)),
                        amount: Box::new(Texture::Checkerboard {
                            color0: Rgb::ZERO,
                            color1: Rgb::ONE,
                            to_uv,
                        }),
                    },
                }
            }
            // pbrt: tex1 where ⌊x⌋ + ⌊y⌋ + ⌊z⌋ of the point in texture space is even.
            3 => Texture::Checker3D {
                a: Box::new(self.inline(&t1)),
                b: Box::new(self.inline(&t2)),
                to_texture: self.texture_space(),
            },
            d => {
                return Err(err(
                    loc,
                    format!("checkerboard '{name}': dimension {d} (expected 2 or 3)"),
                ));
            }
        };
        Ok(self.add_tex(texture, name, loc))
    }

    // -----------------------------------------------------------------------------------------
    // Materials

    fn add_material(&mut self, material: Material, name: Option<String>, loc: &Loc) -> MaterialId {
        self.scene.add_material(MaterialDesc {
            material,
            ambient: Rgb::ZERO,
            name,
            loc: loc.clone(),
        })
    }

    /// uroughness/vroughness (defaulting to roughness), remapped unless `remaproughness` is
    /// false; `prefix` is "" or e.g. "interface." / "conductor.".
    fn roughness(
        &mut self,
        p: &Params,
        prefix: &str,
        default: f32,
        loc: &Loc,
    ) -> Result<(FloatParam, FloatParam)> {
        let r = self.float(p, &format!("{prefix}roughness"), default)?;
        let u = match self.tex_param(p, &format!("{prefix}uroughness"), false, Usage::Unbounded)? {
            Some(t) => float_of(t),
            None => r.clone(),
        };
        let v = match self.tex_param(p, &format!("{prefix}vroughness"), false, Usage::Unbounded)? {
            Some(t) => float_of(t),
            None => r,
        };
        let remap = p.bool("remaproughness", true)?;
        let map = |f: FloatParam, l: &mut Loader| match f {
            // pbrt-v4's RoughnessToAlpha.
            FloatParam::Const(r) if remap => FloatParam::Const(r.max(0.0).sqrt()),
            FloatParam::Texture(t) if remap => {
                l.warn_once(
                    "remap texture",
                    loc,
                    "remaproughness with a roughness texture: the texture is read as α \
                     (unremapped)",
                );
                FloatParam::Texture(t)
            }
            f => f,
        };
        Ok((map(u, self), map(v, self)))
    }

    /// uroughness/vroughness (defaulting to roughness) as declared, and whether they are to
    /// be remapped (α = √r): coated materials remap per lookup, so textures remap too.
    fn raw_roughness(
        &mut self,
        p: &Params,
        prefix: &str,
        default: f32,
    ) -> Result<(FloatParam, FloatParam, bool)> {
        let r = self.float(p, &format!("{prefix}roughness"), default)?;
        let u = match self.tex_param(p, &format!("{prefix}uroughness"), false, Usage::Unbounded)? {
            Some(t) => float_of(t),
            None => r.clone(),
        };
        let v = match self.tex_param(p, &format!("{prefix}vroughness"), false, Usage::Unbounded)? {
            Some(t) => float_of(t),
            None => r,
        };
        Ok((u, v, p.bool("remaproughness", true)?))
    }

    fn conductor_index(
        &mut self,
        p: &Params,
        prefix: &str,
    ) -> Result<(ColorValue, ColorValue, Option<ColorParam>)> {
        let reflectance = self.tex_param(p, "reflectance", true, Usage::Albedo)?;
        let eta = self.value(p, &format!("{prefix}eta"), Usage::Unbounded)?;
        let k = self.value(p, &format!("{prefix}k"), Usage::Unbounded)?;
        let eta = match eta {
            Some(e) => e,
            None => declared(
                named_metal("metal-Cu-eta").expect("Cu"),
                Usage::Unbounded,
                &p.loc,
            )?,
        };
        let k = match k {
            Some(k) => k,
            None => declared(
                named_metal("metal-Cu-k").expect("Cu"),
                Usage::Unbounded,
                &p.loc,
            )?,
        };
        Ok((eta, k, reflectance.map(color_of)))
    }

    /// A dielectric's `eta`: a float, or a spectrum (a named glass disperses).
    fn eta(&mut self, p: &Params, name: &str, default: f32) -> Result<(f32, Option<Dispersion>)> {
        let Some(q) = p.get(name, &[Ty::Float, Ty::Spectrum, Ty::Texture])? else {
            return Ok((default, None));
        };
        match (&q.ty, &q.vals) {
            (Ty::Float, Vals::Nums(v)) if v.len() == 1 => Ok((v[0] as f32, None)),
            (Ty::Spectrum, Vals::Strs(s)) if named_glass(&s[0]).is_some() => {
                let d = named_glass(&s[0]).expect("checked");
                Ok((d.ior(D_LINE_NM) as f32, Some(d)))
            }
            (Ty::Spectrum, _) => {
                let v = self.spectrum_value(q, Usage::Unbounded)?;
                let s = v.spectrum().expect("a spectrum");
                let at_d = s.eval(D_LINE_NM) as f32;
                let (w, vals) = nodes(&s.kind);
                if vals.windows(2).any(|x| x[0] != x[1]) || w.is_empty() {
                    self.warn(
                        &q.loc,
                        "a tabulated index of refraction is used at 587.6 nm only (no \
                         dispersion)",
                    );
                }
                Ok((at_d, None))
            }
            (Ty::Texture, _) => Err(q.err("a textured index of refraction is not supported")),
            _ => Err(q.err("expected one value")),
        }
    }

    /// pbrt-v3's material names, translated as pbrt-v4's `--upgrade` does, with a notice.
    fn upgrade(&mut self, ty: &str, loc: &Loc) {
        self.warn_once(
            &format!("v3 material {ty}"),
            loc,
            format!("pbrt-v3 material \"{ty}\" translated to its pbrt-v4 counterpart"),
        );
    }

    pub(super) fn make_material(
        &mut self,
        ty: &str,
        p: &Params,
        loc: &Loc,
        name: Option<String>,
    ) -> Result<MaterialId> {
        let m = match ty {
            "diffuse" => Material::Diffuse {
                reflectance: self.color(p, "reflectance", 0.5, Usage::Albedo)?,
            },
            "conductor" => {
                let (au, av) = self.roughness(p, "", 0.0, loc)?;
                let (eta, k, refl) = self.conductor_index(p, "")?;
                let (eta, k) = match refl {
                    None => (eta, k),
                    Some(r) => match r.const_rgb() {
                        Some(r) => reflectance_index(r),
                        None => {
                            return Err(err(
                                loc,
                                "conductor: a textured 'reflectance' is not supported",
                            ));
                        }
                    },
                };
                conductor(au, av, eta, k)
            }
            "dielectric" | "thindielectric" => {
                let (eta, dispersion) = self.eta(p, "eta", 1.5)?;
                let thin = ty == "thindielectric";
                let (au, av) = if thin {
                    (FloatParam::Const(0.0), FloatParam::Const(0.0))
                } else {
                    self.roughness(p, "", 0.0, loc)?
                };
                dielectric(thin, au, av, eta, dispersion)
            }
            "diffusetransmission" => {
                let s = p.float("scale", 1.0)?;
                let r = self.color(p, "reflectance", 0.25, Usage::Albedo)?;
                let t = self.color(p, "transmittance", 0.25, Usage::Albedo)?;
                Material::DiffuseTransmission {
                    reflectance: self.scaled(r, s, loc),
                    transmittance: self.scaled(t, s, loc),
                }
            }
            "coateddiffuse" => {
                let (au, av, remap) = self.raw_roughness(p, "", 0.0)?;
                let (eta, _) = self.eta(p, "eta", 1.5)?;
                Material::CoatedDiffuse {
                    reflectance: self.color(p, "reflectance", 0.5, Usage::Albedo)?,
                    alpha_u: au,
                    alpha_v: av,
                    remap_roughness: remap,
                    eta,
                    thickness: self.float(p, "thickness", 0.01)?,
                    albedo: self.color(p, "albedo", 0.0, Usage::Albedo)?,
                    g: self.float(p, "g", 0.0)?,
                    max_depth: p.int_in("maxdepth", 10, 1, 1 << 20)? as u32,
                    n_samples: p.int_in("nsamples", 1, 1, 1 << 20)? as u32,
                }
            }
            "coatedconductor" => {
                let (iu, iv, remap) = self.raw_roughness(p, "interface.", 0.0)?;
                let (cu, cv, _) = self.raw_roughness(p, "conductor.", 0.0)?;
                let (ieta, _) = self.eta(p, "interface.eta", 1.5)?;
                let (ce, ck, refl) = self.conductor_index(p, "conductor.")?;
                Material::CoatedConductor {
                    interface_alpha_u: iu,
                    interface_alpha_v: iv,
                    remap_roughness: remap,
                    interface_eta: ieta,
                    thickness: self.float(p, "thickness", 0.01)?,
                    albedo: self.color(p, "albedo", 0.0, Usage::Albedo)?,
                    g: self.float(p, "g", 0.0)?,
                    max_depth: p.int_in("maxdepth", 10, 1, 1 << 20)? as u32,
                    n_samples: p.int_in("nsamples", 1, 1, 1 << 20)? as u32,
                    conductor_alpha_u: cu,
                    conductor_alpha_v: cv,
                    conductor_eta: ce,
                    conductor_k: ck,
                    reflectance: refl,
                }
            }
            "mix" => {
                let names: Vec<(String, Param)> = match p.get("materials", &[Ty::Str])? {
                    Some(q) => match q.strs() {
                        [a, b] => vec![(a.clone(), q.clone()), (b.clone(), q.clone())],
                        _ => return Err(q.err("expected two material names")),
                    },
                    None => {
                        // pbrt-v3: `amount` weighs namedmaterial1, which pbrt-v4 picks with
                        // probability 1 − amount.
                        let one = p.string_opt("namedmaterial1")?;
                        let two = p.string_opt("namedmaterial2")?;
                        match (one, two) {
                            (Some((a, qa)), Some((b, qb))) => {
                                self.upgrade(ty, loc);
                                vec![(b.to_string(), qb.clone()), (a.to_string(), qa.clone())]
                            }
                            _ => {
                                return Err(err(
                                    loc,
                                    "mix needs \"string materials\" [ \"a\" \"b\" ]",
                                ));
                            }
                        }
                    }
                };
                let mut ids = [MaterialId(0); 2];
                for (i, (n, q)) in names.iter().enumerate() {
                    ids[i] = match self.named_materials.get(n) {
                        Some(&id) => id,
                        None => return Err(q.err(format!("unknown named material '{n}'"))),
                    };
                }
                Material::Mix {
                    materials: ids,
                    amount: self.float(p, "amount", 0.5)?,
                }
            }
            "interface" | "" | "none" => Material::Null,
            // pbrt-v3 materials.
            "matte" => {
                self.upgrade(ty, loc);
                if let Some(q) = p.get("sigma", &[Ty::Float, Ty::Texture])?
                    && q.nums().first().is_none_or(|&s| s != 0.0)
                {
                    self.warn(
                        &q.loc,
                        "matte: Oren–Nayar 'sigma' is not supported (Lambertian)",
                    );
                }
                Material::Diffuse {
                    reflectance: self.color(p, "Kd", 0.5, Usage::Albedo)?,
                }
            }
            "plastic" | "substrate" | "uber" => {
                self.upgrade(ty, loc);
                let (kd_default, rough_default) = match ty {
                    "plastic" => (0.25, 0.1),
                    "substrate" => (0.5, 0.1),
                    _ => (0.25, 0.0),
                };
                let (au, av, remap) = self.raw_roughness(p, "", rough_default)?;
                let (eta, _) = self.eta(p, if ty == "uber" { "index" } else { "eta" }, 1.5)?;
                let _ = p.get("Ks", &[Ty::Rgb, Ty::Spectrum, Ty::Texture, Ty::Float])?;
                Material::CoatedDiffuse {
                    reflectance: self.color(p, "Kd", kd_default, Usage::Albedo)?,
                    alpha_u: au,
                    alpha_v: av,
                    remap_roughness: remap,
                    eta,
                    thickness: FloatParam::Const(0.01),
                    albedo: ColorParam::constant(0.0),
                    g: FloatParam::Const(0.0),
                    max_depth: 10,
                    n_samples: 1,
                }
            }
            "glass" => {
                self.upgrade(ty, loc);
                let (eta, dispersion) = self.eta(p, "index", 1.5)?;
                let (au, av) = self.roughness(p, "", 0.0, loc)?;
                dielectric(false, au, av, eta, dispersion)
            }
            "metal" => {
                self.upgrade(ty, loc);
                let (au, av) = self.roughness(p, "", 0.01, loc)?;
                let (eta, k, _) = self.conductor_index(p, "")?;
                conductor(au, av, eta, k)
            }
            "mirror" => {
                self.upgrade(ty, loc);
                Material::Mirror {
                    reflectance: self.color(p, "Kr", 0.9, Usage::Albedo)?,
                }
            }
            "translucent" => {
                self.upgrade(ty, loc);
                let r = self.color(p, "reflect", 0.5, Usage::Albedo)?;
                let t = self.color(p, "transmit", 0.5, Usage::Albedo)?;
                Material::DiffuseTransmission {
                    reflectance: r,
                    transmittance: t,
                }
            }
            "subsurface" => {
                let (au, av) = self.roughness(p, "", 0.0, loc)?;
                let (eta, dispersion) = self.eta(p, "eta", 1.33)?;
                let boundary = dielectric(false, au, av, eta, dispersion);
                let mut rgb = |name: &str, default: f32, usage: Usage| -> Result<Option<Rgb>> {
                    if !p.has(name) {
                        return Ok(None);
                    }
                    match self.color(p, name, default, usage)?.const_rgb() {
                        Some(c) => Ok(Some(c)),
                        None => Err(err(
                            loc,
                            format!("subsurface: a textured '{name}' is not supported"),
                        )),
                    }
                };
                let sigma_a = rgb("sigma_a", 0.0, Usage::Unbounded)?;
                let sigma_s = rgb("sigma_s", 0.0, Usage::Unbounded)?;
                let reflectance = rgb("reflectance", 0.0, Usage::Albedo)?;
                let mfp = rgb("mfp", 1.0, Usage::Unbounded)?;
                let scale = p.float("scale", 1.0)?;
                // pbrt-v4's order: a name, else σa/σs, else reflectance with mfp, else its
                // defaults (whole milk's coefficients, in mm⁻¹); `scale` multiplies all but the
                // reflectance form.
                let (coefficients, scale) = if let Some((n, q)) = p.string_opt("name")? {
                    let m = base::subsurface::measured(n).ok_or_else(|| {
                        q.err(format!(
                            "subsurface: unknown measured medium \"{n}\" (known: {})",
                            base::subsurface::MEASURED.map(|m| m.name).join(", ")
                        ))
                    })?;
                    (SubsurfaceCoefficients::Measured(m), scale)
                } else if sigma_a.is_some() || sigma_s.is_some() {
                    (
                        SubsurfaceCoefficients::Sigma {
                            sigma_a: sigma_a.unwrap_or(Rgb::new(0.0011, 0.0024, 0.014)),
                            sigma_s: sigma_s.unwrap_or(Rgb::new(2.55, 3.21, 3.77)),
                        },
                        scale,
                    )
                } else if let Some(r) = reflectance {
                    let mfp = mfp.unwrap_or(Rgb::ONE);
                    if mfp.min_element() <= 0.0 {
                        return Err(err(loc, "subsurface: 'mfp' must be > 0"));
                    }
                    (
                        SubsurfaceCoefficients::MeanFreePath {
                            mfp,
                            albedo: r.clamp(Rgb::ZERO, Rgb::ONE),
                        },
                        1.0,
                    )
                } else {
                    (
                        SubsurfaceCoefficients::Sigma {
                            sigma_a: Rgb::new(0.0011, 0.0024, 0.014),
                            sigma_s: Rgb::new(2.55, 3.21, 3.77),
                        },
                        scale,
                    )
                };
                let g = p.float("g", 0.0)?;
                if !(g > -1.0 && g < 1.0) {
                    return Err(err(loc, "subsurface: 'g' must lie in (-1, 1)"));
                }
                Material::Subsurface {
                    boundary: Box::new(boundary),
                    medium: SubsurfaceMedium {
                        coefficients,
                        scale,
                        g,
                    },
                }
            }
            "hair" | "measured" | "kdsubsurface" | "fourier" | "disney" => {
                return Err(err(
                    loc,
                    format!(
                        "material \"{ty}\" is not supported (refused rather than rendered wrong)"
                    ),
                ));
            }
            _ => {
                return Err(err(
                    loc,
                    format!(
                        "unknown material \"{ty}\" (pbrt-v4 has diffuse, conductor, dielectric, \
                         thindielectric, diffusetransmission, coateddiffuse, coatedconductor, \
                         mix, interface, hair, measured, subsurface)"
                    ),
                ));
            }
        };
        // pbrt-v4's BSDFs reflect on both sides of a surface; ours of these kinds (Mitsuba's)
        // only on the side of the normal.
        let one_sided = matches!(
            m,
            Material::Diffuse { .. }
                | Material::Conductor { .. }
                | Material::RoughConductor { .. }
                | Material::Mirror { .. }
        );
        let mut id = self.add_material(m, name.clone(), loc);
        if one_sided {
            id = self.add_material(
                Material::TwoSided {
                    front: id,
                    back: None,
                },
                name.clone(),
                loc,
            );
        }
        if !matches!(ty, "mix" | "interface" | "" | "none") {
            // A constant displacement moves the surface without tilting it: no bump.
            let displacement = if p.has("bumpmap") && !p.has("displacement") {
                self.warn_once(
                    "v3 bumpmap",
                    loc,
                    "pbrt-v3's 'bumpmap' read as 'displacement'",
                );
                "bumpmap"
            } else {
                "displacement"
            };
            if p.get(displacement, &[Ty::Float, Ty::Texture])?
                .is_some_and(|q| q.ty == Ty::Texture)
                && let Some(TexVal::Tex(t)) =
                    self.tex_param(p, displacement, false, Usage::Unbounded)?
            {
                self.warn_once(
                    "displacement",
                    loc,
                    "'displacement' is rendered as our bump map, whose slope is the height \
                     difference between neighbouring texels (pbrt-v4 divides by the texel's \
                     size in uv and scales with the surface's parametrisation): bumps differ \
                     in strength",
                );
                id = self.add_material(
                    Material::BumpMap {
                        nested: id,
                        texture: t,
                        factor: 1.0,
                    },
                    name.clone(),
                    loc,
                );
            }
            if let Some((file, fp)) = p.string_opt("normalmap")? {
                let path = self.resolve(file);
                if !path.is_file() {
                    return Err(fp.err(format!("normal map '{}' not found", path.display())));
                }
                let texture = self.scene.add_texture(TextureDesc {
                    texture: Texture::Bitmap {
                        // pbrt-v4 reads normal maps bilinearly at full resolution.
                        mipmapped: false,
                        path,
                        filter: TextureFilter::Bilinear,
                        wrap: WrapMode::Repeat,
                        raw: true,
                        gamma: None,
                        to_uv: Mat3::from_cols(
                            Vec3::X,
                            Vec3::new(0.0, -1.0, 0.0),
                            Vec3::new(0.0, 1.0, 1.0),
                        ),
                        corner_texels: false,
                    },
                    name: None,
                    loc: loc.clone(),
                });
                id = self.add_material(
                    Material::NormalMap {
                        nested: id,
                        texture,
                    },
                    name.clone(),
                    loc,
                );
            }
        }
        let _ = p.get("type", &[Ty::Str])?;
        self.finish_params("Material", ty, p);
        Ok(id)
    }

    fn scaled(&mut self, c: ColorParam, s: f32, loc: &Loc) -> ColorParam {
        if s == 1.0 {
            return c;
        }
        match c {
            ColorParam::Const(v) => ColorParam::Const(v * s),
            ColorParam::Spectrum(d) => ColorParam::Spectrum(Arc::new(SpectrumDesc {
                rgb: d.rgb * s,
                kind: d.kind.clone(),
                scale: d.scale * f64::from(s),
            })),
            ColorParam::Texture(t) => match self.affine(t, s, Rgb::ZERO, "scaled", loc) {
                TexVal::Tex(t) => ColorParam::Texture(t),
                _ => unreachable!(),
            },
        }
    }

    // -----------------------------------------------------------------------------------------
    // Media

    pub(super) fn make_medium(&mut self, name: String, p: Params, loc: &Loc) -> Result<()> {
        let ty = p.string("type", "")?.to_string();
        let medium = match ty.as_str() {
            "homogeneous" => {
                if let Some((preset, _)) = p.string_opt("preset")? {
                    return Err(err(
                        loc,
                        format!("medium '{name}': named preset \"{preset}\" is not supported"),
                    ));
                }
                let sa = self
                    .value(&p, "sigma_a", Usage::Unbounded)?
                    .map_or(Rgb::new(0.0011, 0.0024, 0.014), |v| v.rgb());
                let ss = self
                    .value(&p, "sigma_s", Usage::Unbounded)?
                    .map_or(Rgb::new(2.55, 3.21, 3.77), |v| v.rgb());
                let scale = p.float("scale", 1.0)?;
                let g = p.float("g", 0.0)?;
                if !(g > -1.0 && g < 1.0) {
                    return Err(err(
                        loc,
                        format!("medium '{name}': g = {g} is outside (−1, 1)"),
                    ));
                }
                let le = self
                    .value(&p, "Le", Usage::Illuminant)?
                    .map_or(Rgb::ZERO, |v| v.rgb())
                    * p.float("Lescale", 1.0)?;
                let st = sa + ss;
                let albedo = Rgb::select(st.cmpgt(Rgb::ZERO), ss / st, Rgb::ZERO);
                MediumDesc {
                    medium: Medium::Homogeneous {
                        sigma_t: st,
                        albedo,
                        scale,
                    },
                    phase: if g == 0.0 {
                        PhaseDesc::Isotropic
                    } else {
                        PhaseDesc::HenyeyGreenstein { g }
                    },
                    emission: (le != Rgb::ZERO)
                        .then_some(MediumEmission::Radiance(VolumeParam::Const(le))),
                    name: Some(name.clone()),
                    loc: loc.clone(),
                }
            }
            "" => {
                return Err(err(
                    loc,
                    format!("MakeNamedMedium \"{name}\" needs a \"string type\" parameter"),
                ));
            }
            "uniformgrid" | "rgbgrid" => self.grid_medium(&name, &ty, &p, loc)?,
            "nanovdb" | "cloud" => {
                return Err(err(
                    loc,
                    format!(
                        "medium '{name}': type \"{ty}\" is not supported yet (homogeneous, \
                         uniformgrid and rgbgrid are)"
                    ),
                ));
            }
            _ => {
                return Err(err(
                    loc,
                    format!(
                        "medium '{name}': unknown type \"{ty}\" (pbrt-v4 has homogeneous, \
                         uniformgrid, rgbgrid, nanovdb, cloud)"
                    ),
                ));
            }
        };
        self.finish_params("MakeNamedMedium", &ty, &p);
        let id = self.scene.add_medium(medium);
        self.media.insert(name, id);
        Ok(())
    }

    /// pbrt-v4's `uniformgrid` and `rgbgrid`: inline grids over the box `p0`–`p1` of the
    /// medium's space (the CTM at `MakeNamedMedium`), looked up as pbrt-v4's `SampledGrid`
    /// (voxel centres at (i + ½)/n, 0 beyond the voxels) — our inline grids' convention.
    fn grid_medium(&mut self, name: &str, ty: &str, p: &Params, loc: &Loc) -> Result<MediumDesc> {
        let fail = |m: String| err(loc, format!("medium '{name}' ({ty}): {m}"));
        let mut res = [1usize; 3];
        for (r, key) in res.iter_mut().zip(["nx", "ny", "nz"]) {
            *r = p.int_in(key, 1, 1, 1 << 20)? as usize;
        }
        let n = res
            .iter()
            .try_fold(1usize, |a, &r| a.checked_mul(r))
            .filter(|&n| n <= 1 << 28)
            .ok_or_else(|| fail(format!("{res:?} voxels are too many")))?;
        // pbrt-v4 orders the corners itself (a Bounds3f of the two points).
        let (a, b) = (
            Vec3::from(p.vec3("p0", Ty::Point3, [0.0; 3])?),
            Vec3::from(p.vec3("p1", Ty::Point3, [1.0; 3])?),
        );
        let (lo, hi) = (a.min(b), a.max(b));
        if !(hi - lo).cmpgt(Vec3::ZERO).all() {
            return Err(fail(format!("the box {lo} – {hi} is empty")));
        }
        let to_world = self.gs.ctm[0] * Mat4::from_translation(lo) * Mat4::from_scale(hi - lo);
        let g = p.float("g", 0.0)?;
        if !(g > -1.0 && g < 1.0) {
            return Err(fail(format!("g = {g} is outside (−1, 1)")));
        }
        let scale = p.float("scale", 1.0)?;
        let volume = |res: [usize; 3], channels: usize, data: Vec<f32>| {
            Box::new(VolumeDesc {
                path: (*loc.file).clone(),
                format: VolumeFormat::Inline {
                    res,
                    channels,
                    data: data.into(),
                },
                to_world,
                trilinear: true,
                loc: loc.clone(),
            })
        };
        // A list of `count` values of `ty` (×3 for RGB), each finite and ≥ 0.
        let list = |key: &str, t: Ty, count: usize| -> Result<Option<Vec<f32>>> {
            let Some(q) = p.nums(key, t)? else {
                return Ok(None);
            };
            let per = if t == Ty::Rgb { 3 } else { 1 };
            if q.nums().len() != count * per {
                return Err(q.err(format!(
                    "{} values for {res:?} voxels; expected {}",
                    q.nums().len() / per,
                    count
                )));
            }
            if let Some(v) = q.nums().iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(q.err(format!("value {v}: values must be finite and ≥ 0")));
            }
            Ok(Some(q.nums().iter().map(|&v| v as f32).collect()))
        };
        let (medium, emission) = if ty == "uniformgrid" {
            if p.has("temperature") {
                return Err(fail(
                    "\"temperature\" grids are not supported: pbrt-v4's emission is then its \
                     peak-normalised black body times the \"Lescale\" grid, a product of two \
                     lookups our media do not express"
                        .into(),
                ));
            }
            let density = list("density", Ty::Float, n)?
                .ok_or_else(|| fail("no \"density\" values".into()))?;
            let sa = self
                .value(p, "sigma_a", Usage::Unbounded)?
                .map_or(Rgb::ONE, |v| v.rgb());
            let ss = self
                .value(p, "sigma_s", Usage::Unbounded)?
                .map_or(Rgb::ONE, |v| v.rgb());
            let st = sa + ss;
            if st.max_element() - st.min_element() > 1e-6 * st.max_element() {
                return Err(fail(format!(
                    "sigma_a + sigma_s = {st} is not grey: our grid media have one extinction \
                     for all wavelengths"
                )));
            }
            let albedo = Rgb::select(st.cmpgt(Rgb::ZERO), ss / st, Rgb::ZERO);
            let le = self.value(p, "Le", Usage::Illuminant)?.map(|v| v.rgb());
            // Without a "Lescale" grid pbrt-v4 scales Le by a one-voxel grid: a tent over
            // the box, 1 at its centre.
            let (le_res, le_scale) = match list("Lescale", Ty::Float, n)? {
                Some(s) => (res, s),
                None => ([1; 3], vec![1.0]),
            };
            let emission = le.filter(|l| *l != Rgb::ZERO).map(|l| {
                let data = le_scale.iter().flat_map(|&s| (l * s).to_array()).collect();
                MediumEmission::Radiance(VolumeParam::Grid(volume(le_res, 3, data)))
            });
            let medium = Medium::Heterogeneous {
                sigma_t: volume(res, 1, density),
                albedo: VolumeParam::Const(albedo),
                scale: scale * st.x,
            };
            (medium, emission)
        } else {
            let (Some(sa), Some(ss)) = (list("sigma_a", Ty::Rgb, n)?, list("sigma_s", Ty::Rgb, n)?)
            else {
                return Err(fail(
                    "both \"sigma_a\" and \"sigma_s\" grids are needed (pbrt-v4 takes a \
                     missing one as 1 everywhere in the box, which our grids do not express)"
                        .into(),
                ));
            };
            let mut density = Vec::with_capacity(n);
            for (i, (a, s)) in sa.chunks_exact(3).zip(ss.chunks_exact(3)).enumerate() {
                let t = [a[0] + s[0], a[1] + s[1], a[2] + s[2]];
                let (mn, mx) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                if mx - mn > 1e-6 * mx {
                    return Err(fail(format!(
                        "voxel {i}: sigma_a + sigma_s = {t:?} is not grey: our grid media \
                         have one extinction for all wavelengths"
                    )));
                }
                density.push(t[0]);
            }
            let le_scale = p.float("Lescale", 1.0)?;
            let emission = list("Le", Ty::Rgb, n)?
                .filter(|l| le_scale != 0.0 && l.iter().any(|&v| v > 0.0))
                .map(|l| {
                    let data = l.iter().map(|&v| v * le_scale).collect();
                    MediumEmission::Radiance(VolumeParam::Grid(volume(res, 3, data)))
                });
            let medium = Medium::Heterogeneous {
                sigma_t: volume(res, 1, density),
                albedo: VolumeParam::SigmaSGrid(volume(res, 3, ss)),
                scale,
            };
            (medium, emission)
        };
        Ok(MediumDesc {
            medium,
            phase: if g == 0.0 {
                PhaseDesc::Isotropic
            } else {
                PhaseDesc::HenyeyGreenstein { g }
            },
            emission,
            name: Some(name.to_string()),
            loc: loc.clone(),
        })
    }

    pub(super) fn medium_id(&self, name: &Option<String>, loc: &Loc) -> Result<Option<MediumId>> {
        match name {
            None => Ok(None),
            Some(n) => self
                .media
                .get(n)
                .copied()
                .map(Some)
                .ok_or_else(|| err(loc, format!("unknown medium '{n}'"))),
        }
    }

    // -----------------------------------------------------------------------------------------
    // Lights

    /// A light's spectrum parameter times `scale` (and the spectrum's normalisation).
    fn light_value(&mut self, p: &Params, name: &str, factor: f32) -> Result<ColorValue> {
        let v = self
            .value(p, name, Usage::Illuminant)?
            .unwrap_or(ColorValue::Rgb(Rgb::ONE));
        Ok(v.divided(1.0 / factor))
    }

    pub(super) fn make_light(&mut self, ty: &str, p: &Params, loc: &Loc) -> Result<()> {
        let ctm = self.gs.ctm[0];
        if self.gs.ctm[0] != self.gs.ctm[1] {
            self.warn_once(
                "light motion",
                loc,
                "moving lights use their shutter-open transform",
            );
        }
        let scale = p.float("scale", 1.0)?;
        let medium = self.medium_id(&self.gs.outside.clone(), loc)?;
        let emitter = match ty {
            "point" => {
                let from = Vec3::from(p.vec3("from", Ty::Point3, [0.0; 3])?);
                let mut s = scale;
                if let Some(phi) = p.float_opt("power")?
                    && phi > 0.0
                {
                    s *= phi / (4.0 * std::f32::consts::PI);
                }
                Emitter::Point {
                    position: ctm.transform_point3(from),
                    intensity: self.light_value(p, "I", s)?,
                }
            }
            "spot" => {
                let from = Vec3::from(p.vec3("from", Ty::Point3, [0.0; 3])?);
                let to = Vec3::from(p.vec3("to", Ty::Point3, [0.0, 0.0, 1.0])?);
                let cone = p.float("coneangle", 30.0)?;
                let delta = p.float("conedelta", 5.0)?;
                let dir = (to - from).normalize_or_zero();
                if dir == Vec3::ZERO {
                    return Err(err(loc, "spot: 'from' and 'to' coincide"));
                }
                let frame = Mat3::from_cols(
                    dir.any_orthonormal_pair().0,
                    dir.any_orthonormal_pair().1,
                    dir,
                );
                let to_world = ctm * Mat4::from_translation(from) * Mat4::from_mat3(frame);
                let cos_end = cone.to_radians().cos();
                let cos_start = (cone - delta).to_radians().cos();
                let mut s = scale;
                if let Some(phi) = p.float_opt("power")?
                    && phi > 0.0
                {
                    let k = 2.0
                        * std::f32::consts::PI
                        * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0);
                    s *= phi / k;
                }
                Emitter::Spot {
                    to_world,
                    intensity: self.light_value(p, "I", s)?,
                    cutoff_angle: cone,
                    beam_width: (cone - delta).max(0.0),
                    falloff: SpotFalloff::SmoothStep,
                }
            }
            "distant" => {
                let from = Vec3::from(p.vec3("from", Ty::Point3, [0.0; 3])?);
                let to = Vec3::from(p.vec3("to", Ty::Point3, [0.0, 0.0, 1.0])?);
                let dir = ctm.transform_vector3(to - from).normalize_or_zero();
                if dir == Vec3::ZERO || !dir.is_finite() {
                    return Err(err(loc, "distant: 'from' and 'to' coincide"));
                }
                let mut s = scale;
                if let Some(e) = p.float_opt("illuminance")?
                    && e > 0.0
                {
                    s *= e;
                }
                Emitter::Directional {
                    direction: dir,
                    irradiance: self.light_value(p, "L", s)?,
                }
            }
            "infinite" => {
                let file = p
                    .string_opt("filename")?
                    .map(|(f, q)| (f.to_string(), q.loc.clone()));
                if p.get("portal", &[Ty::Point3])?.is_some() {
                    self.warn(loc, "infinite: 'portal' is not supported (ignored)");
                }
                let illum = p.float_opt("illuminance")?.filter(|&e| e > 0.0);
                match file {
                    Some((f, floc)) => {
                        if p.has("L") {
                            return Err(err(loc, "infinite: both 'L' and 'filename' given"));
                        }
                        if illum.is_some() {
                            self.warn(
                                loc,
                                "infinite: 'illuminance' with an image is not supported (ignored)",
                            );
                        }
                        let path = self.resolve(&f);
                        if !path.is_file() {
                            return Err(err(
                                &floc,
                                format!("environment map '{}' not found", path.display()),
                            ));
                        }
                        Emitter::EnvMap {
                            path,
                            scale,
                            to_world: ctm,
                            mapping: EnvMapping::EqualArea,
                        }
                    }
                    None => {
                        let s = scale * illum.map_or(1.0, |e| e / std::f32::consts::PI);
                        Emitter::Constant {
                            radiance: self.light_value(p, "L", s)?,
                        }
                    }
                }
            }
            "goniometric" | "projection" => {
                let Some((f, fp)) = p.string_opt("filename")? else {
                    return Err(err(loc, format!("{ty}: needs a \"string filename\"")));
                };
                let path = self.resolve(f);
                if !path.is_file() {
                    return Err(fp.err(format!("image '{}' not found", path.display())));
                }
                let power = p.float_opt("power")?.filter(|&v| v > 0.0);
                if ty == "goniometric" {
                    // pbrt-v4 looks the image up with the light's y and z swapped: the
                    // equal-area map's pole is the light's +y.
                    let swap =
                        Mat4::from_cols(glam::Vec4::X, glam::Vec4::Z, glam::Vec4::Y, glam::Vec4::W);
                    Emitter::ImagePoint {
                        to_world: ctm * swap,
                        path,
                        intensity: self.light_value(p, "I", scale)?.rgb(),
                        profile: ImageProfile::Goniometric,
                        power,
                    }
                } else {
                    let fov = p.float("fov", 90.0)?;
                    if !(fov > 0.0 && fov < 180.0) {
                        return Err(err(
                            loc,
                            format!("projection: fov {fov} is outside (0, 180)"),
                        ));
                    }
                    // pbrt-v4 flips the light's y so that the image's first row is lit
                    // towards the light's +y.
                    Emitter::ImagePoint {
                        to_world: ctm * Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0)),
                        path,
                        intensity: Rgb::splat(scale),
                        profile: ImageProfile::Projection { fov },
                        power,
                    }
                }
            }
            _ => {
                return Err(err(
                    loc,
                    format!(
                        "unknown light \"{ty}\" (pbrt-v4 has point, spot, distant, infinite, \
                         goniometric, projection)"
                    ),
                ));
            }
        };
        self.finish_params("LightSource", ty, p);
        self.scene.emitters.push(EmitterDesc {
            name: None,
            emitter,
            medium,
            loc: loc.clone(),
        });
        Ok(())
    }

    /// The emission of an area light on a shape of world-space `area` (for `power`).
    pub(super) fn area_emission(
        &mut self,
        p: &Params,
        area: Option<f32>,
        loc: &Loc,
    ) -> Result<AreaEmission> {
        let two_sided = p.bool("twosided", false)?;
        if p.string_opt("filename")?.is_some() {
            return Err(err(
                loc,
                "diffuse area light: an emission image ('filename') is not supported",
            ));
        }
        let mut s = p.float("scale", 1.0)?;
        if let Some(phi) = p.float_opt("power")?
            && phi > 0.0
        {
            match area {
                Some(a) if a > 0.0 => {
                    s *= phi / ((if two_sided { 2.0 } else { 1.0 }) * a * std::f32::consts::PI);
                }
                _ => self.warn_once(
                    "area power",
                    loc,
                    "diffuse area light: 'power' needs the shape's area, unknown here (ignored)",
                ),
            }
        }
        let v = self.light_value(p, "L", s)?;
        self.finish_params("AreaLightSource", "diffuse", p);
        Ok(AreaEmission {
            radiance: v.into(),
            two_sided,
            directional: false,
            loc: loc.clone(),
        })
    }

    // -----------------------------------------------------------------------------------------
    // Options → sensor and integrator

    pub(super) fn finish(mut self) -> Result<SceneDesc> {
        let loc0 = Loc::file(&self.scene.source);
        let opts = std::mem::take(&mut self.opts);
        // Film.
        let (film_ty, fp) = opts.film.unwrap_or((
            "rgb".into(),
            Params {
                list: vec![],
                loc: loc0.clone(),
            },
        ));
        if film_ty == "image" {
            self.warn_once(
                "v3 film",
                &fp.loc,
                "pbrt-v3's film \"image\" read as \"rgb\"",
            );
        } else if film_ty != "rgb" {
            self.warn(
                &fp.loc,
                format!("film \"{film_ty}\" is rendered as an \"rgb\" film"),
            );
        }
        let w = fp.int_in("xresolution", 1280, 1, MAX_FILM_SIDE)?;
        let h = fp.int_in("yresolution", 720, 1, MAX_FILM_SIDE)?;
        if w * h > MAX_FILM_PIXELS {
            return Err(err(&fp.loc, format!("film of {w}×{h} pixels is too large")));
        }
        let (w, h) = (w as u32, h as u32);
        // The pixel window [x0, x1) × [y0, y1) of a crop window (fractions of the film,
        // rounded up as pbrt-v4 does) or of pixel bounds (pixels); the latter wins.
        let mut crop = None;
        for (key, ty, what) in [
            ("cropwindow", Ty::Float, "crop window"),
            ("pixelbounds", Ty::Integer, "pixel bounds"),
        ] {
            let Some(q) = fp.get(key, &[ty])? else {
                continue;
            };
            let [x0, x1, y0, y1] = q.nums() else {
                return Err(q.err("expected 4 values"));
            };
            let px = |v: f64, n: u32| match ty {
                Ty::Float => ((v.clamp(0.0, 1.0) * f64::from(n)).ceil() as u32).min(n),
                _ => (v.max(0.0) as u32).min(n),
            };
            let (a, b, c, d) = (px(*x0, w), px(*x1, w), px(*y0, h), px(*y1, h));
            if b <= a || d <= c {
                return Err(q.err(format!("empty {what}")));
            }
            crop = Some(CropWindow {
                offset_x: a,
                offset_y: c,
                width: b - a,
                height: d - c,
            });
        }
        let output = fp
            .string_opt("filename")?
            .map(|(f, _)| std::path::PathBuf::from(f));
        let iso = fp.float("iso", 100.0)?;
        let exposure = fp.float("exposuretime", 1.0)?;
        if iso * exposure != 100.0 {
            self.warn(
                &fp.loc,
                "film 'iso'/'exposuretime' scale the image in pbrt-v4; not applied here",
            );
        }
        if let Some(q) = fp.get("whitebalance", &[Ty::Float])?
            && q.nums().first().is_some_and(|&v| v != 0.0)
        {
            self.warn(&q.loc, "film 'whitebalance' is not supported (ignored)");
        }
        if let Some((s, q)) = fp.string_opt("sensor")?
            && s != "cie1931"
        {
            let l = q.loc.clone();
            self.warn(
                &l,
                format!("film sensor \"{s}\" is not supported (cie1931 used)"),
            );
        }
        let clamp = fp
            .float_opt("maxcomponentvalue")?
            .filter(|v| v.is_finite() && *v > 0.0);
        let _ = fp.bool("savefp16", true)?;
        let _ = fp.float("diagonal", 35.0)?;
        self.finish_params("Film", &film_ty, &fp);

        // Filter.
        let filter = match &opts.filter {
            None => FilterDesc::Gaussian {
                stddev: 0.5,
                radius: 1.5,
            },
            Some((ty, q)) => {
                let r = |d: f32| -> Result<f32> {
                    let x = q.float("xradius", d)?;
                    let y = q.float("yradius", d)?;
                    Ok(x.max(y))
                };
                let f = match ty.as_str() {
                    "box" => FilterDesc::Box { radius: r(0.5)? },
                    "triangle" => FilterDesc::Tent { radius: r(2.0)? },
                    "gaussian" => FilterDesc::Gaussian {
                        stddev: q.float("sigma", 0.5)?,
                        radius: r(1.5)?,
                    },
                    "mitchell" => FilterDesc::Mitchell {
                        b: q.float("B", 1.0 / 3.0)?,
                        c: q.float("C", 1.0 / 3.0)?,
                        radius: r(2.0)?,
                    },
                    "sinc" => FilterDesc::Lanczos {
                        radius: r(4.0)?,
                        tau: q.float("tau", 3.0)?,
                    },
                    _ => return Err(err(&q.loc, format!("unknown pixel filter \"{ty}\""))),
                };
                if q.float("xradius", 0.0)? != q.float("yradius", 0.0)? {
                    self.warn(
                        &q.loc,
                        "pixel filter: different x and y radii; the larger is used",
                    );
                }
                self.finish_params("PixelFilter", ty, q);
                if let FilterDesc::Box { radius: r }
                | FilterDesc::Tent { radius: r }
                | FilterDesc::Gaussian { radius: r, .. }
                | FilterDesc::Mitchell { radius: r, .. }
                | FilterDesc::Lanczos { radius: r, .. } = f
                    && !(r > 0.0 && r <= 64.0)
                {
                    return Err(err(
                        &q.loc,
                        format!("pixel filter radius {r} is outside (0, 64]"),
                    ));
                }
                f
            }
        };

        // Sampler.
        let mut sampler = SamplerDesc {
            kind: SamplerKind::Sobol,
            spp: 16,
            seed: opts.seed.unwrap_or(0),
        };
        if let Some((ty, q)) = &opts.sampler {
            sampler.kind = match ty.as_str() {
                "independent" => SamplerKind::Independent,
                "stratified" => SamplerKind::Stratified,
                "halton" => SamplerKind::Halton,
                // pbrt-v3's names as pbrt-v4's --upgrade renames them.
                "sobol" | "zsobol" | "paddedsobol" | "pmj02bn" | "lowdiscrepancy"
                | "02sequence" | "maxmindist" => SamplerKind::Sobol,
                _ => return Err(err(&q.loc, format!("unknown sampler \"{ty}\""))),
            };
            sampler.spp = if ty == "stratified" {
                let x = q.int_in("xsamples", 4, 1, 1 << 16)?;
                let y = q.int_in("ysamples", 4, 1, 1 << 16)?;
                let _ = q.bool("jitter", true)?;
                (x * y).min(1 << 24) as u32
            } else {
                q.int_in("pixelsamples", 16, 1, 1 << 24)? as u32
            };
            if let Some(s) = q.float_opt("seed").ok().flatten() {
                sampler.seed = s.max(0.0) as u64;
            } else if let Ok(s) = q.int("seed", -1)
                && s >= 0
            {
                sampler.seed = s as u64;
            }
            let _ = q.string("randomization", "");
            self.finish_params("Sampler", ty, q);
        }

        // Integrator.
        let (ity, ip) = opts.integrator.unwrap_or((
            "volpath".into(),
            Params {
                list: vec![],
                loc: loc0.clone(),
            },
        ));
        let depth = ip.int_in("maxdepth", 5, 0, 1 << 20)? as i32 + 1;
        if let Some((ls, q)) = ip.string_opt("lightsampler")? {
            self.scene.light_selection = match ls {
                "bvh" => LightSelection::Bvh,
                "power" => LightSelection::Power,
                "uniform" => LightSelection::Uniform,
                _ => return Err(q.err(format!("unknown light sampler \"{ls}\""))),
            };
        }
        if ip.bool("regularize", false)? {
            self.warn(
                &ip.loc,
                "integrator 'regularize' is not supported (ignored)",
            );
        }
        let hide = false;
        let path = |nee: bool| {
            IntegratorDesc::Path(PathDesc {
                max_depth: depth,
                nee,
                clamp,
                ..PathDesc::default()
            })
        };
        let volpath = IntegratorDesc::VolPath {
            max_depth: depth,
            rr_depth: 5,
            hide_emitters: hide,
            equiangular: true,
            transmittance: TransmittanceEstimator::default(),
            sample_emission: false,
        };
        let integrator = match ity.as_str() {
            "path" => path(true),
            "simplepath" => {
                let nee = ip.bool("samplelights", true)?;
                let _ = ip.bool("samplebsdf", true)?;
                path(nee)
            }
            "randomwalk" => path(false),
            "volpath" | "simplevolpath" => volpath,
            "bdpt" => {
                let vs = ip.bool("visualizestrategies", false)?;
                let vw = ip.bool("visualizeweights", false)?;
                IntegratorDesc::Bdpt {
                    max_depth: depth,
                    visualize_strategies: vs,
                    visualize_weights: vw,
                }
            }
            "mlt" => IntegratorDesc::Mlt {
                max_depth: depth,
                bootstrap: ip.int_in("bootstrapsamples", 100_000, 1, 1 << 30)? as u32,
                chains: ip.int_in("chains", 1000, 1, 1 << 24)? as u32,
                large_step: ip.float("largestepprobability", 0.3)?,
                sigma: ip.float("sigma", 0.01)?,
                direct_samples: -1,
                multiplexed: true,
            },
            "sppm" => {
                let photons = ip.int("photonsperiteration", -1)?;
                // pbrt-v4 runs one iteration per pixel sample; pbrt-v3 named the count.
                let mut passes = None;
                for n in ["iterations", "numiterations"] {
                    if ip.has(n) {
                        passes = Some(ip.int_in(n, 64, 1, 1 << 24)? as u32);
                    }
                }
                let _ = ip.int("seed", 0)?;
                IntegratorDesc::Sppm(SppmDesc {
                    max_depth: depth,
                    photons: (photons > 0).then_some(photons as u64),
                    initial_radius: Some(ip.float("radius", 1.0)?),
                    passes,
                    ..SppmDesc::default()
                })
            }
            "lightpath" => IntegratorDesc::Ptracer {
                max_depth: depth,
                hide_emitters: false,
            },
            "ambientocclusion" => {
                let d = ip.float("maxdistance", f32::INFINITY)?;
                let _ = ip.bool("cossample", true)?;
                IntegratorDesc::AmbientOcclusion {
                    samples: 1,
                    length: d.is_finite().then_some(d),
                }
            }
            "directlighting" | "whitted" => {
                self.warn_once(
                    "v3 integrator",
                    &ip.loc,
                    format!("pbrt-v3 integrator \"{ity}\" rendered by the path tracer"),
                );
                let _ = ip.string("strategy", "");
                path(true)
            }
            "aov" => {
                self.warn(&ip.loc, "integrator \"aov\" is not supported: volpath used");
                volpath
            }
            _ => return Err(err(&ip.loc, format!("unknown integrator \"{ity}\""))),
        };
        if clamp.is_some() && !matches!(integrator, IntegratorDesc::Path(_)) {
            self.warn(
                &fp.loc,
                "film 'maxcomponentvalue' applies to the path integrator only (ignored)",
            );
        }
        if matches!(ity.as_str(), "simplevolpath" | "randomwalk") {
            self.warn(
                &ip.loc,
                format!("integrator \"{ity}\" is rendered by an unbiased counterpart (same mean)"),
            );
        }
        self.finish_params("Integrator", &ity, &ip);
        self.scene.integrator = integrator;

        // Camera.
        let (cty, cp, cam_from_world, medium) = opts.camera.unwrap_or((
            "perspective".into(),
            Params {
                list: vec![],
                loc: loc0.clone(),
            },
            [Mat4::IDENTITY; 2],
            None,
        ));
        let world_from_camera = cam_from_world[0].inverse();
        if !world_from_camera.is_finite() {
            return Err(err(&cp.loc, "the camera transform is not invertible"));
        }
        if cam_from_world[0] != cam_from_world[1] {
            self.warn(
                &cp.loc,
                "camera motion is not supported (shutter-open transform used)",
            );
        }
        // pbrt's camera space has +x to the image's right; ours (Mitsuba's) to its left.
        let mut to_world = world_from_camera * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let _ = (
            cp.float("shutteropen", 0.0)?,
            cp.float("shutterclose", 1.0)?,
        );
        let frame = cp.float_opt("frameaspectratio")?.filter(|a| *a > 0.0);
        let aspect = frame.unwrap_or(w as f32 / h as f32);
        let screen = match cp.get("screenwindow", &[Ty::Float])? {
            Some(q) => match q.nums() {
                [a, b, c, d] => Some([*a as f32, *b as f32, *c as f32, *d as f32]),
                _ => return Err(q.err("expected 4 values")),
            },
            // A frame aspect ratio other than the film's: pbrt's default window for it (the
            // shorter side spans [-1, 1]), stretched over the film.
            None if frame.is_some_and(|a| a != w as f32 / h as f32) => Some(if aspect > 1.0 {
                [-aspect, aspect, -1.0, 1.0]
            } else {
                [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect]
            }),
            None => None,
        };
        let lens = cp.float("lensradius", 0.0)?;
        let focus = cp.float("focaldistance", 1e6)?;
        let projection = match cty.as_str() {
            "perspective" => {
                let fov = cp.float("fov", 90.0)?;
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(err(&cp.loc, format!("fov {fov} is outside (0, 180)")));
                }
                match screen {
                    Some([x0, x1, y0, y1]) => {
                        if lens > 0.0 {
                            self.warn(&cp.loc, "a screenwindow with a lens: rendered as a pinhole");
                        }
                        let t = (fov.to_radians() / 2.0).tan();
                        Projection::Window {
                            left: x0 * t,
                            right: x1 * t,
                            bottom: y0 * t,
                            top: y1 * t,
                        }
                    }
                    None if lens > 0.0 => Projection::ThinLens {
                        fov,
                        fov_axis: FovAxis::Smaller,
                        aperture_radius: lens,
                        focus_distance: focus,
                    },
                    None => Projection::Perspective {
                        fov,
                        fov_axis: FovAxis::Smaller,
                    },
                }
            }
            "orthographic" => {
                if lens > 0.0 {
                    self.warn(
                        &cp.loc,
                        "orthographic camera: the lens is not supported (pinhole)",
                    );
                }
                // pbrt's screen window spans [-1, 1] on the shorter axis; ours on x.
                let s = match screen {
                    Some([x0, x1, _, _]) => {
                        let cx = (x0 + x1) / 2.0;
                        to_world *= Mat4::from_translation(Vec3::new(-cx, 0.0, 0.0));
                        (x1 - x0) / 2.0
                    }
                    None => aspect.max(1.0),
                };
                to_world *= Mat4::from_scale(Vec3::new(s, s, 1.0));
                Projection::Orthographic
            }
            "realistic" | "spherical" => {
                return Err(err(&cp.loc, format!("camera \"{cty}\" is not supported")));
            }
            _ => return Err(err(&cp.loc, format!("unknown camera \"{cty}\""))),
        };
        self.finish_params("Camera", &cty, &cp);
        let medium = self.medium_id(&medium, &cp.loc)?;
        self.scene.sensors.push(Sensor {
            camera: Camera {
                projection,
                to_world,
                near_clip: 1e-4,
                far_clip: f32::INFINITY.min(1e30),
            },
            film: Film {
                width: w,
                height: h,
                crop,
                filter,
                output,
                tonemap: None,
            },
            sampler,
            integrator: None,
            medium,
            name: None,
            loc: cp.loc.clone(),
        });
        Ok(self.scene)
    }
}

fn tabulated(v: &[f64], p: &Param) -> Result<SpectrumKind> {
    if v.len() < 4 || !v.len().is_multiple_of(2) {
        return Err(p.err("a tabulated spectrum needs pairs of wavelength and value"));
    }
    let wavelengths: Vec<f64> = v.iter().step_by(2).copied().collect();
    let values: Vec<f64> = v.iter().skip(1).step_by(2).copied().collect();
    if wavelengths.windows(2).any(|w| w[1] <= w[0]) {
        return Err(p.err("wavelengths must be strictly increasing"));
    }
    Ok(SpectrumKind::Tabulated {
        wavelengths,
        values,
    })
}

fn const_of(t: &TexVal) -> Option<Rgb> {
    match t {
        TexVal::Const(c) => Some(*c),
        TexVal::Spectrum(s) => Some(s.rgb),
        TexVal::Tex(_) => None,
    }
}

fn color_of(t: TexVal) -> ColorParam {
    match t {
        TexVal::Const(c) => ColorParam::Const(c),
        TexVal::Spectrum(s) => ColorParam::Spectrum(s),
        TexVal::Tex(t) => ColorParam::Texture(t),
    }
}

fn float_of(t: TexVal) -> FloatParam {
    match t {
        TexVal::Const(c) => FloatParam::Const(c.x),
        TexVal::Spectrum(s) => FloatParam::Const(s.rgb.x),
        TexVal::Tex(t) => FloatParam::Texture(t),
    }
}

fn is_smooth(u: &FloatParam, v: &FloatParam) -> bool {
    matches!((u, v), (FloatParam::Const(a), FloatParam::Const(b)) if a.max(*b) < SMOOTH_ALPHA)
}

/// pbrt-v4's conductor index from a normal-incidence reflectance r: η = 1, k = 2√r/√(1−r).
fn reflectance_index(r: Rgb) -> (ColorValue, ColorValue) {
    let r = r.clamp(Rgb::ZERO, Rgb::splat(0.9999));
    let k = Rgb::new(
        2.0 * r.x.sqrt() / (1.0 - r.x).sqrt(),
        2.0 * r.y.sqrt() / (1.0 - r.y).sqrt(),
        2.0 * r.z.sqrt() / (1.0 - r.z).sqrt(),
    );
    (ColorValue::Rgb(Rgb::ONE), ColorValue::Rgb(k))
}

fn conductor(au: FloatParam, av: FloatParam, eta: ColorValue, k: ColorValue) -> Material {
    if is_smooth(&au, &av) {
        Material::Conductor {
            eta,
            k,
            specular_reflectance: ColorParam::constant(1.0),
        }
    } else {
        Material::RoughConductor {
            distribution: MicrofacetDistribution::Ggx,
            alpha_u: au,
            alpha_v: av,
            eta,
            k,
            specular_reflectance: ColorParam::constant(1.0),
        }
    }
}

fn dielectric(
    thin: bool,
    au: FloatParam,
    av: FloatParam,
    eta: f32,
    dispersion: Option<Dispersion>,
) -> Material {
    let one = || ColorParam::constant(1.0);
    if thin {
        Material::ThinDielectric {
            int_ior: eta,
            ext_ior: 1.0,
            dispersion,
            specular_reflectance: one(),
            specular_transmittance: one(),
        }
    } else if is_smooth(&au, &av) {
        Material::Dielectric {
            int_ior: eta,
            ext_ior: 1.0,
            dispersion,
            specular_reflectance: one(),
            specular_transmittance: one(),
            absorption: None,
        }
    } else {
        Material::RoughDielectric {
            distribution: MicrofacetDistribution::Ggx,
            alpha_u: au,
            alpha_v: av,
            int_ior: eta,
            ext_ior: 1.0,
            dispersion,
            dispersion_sampling: DispersionSampling::Terminate,
            specular_reflectance: one(),
            specular_transmittance: one(),
        }
    }
}
