//! The runtime scene: world-space geometry and its accelerator, materials, textures, lights,
//! the camera and the render settings, with the queries integrators make of them (closest
//! hit, occlusion, parameters at a hit, light selection). Built by [`crate::build`]; the
//! integrators, lights and materials read it and never the builder.

use std::sync::Arc;

use base::SamplerKind;
use base::spectrum::DeclaredSpectrum;

use crate::accel::{Accel, Hit};
use crate::bsdf::Bsdf;
use crate::camera::Camera;
use crate::film::FilmSettings;
use crate::geometry::Ray;
use crate::lights::select::LightSampler;
use crate::lights::{Light, LightScene, Receiver};
use crate::materials::RtMaterial;
use crate::math::{Frame, Vec2, Vec3};
use crate::media::Medium;
use crate::sampling::sampler::{mix64, u64_to_unit};
use crate::shapes::{ShapeInfo, SurfaceInteraction, interaction};
use crate::spectral::lanes::{ColorMode, RgbMode};
use crate::textures::{ColorRef, FloatRef, Params, TexCoord, Textures};

/// The lights of one shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeLights {
    None,
    /// One light for the whole shape.
    Whole(u32),
    /// One light per triangle: triangle `t` is light `first + t`.
    PerTriangle {
        first: u32,
        count: u32,
    },
}

/// The sampler a scene's pixel samples draw from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SamplerSettings {
    pub kind: SamplerKind,
    pub seed: u64,
}

pub struct Scene {
    /// The colour mode the scene was built for and its paths run in.
    pub mode: base::RenderMode,
    /// Shared, so that a build of an edited description that keeps the geometry (a material
    /// or light edit from Python's `scene.update`) reuses the tree instead of rebuilding it.
    pub accel: Arc<Accel>,
    pub shapes: Vec<ShapeInfo>,
    pub materials: Vec<RtMaterial>,
    /// Findings of the build step worth telling the user (unsupported features).
    pub warnings: Vec<String>,
    pub textures: Textures,
    pub camera: Camera,
    pub film: FilmSettings,
    /// How pixel samples draw their numbers (the samples per pixel are the render's,
    /// `RenderOptions::spp`).
    pub sampler: SamplerSettings,
    pub background: Option<Vec3>,
    /// A texture over the image seen by escaping camera rays (CENG795 `replace_background`).
    pub background_texture: Option<u32>,
    /// Whether any material is unlit (only then does the path loop look).
    pub has_unlit: bool,
    /// Sum of the scene's ambient lights, used by Whitted.
    pub ambient: Vec3,
    pub lights: Vec<Light>,
    /// Participating media, referenced by shapes and the camera.
    pub media: Vec<Medium>,
    /// The medium the camera sits in.
    pub camera_medium: Option<u32>,
    /// The light(s) of each shape; see [`Scene::shape_light`].
    pub shape_lights: Vec<ShapeLights>,
    /// How `sample_light` chooses.
    pub light_sampler: LightSampler,
    /// Lights seen by escaping rays (environment).
    pub infinite_lights: Vec<u32>,
    /// The medium each light emits into (indexed like `lights`): an emitting shape's
    /// exterior, the medium a point-like emitter was declared in. Paths that start on lights
    /// (photons) begin there.
    pub light_media: Vec<Option<u32>>,
    /// Bounds of the bounded geometry.
    pub bounds: (Vec3, Vec3),
    pub triangle_count: usize,
    /// Whether any shape has an [`ShapeInfo::opacity`] (only then do queries look at it).
    pub has_cutouts: bool,
    /// Whether any shape is an index-matched (`null`) boundary: without one, whatever a
    /// shadow ray hits blocks it, and `volpath` tests occlusion instead of walking hits.
    pub has_nulls: bool,
    /// Whether any shape moves (only then do camera rays draw a time).
    pub has_motion: bool,
    /// Set when a texture is MIP-filtered: texture lookups then carry a footprint, the
    /// camera's pixel spacing at the hit times this scale (pbrt-v4's max(1/8, 1/√spp):
    /// pixels are sampled many times, so each sample filters over less than a pixel).
    pub texture_footprint: Option<f32>,
}

impl Scene {
    /// Closest surface hit along `ray` with 0 < t < `t_max`. Alpha cut-outs are skipped as
    /// pbrt-v4 does: a hit on a shape with opacity α < 1 counts with probability α, decided by
    /// a hash of the ray and the primitive (so the decision is the same for every query of the
    /// same ray), and the search goes on from the far side of a skipped surface.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceInteraction> {
        self.surface(ray, t_max, self.hit(ray, t_max), |si| si.copied())
    }

    /// The closest primitive hit along `ray` with 0 < t < `t_max`, before cut-outs are
    /// considered: [`Scene::surface`] turns it into what [`Scene::intersect`] returns.
    #[inline]
    pub fn hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.accel.intersect(ray, t_max)
    }

    /// The closest surface along `ray` (as [`Scene::intersect`] finds it) with its interaction
    /// computed only when [`Closest::surface`] asks for it: the volumetric path tracer needs
    /// only the distance when a medium collision comes first, and only the shape when a
    /// shadow ray is blocked. Cut-outs are resolved at once.
    #[inline]
    pub fn closest(&self, ray: &Ray, t_max: f32) -> Closest {
        let hit = self.hit(ray, t_max);
        match hit {
            Some(h) if self.shapes[h.shape as usize].opacity.is_some() => {
                Closest::Surface(self.surface(ray, t_max, hit, |si| si.copied()))
            }
            _ => Closest::Hit(hit),
        }
    }

    /// Whether `shape`'s material is an index-matched boundary (see [`RtMaterial::is_null`]).
    #[inline]
    pub fn shape_is_null(&self, shape: u32) -> bool {
        self.shapes[shape as usize]
            .material
            .is_some_and(|m| self.materials[m as usize].is_null())
    }

    /// `f` applied to the surface interaction of `hit`, the result of [`Scene::hit`] for the
    /// same `ray` and `t_max` (cut-outs skipped as [`Scene::intersect`] does). The interaction
    /// is computed in place and lent to `f`: the hot loops would otherwise copy its 144 bytes
    /// once or twice per hit.
    #[inline(always)]
    pub fn surface<R>(
        &self,
        ray: &Ray,
        t_max: f32,
        hit: Option<Hit>,
        f: impl FnOnce(Option<&SurfaceInteraction>) -> R,
    ) -> R {
        let Some(hit) = hit else {
            return f(None);
        };
        let shape = &self.shapes[hit.shape as usize];
        let si = interaction(&shape.geom, &hit, ray, shape.flip_normals, shape.reads);
        if shape.opacity.is_none() {
            return f(Some(&si));
        }
        f(self.skip_cutouts(ray, t_max, hit, si).as_ref())
    }

    /// The first hit from `hit` (on a shape with an opacity) on that is not cut out (see
    /// [`Scene::intersect`]).
    #[cold]
    fn skip_cutouts(
        &self,
        ray: &Ray,
        t_max: f32,
        mut hit: Hit,
        mut si: SurfaceInteraction,
    ) -> Option<SurfaceInteraction> {
        let key = ray_hash(ray);
        let (mut cur, mut t_left) = (*ray, t_max);
        // Bounded: a ray crosses each primitive at most once (plus spheres' second side).
        for _ in 0..4096 {
            let shape = &self.shapes[hit.shape as usize];
            let Some(opacity) = &shape.opacity else {
                return Some(si);
            };
            let alpha = self.float(opacity, si.tex());
            let u = u64_to_unit(mix64(key ^ ((hit.shape as u64) << 32 | hit.prim as u64)));
            if alpha >= 1.0 || u < alpha {
                return Some(si);
            }
            // Cut out: continue from the far side, in the same direction and parameter units.
            t_left -= hit.t;
            cur = si.spawn_ray(cur.d);
            if t_left <= 0.0 {
                return None;
            }
            hit = self.accel.intersect(&cur, t_left)?;
            let shape = &self.shapes[hit.shape as usize];
            si = interaction(&shape.geom, &hit, &cur, shape.flip_normals, shape.reads);
        }
        None
    }

    /// Choose one light for next-event estimation at receiver `r`: its index, the light and
    /// the probability of that choice (`None` when no light can be chosen). Uniform (as
    /// Mitsuba), by power or with the light BVH, as the scene's light selection says.
    #[inline]
    pub fn sample_light(&self, u: f32, r: &Receiver) -> Option<(u32, &Light, f32)> {
        let (i, pmf) = self.light_sampler.sample(u, r, self.lights.len())?;
        Some((i, &self.lights[i as usize], pmf))
    }

    /// Probability that `sample_light` picks light `light` at receiver `r`.
    #[inline]
    pub fn light_pmf(&self, r: &Receiver, light: u32) -> f32 {
        self.light_sampler.pmf(r, light, self.lights.len())
    }

    /// The light that emits at `si` (the emitting shape's light, or with light selection by
    /// power or BVH the light of its triangle), if any.
    #[inline]
    pub fn shape_light(&self, si: &SurfaceInteraction) -> Option<u32> {
        match self.shape_lights.get(si.shape as usize)? {
            ShapeLights::None => None,
            ShapeLights::Whole(l) => Some(*l),
            ShapeLights::PerTriangle { first, count } => {
                (si.prim < *count).then_some(*first + si.prim)
            }
        }
    }

    /// Whether anything is hit with 0 < t < `t_max` (cut-outs skipped as in `intersect`).
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.has_cutouts {
            self.intersect(ray, t_max).is_some()
        } else {
            self.accel.occluded(ray, t_max)
        }
    }

    /// The value of a colour parameter at `at`.
    #[inline(always)]
    pub fn color(&self, p: &ColorRef, at: TexCoord) -> Vec3 {
        self.textures.color(p, at)
    }

    /// [`Scene::color`] for a scalar parameter.
    #[inline(always)]
    pub fn float(&self, p: &FloatRef, at: TexCoord) -> f32 {
        self.textures.float(p, at)
    }

    #[inline]
    fn material(&self, si: &SurfaceInteraction) -> Option<&RtMaterial> {
        let id = self.shapes[si.shape as usize].material?;
        Some(&self.materials[id as usize])
    }

    /// The BSDF at `si` and the shading frame it lives in (see [`RtMaterial::resolve`]).
    /// `None`: the surface does not scatter.
    #[inline]
    pub fn bsdf_at(&self, si: &SurfaceInteraction) -> Option<(Bsdf, Frame)> {
        self.bsdf_at_in(si, &RgbMode)
    }

    /// [`Scene::bsdf_at`] in the colour mode `m`. Kept out of line with the material's
    /// resolution and parameter evaluation inside, as the compiler chose for the RGB-only
    /// loop: inlined into the path loop instead, bench-cbox ran 7 % slower.
    #[inline(never)]
    pub fn bsdf_at_in<M: ColorMode>(
        &self,
        si: &SurfaceInteraction,
        m: &M,
    ) -> Option<(Bsdf<M::C>, Frame)> {
        let at = self.tex_at(si);
        let derivs = || self.shapes[si.shape as usize].geom.uv_derivatives(si.prim);
        let (kind, frame, bump) = self.material(si)?.resolve(&self.textures, si, at, derivs)?;
        let bsdf = kind.bsdf_in(&self.textures, at, m);
        Some(match bump {
            None => (bsdf, frame),
            Some(b) => (b.wrap(bsdf, &frame), frame),
        })
    }

    /// Where textures are looked up at `si`, with the lookup's footprint in uv when the
    /// scene filters textures (see [`Scene::texture_footprint`]).
    #[inline]
    pub fn tex_at(&self, si: &SurfaceInteraction) -> TexCoord {
        let mut at = si.tex();
        if let Some(scale) = self.texture_footprint
            && let Some((dpdu, dpdv)) = self.shapes[si.shape as usize].geom.uv_derivatives(si.prim)
        {
            let (dpdx, dpdy) = self.camera.approximate_dp_dxy(si.p, si.ng);
            at.duv = uv_footprint(dpdu, dpdv, [dpdx * scale, dpdy * scale]);
        }
        at
    }

    /// Whether the surface at `si` is an index-matched boundary (see [`RtMaterial::is_null`]).
    #[inline]
    pub fn is_null(&self, si: &SurfaceInteraction) -> bool {
        self.shape_is_null(si.shape)
    }

    /// The medium a path is in after leaving the surface at `si` in direction `d`, having been
    /// in `current`: the side `d` goes to when the shape bounds media, else unchanged.
    #[inline]
    pub fn medium_after(
        &self,
        si: &SurfaceInteraction,
        d: Vec3,
        current: Option<u32>,
    ) -> Option<u32> {
        let s = &self.shapes[si.shape as usize];
        if s.interior.is_none() && s.exterior.is_none() {
            current
        } else if d.dot(si.ng) > 0.0 {
            s.exterior
        } else {
            s.interior
        }
    }

    /// The medium on the far side of the surface at `si` for a path crossing it: the shape's
    /// interior when it crosses from the front, its exterior otherwise (the path tracer's
    /// choice, by the shading frame; `medium_after` decides by the geometric normal).
    #[inline]
    pub fn medium_across(&self, si: &SurfaceInteraction, from_front: bool) -> Option<u32> {
        let s = &self.shapes[si.shape as usize];
        if from_front { s.interior } else { s.exterior }
    }

    /// The medium at the point `p`, as the first surface that bounds media along a probe ray
    /// from `p` tells (the side of it `p` is on); `None` when no such surface lies along the
    /// probe (`p` is in whatever surrounds the scene's media).
    pub fn medium_at(&self, p: Vec3) -> Option<Option<u32>> {
        // An oblique direction: probes along an axis would run along the faces of boxes.
        let d = Vec3::new(0.267_261_24, 0.801_783_7, 0.534_522_5);
        let mut ray = Ray::new(p, d);
        for _ in 0..256 {
            let si = self.intersect(&ray, f32::INFINITY)?;
            let s = &self.shapes[si.shape as usize];
            if s.interior.is_some() || s.exterior.is_some() {
                return Some(self.medium_after(&si, -d, None));
            }
            ray = si.spawn_ray(d);
        }
        None
    }

    /// The colour an unlit surface shows at `si` (`None` for other materials).
    pub fn unlit_color(&self, si: &SurfaceInteraction) -> Option<Vec3> {
        let c = self.material(si)?.unlit.as_ref()?;
        Some(self.color(c, si.tex()))
    }

    /// The ambient reflectance of the material at `si` (`None` without a material).
    pub fn ambient_reflectance(&self, si: &SurfaceInteraction) -> Option<Vec3> {
        Some(self.material(si)?.ambient)
    }

    /// A representative reflectance colour at `si` (the `albedo` AOV).
    pub fn albedo(&self, si: &SurfaceInteraction) -> Vec3 {
        self.bsdf_at(si).map_or(Vec3::ZERO, |(b, _)| b.albedo())
    }
}

/// The changes of uv that best explain the surface steps `dp` (least squares through ∂p/∂u
/// and ∂p/∂v, as pbrt-v4's `SurfaceInteraction::ComputeDifferentials`); zero where the
/// parameterisation degenerates.
fn uv_footprint(dpdu: Vec3, dpdv: Vec3, dp: [Vec3; 2]) -> [Vec2; 2] {
    let (a00, a01, a11) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
    let inv = 1.0 / (a00 * a11 - a01 * a01);
    if !inv.is_finite() {
        return [Vec2::ZERO; 2];
    }
    dp.map(|d| {
        let (b0, b1) = (dpdu.dot(d), dpdv.dot(d));
        let duv = Vec2::new(a11 * b0 - a01 * b1, a00 * b1 - a01 * b0) * inv;
        if duv.is_finite() {
            duv.clamp(Vec2::splat(-1e8), Vec2::splat(1e8))
        } else {
            Vec2::ZERO
        }
    })
}

/// A 64-bit hash of a ray's origin and direction (the cut-out decision's randomness).
fn ray_hash(ray: &Ray) -> u64 {
    let bits = |v: Vec3| {
        (v.x.to_bits() as u64) ^ (v.y.to_bits() as u64) << 21 ^ (v.z.to_bits() as u64) << 42
    };
    mix64(bits(ray.o) ^ mix64(bits(ray.d)))
}

impl LightScene for Scene {
    #[inline(always)]
    fn shape(&self, i: u32) -> &ShapeInfo {
        &self.shapes[i as usize]
    }

    #[inline(always)]
    fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }
}

impl Params for Scene {
    #[inline(always)]
    fn color(&self, p: &ColorRef, at: TexCoord) -> Vec3 {
        self.textures.color(p, at)
    }

    #[inline(always)]
    fn float(&self, p: &FloatRef, at: TexCoord) -> f32 {
        self.textures.float(p, at)
    }

    #[inline(always)]
    fn spectrum(&self, p: &ColorRef) -> Option<&DeclaredSpectrum> {
        self.textures.spectrum(p)
    }
}

/// The result of [`Scene::closest`]: a hit whose interaction is not computed yet, or (on a
/// shape with cut-outs) the surface already resolved.
pub enum Closest {
    Hit(Option<Hit>),
    Surface(Option<SurfaceInteraction>),
}

impl Closest {
    /// The hit's ray parameter (`t_max` when nothing is hit). A surface found past cut-outs
    /// has its `t` on a ray spawned beyond them, so its parameter is measured from `ray`'s
    /// origin again.
    #[inline]
    pub fn t(&self, ray: &Ray, t_max: f32) -> f32 {
        match self {
            Closest::Hit(h) => h.as_ref().map_or(t_max, |h| h.t),
            Closest::Surface(si) => si.as_ref().map_or(t_max, |si| {
                (si.p - ray.o).dot(ray.d) / ray.d.length_squared()
            }),
        }
    }

    /// The shape hit, if any.
    #[inline]
    pub fn shape(&self) -> Option<u32> {
        match self {
            Closest::Hit(h) => h.as_ref().map(|h| h.shape),
            Closest::Surface(si) => si.as_ref().map(|si| si.shape),
        }
    }

    /// The surface interaction (what [`Scene::intersect`] returns for the same query).
    #[inline]
    pub fn surface(self, scene: &Scene, ray: &Ray, t_max: f32) -> Option<SurfaceInteraction> {
        match self {
            Closest::Hit(hit) => scene.surface(ray, t_max, hit, |si| si.copied()),
            Closest::Surface(si) => si,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_footprint_inverts_the_parameterisation() {
        let (dpdu, dpdv) = (Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
        let want = [Vec2::new(0.1, -0.2), Vec2::new(0.03, 0.05)];
        let dp = want.map(|d| dpdu * d.x + dpdv * d.y);
        let got = uv_footprint(dpdu, dpdv, dp);
        for (g, w) in got.iter().zip(want) {
            assert!((*g - w).length() < 1e-6, "{g} vs {w}");
        }
        assert_eq!(uv_footprint(dpdu, dpdu, dp), [Vec2::ZERO; 2], "degenerate");
    }
}
