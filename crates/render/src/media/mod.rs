//! Participating media, a file per kind: [`homogeneous`] (constant coefficients), and
//! [`heterogeneous`] (a density grid, [`grid`], with its [`majorant`] grid); phase functions
//! in [`phase`].
//!
//! Units: media work on rays with unit directions, so ray parameters are distances. The
//! volumetric path tracer (`integrators::volpath`) asks a medium for a free flight
//! ([`Medium::sample`]: a collision with its throughput weight, or a pass) and for the
//! transmittance of shadow-ray segments ([`Medium::transmittance`]).

pub mod grid;
pub mod heterogeneous;
pub mod homogeneous;
pub mod majorant;
pub mod phase;

pub use heterogeneous::Heterogeneous;
pub use homogeneous::{Flight, Homogeneous};
pub use phase::Phase;

use base::TransmittanceEstimator;

use crate::geometry::Ray;
use crate::math::{Mat4, Vec3};
use crate::sampling::Sampler;

#[derive(Clone, Debug)]
pub enum MediumKind {
    Homogeneous(Homogeneous),
    Heterogeneous(Box<Heterogeneous>),
}

/// A medium of the scene: its coefficients, its phase function and what it emits.
#[derive(Clone, Debug)]
pub struct Medium {
    pub kind: MediumKind,
    pub phase: Phase,
    pub emission: Option<Emission>,
}

/// The radiance Le a medium emits (the source term is σa·Le).
#[derive(Clone, Debug)]
pub enum Emission {
    Const(Vec3),
    /// From a grid placed by `to_grid` (world → [0,1]³): RGB radiance, or a temperature
    /// turned into radiance by `blackbody`.
    Grid {
        grid: grid::VoxelGrid,
        to_grid: Mat4,
        blackbody: Option<Blackbody>,
    },
}

/// Black-body RGB radiance tabulated over temperature (kelvin), times a scale.
#[derive(Clone, Debug)]
pub struct Blackbody {
    /// RGB at 0, `step`, 2·`step`, … kelvin (already scaled).
    pub table: Vec<Vec3>,
    pub step: f32,
}

impl Blackbody {
    /// Linear interpolation in the table (clamped at its ends).
    pub fn rgb(&self, kelvin: f32) -> Vec3 {
        let x = (kelvin / self.step).max(0.0);
        let i = (x as usize).min(self.table.len() - 2);
        let f = (x - i as f32).min(1.0);
        self.table[i] * (1.0 - f) + self.table[i + 1] * f
    }
}

impl Emission {
    /// Le at the world point `p` (zero outside a grid's box).
    pub fn radiance(&self, p: Vec3) -> Vec3 {
        match self {
            Emission::Const(le) => *le,
            Emission::Grid {
                grid,
                to_grid,
                blackbody,
            } => {
                let q = to_grid.transform_point3a(p);
                if !(q.cmpge(Vec3::ZERO).all() && q.cmple(Vec3::ONE).all()) {
                    return Vec3::ZERO;
                }
                match blackbody {
                    Some(b) => b.rgb(grid.scalar(q)),
                    None => grid.rgb(q),
                }
            }
        }
    }
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
    /// homogeneous media, an unbiased estimate by `estimator` for grids.
    #[inline]
    pub fn transmittance(
        &self,
        ray: &Ray,
        d_max: f32,
        estimator: TransmittanceEstimator,
        sampler: &mut Sampler,
    ) -> Vec3 {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.transmittance(d_max),
            MediumKind::Heterogeneous(h) => h.transmittance(ray, d_max, estimator, sampler),
        }
    }
}
