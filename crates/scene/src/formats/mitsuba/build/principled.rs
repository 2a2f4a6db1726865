//! Mitsuba 3's `principled`, `principledthin`, `pplastic`, `blendbsdf` and `bumpmap` BSDFs →
//! the scene model, with Mitsuba 3.9's parameter names and defaults. A child of `build.rs`
//! (it uses the builder's parameter readers); `material_of` calls into it.

use super::{Result, SceneBuilder, err, ior};
use crate::formats::mitsuba::plugin::Plugin;
use crate::model::*;

/// Mitsuba's `get_flag`: a parameter is "on" when given, unless given as the float 0.
fn flag(pl: &Plugin<'_>, name: &str) -> bool {
    if pl.named_child(name).is_some() {
        return true;
    }
    match pl.props.float_opt(name) {
        Ok(Some(v)) => v != 0.0,
        Ok(None) => false,
        Err(_) => pl.props.has(name),
    }
}

impl<'s> SceneBuilder<'_, 's> {
    /// `principled`: every parameter but `eta`, `specular` and the sampling rates may be a
    /// texture; `eta` and `specular` exclude each other (Mitsuba refuses both).
    pub(super) fn principled(&mut self, pl: &Plugin<'s>) -> Result<Material> {
        let has_spec_trans = flag(pl, "spec_trans");
        let eta = match (pl.props.has("eta"), pl.props.has("specular")) {
            (true, true) => {
                return Err(err(
                    pl.loc(),
                    "principled: give either 'eta' or 'specular', not both",
                ));
            }
            (true, false) => {
                let eta = pl.props.float("eta", 1.5)?;
                // η = 1 cannot transmit: Mitsuba nudges it.
                if has_spec_trans && eta == 1.0 {
                    1.001
                } else {
                    eta
                }
            }
            (false, _) => {
                let mut specular = pl.props.float("specular", 0.5)?;
                if has_spec_trans && specular == 0.0 {
                    specular = 1e-3;
                }
                2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
            }
        };
        if !(eta > 0.0 && eta.is_finite()) {
            return Err(err(
                pl.loc(),
                format!("principled: the index of refraction must be positive, found {eta}"),
            ));
        }
        Ok(Material::Principled(Box::new(PrincipledDesc {
            base_color: self.color(pl, "base_color", 0.5, false)?,
            roughness: self.float_param(pl, "roughness", 0.5)?,
            anisotropic: self.float_param(pl, "anisotropic", 0.0)?,
            metallic: self.float_param(pl, "metallic", 0.0)?,
            spec_trans: self.float_param(pl, "spec_trans", 0.0)?,
            spec_tint: self.float_param(pl, "spec_tint", 0.0)?,
            sheen: self.float_param(pl, "sheen", 0.0)?,
            sheen_tint: self.float_param(pl, "sheen_tint", 0.0)?,
            flatness: self.float_param(pl, "flatness", 0.0)?,
            clearcoat: self.float_param(pl, "clearcoat", 0.0)?,
            clearcoat_gloss: self.float_param(pl, "clearcoat_gloss", 0.0)?,
            eta,
            rates: [
                pl.props.float("main_specular_sampling_rate", 1.0)?,
                pl.props.float("clearcoat_sampling_rate", 1.0)?,
                pl.props.float("diffuse_reflectance_sampling_rate", 1.0)?,
            ],
        })))
    }

    /// `principledthin`: every parameter but the sampling rates may be a texture (`eta`
    /// too); there is no `specular`.
    pub(super) fn principledthin(&mut self, pl: &Plugin<'s>) -> Result<Material> {
        Ok(Material::PrincipledThin(Box::new(PrincipledThinDesc {
            base_color: self.color(pl, "base_color", 0.5, false)?,
            roughness: self.float_param(pl, "roughness", 0.5)?,
            anisotropic: self.float_param(pl, "anisotropic", 0.0)?,
            spec_trans: self.float_param(pl, "spec_trans", 0.0)?,
            spec_tint: self.float_param(pl, "spec_tint", 0.0)?,
            sheen: self.float_param(pl, "sheen", 0.0)?,
            sheen_tint: self.float_param(pl, "sheen_tint", 0.0)?,
            flatness: self.float_param(pl, "flatness", 0.0)?,
            diff_trans: self.float_param(pl, "diff_trans", 0.0)?,
            eta: self.float_param(pl, "eta", 1.5)?,
            rates: [
                pl.props.float("specular_reflectance_sampling_rate", 1.0)?,
                pl.props
                    .float("specular_transmittance_sampling_rate", 1.0)?,
                pl.props.float("diffuse_reflectance_sampling_rate", 1.0)?,
                pl.props.float("diffuse_transmittance_sampling_rate", 1.0)?,
            ],
        })))
    }

    /// `blendbsdf`: two nested bsdfs and a `weight` (float or texture, required), the second
    /// one's share.
    pub(super) fn blendbsdf(&mut self, pl: &Plugin<'s>) -> Result<Material> {
        let nested = self.nested_bsdfs(pl)?;
        let [first, second] = nested[..] else {
            return Err(err(
                pl.loc(),
                format!("blendbsdf needs two nested bsdfs, found {}", nested.len()),
            ));
        };
        if !pl.props.has("weight") && pl.named_child("weight").is_none() {
            return Err(err(
                pl.loc(),
                "blendbsdf needs a 'weight' (float or texture)",
            ));
        }
        Ok(Material::Blend {
            materials: [first, second],
            weight: self.float_param(pl, "weight", 0.5)?,
        })
    }

    /// `bumpmap`: one nested bsdf, one texture (the height, any name), `scale` (1),
    /// `flip_invalid_normals` and `use_shadowing_function` (both true).
    pub(super) fn bumpmap(&mut self, pl: &Plugin<'s>) -> Result<Material> {
        let nested = self.one_nested_bsdf(pl)?;
        let textures: Vec<_> = pl.children_with(&["texture"]).collect();
        let [c] = textures[..] else {
            return Err(err(
                pl.loc(),
                format!("bumpmap needs one nested texture, found {}", textures.len()),
            ));
        };
        Ok(Material::HeightBump {
            nested,
            texture: self.texture(c)?,
            scale: pl.props.float("scale", 1.0)?,
            flip_invalid_normals: pl.props.bool("flip_invalid_normals", true)?,
            shadowing: pl.props.bool("use_shadowing_function", true)?,
        })
    }

    /// `pplastic`: `alpha` or `alpha_u`/`alpha_v` (floats), `distribution`, the reflectances
    /// (textures allowed), `int_ior`/`ext_ior`, which must differ.
    pub(super) fn pplastic(&mut self, pl: &Plugin<'s>) -> Result<Material> {
        let int_ior = self.ior(pl, "int_ior", ior::POLYPROPYLENE)?;
        let ext_ior = self.ior(pl, "ext_ior", ior::AIR)?;
        if int_ior == ext_ior {
            return Err(err(
                pl.loc(),
                "pplastic: the interior and exterior indices of refraction must differ",
            ));
        }
        let (alpha_u, alpha_v) = if pl.props.has("alpha_u") || pl.props.has("alpha_v") {
            (
                pl.props.float("alpha_u", 0.1)?,
                pl.props.float("alpha_v", 0.1)?,
            )
        } else {
            let a = pl.props.float("alpha", 0.1)?;
            (a, a)
        };
        // Visible normals are always sampled: without them only the noise would differ.
        pl.props.bool("sample_visible", true)?;
        Ok(Material::PolarizedPlastic {
            distribution: self.distribution(pl)?,
            alpha_u,
            alpha_v,
            diffuse_reflectance: self.color(pl, "diffuse_reflectance", 0.5, false)?,
            specular_reflectance: self.color(pl, "specular_reflectance", 1.0, false)?,
            int_ior,
            ext_ior,
        })
    }
}
