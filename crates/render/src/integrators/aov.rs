//! Arbitrary-output-variable integrators: normals, albedo, depth, ambient occlusion.
//! They prove loaders, geometry, cameras and film right before any light transport exists.

use super::IntegratorModel;
use crate::camera::CameraRay;
use crate::drive::{self, Estimator};
use crate::math::{Frame, Vec3};
use crate::sampling::Sampler;
use crate::sampling::warp::square_to_cosine_hemisphere;
use crate::session::{Job, RenderOptions, RenderOutcome};
use crate::spectral::lanes::PathMode;
use crate::world::Scene;

/// The arbitrary output variables: what is seen at the first hit (RGB whatever the colour
/// mode).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aov {
    /// Shading normal at the first hit (world space, components in [-1,1]); 0 on a miss.
    Normals,
    /// Reflectance colour at the first hit; 0 on a miss.
    Albedo,
    /// Distance along the camera ray to the first hit; 0 on a miss.
    Depth,
    /// Fraction of the cosine-weighted hemisphere that is unoccluded within `length`.
    AmbientOcclusion { samples: u32, length: f32 },
    /// The denoiser's albedo: the reflectance colour of the first non-delta hit, seen through
    /// mirrors, glass and null boundaries (their sampled weights multiplied in), clamped to
    /// [0, 1]; 0 on an emitter; where the ray escapes, the environment's radiance clamped to
    /// [0, 1].
    DenoiseAlbedo,
    /// The denoiser's normal: the world-space shading normal of the same first non-delta hit;
    /// 0 on an emitter and where the ray escapes.
    DenoiseNormal,
}

/// Longest chain of delta or null surfaces the denoiser's auxiliary rays follow.
const MAX_DELTA_CHAIN: u32 = 16;

impl<M: PathMode> Estimator<M> for Aov {
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        match *self {
            Aov::Normals => normals(scene, cray),
            Aov::Albedo => albedo(scene, cray),
            Aov::Depth => depth(scene, cray),
            Aov::AmbientOcclusion { samples, length } => {
                ambient_occlusion(scene, cray, sampler, samples, length)
            }
            Aov::DenoiseAlbedo => first_non_delta(scene, cray, sampler, false),
            Aov::DenoiseNormal => first_non_delta(scene, cray, sampler, true),
        }
    }
}

impl IntegratorModel for Aov {
    fn name(&self) -> &'static str {
        match self {
            Aov::Normals => "normals",
            Aov::Albedo => "albedo",
            Aov::Depth => "depth",
            Aov::AmbientOcclusion { .. } => "ao",
            Aov::DenoiseAlbedo => "denoise-albedo",
            Aov::DenoiseNormal => "denoise-normal",
        }
    }

    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        drive::render_tiles::<M, Self>(job, self)
    }

    fn work_items(&self, scene: &Scene, opts: &RenderOptions) -> Result<u64, String> {
        Ok(drive::TileWork::new(scene, opts).len())
    }
}

fn normals(scene: &Scene, cray: &CameraRay) -> Vec3 {
    scene
        .intersect(&cray.ray, cray.t_max)
        .map_or(Vec3::ZERO, |si| si.shading.n)
}

fn albedo(scene: &Scene, cray: &CameraRay) -> Vec3 {
    scene
        .intersect(&cray.ray, cray.t_max)
        .map_or(Vec3::ZERO, |si| scene.albedo(&si))
}

/// The albedo (or, with `normal`, the normal) of the first hit whose BSDF has a non-delta
/// part, following delta lobes as sampled (so glass shows what lies behind or is reflected
/// in it, in proportion) and null surfaces straight on.
fn first_non_delta(scene: &Scene, cray: &CameraRay, sampler: &mut Sampler, normal: bool) -> Vec3 {
    use crate::bsdf::TransportMode;
    use crate::integrators::transport::{emitter_hit, environment};
    use crate::spectral::lanes::RgbMode;
    let mut ray = cray.ray;
    let mut t_max = cray.t_max;
    let mut weight = Vec3::ONE;
    for _ in 0..MAX_DELTA_CHAIN {
        let Some(si) = scene.intersect(&ray, t_max) else {
            if normal {
                return Vec3::ZERO;
            }
            let le = environment(scene, ray.d, &RgbMode, weight, |_, _| 1.0);
            return le.clamp(Vec3::ZERO, Vec3::ONE);
        };
        let Some((bsdf, frame)) = scene.bsdf_at(&si) else {
            // A null boundary (or no material): on through it.
            ray = si.spawn_ray(ray.d);
            t_max = f32::INFINITY;
            continue;
        };
        if bsdf.has_smooth() {
            // An emitter seen directly is "no surface" to the denoiser (albedo and normal 0),
            // which sets it apart from the surface around it: a luminaire in a ceiling has the
            // ceiling's normal and often its reflectance (bench/README.md, "Denoising",
            // compares this with the emitter's reflectance or colour as its albedo).
            if emitter_hit(scene, &si, &RgbMode).is_some() {
                return Vec3::ZERO;
            }
            return if normal {
                si.shading.n
            } else {
                (weight * bsdf.albedo()).clamp(Vec3::ZERO, Vec3::ONE)
            };
        }
        let (u1, u2) = (sampler.next_1d(), sampler.next_2d());
        let Some(s) = bsdf.sample(frame.to_local(si.wo), u1, u2, TransportMode::Radiance) else {
            return Vec3::ZERO;
        };
        weight *= s.weight;
        ray = si.spawn_ray(frame.to_world(s.wi));
        t_max = f32::INFINITY;
    }
    Vec3::ZERO
}

/// Distance along the camera ray from its origin on the near-clip plane (Mitsuba's `depth`
/// AOV; with `near_clip` 0 this is the distance from the camera centre).
fn depth(scene: &Scene, cray: &CameraRay) -> Vec3 {
    scene
        .intersect(&cray.ray, cray.t_max)
        .map_or(Vec3::ZERO, |si| Vec3::splat(si.t))
}

/// Cosine-weighted visibility: with pdf cos θ / π the estimator of (1/π)∫V cos θ dω is the
/// plain fraction of unoccluded rays. The hemisphere is the one the viewer sees.
fn ambient_occlusion(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    samples: u32,
    length: f32,
) -> Vec3 {
    let Some(si) = scene.intersect(&cray.ray, cray.t_max) else {
        return Vec3::ZERO;
    };
    let n = if si.wo.dot(si.shading.n) < 0.0 {
        -si.shading.n
    } else {
        si.shading.n
    };
    let frame = Frame::from_normal(n);
    let mut visible = 0u32;
    for _ in 0..samples {
        let d = frame.to_world(square_to_cosine_hemisphere(sampler.next_2d()));
        // Directions below the geometric surface are blocked by the surface itself.
        if d.dot(si.ng) * si.wo.dot(si.ng) <= 0.0 {
            continue;
        }
        let ray = si.spawn_ray(d);
        if !scene.occluded(&ray, length) {
            visible += 1;
        }
    }
    Vec3::splat(visible as f32 / samples as f32)
}
