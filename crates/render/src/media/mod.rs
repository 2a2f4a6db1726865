//! Participating media, a file per kind: [`homogeneous`] (constant coefficients), and
//! [`heterogeneous`] (a density grid, [`grid`]); phase functions in [`phase`].
//!
//! Units: media work on rays with unit directions, so ray parameters are distances. The
//! volumetric path tracer (`integrators::volpath`) asks a medium for a free flight
//! ([`Medium::sample`]: a collision with its throughput weight, or a pass) and for the
//! transmittance of shadow-ray segments ([`Medium::transmittance`]).

pub mod grid;
pub mod heterogeneous;
pub mod homogeneous;
pub mod phase;
mod vdb;

pub use heterogeneous::Heterogeneous;
pub use homogeneous::{Flight, Homogeneous};
pub use phase::Phase;

use crate::geometry::Ray;
use crate::math::Vec3;
use crate::sampling::Sampler;

#[derive(Clone, Debug)]
pub enum MediumKind {
    Homogeneous(Homogeneous),
    Heterogeneous(Box<Heterogeneous>),
}

/// A medium of the scene: its coefficients and its phase function.
#[derive(Clone, Debug)]
pub struct Medium {
    pub kind: MediumKind,
    pub phase: Phase,
}

impl Medium {
    /// A free flight along `ray` (unit direction) over `[0, d_max)`, with the path's hero
    /// channel `hero` (see [`Flight`]).
    #[inline]
    pub fn sample(&self, ray: &Ray, d_max: f32, hero: usize, sampler: &mut Sampler) -> Flight {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.sample(d_max, sampler.next_1d(), hero),
            MediumKind::Heterogeneous(h) => h.sample(ray, d_max, sampler),
        }
    }

    /// σt and σs of a homogeneous medium whose coefficients are the same in every channel.
    pub fn grey_homogeneous(&self) -> Option<(f32, f32)> {
        match &self.kind {
            MediumKind::Homogeneous(h)
                if h.sigma_t.x == h.sigma_t.y
                    && h.sigma_t.y == h.sigma_t.z
                    && h.sigma_s.x == h.sigma_s.y
                    && h.sigma_s.y == h.sigma_s.z =>
            {
                Some((h.sigma_t.x, h.sigma_s.x))
            }
            _ => None,
        }
    }

    /// The transmittance along `ray` (unit direction) over `[0, d_max)`: exact for
    /// homogeneous media, an unbiased estimate (ratio tracking) for grids.
    #[inline]
    pub fn transmittance(&self, ray: &Ray, d_max: f32, sampler: &mut Sampler) -> Vec3 {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.transmittance(d_max),
            MediumKind::Heterogeneous(h) => h.transmittance(ray, d_max, sampler),
        }
    }
}
