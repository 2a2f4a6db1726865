//! Arbitrary-output-variable integrators: normals, albedo, depth, ambient occlusion.
//! They prove loaders, geometry, cameras and film right before any light transport exists.

use crate::camera::CameraRay;
use crate::math::{Frame, Vec3};
use crate::sampling::Sampler;
use crate::sampling::warp::square_to_cosine_hemisphere;
use crate::world::Scene;

pub fn normals(scene: &Scene, cray: &CameraRay) -> Vec3 {
    scene
        .intersect(&cray.ray, cray.t_max)
        .map_or(Vec3::ZERO, |si| si.shading.n)
}

pub fn albedo(scene: &Scene, cray: &CameraRay) -> Vec3 {
    scene
        .intersect(&cray.ray, cray.t_max)
        .map_or(Vec3::ZERO, |si| scene.albedo(&si))
}

/// Distance along the camera ray from its origin on the near-clip plane (Mitsuba's `depth`
/// AOV; with `near_clip` 0 this is the distance from the camera centre).
pub fn depth(scene: &Scene, cray: &CameraRay) -> Vec3 {
    scene
        .intersect(&cray.ray, cray.t_max)
        .map_or(Vec3::ZERO, |si| Vec3::splat(si.t))
}

/// Cosine-weighted visibility: with pdf cos θ / π the estimator of (1/π)∫V cos θ dω is the
/// plain fraction of unoccluded rays. The hemisphere is the one the viewer sees.
pub fn ambient_occlusion(
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
