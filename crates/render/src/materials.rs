//! Materials at run time: scene materials plus what is precomputed once per material (rough
//! plastic's Fresnel tables), and the per-hit construction of a [`Bsdf`] with its textures
//! evaluated at the hit.
//!
//! `twosided` is resolved here: when the viewer is on the back side, the shading frame is
//! flipped and the back (or front) material is used, as Mitsuba does. Shapes without a material
//! get Mitsuba's default, a one-sided diffuse of reflectance 0.5 — or, on an emitter, none.

use std::sync::Arc;

use scene::{ColorParam, CourseIdealKind, FloatParam, Material};

use crate::bsdf::Microfacet;
use crate::bsdf::{
    Bsdf, Conductor, CourseMaterial, Dielectric, Diffuse, IdealLobe, MicrofacetType,
    NoriMicrofacet, PhongFamily, Plastic, RoughConductor, RoughDielectric, RoughPlastic,
    RoughPlasticTables, ThinDielectric,
};
use crate::math::{Frame, PVec3, Vec3};
use crate::shapes::SurfaceInteraction;
use crate::textures::TexCoord;
use crate::world::Scene;

#[derive(Clone, Debug)]
pub struct RtMaterial {
    pub material: Material,
    /// Ambient reflectance (the Whitted integrator's ambient term).
    pub ambient: Vec3,
    /// Rough plastic's tables (depend only on α, the distribution and η).
    pub rough_plastic: Option<Arc<RoughPlasticTables>>,
}

/// Evaluates colour and scalar parameters (textures) at a surface point.
pub trait Params {
    fn color(&self, p: &ColorParam, at: TexCoord) -> Vec3;
    fn float(&self, p: &FloatParam, at: TexCoord) -> f32;
}

impl Params for Scene {
    fn color(&self, p: &ColorParam, at: TexCoord) -> Vec3 {
        Scene::color(self, p, at)
    }
    fn float(&self, p: &FloatParam, at: TexCoord) -> f32 {
        Scene::float(self, p, at)
    }
}

/// Parameters without textures (statistical tests of single BSDFs); a texture reads as 0.5.
pub struct ConstantParams;

impl Params for ConstantParams {
    fn color(&self, p: &ColorParam, _at: TexCoord) -> Vec3 {
        match p {
            ColorParam::Const(c) => (*c).into(),
            ColorParam::Texture(_) => Vec3::splat(0.5),
        }
    }
    fn float(&self, p: &FloatParam, _at: TexCoord) -> f32 {
        match p {
            FloatParam::Const(c) => *c,
            FloatParam::Texture(_) => 0.5,
        }
    }
}

impl RtMaterial {
    pub fn new(material: Material, ambient: Vec3) -> RtMaterial {
        let rough_plastic = match &material {
            Material::RoughPlastic {
                distribution,
                alpha,
                int_ior,
                ext_ior,
                ..
            } => Some(Arc::new(RoughPlasticTables::new(
                Microfacet::isotropic(MicrofacetType::from(*distribution), *alpha),
                int_ior / ext_ior,
            ))),
            _ => None,
        };
        RtMaterial {
            material,
            ambient,
            rough_plastic,
        }
    }
}

impl RtMaterial {
    /// The BSDF of this material with its parameters evaluated at `at` (`None` for `null`,
    /// `unlit` and an unresolved `twosided`, `normalmap` or `bumpmap`).
    pub fn bsdf<P: Params>(&self, p: &P, at: TexCoord) -> Option<Bsdf> {
        let bsdf = match &self.material {
            Material::Diffuse { reflectance } => {
                Bsdf::Diffuse(Diffuse::new(p.color(reflectance, at)))
            }
            Material::Conductor {
                eta,
                k,
                specular_reflectance,
            } => Bsdf::Conductor(Conductor::new(
                (*eta).into(),
                (*k).into(),
                p.color(specular_reflectance, at),
            )),
            Material::Mirror { reflectance } => {
                Bsdf::Conductor(Conductor::mirror(p.color(reflectance, at)))
            }
            Material::RoughConductor {
                distribution,
                alpha_u,
                alpha_v,
                eta,
                k,
                specular_reflectance,
            } => Bsdf::RoughConductor(RoughConductor::new(
                MicrofacetType::from(*distribution),
                alpha(p.float(alpha_u, at)),
                alpha(p.float(alpha_v, at)),
                (*eta).into(),
                (*k).into(),
                p.color(specular_reflectance, at),
            )),
            Material::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
                ..
            } => {
                let mut d = Dielectric::new(*int_ior, *ext_ior);
                d.specular_reflectance = p.color(specular_reflectance, at);
                d.specular_transmittance = p.color(specular_transmittance, at);
                Bsdf::Dielectric(d)
            }
            Material::ThinDielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => {
                let mut d = ThinDielectric::new(*int_ior, *ext_ior);
                d.specular_reflectance = p.color(specular_reflectance, at);
                d.specular_transmittance = p.color(specular_transmittance, at);
                Bsdf::ThinDielectric(d)
            }
            Material::RoughDielectric {
                distribution,
                alpha_u,
                alpha_v,
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => {
                let mut d = RoughDielectric::new(
                    MicrofacetType::from(*distribution),
                    alpha(p.float(alpha_u, at)),
                    alpha(p.float(alpha_v, at)),
                    *int_ior,
                    *ext_ior,
                );
                d.specular_reflectance = p.color(specular_reflectance, at);
                d.specular_transmittance = p.color(specular_transmittance, at);
                Bsdf::RoughDielectric(d)
            }
            Material::Plastic {
                diffuse_reflectance,
                specular_reflectance,
                int_ior,
                ext_ior,
                nonlinear,
            } => Bsdf::Plastic(Plastic::new(
                p.color(diffuse_reflectance, at),
                p.color(specular_reflectance, at),
                *int_ior,
                *ext_ior,
                *nonlinear,
            )),
            Material::RoughPlastic {
                distribution,
                alpha: a,
                diffuse_reflectance,
                specular_reflectance,
                int_ior,
                ext_ior,
                nonlinear,
            } => {
                let tables = self.rough_plastic.clone()?;
                Bsdf::RoughPlastic(RoughPlastic::with_tables(
                    Microfacet::isotropic(MicrofacetType::from(*distribution), alpha(*a)),
                    int_ior / ext_ior,
                    tables,
                    p.color(diffuse_reflectance, at),
                    p.color(specular_reflectance, at),
                    *nonlinear,
                ))
            }
            Material::NoriMicrofacet {
                alpha: a,
                int_ior,
                ext_ior,
                kd,
            } => Bsdf::NoriMicrofacet(NoriMicrofacet::new(
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
            } => {
                let phong = PhongFamily::new(
                    *model,
                    *normalized,
                    *kd_fresnel,
                    *exponent,
                    p.color(diffuse, at),
                    p.color(specular, at),
                    *ior,
                )
                .with_absorption(*ior, *absorption);
                match ideal {
                    None => Bsdf::PhongFamily(phong),
                    Some(i) => {
                        let lobe = match i.kind {
                            CourseIdealKind::Mirror => IdealLobe::Mirror,
                            CourseIdealKind::Conductor { eta, k } => {
                                IdealLobe::Conductor { eta, k }
                            }
                            CourseIdealKind::Dielectric { ior, .. } => {
                                IdealLobe::Dielectric { eta: ior }
                            }
                        };
                        Bsdf::from(CourseMaterial::new(
                            phong,
                            lobe,
                            i.reflectance.into(),
                            i.roughness,
                        ))
                    }
                }
            }
            Material::Null
            | Material::Unlit { .. }
            | Material::TwoSided { .. }
            | Material::NormalMap { .. }
            | Material::BumpMap { .. }
            | Material::Mask { .. } => return None,
        };
        Some(bsdf)
    }
}

/// Whether shading with material `id` is unchanged when the tangent frame turns about the
/// normal: no normal map and no anisotropic roughness anywhere in its `twosided`/`mask` chain
/// (`None`, Mitsuba's default diffuse, is). Interaction may then take the tangent from a
/// triangle edge instead of the uv parameterisation (see [`crate::shapes::interaction`]); only
/// the mapping of random numbers to directions changes, not any distribution. An unknown id
/// counts as not isotropic.
pub fn isotropic(materials: &[scene::MaterialDesc], id: Option<scene::MaterialId>) -> bool {
    let Some(id) = id else { return true };
    let mut todo = vec![id];
    // The ids walked so far: chains are a few materials long, and a set sized by the material
    // count would make the per-shape call quadratic over the scene.
    let mut seen: Vec<u32> = Vec::new();
    let same = |a: &FloatParam, b: &FloatParam| match (a, b) {
        (FloatParam::Const(a), FloatParam::Const(b)) => a == b,
        (FloatParam::Texture(a), FloatParam::Texture(b)) => a == b,
        _ => false,
    };
    while let Some(id) = todo.pop() {
        let Some(m) = materials.get(id.0 as usize) else {
            return false;
        };
        if seen.contains(&id.0) {
            continue;
        }
        seen.push(id.0);
        match &m.material {
            Material::TwoSided { front, back } => todo.extend(std::iter::once(*front).chain(*back)),
            Material::Mask { nested, .. } => todo.push(*nested),
            Material::NormalMap { .. } | Material::BumpMap { .. } => return false,
            Material::RoughConductor {
                alpha_u, alpha_v, ..
            }
            | Material::RoughDielectric {
                alpha_u, alpha_v, ..
            } => {
                if !same(alpha_u, alpha_v) {
                    return false;
                }
            }
            Material::Diffuse { .. }
            | Material::Conductor { .. }
            | Material::Mirror { .. }
            | Material::Dielectric { .. }
            | Material::ThinDielectric { .. }
            | Material::Plastic { .. }
            | Material::RoughPlastic { .. }
            | Material::NoriMicrofacet { .. }
            | Material::PhongFamily { .. }
            | Material::Unlit { .. }
            | Material::Null => {}
        }
    }
    true
}

/// Mitsuba clamps roughness away from 0 to keep the microfacet models finite.
fn alpha(a: f32) -> f32 {
    a.max(1e-4)
}

impl Scene {
    /// The BSDF at `si` and the shading frame it lives in (flipped for the back side of a
    /// two-sided material). `None`: the surface does not scatter (null material).
    /// The Beer–Lambert absorption coefficient inside the material at `si` (a smooth
    /// dielectric with `absorption`), evaluated when a path enters it.
    pub fn interior_absorption(&self, si: &SurfaceInteraction) -> Option<Vec3> {
        let id = self.shapes[si.shape as usize].material?;
        match &self.materials[id.0 as usize].material {
            Material::Dielectric {
                absorption: Some(sigma),
                ..
            }
            | Material::PhongFamily {
                ideal:
                    Some(scene::CourseIdeal {
                        kind:
                            CourseIdealKind::Dielectric {
                                absorption: Some(sigma),
                                ..
                            },
                        ..
                    }),
                ..
            } if *sigma != PVec3::ZERO => Some((*sigma).into()),
            _ => None,
        }
    }

    /// The colour an [`Material::Unlit`] surface shows at `si` (`None` for other materials).
    pub fn unlit_color(&self, si: &SurfaceInteraction) -> Option<Vec3> {
        let id = self.shapes[si.shape as usize].material?;
        match &self.materials[id.0 as usize].material {
            Material::Unlit { color } => Some(self.color(color, si.tex())),
            _ => None,
        }
    }

    /// The ambient reflectance of the material at `si` (`None` without a material).
    pub fn ambient_reflectance(&self, si: &SurfaceInteraction) -> Option<Vec3> {
        let id = self.shapes[si.shape as usize].material?;
        Some(self.materials[id.0 as usize].ambient)
    }

    pub fn bsdf_at(&self, si: &SurfaceInteraction) -> Option<(Bsdf, Frame)> {
        let mut frame = si.shading;
        let shape = &self.shapes[si.shape as usize];
        let Some(mut id) = shape.material else {
            // Mitsuba's default: diffuse 0.5, but black (non-scattering) on emitters.
            return (shape.emission.is_none())
                .then(|| (Bsdf::Diffuse(Diffuse::new(Vec3::splat(0.5))), frame));
        };
        // Bounded walk: a longer twosided chain than the material count is a cycle.
        let mut mat = None;
        for _ in 0..=self.materials.len() {
            let m = &self.materials[id.0 as usize];
            match &m.material {
                Material::TwoSided { front, back } => {
                    if si.wo.dot(frame.n) < 0.0 {
                        frame = Frame {
                            s: frame.s,
                            t: -frame.t,
                            n: -frame.n,
                        };
                        id = back.unwrap_or(*front);
                    } else {
                        id = *front;
                    }
                }
                Material::NormalMap { nested, texture } => {
                    let c = self.textures[texture.0 as usize].eval(si.tex());
                    let local = (c * 2.0 - Vec3::ONE).normalize_or_zero();
                    if local.z > 0.0 {
                        let n = frame.to_world(local).normalize();
                        frame = Frame::from_normal_tangent(n, frame.s);
                    }
                    id = *nested;
                }
                Material::BumpMap {
                    nested,
                    texture,
                    factor,
                } => {
                    let t = &self.textures[texture.0 as usize];
                    let g = t.height_gradient(si.tex(), frame.s, frame.t);
                    let n = frame.n;
                    let tilted = (n - *factor * (g - g.dot(n) * n)).normalize_or(n);
                    frame = Frame::from_normal_tangent(tilted, frame.s);
                    id = *nested;
                }
                // The opacity acts in `Scene::intersect` (a cut-out is never hit).
                Material::Mask { nested, .. } => id = *nested,
                _ => {
                    mat = Some(m);
                    break;
                }
            }
        }
        let bsdf = mat?.bsdf(self, si.tex())?;
        Some((bsdf, frame))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene::{MaterialDesc, MaterialId, MicrofacetDistribution, Rgb};

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
            distribution: MicrofacetDistribution::Ggx,
            alpha_u: FloatParam::Const(alpha_u),
            alpha_v: FloatParam::Const(alpha_v),
            eta: Rgb::splat(1.5),
            k: Rgb::splat(0.0),
            specular_reflectance: ColorParam::Const(Rgb::splat(1.0)),
        }
    }

    #[test]
    fn isotropy_follows_the_whole_chain() {
        let diffuse = Material::Diffuse {
            reflectance: ColorParam::Const(Rgb::splat(0.5)),
        };
        let mats = [
            desc(diffuse),         // 0
            desc(rough(0.1, 0.1)), // 1
            desc(rough(0.1, 0.3)), // 2
            desc(Material::TwoSided {
                front: MaterialId(0),
                back: Some(MaterialId(2)),
            }), // 3
            desc(Material::NormalMap {
                nested: MaterialId(0),
                texture: scene::TextureId(0),
            }), // 4
            desc(Material::Mask {
                nested: MaterialId(1),
                opacity: FloatParam::Const(0.5),
            }), // 5
            desc(Material::TwoSided {
                front: MaterialId(6),
                back: None,
            }), // 6: a cycle
            desc(Material::Mask {
                nested: MaterialId(4),
                opacity: FloatParam::Const(0.5),
            }), // 7
        ];
        let iso = |id: Option<u32>| isotropic(&mats, id.map(MaterialId));
        assert!(iso(None), "Mitsuba's default diffuse");
        assert!(iso(Some(0)) && iso(Some(1)) && iso(Some(5)) && iso(Some(6)));
        assert!(!iso(Some(2)), "alpha_u != alpha_v");
        assert!(!iso(Some(3)), "anisotropic back side");
        assert!(!iso(Some(4)) && !iso(Some(7)), "normal map");
        assert!(!iso(Some(99)), "unknown id");
    }
}
