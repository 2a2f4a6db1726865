//! Arbitrary-output-variable integrators: normals, albedo, depth, ambient occlusion.
//! They prove loaders, geometry, cameras and film right before any light transport exists.

use super::IntegratorModel;
use crate::camera::CameraRay;
use crate::drive::{self, Estimator};
use crate::math::{Frame, Vec3};
use crate::sampling::Sampler;
use crate::sampling::warp::square_to_cosine_hemisphere;
use crate::session::{Job, RenderOutcome};
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
}

impl<M: PathMode> Estimator<M> for Aov {
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        match *self {
            Aov::Normals => normals(scene, cray),
            Aov::Albedo => albedo(scene, cray),
            Aov::Depth => depth(scene, cray),
            Aov::AmbientOcclusion { samples, length } => {
                ambient_occlusion(scene, cray, sampler, samples, length)
            }
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
        }
    }

    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        drive::render_tiles::<M, Self>(job, self)
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
