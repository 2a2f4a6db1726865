//! A heterogeneous medium: extinction from a density grid, σt(x) = scale·density(x), and an
//! albedo that is constant or a grid; the grid fills [0,1]³ of its space, placed in the
//! world by an affine map. Outside that box the medium is empty.
//!
//! Free flights are sampled by delta tracking and transmittance is estimated by ratio
//! tracking (Novák et al. 2014), both against a majorant σ̄ ≥ σt: tentative collisions at
//! rate σ̄, each real with probability σt/σ̄ (delta tracking) or weighting the estimate by
//! 1 − σt/σ̄ (ratio tracking). Both are unbiased for any σ̄ ≥ max σt.

use super::grid::VoxelGrid;
use super::homogeneous::Flight;
use crate::geometry::Ray;
use crate::math::{Mat4, Vec3};
use crate::sampling::Sampler;

#[derive(Clone, Debug)]
pub enum Albedo {
    Const(Vec3),
    Grid(VoxelGrid),
}

#[derive(Clone, Debug)]
pub struct Heterogeneous {
    pub density: VoxelGrid,
    pub albedo: Albedo,
    pub scale: f32,
    /// World → grid space ([0,1]³).
    pub to_grid: Mat4,
    /// The majorant: scale · the largest density.
    pub majorant: f32,
}

impl Heterogeneous {
    pub fn new(density: VoxelGrid, albedo: Albedo, scale: f32, to_world: Mat4) -> Heterogeneous {
        let majorant = scale * density.max_value();
        Heterogeneous {
            density,
            albedo,
            scale,
            to_grid: to_world.inverse(),
            majorant,
        }
    }

    /// The part of the ray's `[0, d_max)` inside the grid's box, as ray parameters (the ray
    /// direction is unit, so parameters are distances), with the ray in grid space.
    #[inline]
    fn clip(&self, ray: &Ray, d_max: f32) -> Option<(f32, f32, Vec3, Vec3)> {
        let o = self.to_grid.transform_point3a(ray.o);
        let d = self.to_grid.transform_vector3a(ray.d);
        let inv = d.recip();
        let t0 = (Vec3::ZERO - o) * inv;
        let t1 = (Vec3::ONE - o) * inv;
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element().min(d_max);
        (near < far && self.majorant > 0.0).then_some((near, far, o, d))
    }

    #[inline]
    fn sigma_t(&self, p: Vec3) -> f32 {
        self.scale * self.density.scalar(p)
    }

    /// Delta tracking over `[0, d_max)` of the (unit-direction) ray.
    pub fn sample(&self, ray: &Ray, d_max: f32, sampler: &mut Sampler) -> Flight {
        let Some((mut t, far, o, d)) = self.clip(ray, d_max) else {
            return Flight::Pass {
                weight: Vec3::ONE,
                ratio: Vec3::ONE,
            };
        };
        loop {
            t -= (1.0 - sampler.next_1d()).ln() / self.majorant;
            if t >= far {
                return Flight::Pass {
                    weight: Vec3::ONE,
                    ratio: Vec3::ONE,
                };
            }
            let p = o + d * t;
            if sampler.next_1d() * self.majorant < self.sigma_t(p) {
                let albedo = match &self.albedo {
                    Albedo::Const(a) => *a,
                    Albedo::Grid(g) => g.rgb(p),
                };
                return Flight::Scatter {
                    d: t,
                    weight: albedo,
                    ratio: Vec3::ONE,
                };
            }
        }
    }

    /// Ratio tracking over `[0, d_max)`.
    pub fn transmittance(&self, ray: &Ray, d_max: f32, sampler: &mut Sampler) -> Vec3 {
        let Some((mut t, far, o, d)) = self.clip(ray, d_max) else {
            return Vec3::ONE;
        };
        let mut tr = 1.0f32;
        loop {
            t -= (1.0 - sampler.next_1d()).ln() / self.majorant;
            if t >= far {
                return Vec3::splat(tr);
            }
            tr *= 1.0 - self.sigma_t(o + d * t) / self.majorant;
            // Russian roulette on small estimates keeps long rays cheap, unbiased.
            if tr < 0.1 {
                let q = 0.75;
                if sampler.next_1d() < q {
                    return Vec3::ZERO;
                }
                tr /= 1.0 - q;
            }
        }
    }
}
