//! The shadow query: the transmittance of the segment from a scattering vertex to a point it
//! connects to (a light sample's target, a lens point, another vertex). Any surface but a
//! `null` one blocks it; `null` surfaces let it through and switch the medium when they bound
//! one; every medium crossed attenuates it (exactly in homogeneous media, by the
//! integrator's unbiased estimator in grids). Every integrator that connects two points asks
//! this one query, so that media and index-matched boundaries are seen alike everywhere.

use base::TransmittanceEstimator;

use crate::geometry::Ray;
use crate::lights::ShadowTarget;
use crate::math::Vec3;
use crate::sampling::Samples;
use crate::shapes::{SHADOW_EPSILON, SurfaceInteraction, offset_ray_origin};
use crate::spectral::lanes::{Color, ColorMode};
use crate::world::Scene;

/// Where a connection starts: a surface (its ray leaves off the surface by the error bound)
/// or a point in a medium (at the path's time).
#[derive(Clone, Copy)]
pub enum From<'a> {
    Surface(&'a SurfaceInteraction),
    Medium(Vec3, f32),
}

impl From<'_> {
    /// The point the connection starts at.
    #[inline]
    pub fn p(&self) -> Vec3 {
        match self {
            From::Surface(si) => si.p,
            From::Medium(p, _) => *p,
        }
    }
}

/// A connection to test: from `from`, along the unit direction `wi`, to `target`.
#[derive(Clone, Copy)]
pub struct Connection<'a> {
    pub from: From<'a>,
    pub wi: Vec3,
    pub target: ShadowTarget,
    /// The medium the path was in at `from` (for a surface, the one it arrived through: the
    /// connection starts in the medium on `wi`'s side of it).
    pub medium: Option<u32>,
}

/// The ray from `from` towards `target` (direction `wi`) and its parameter range.
#[inline]
fn shadow_ray(from: &From<'_>, wi: Vec3, target: ShadowTarget) -> (Ray, f32) {
    match *from {
        From::Surface(si) => target.ray_from(si, wi),
        From::Medium(p, time) => match target {
            ShadowTarget::Infinite => (Ray::at_time(p, wi, time), f32::INFINITY),
            ShadowTarget::Point(q) => (Ray::at_time(p, q - p, time), 1.0 - SHADOW_EPSILON),
            ShadowTarget::Surface { p: q, p_error, n } => {
                let q = offset_ray_origin(q, p_error, n, p - q);
                (Ray::at_time(p, q - p, time), 1.0 - SHADOW_EPSILON)
            }
        },
    }
}

/// The transmittance along connection `c` (0 when a surface other than a `null` one blocks
/// it); grids' transmittance is estimated by `estimator` with numbers from `sampler`. Without
/// `null` surfaces one occlusion query, then the medium over the whole segment.
pub fn transmittance<M: ColorMode>(
    scene: &Scene,
    c: &Connection<'_>,
    estimator: TransmittanceEstimator,
    sampler: &mut impl Samples,
    mode: &M,
) -> M::C {
    let mut medium = match c.from {
        From::Surface(si) => scene.medium_after(si, c.wi, c.medium),
        From::Medium(..) => c.medium,
    };
    let (mut ray, mut t_max) = shadow_ray(&c.from, c.wi, c.target);
    let through = |m: u32, ray: &Ray, end: f32, sampler: &mut _| {
        let len = ray.d.length();
        let unit = Ray::at_time(ray.o, ray.d / len, ray.time);
        scene.media[m as usize].transmittance_in(&unit, end * len, estimator, sampler, mode)
    };
    if !scene.has_nulls {
        // Any surface blocks: one occlusion query, then the medium over the whole segment.
        if scene.occluded(&ray, t_max) {
            return M::C::ZERO;
        }
        return medium.map_or(M::C::ONE, |m| through(m, &ray, t_max, sampler));
    }
    let mut tr = M::C::ONE;
    for _ in 0..256 {
        let closest = scene.closest(&ray, t_max);
        // A blocking surface ends the query before any medium is estimated.
        if closest.shape().is_some_and(|s| !scene.shape_is_null(s)) {
            return M::C::ZERO;
        }
        if let Some(m) = medium {
            tr *= through(m, &ray, closest.t(&ray, t_max), sampler);
            if tr.is_black() {
                return tr;
            }
        }
        let Some(si) = closest.surface(scene, &ray, t_max) else {
            return tr;
        };
        medium = scene.medium_after(&si, ray.d, medium);
        (ray, t_max) = shadow_ray(&From::Surface(&si), c.wi, c.target);
    }
    M::C::ZERO
}
