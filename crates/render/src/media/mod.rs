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
mod vdb;

pub use heterogeneous::Heterogeneous;
pub use homogeneous::{Flight, Homogeneous};
pub use phase::Phase;

use base::TransmittanceEstimator;

use crate::geometry::Ray;
use crate::math::{Mat4, Vec2, Vec3};
use crate::sampling::distrib::AliasTable;
use crate::sampling::{Sampler, Samples};
use crate::spectral::lanes::{Color, ColorMode, RgbMode};

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
    /// Importance sampling of a grid emission (next-event estimation towards the volume).
    pub emission_sampler: Option<EmissionSampler>,
}

/// Points of an emission grid chosen in proportion to the emitted radiance (the luminance of
/// the largest Le a trilinear lookup in each voxel's cell can see, so that every point that
/// emits can be chosen), uniformly inside the chosen cell.
#[derive(Clone, Debug)]
pub struct EmissionSampler {
    table: AliasTable,
    res: [usize; 3],
    to_world: Mat4,
    to_grid: Mat4,
    /// World volume of one cell.
    cell_volume: f32,
}

impl EmissionSampler {
    /// `None` when the grid emits nothing or its placement is singular.
    pub fn new(
        grid: &grid::VoxelGrid,
        to_world: Mat4,
        radiance: impl Fn(usize) -> f32,
    ) -> Option<Self> {
        let [nx, ny, nz] = grid.res;
        let lum: Vec<f32> = (0..nx * ny * nz).map(&radiance).collect();
        let mut w = vec![0.0f32; lum.len()];
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let mut m = 0.0f32;
                    for dz in z.saturating_sub(1)..=(z + 1).min(nz - 1) {
                        for dy in y.saturating_sub(1)..=(y + 1).min(ny - 1) {
                            for dx in x.saturating_sub(1)..=(x + 1).min(nx - 1) {
                                m = m.max(lum[(dz * ny + dy) * nx + dx]);
                            }
                        }
                    }
                    w[(z * ny + y) * nx + x] = m;
                }
            }
        }
        let det = to_world.determinant().abs();
        if !(w.iter().any(|&v| v > 0.0) && det > 0.0 && det.is_finite()) {
            return None;
        }
        Some(EmissionSampler {
            table: AliasTable::new(&w),
            res: grid.res,
            to_world,
            to_grid: to_world.inverse(),
            cell_volume: det / (nx * ny * nz) as f32,
        })
    }

    /// A world point and its density per unit volume.
    pub fn sample(&self, u: f32, v: Vec2, w: f32) -> Option<(Vec3, f32)> {
        let (i, pmf) = self.table.sample(u);
        if pmf <= 0.0 {
            return None;
        }
        let [nx, ny, nz] = self.res;
        let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
        let q = Vec3::new(
            (x as f32 + v.x) / nx as f32,
            (y as f32 + v.y) / ny as f32,
            (z as f32 + w) / nz as f32,
        );
        Some((self.to_world.transform_point3a(q), pmf / self.cell_volume))
    }

    /// The density per unit volume with which [`EmissionSampler::sample`] picks the world
    /// point `p`.
    pub fn pdf(&self, p: Vec3) -> f32 {
        let q = self.to_grid.transform_point3a(p);
        if !(q.cmpge(Vec3::ZERO).all() && q.cmplt(Vec3::ONE).all()) {
            return 0.0;
        }
        let [nx, ny, nz] = self.res;
        let cell = |c: f32, n: usize| ((c * n as f32) as usize).min(n - 1);
        let i = (cell(q.z, nz) * ny + cell(q.y, ny)) * nx + cell(q.x, nx);
        self.table.pmf(i) / self.cell_volume
    }
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

/// Black-body radiance at a temperature (kelvin), times a scale: exact (Planck's law per
/// nanometre) in spectral mode, tabulated as RGB for RGB mode.
#[derive(Clone, Debug)]
pub struct Blackbody {
    /// RGB at 0, `step`, 2·`step`, … kelvin (already scaled).
    pub table: Vec<Vec3>,
    pub step: f32,
    /// The scale applied to Planck's law (W·m⁻²·sr⁻¹·nm⁻¹, Mitsuba's `blackbody` units).
    pub scale: f32,
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
        self.radiance_in(p, &RgbMode)
    }

    /// [`Self::radiance`] in the colour of `m`: RGB radiance as an illuminant spectrum, a
    /// temperature by Planck's law at the path's wavelengths.
    pub fn radiance_in<M: ColorMode>(&self, p: Vec3, m: &M) -> M::C {
        match self {
            Emission::Const(le) => m.illuminant(*le),
            Emission::Grid {
                grid,
                to_grid,
                blackbody,
            } => {
                let q = to_grid.transform_point3a(p);
                if !grid::inside(q) {
                    return M::C::ZERO;
                }
                match blackbody {
                    Some(b) => {
                        let t = grid.scalar(q);
                        let planck = |l: f32| {
                            (crate::spectral::planck(f64::from(l), f64::from(t)) * 1e-9) as f32
                                * b.scale
                        };
                        m.spectrum(planck, b.rgb(t))
                    }
                    None => m.illuminant(grid.rgb(q)),
                }
            }
        }
    }
}

impl Medium {
    /// A purely absorbing homogeneous medium: σt = `sigma` exactly, albedo 0, isotropic
    /// phase, no emission (Beer–Lambert absorption inside a course dielectric).
    pub fn absorbing(sigma: Vec3) -> Medium {
        Medium {
            kind: MediumKind::Homogeneous(Homogeneous::new(sigma, Vec3::ZERO)),
            phase: Phase::Isotropic,
            emission: None,
            emission_sampler: None,
        }
    }

    /// Whether the medium only absorbs: homogeneous, with σs = 0 and no emission. Its whole
    /// effect on a path is then its transmittance, which is what lets the surface path
    /// tracer apply it (`integrators::path::PathConfig::media_absorption`).
    pub fn is_purely_absorbing(&self) -> bool {
        matches!(&self.kind, MediumKind::Homogeneous(h) if h.sigma_s == Vec3::ZERO)
            && self.emission.is_none()
    }

    /// The analytic transmittance exp(−σt·`d`) over a distance `d` of a homogeneous medium
    /// ([`Homogeneous::transmittance`]: for finite `d` the float expression
    /// `(-sigma_t * d).exp()`, nothing else); `None` for a grid, which has none.
    #[inline]
    pub fn analytic_transmittance(&self, d: f32) -> Option<Vec3> {
        match &self.kind {
            MediumKind::Homogeneous(h) => Some(h.transmittance(d)),
            MediumKind::Heterogeneous(_) => None,
        }
    }

    /// [`Self::analytic_transmittance`] in the colour of `m` (σt converted as an unbounded
    /// spectrum), over a finite distance `d`: in RGB mode the same float expression.
    #[inline]
    pub fn analytic_transmittance_in<M: ColorMode>(&self, d: f32, m: &M) -> Option<M::C> {
        match &self.kind {
            MediumKind::Homogeneous(h) => Some((-m.unbounded(h.sigma_t) * d).exp()),
            MediumKind::Heterogeneous(_) => None,
        }
    }

    /// A free flight along `ray` (unit direction) over `[0, d_max)`, with the path's hero
    /// channel `hero` (see [`Flight`]). Through a purely absorbing homogeneous medium (Beer
    /// absorption) no collision could scatter, so the flight passes with the analytic
    /// transmittance as its weight: the same mean as sampling collisions that end the path,
    /// without their noise.
    #[inline]
    pub fn sample(&self, ray: &Ray, d_max: f32, hero: usize, sampler: &mut Sampler) -> Flight {
        self.sample_in(ray, d_max, hero, sampler, &RgbMode)
    }

    /// [`Self::sample`] in the colour of `m` (`hero` a lane of it).
    #[inline]
    pub fn sample_in<M: ColorMode>(
        &self,
        ray: &Ray,
        d_max: f32,
        hero: usize,
        sampler: &mut impl Samples,
        m: &M,
    ) -> Flight<M::C> {
        if let Some(k) = self.phase.extinction_scale(ray.d) {
            return self.microflake_sample_in(k, d_max, hero, sampler, m);
        }
        match &self.kind {
            MediumKind::Homogeneous(h) if h.sigma_s == Vec3::ZERO && self.emission.is_none() => {
                Flight::Pass {
                    weight: h.transmittance_in(d_max, m),
                    ratio: M::C::ONE,
                }
            }
            MediumKind::Homogeneous(h) => h.sample_in(d_max, sampler.next_1d(), hero, m),
            MediumKind::Heterogeneous(h) => {
                h.sample_with_in(ray, d_max, &mut || sampler.next_1d(), m)
            }
        }
    }

    /// [`Self::sample_in`] in a homogeneous medium of microflakes whose extinction along the
    /// ray is `k`·σt (Mitsuba 3 scales σt by the phase function's projected area σ(ω) when
    /// it is a microflake one, the albedo kept): the flight of the unscaled medium over
    /// `k`·d_max, its distance divided by `k` (the weights depend on σt·d only). `build`
    /// allows microflakes only in homogeneous media.
    #[inline(never)]
    fn microflake_sample_in<M: ColorMode>(
        &self,
        k: f32,
        d_max: f32,
        hero: usize,
        sampler: &mut impl Samples,
        m: &M,
    ) -> Flight<M::C> {
        let MediumKind::Homogeneous(h) = &self.kind else {
            unreachable!("microflake phase functions are refused in grids by build")
        };
        match h.sample_in(d_max * k, sampler.next_1d(), hero, m) {
            Flight::Scatter {
                d,
                weight,
                ratio,
                emit,
            } => Flight::Scatter {
                d: (d / k).min(d_max),
                weight,
                ratio,
                emit,
            },
            pass => pass,
        }
    }

    /// The absorption coefficient σa = σt − σs at the world point `p`.
    pub fn sigma_a(&self, p: Vec3) -> Vec3 {
        self.sigma_a_in(p, &RgbMode)
    }

    /// [`Self::sigma_a`] in the colour of `m`.
    pub fn sigma_a_in<M: ColorMode>(&self, p: Vec3, m: &M) -> M::C {
        match &self.kind {
            MediumKind::Homogeneous(h) => {
                let (sigma_t, sigma_s) = h.coefficients(m);
                sigma_t - sigma_s
            }
            MediumKind::Heterogeneous(h) => h.sigma_a_in(p, m),
        }
    }

    /// The scattering coefficient σs at the world point `p` (RGB).
    pub fn sigma_s(&self, p: Vec3) -> Vec3 {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.sigma_s,
            MediumKind::Heterogeneous(h) => {
                let sigma_t = h.sigma_t_along(&Ray::new(p, Vec3::Z), 0.0);
                (Vec3::splat(sigma_t) - h.sigma_a(p)).max(Vec3::ZERO)
            }
        }
    }

    /// [`Self::sigma_s`] in the colour of `m`.
    pub fn sigma_s_in<M: ColorMode>(&self, p: Vec3, m: &M) -> M::C {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.coefficients(m).1,
            MediumKind::Heterogeneous(h) => {
                let sigma_t = h.sigma_t_along(&Ray::new(p, Vec3::Z), 0.0);
                let sigma_a = h.sigma_a_in(p, m);
                M::C::from_fn(|i| (sigma_t - sigma_a.lane(i)).max(0.0))
            }
        }
    }

    /// σt and σs of a homogeneous medium whose coefficients are the same in every channel.
    pub fn grey_homogeneous(&self) -> Option<(f32, f32)> {
        if self.phase.is_microflake() {
            // Its extinction depends on the direction.
            return None;
        }
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
        self.transmittance_in(ray, d_max, estimator, sampler, &RgbMode)
    }

    /// [`Self::transmittance`] in the colour of `m` (grids are grey: the estimate in every
    /// lane).
    #[inline]
    pub fn transmittance_in<M: ColorMode>(
        &self,
        ray: &Ray,
        d_max: f32,
        estimator: TransmittanceEstimator,
        sampler: &mut impl Samples,
        m: &M,
    ) -> M::C {
        let k = self.phase.extinction_scale(ray.d);
        match &self.kind {
            MediumKind::Homogeneous(h) => h.transmittance_in(k.map_or(d_max, |k| d_max * k), m),
            MediumKind::Heterogeneous(h) => {
                M::C::splat(h.estimate(ray, d_max, estimator, &mut || sampler.next_1d()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Through Beer absorption a flight never collides: it passes with weight e^{−σt·d}.
    #[test]
    fn flights_through_an_absorbing_medium_pass_with_the_transmittance() {
        let sigma = Vec3::new(0.1, 0.0, 2.5);
        let m = Medium::absorbing(sigma);
        let mut sampler = Sampler::new(base::SamplerKind::Independent, 1, 7);
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        for hero in 0..3 {
            let f = m.sample(&ray, 0.8, hero, &mut sampler);
            assert_eq!(
                f,
                Flight::Pass {
                    weight: (-sigma * 0.8).exp(),
                    ratio: Vec3::ONE
                }
            );
        }
        let beyond = m.sample(&ray, f32::INFINITY, 0, &mut sampler);
        assert!(
            matches!(beyond, Flight::Pass { weight, .. } if weight.x == 0.0 && weight.z == 0.0)
        );
    }

    /// A temperature grid emits Planck's law itself at the path's wavelengths in spectral
    /// mode (W·m⁻²·sr⁻¹·nm⁻¹ times the scale), and its tabulated RGB in RGB mode.
    #[test]
    fn blackbody_emission_is_exact_in_spectral_mode() {
        use crate::spectral::{RgbToSpectrumTable, SampledWavelengths, lanes::SpectralMode};
        let (t, scale) = (2750.0f32, 3.0f32);
        let grid = grid::VoxelGrid {
            res: [1, 1, 1],
            channels: 1,
            data: vec![t],
            trilinear: false,
            zero_outside: false,
        };
        let table = vec![Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.4, 0.5, 0.6)];
        let e = Emission::Grid {
            grid,
            to_grid: Mat4::IDENTITY,
            blackbody: Some(Blackbody {
                table,
                step: 1e4,
                scale,
            }),
        };
        let p = Vec3::splat(0.5);
        let rgb = Vec3::new(0.1, 0.2, 0.3) * (1.0 - 0.275) + Vec3::new(0.4, 0.5, 0.6) * 0.275;
        assert!((e.radiance(p) - rgb).abs().max_element() < 1e-6);
        let m = SpectralMode::new(
            SampledWavelengths::sample_visible(0.37),
            RgbToSpectrumTable::srgb(),
        );
        let le = e.radiance_in(p, &m);
        for i in 0..4 {
            let want = crate::spectral::planck(m.wavelengths().lambda(i) as f64, t as f64)
                * 1e-9
                * scale as f64;
            assert!(
                (le[i] as f64 / want - 1.0).abs() < 1e-5,
                "{} vs {want}",
                le[i]
            );
        }
        assert!(e.radiance_in(Vec3::splat(2.0), &m).is_black());
    }

    #[test]
    fn an_absorbing_medium_is_beer_lambert() {
        let sigma = Vec3::new(0.1, 0.0, 2.5);
        let m = Medium::absorbing(sigma);
        assert!(m.is_purely_absorbing());
        assert_eq!(m.phase, Phase::Isotropic);
        assert_eq!(m.sigma_a(Vec3::ZERO), sigma);
        let d = 0.731 * 1.7;
        assert_eq!(
            m.analytic_transmittance(d).map(|t| t.to_array()),
            Some((-sigma * d).exp().to_array())
        );
        let scattering = Medium {
            kind: MediumKind::Homogeneous(Homogeneous::new(sigma, Vec3::splat(0.5))),
            ..m.clone()
        };
        assert!(!scattering.is_purely_absorbing());
        let glowing = Medium {
            emission: Some(Emission::Const(Vec3::ONE)),
            ..m
        };
        assert!(!glowing.is_purely_absorbing());
    }
}
