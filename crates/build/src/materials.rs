//! Material factories: scene materials to runtime ones ([`RtMaterial`]). `twosided`,
//! `normalmap`, `bumpmap` and `mask` chains are resolved here, once, into layers; parameters
//! become texture references.

use std::collections::HashMap;
use std::sync::Arc;

use render::bsdf::{IdealLobe, Microfacet, MicrofacetType, NoriMicrofacet, RoughPlasticTables};
use render::materials::{
    Coated, CoatedBase, ConductorSpectra, CourseLobe, Layer, MaterialKind, Perturb,
    PrincipledParams, PrincipledThinParams, RtMaterial, Then, alpha,
};
use render::math::PVec3;
use render::spectral::DeclaredSpectrum;
use render::textures::{ColorRef, FloatRef, TexRef, Texture};
use scene::{
    ColorParam, ColorValue, CourseIdeal, CourseIdealKind, FloatParam, Loc, Material, MaterialDesc,
    MaterialId, Rgb, SpectrumDesc, SpectrumKind, SubsurfaceMedium,
};

use crate::BuildError;

/// The runtime materials of `materials`, in order, followed by Mitsuba's default diffuse
/// (for shapes without a material) whose index is returned too.
pub(crate) fn materials(
    materials: &[MaterialDesc],
    declared: &mut Declared,
    tables: &mut PlasticTables,
) -> Result<(Vec<RtMaterial>, u32), BuildError> {
    let mut resolver = MaterialResolver {
        materials,
        kinds: vec![None; materials.len()],
        declared,
        tables,
    };
    let mut list = (0..materials.len() as u32)
        .map(|id| resolver.material(MaterialId(id)))
        .collect::<Result<Vec<_>, _>>()?;
    let default_material = list.len() as u32;
    list.push(RtMaterial::default_diffuse());
    Ok((list, default_material))
}

/// What lies inside the shapes of a material, when the material itself says so.
pub(crate) enum Interior<'a> {
    /// Beer–Lambert absorption per unit length.
    Beer(Rgb),
    /// A subsurface material's scattering medium.
    Subsurface(&'a SubsurfaceMedium),
}

/// The material that declares what lies inside shapes using material `id`, and what that
/// is: `id` itself when it is a smooth dielectric (Mitsuba's or a course one) with a
/// non-zero Beer–Lambert `absorption`, or a `subsurface` material; or the material that the
/// normal maps, bump maps and masks around it wrap (they change the surface, not what lies
/// behind it). A `twosided` material has no inside, so none through it.
pub(crate) fn interior_of(
    materials: &[MaterialDesc],
    mut id: MaterialId,
) -> Option<(MaterialId, Interior<'_>)> {
    // A chain of wrappers longer than the material list is a cycle.
    for _ in 0..=materials.len() {
        match &materials.get(id.0 as usize)?.material {
            Material::NormalMap { nested, .. }
            | Material::BumpMap { nested, .. }
            | Material::HeightBump { nested, .. }
            | Material::Mask { nested, .. } => id = *nested,
            Material::Subsurface { medium, .. } => {
                return Some((id, Interior::Subsurface(medium)));
            }
            Material::Dielectric {
                absorption: Some(sigma),
                ..
            }
            | Material::PhongFamily {
                ideal:
                    Some(CourseIdeal {
                        kind:
                            CourseIdealKind::Dielectric {
                                absorption: Some(sigma),
                                ..
                            },
                        ..
                    }),
                ..
            } if *sigma != PVec3::ZERO => return Some((id, Interior::Beer(*sigma))),
            _ => return None,
        }
    }
    None
}

/// Rough plastic's tables (its coating's transmittance and internal reflectance, integrated
/// numerically: most of a build's time in scenes with several rough plastics), by what they
/// depend on: the distribution, α and η. Kept by [`crate::BuildCache`] so that a build after
/// an edit computes only the tables of the materials whose α or η changed.
#[derive(Default)]
pub(crate) struct PlasticTables {
    tables: HashMap<(u8, u32, u32), Arc<RoughPlasticTables>>,
    /// The keys the build in progress asked for (see [`PlasticTables::keep_used`]).
    used: Vec<(u8, u32, u32)>,
}

impl PlasticTables {
    fn get(&mut self, kind: MicrofacetType, alpha: f32, eta: f32) -> Arc<RoughPlasticTables> {
        let key = (kind as u8, alpha.to_bits(), eta.to_bits());
        self.used.push(key);
        self.tables
            .entry(key)
            .or_insert_with(|| {
                Arc::new(RoughPlasticTables::new(
                    Microfacet::isotropic(kind, alpha),
                    eta,
                ))
            })
            .clone()
    }

    /// Forget the tables the last build did not use (a roughness sweep keeps one per
    /// material, not one per value swept).
    pub fn keep_used(&mut self) {
        let used = std::mem::take(&mut self.used);
        self.tables.retain(|k, _| used.contains(k));
    }
}

/// Declared spectra on their way to the runtime scene. In RGB mode there are none: a
/// parameter declared as a spectrum is the constant of its RGB value, exactly as before
/// spectra were kept. In spectral mode each becomes a [`Texture::Spectrum`], appended after
/// the scene's own textures, which [`render::spectral::lanes::SpectralMode`] samples as
/// declared; conductor η/k and light constants carry theirs beside their RGB value.
pub(crate) struct Declared {
    spectral: bool,
    /// Index of the first texture made here (the scene's own texture count).
    first: u32,
    pub textures: Vec<Texture>,
}

impl Declared {
    pub fn new(spectral: bool, scene_textures: usize) -> Declared {
        Declared {
            spectral,
            first: scene_textures as u32,
            textures: Vec::new(),
        }
    }

    /// RGB mode, for callers outside a scene build (Nori's BSDF tests).
    pub fn rgb() -> Declared {
        Declared::new(false, 0)
    }

    /// A colour parameter as a runtime reference.
    pub fn color_ref(&mut self, p: &ColorParam) -> ColorRef {
        match p {
            ColorParam::Const(c) => TexRef::Const((*c).into()),
            ColorParam::Texture(t) => TexRef::Texture(t.0),
            ColorParam::Spectrum(s) => match self.spectrum(s) {
                Some(spectrum) => {
                    self.textures.push(Texture::Spectrum {
                        rgb: s.rgb.into(),
                        spectrum: Arc::new(spectrum),
                    });
                    TexRef::Texture(self.first + self.textures.len() as u32 - 1)
                }
                None => TexRef::Const(s.rgb.into()),
            },
        }
    }

    /// The runtime spectrum of a constant colour, in spectral mode when it was declared as one.
    pub fn value(&self, v: &ColorValue) -> Option<DeclaredSpectrum> {
        self.spectrum(v.spectrum()?)
    }

    fn spectrum(&self, s: &SpectrumDesc) -> Option<DeclaredSpectrum> {
        self.spectral.then(|| declared_spectrum(s)).flatten()
    }

    /// A conductor's declared η and k (spectral mode, when either was declared).
    fn conductor(&self, eta: &ColorValue, k: &ColorValue) -> Option<Arc<ConductorSpectra>> {
        let s = ConductorSpectra {
            eta: self.value(eta),
            k: self.value(k),
        };
        (s.eta.is_some() || s.k.is_some()).then(|| Arc::new(s))
    }
}

/// The runtime form of a declared spectrum, in Mitsuba 3's spectral units (see
/// `render::spectral::declared`): tables (lists, files, D65's 5 nm table, measured η/k) with
/// the scale applied, constants, black bodies. `None` for a table the model cannot give
/// (an unknown conductor name: the loader refuses those).
pub fn declared_spectrum(s: &SpectrumDesc) -> Option<DeclaredSpectrum> {
    Some(match &s.kind {
        SpectrumKind::Uniform(v) => DeclaredSpectrum::Constant((v * s.scale) as f32),
        SpectrumKind::Blackbody { temperature } => DeclaredSpectrum::Blackbody {
            temperature: *temperature,
            scale: s.scale,
        },
        kind => {
            let (w, v) = kind.table()?;
            let w: Vec<f32> = w.iter().map(|&w| w as f32).collect();
            let v: Vec<f32> = v.iter().map(|&v| (v * s.scale) as f32).collect();
            DeclaredSpectrum::tabulated(&w, &v)?
        }
    })
}

pub(crate) fn float_ref(p: &FloatParam) -> FloatRef {
    match p {
        FloatParam::Const(c) => TexRef::Const(*c),
        FloatParam::Texture(t) => TexRef::Texture(t.0),
    }
}

/// How deep `twosided` materials may nest with a normal or bump map between them (each level
/// doubles the resolved material). Nested directly, a `twosided` is resolved statically.
const MAX_SIDE_NESTING: usize = 8;

/// Resolves scene materials into runtime ones: `twosided`, `normalmap`, `bumpmap` and `mask`
/// chains become [`Layer`]s, each scattering model is converted once.
struct MaterialResolver<'a> {
    materials: &'a [MaterialDesc],
    kinds: Vec<Option<Option<MaterialKind>>>,
    declared: &'a mut Declared,
    tables: &'a mut PlasticTables,
}

impl MaterialResolver<'_> {
    fn material(&mut self, id: MaterialId) -> Result<RtMaterial, BuildError> {
        let m = &self.materials[id.0 as usize];
        Ok(RtMaterial {
            surface: self.layer(id, &mut Vec::new(), 0, &m.loc)?,
            ambient: m.ambient.into(),
            unlit: match &m.material {
                Material::Unlit { color } => Some(self.declared.color_ref(color)),
                _ => None,
            },
        })
    }

    /// The layer from material `id` down. `outer` holds the ids of the enclosing layers (a
    /// cycle ends in a surface that does not scatter); `depth` counts the `twosided` splits
    /// above: inside one, the frame already faces the viewer.
    fn layer(
        &mut self,
        mut id: MaterialId,
        outer: &mut Vec<u32>,
        depth: usize,
        loc: &Loc,
    ) -> Result<Layer, BuildError> {
        let mut perturbs = Vec::new();
        let start = outer.len();
        let done = |perturbs: Vec<Perturb>, outer: &mut Vec<u32>, then| {
            outer.truncate(start);
            Ok(Layer {
                perturbs: perturbs.into(),
                then,
            })
        };
        loop {
            let Some(m) = self.materials.get(id.0 as usize) else {
                return done(perturbs, outer, Then::Model(None));
            };
            if outer.contains(&id.0) {
                return done(perturbs, outer, Then::Model(None));
            }
            outer.push(id.0);
            match &m.material {
                // Directly inside a side the frame faces the viewer: the front is seen.
                Material::TwoSided { front, .. } if depth > 0 && perturbs.is_empty() => id = *front,
                Material::TwoSided { front, back } => {
                    if depth >= MAX_SIDE_NESTING {
                        return Err(BuildError {
                            loc: loc.clone(),
                            message: format!(
                                "twosided materials nested more than {MAX_SIDE_NESTING} deep"
                            ),
                        });
                    }
                    let f = self.layer(*front, outer, depth + 1, loc)?;
                    let b = match back {
                        Some(b) => self.layer(*b, outer, depth + 1, loc)?,
                        None => f.clone(),
                    };
                    return done(perturbs, outer, Then::Sides(Box::new([f, b])));
                }
                Material::NormalMap { nested, texture } => {
                    perturbs.push(Perturb::NormalMap { texture: texture.0 });
                    id = *nested;
                }
                Material::BumpMap {
                    nested,
                    texture,
                    factor,
                } => {
                    perturbs.push(Perturb::BumpMap {
                        texture: texture.0,
                        factor: *factor,
                    });
                    id = *nested;
                }
                Material::HeightBump {
                    nested,
                    texture,
                    scale,
                    flip_invalid_normals,
                    shadowing,
                } => {
                    perturbs.push(Perturb::HeightBump {
                        texture: texture.0,
                        scale: *scale,
                        flip: *flip_invalid_normals,
                        shadowing: *shadowing,
                    });
                    id = *nested;
                }
                // The opacity acts in `Scene::intersect` (a cut-out is never hit).
                Material::Mask { nested, .. } => id = *nested,
                Material::Mix { materials, amount } => {
                    if depth >= MAX_SIDE_NESTING {
                        return Err(BuildError {
                            loc: loc.clone(),
                            message: format!(
                                "twosided and mix materials nested more than {MAX_SIDE_NESTING} deep"
                            ),
                        });
                    }
                    let a = self.layer(materials[0], outer, depth + 1, loc)?;
                    let b = self.layer(materials[1], outer, depth + 1, loc)?;
                    return done(
                        perturbs,
                        outer,
                        Then::Mix {
                            amount: float_ref(amount),
                            layers: Box::new([a, b]),
                        },
                    );
                }
                Material::Blend { materials, weight } => {
                    if depth >= MAX_SIDE_NESTING {
                        return Err(BuildError {
                            loc: loc.clone(),
                            message: format!(
                                "twosided, mix and blend materials nested more than {MAX_SIDE_NESTING} deep"
                            ),
                        });
                    }
                    let a = self.layer(materials[0], outer, depth + 1, loc)?;
                    let b = self.layer(materials[1], outer, depth + 1, loc)?;
                    let then = match (a, b) {
                        // Two scattering models in the same frame: Mitsuba's blend, both
                        // evaluated.
                        (
                            Layer {
                                perturbs: pa,
                                then: Then::Model(Some(ka)),
                            },
                            Layer {
                                perturbs: pb,
                                then: Then::Model(Some(kb)),
                            },
                        ) if pa.is_empty() && pb.is_empty() => {
                            Then::Model(Some(MaterialKind::Blend {
                                weight: float_ref(weight),
                                kinds: Box::new([ka, kb]),
                            }))
                        }
                        // A wrapper (two-sided, bump or normal map, null) below the blend:
                        // one of the two chosen per hit with the blend's probability, which
                        // has the blend's mean but not its MIS densities.
                        (a, b) => Then::Mix {
                            amount: float_ref(weight),
                            layers: Box::new([a, b]),
                        },
                    };
                    return done(perturbs, outer, then);
                }
                _ => {
                    let kind = self.kind(id);
                    return done(perturbs, outer, Then::Model(kind));
                }
            }
        }
    }

    /// The scattering model of material `id` (a leaf: not a wrapper), converted once.
    fn kind(&mut self, id: MaterialId) -> Option<MaterialKind> {
        let slot = &mut self.kinds[id.0 as usize];
        if slot.is_none() {
            *slot = Some(material_kind_in(
                &self.materials[id.0 as usize].material,
                self.declared,
                self.tables,
            ));
        }
        slot.clone().flatten()
    }
}

/// The runtime model of a leaf material (`None`: it does not scatter), in RGB mode.
pub fn material_kind(m: &Material) -> Option<MaterialKind> {
    material_kind_in(m, &mut Declared::rgb(), &mut PlasticTables::default())
}

/// The runtime model of a leaf material, its declared spectra kept by `declared`.
fn material_kind_in(
    m: &Material,
    declared: &mut Declared,
    tables: &mut PlasticTables,
) -> Option<MaterialKind> {
    Some(match m {
        Material::Diffuse { reflectance } => MaterialKind::Diffuse {
            reflectance: declared.color_ref(reflectance),
        },
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
        } => MaterialKind::Conductor {
            eta: eta.rgb().into(),
            k: k.rgb().into(),
            specular: declared.color_ref(specular_reflectance),
            spectra: declared.conductor(eta, k),
        },
        Material::Mirror { reflectance } => MaterialKind::Mirror {
            reflectance: declared.color_ref(reflectance),
        },
        Material::DiffuseTransmission {
            reflectance,
            transmittance,
        } => MaterialKind::DiffuseTransmission {
            reflectance: declared.color_ref(reflectance),
            transmittance: declared.color_ref(transmittance),
        },
        Material::CoatedDiffuse {
            reflectance,
            alpha_u,
            alpha_v,
            remap_roughness,
            eta,
            thickness,
            albedo,
            g,
            max_depth,
            n_samples,
        } => MaterialKind::Coated(Box::new(Coated {
            alpha_u: float_ref(alpha_u),
            alpha_v: float_ref(alpha_v),
            remap_roughness: *remap_roughness,
            eta: *eta,
            thickness: float_ref(thickness),
            albedo: declared.color_ref(albedo),
            g: float_ref(g),
            max_depth: *max_depth,
            n_samples: *n_samples,
            base: CoatedBase::Diffuse {
                reflectance: declared.color_ref(reflectance),
            },
        })),
        Material::CoatedConductor {
            interface_alpha_u,
            interface_alpha_v,
            remap_roughness,
            interface_eta,
            thickness,
            albedo,
            g,
            max_depth,
            n_samples,
            conductor_alpha_u,
            conductor_alpha_v,
            conductor_eta,
            conductor_k,
            reflectance,
        } => MaterialKind::Coated(Box::new(Coated {
            alpha_u: float_ref(interface_alpha_u),
            alpha_v: float_ref(interface_alpha_v),
            remap_roughness: *remap_roughness,
            eta: *interface_eta,
            thickness: float_ref(thickness),
            albedo: declared.color_ref(albedo),
            g: float_ref(g),
            max_depth: *max_depth,
            n_samples: *n_samples,
            base: CoatedBase::Conductor {
                alpha_u: float_ref(conductor_alpha_u),
                alpha_v: float_ref(conductor_alpha_v),
                eta: conductor_eta.rgb().into(),
                k: conductor_k.rgb().into(),
                spectra: declared.conductor(conductor_eta, conductor_k),
                reflectance: reflectance.as_ref().map(|r| declared.color_ref(r)),
            },
        })),
        Material::RoughConductor {
            distribution,
            alpha_u,
            alpha_v,
            eta,
            k,
            specular_reflectance,
        } => MaterialKind::RoughConductor {
            distribution: MicrofacetType::from(*distribution),
            alpha_u: float_ref(alpha_u),
            alpha_v: float_ref(alpha_v),
            eta: eta.rgb().into(),
            k: k.rgb().into(),
            specular: declared.color_ref(specular_reflectance),
            spectra: declared.conductor(eta, k),
        },
        Material::Dielectric {
            int_ior,
            ext_ior,
            dispersion,
            specular_reflectance,
            specular_transmittance,
            ..
        } => MaterialKind::Dielectric {
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            dispersion: *dispersion,
            reflectance: declared.color_ref(specular_reflectance),
            transmittance: declared.color_ref(specular_transmittance),
        },
        // The boundary only: the medium inside is the build's (`media::interior_media`).
        Material::Subsurface { boundary, .. } => {
            return material_kind_in(boundary, declared, tables);
        }
        Material::ThinDielectric {
            int_ior,
            ext_ior,
            dispersion,
            specular_reflectance,
            specular_transmittance,
        } => MaterialKind::ThinDielectric {
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            dispersion: *dispersion,
            reflectance: declared.color_ref(specular_reflectance),
            transmittance: declared.color_ref(specular_transmittance),
        },
        Material::RoughDielectric {
            distribution,
            alpha_u,
            alpha_v,
            int_ior,
            ext_ior,
            dispersion,
            dispersion_sampling,
            specular_reflectance,
            specular_transmittance,
        } => MaterialKind::RoughDielectric {
            distribution: MicrofacetType::from(*distribution),
            alpha_u: float_ref(alpha_u),
            alpha_v: float_ref(alpha_v),
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            dispersion: *dispersion,
            dispersion_sampling: *dispersion_sampling,
            reflectance: declared.color_ref(specular_reflectance),
            transmittance: declared.color_ref(specular_transmittance),
        },
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
            nonlinear,
        } => MaterialKind::Plastic {
            diffuse: declared.color_ref(diffuse_reflectance),
            specular: declared.color_ref(specular_reflectance),
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            nonlinear: *nonlinear,
        },
        Material::RoughPlastic {
            distribution,
            alpha: a,
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
            nonlinear,
        } => {
            let kind = MicrofacetType::from(*distribution);
            let eta = int_ior / ext_ior;
            MaterialKind::RoughPlastic {
                microfacet: Microfacet::isotropic(kind, alpha(*a)),
                eta,
                tables: tables.get(kind, *a, eta),
                diffuse: declared.color_ref(diffuse_reflectance),
                specular: declared.color_ref(specular_reflectance),
                nonlinear: *nonlinear,
            }
        }
        Material::NoriMicrofacet {
            alpha: a,
            int_ior,
            ext_ior,
            kd,
        } => MaterialKind::NoriMicrofacet(NoriMicrofacet::new(
            alpha(*a),
            *int_ior,
            *ext_ior,
            (*kd).into(),
        )),
        Material::PhongFamily {
            model,
            normalized,
            kd_fresnel,
            exponent,
            diffuse,
            specular,
            ior,
            absorption,
            ideal,
        } => MaterialKind::Phong {
            model: *model,
            normalized: *normalized,
            kd_fresnel: *kd_fresnel,
            exponent: *exponent,
            diffuse: declared.color_ref(diffuse),
            specular: declared.color_ref(specular),
            ior: *ior,
            absorption: *absorption,
            ideal: ideal.map(|i| CourseLobe {
                lobe: match i.kind {
                    CourseIdealKind::Mirror => IdealLobe::Mirror,
                    CourseIdealKind::Conductor { eta, k } => IdealLobe::Conductor { eta, k },
                    CourseIdealKind::Dielectric { ior, .. } => IdealLobe::Dielectric { eta: ior },
                },
                reflectance: i.reflectance.into(),
                roughness: i.roughness,
            }),
        },
        Material::PolarizedPlastic {
            distribution,
            alpha_u,
            alpha_v,
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
        } => MaterialKind::PolarizedPlastic {
            microfacet: Microfacet::new(
                MicrofacetType::from(*distribution),
                alpha(*alpha_u),
                alpha(*alpha_v),
            ),
            eta: int_ior / ext_ior,
            diffuse: declared.color_ref(diffuse_reflectance),
            specular: declared.color_ref(specular_reflectance),
        },
        Material::Principled(d) => MaterialKind::Principled(Box::new(PrincipledParams {
            base_color: declared.color_ref(&d.base_color),
            roughness: float_ref(&d.roughness),
            anisotropic: float_ref(&d.anisotropic),
            metallic: float_ref(&d.metallic),
            spec_trans: float_ref(&d.spec_trans),
            spec_tint: float_ref(&d.spec_tint),
            sheen: float_ref(&d.sheen),
            sheen_tint: float_ref(&d.sheen_tint),
            flatness: float_ref(&d.flatness),
            clearcoat: float_ref(&d.clearcoat),
            clearcoat_gloss: float_ref(&d.clearcoat_gloss),
            eta: d.eta,
            rates: d.rates,
        })),
        Material::PrincipledThin(d) => {
            MaterialKind::PrincipledThin(Box::new(PrincipledThinParams {
                base_color: declared.color_ref(&d.base_color),
                roughness: float_ref(&d.roughness),
                anisotropic: float_ref(&d.anisotropic),
                spec_trans: float_ref(&d.spec_trans),
                spec_tint: float_ref(&d.spec_tint),
                sheen: float_ref(&d.sheen),
                sheen_tint: float_ref(&d.sheen_tint),
                flatness: float_ref(&d.flatness),
                diff_trans: float_ref(&d.diff_trans),
                eta: float_ref(&d.eta),
                rates: d.rates,
            }))
        }
        Material::Null
        | Material::Unlit { .. }
        | Material::TwoSided { .. }
        | Material::NormalMap { .. }
        | Material::BumpMap { .. }
        | Material::HeightBump { .. }
        | Material::Mask { .. }
        | Material::Mix { .. }
        | Material::Blend { .. } => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene::MaterialDesc;

    fn desc(material: Material) -> MaterialDesc {
        MaterialDesc {
            material,
            ambient: Default::default(),
            name: None,
            loc: Default::default(),
        }
    }

    fn rough(alpha_u: f32, alpha_v: f32) -> Material {
        Material::RoughConductor {
            distribution: scene::MicrofacetDistribution::Ggx,
            alpha_u: FloatParam::Const(alpha_u),
            alpha_v: FloatParam::Const(alpha_v),
            eta: PVec3::splat(1.5).into(),
            k: PVec3::splat(0.0).into(),
            specular_reflectance: ColorParam::constant(1.0),
        }
    }

    fn resolve(mats: &[MaterialDesc], id: u32) -> Result<RtMaterial, BuildError> {
        MaterialResolver {
            materials: mats,
            kinds: vec![None; mats.len()],
            declared: &mut Declared::rgb(),
            tables: &mut PlasticTables::default(),
        }
        .material(MaterialId(id))
    }

    /// The shape of a resolved layer: perturbation count, then the model's name or the sides.
    fn shape(l: &Layer) -> String {
        let then = match &l.then {
            Then::Model(None) => "none".to_string(),
            Then::Model(Some(MaterialKind::Diffuse { .. })) => "diffuse".to_string(),
            Then::Model(Some(_)) => "other".to_string(),
            Then::Sides(s) => format!("[{} | {}]", shape(&s[0]), shape(&s[1])),
            Then::Mix { layers: s, .. } => format!("mix({}, {})", shape(&s[0]), shape(&s[1])),
        };
        format!("{}{then}", "p".repeat(l.perturbs.len()))
    }

    #[test]
    fn material_chains_resolve_into_layers() {
        let diffuse = Material::Diffuse {
            reflectance: ColorParam::constant(0.5),
        };
        let two = |front, back: Option<u32>| Material::TwoSided {
            front: MaterialId(front),
            back: back.map(MaterialId),
        };
        let normal = |nested| Material::NormalMap {
            nested: MaterialId(nested),
            texture: scene::TextureId(0),
        };
        let mask = |nested| Material::Mask {
            nested: MaterialId(nested),
            opacity: FloatParam::Const(0.5),
        };
        let mats = [
            desc(diffuse),         // 0
            desc(rough(0.1, 0.1)), // 1
            desc(rough(0.1, 0.3)), // 2
            desc(two(0, Some(2))), // 3
            desc(normal(0)),       // 4
            desc(mask(1)),         // 5
            desc(two(6, None)),    // 6: a cycle
            desc(mask(4)),         // 7
            desc(two(3, None)),    // 8: twosided directly inside twosided: its front
            desc(normal(3)),       // 9: a normal map around a twosided
            desc(two(9, Some(7))), // 10: twosided, normal map, twosided
            desc(Material::Null),  // 11
            desc(Material::Mix {
                materials: [MaterialId(0), MaterialId(4)],
                amount: FloatParam::Const(0.3),
            }), // 12
            desc(Material::Mix {
                materials: [MaterialId(12), MaterialId(2)],
                amount: FloatParam::Const(0.5),
            }), // 13
        ];
        let layer = |id| shape(&resolve(&mats, id).unwrap().surface);
        assert_eq!(layer(0), "diffuse");
        assert_eq!(layer(3), "[diffuse | other]");
        assert_eq!(layer(4), "pdiffuse");
        assert_eq!(layer(5), "other");
        assert_eq!(layer(6), "[none | none]");
        assert_eq!(layer(7), "pdiffuse");
        assert_eq!(layer(8), "[diffuse | diffuse]");
        assert_eq!(layer(9), "p[diffuse | other]");
        assert_eq!(layer(10), "[p[diffuse | other] | pdiffuse]");
        assert_eq!(layer(11), "none");
        assert_eq!(layer(12), "mix(diffuse, pdiffuse)");
        assert_eq!(layer(13), "mix(mix(diffuse, pdiffuse), other)");

        let iso = |id| resolve(&mats, id).unwrap().isotropic();
        assert!(iso(0) && iso(1) && iso(5) && iso(6) && iso(8) && iso(11));
        assert!(!iso(2), "alpha_u != alpha_v");
        assert!(!iso(3), "anisotropic back side");
        assert!(!iso(4) && !iso(7) && !iso(9), "normal map");
        assert!(!iso(12) && !iso(13), "a normal map or anisotropy in a mix");
        assert!(RtMaterial::default_diffuse().isotropic());
    }

    #[test]
    fn twosided_nesting_through_normal_maps_is_bounded() {
        // twosided(normalmap(twosided(normalmap(... diffuse)))) 20 levels deep.
        let mut mats = vec![desc(Material::Diffuse {
            reflectance: ColorParam::constant(0.5),
        })];
        for _ in 0..20 {
            let below = mats.len() as u32 - 1;
            mats.push(desc(Material::NormalMap {
                nested: MaterialId(below),
                texture: scene::TextureId(0),
            }));
            mats.push(desc(Material::TwoSided {
                front: MaterialId(below + 1),
                back: None,
            }));
        }
        let err = resolve(&mats, mats.len() as u32 - 1).unwrap_err();
        assert!(err.message.contains("nested more than"), "{}", err.message);
        assert!(resolve(&mats, 2 * MAX_SIDE_NESTING as u32).is_ok());
    }
}
