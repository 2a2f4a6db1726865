//! Where light paths start: the scene's lights and its emitting media, chosen in proportion
//! to their power ([`PhotonLights`]).
//!
//! An emitting medium sends light from every point of its volume, isotropically: a path
//! starts at a point x of the medium with density p_V(x) (in proportion to the radiance of
//! an emission grid that has an importance sampler, else uniform in the box of the shapes
//! the medium fills), a direction uniform on the sphere, and the power
//! σa(x)·Le(x)·4π / p_V(x). Points of the box outside the medium (the shapes' own outside,
//! other media) carry nothing: the medium at a point is told by the first surface bounding
//! media along a probe ray ([`Scene::medium_at`]). Only media inside bounded shapes can
//! emit paths; [`volume_emitters`] says why not otherwise.

use crate::geometry::Ray;
use crate::math::{INV_4PI, Vec2, Vec3};
use crate::sampling::{Distribution1D, Samples, warp};
use crate::spectral::lanes::{Color, ColorMode};
use crate::world::Scene;

/// The region an emitting medium fills, as light paths sample it.
#[derive(Clone, Debug)]
pub struct VolumeEmitter {
    pub medium: u32,
    /// The box of the bounded shapes whose interior the medium is.
    lo: Vec3,
    hi: Vec3,
}

/// A light path's first ray, the medium it starts in and its power (given that its emitter
/// was chosen: divide by that probability).
pub struct PathStart<C> {
    pub ray: Ray,
    pub medium: Option<u32>,
    pub beta: C,
    /// Started in an emitting medium (no light sample next-event estimation draws).
    pub in_volume: bool,
}

/// The emitting media of `scene` as light paths start in them, or why one cannot be: its
/// volume must be the interior of bounded shapes, so that a point of it can be sampled.
pub fn volume_emitters(scene: &Scene) -> Result<Vec<VolumeEmitter>, String> {
    let mut out = Vec::new();
    for (i, m) in scene.media.iter().enumerate() {
        if m.emission.is_none() {
            continue;
        }
        let mut lo = Vec3::INFINITY;
        let mut hi = Vec3::NEG_INFINITY;
        for s in scene.shapes.iter().filter(|s| s.interior == Some(i as u32)) {
            let Some((a, b)) = s.geom.bounds() else {
                return Err(format!(
                    "emitting medium {i} fills an unbounded shape: light paths cannot start in it"
                ));
            };
            lo = lo.min(a);
            hi = hi.max(b);
        }
        if !(lo.cmple(hi).all() && (hi - lo).is_finite()) {
            return Err(format!(
                "emitting medium {i} is not the interior of any shape: light paths can start \
                 only inside bounded shapes (use volpath or bdpt)"
            ));
        }
        out.push(VolumeEmitter {
            medium: i as u32,
            lo,
            hi,
        });
    }
    Ok(out)
}

impl VolumeEmitter {
    /// The world volume of the sampling box.
    fn volume(&self) -> f32 {
        let e = self.hi - self.lo;
        e.x * e.y * e.z
    }

    /// A point of the medium from four uniform numbers and its density per unit volume
    /// (zero outside the medium).
    fn point(&self, scene: &Scene, u: Vec2, v: Vec2) -> (Vec3, f32) {
        let m = &scene.media[self.medium as usize];
        let (x, pdf) = match &m.emission_sampler {
            Some(es) => es
                .sample(u.x, Vec2::new(u.y, v.x), v.y)
                .unwrap_or((Vec3::ZERO, 0.0)),
            None => (
                self.lo + (self.hi - self.lo) * Vec3::new(u.x, u.y, v.x),
                1.0 / self.volume(),
            ),
        };
        let inside = pdf > 0.0 && scene.medium_at(x) == Some(Some(self.medium));
        (x, if inside { pdf } else { 0.0 })
    }

    /// The power of the medium's emission (4π ∫ σa·Le dV, the mean over the RGB channels),
    /// estimated from a fixed set of points.
    fn power(&self, scene: &Scene) -> f32 {
        let m = &scene.media[self.medium as usize];
        let Some(e) = &m.emission else { return 0.0 };
        const N: u32 = 512;
        let radical = |mut i: u32, b: u32| {
            let (mut f, mut r) = (1.0f32, 0.0f32);
            while i > 0 {
                f /= b as f32;
                r += f * (i % b) as f32;
                i /= b;
            }
            r
        };
        let sum: f32 = (0..N)
            .map(|k| {
                let u = Vec2::new((k as f32 + 0.5) / N as f32, radical(k, 2));
                let v = Vec2::new(radical(k, 3), radical(k, 5));
                let (x, pdf) = self.point(scene, u, v);
                if pdf <= 0.0 {
                    return 0.0;
                }
                (m.sigma_a(x) * e.radiance(x)).element_sum() / 3.0 / pdf
            })
            .sum();
        let p = 4.0 * std::f32::consts::PI * sum / N as f32;
        if p.is_finite() { p.max(0.0) } else { 0.0 }
    }

    /// A light path from the medium: a point from `u`, `v`, a direction from `w`.
    fn start<M: ColorMode>(
        &self,
        scene: &Scene,
        u: Vec2,
        v: Vec2,
        w: Vec2,
        mode: &M,
    ) -> Option<PathStart<M::C>> {
        let (x, pdf) = self.point(scene, u, v);
        if pdf <= 0.0 {
            return None;
        }
        let m = &scene.media[self.medium as usize];
        let le = m.emission.as_ref()?.radiance_in(x, mode);
        let beta = m.sigma_a_in(x, mode) * le / (pdf * INV_4PI);
        (!beta.is_black()).then(|| PathStart {
            ray: Ray::new(x, warp::square_to_uniform_sphere(w)),
            medium: Some(self.medium),
            beta,
            in_volume: true,
        })
    }
}

/// How light paths choose where to start: the lights and the emitting media, in proportion
/// to their power.
pub struct PhotonLights {
    dist: Distribution1D,
    any: bool,
    volumes: Vec<VolumeEmitter>,
}

impl PhotonLights {
    /// The scene's lights and the emitting media that can start light paths (the
    /// integrators that trace them refuse scenes where [`volume_emitters`] fails).
    pub fn new(scene: &Scene) -> PhotonLights {
        let volumes = volume_emitters(scene).unwrap_or_default();
        let powers: Vec<f32> = (scene.lights.iter().map(|l| l.power(scene)))
            .chain(volumes.iter().map(|v| v.power(scene)))
            .collect();
        PhotonLights {
            any: powers.iter().any(|&p| p > 0.0),
            dist: Distribution1D::new(&powers),
            volumes,
        }
    }

    /// Whether anything emits.
    pub fn any(&self) -> bool {
        self.any
    }

    /// A light path's start: an emitter by power (one 1D number), a point and direction on
    /// it (two 2D numbers; two more 1D ones for a volume), the power divided by the choice's
    /// probability.
    pub fn start<M: ColorMode>(
        &self,
        scene: &Scene,
        sampler: &mut impl Samples,
        mode: &M,
    ) -> Option<PathStart<M::C>> {
        let (k, pmf, _) = self.dist.sample_discrete(sampler.next_1d());
        let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
        if pmf.is_nan() || pmf <= 0.0 {
            return None;
        }
        let n = scene.lights.len();
        let mut s = if k < n {
            let e = scene.lights[k].sample_le(scene, u_pos, u_dir, mode)?;
            PathStart {
                ray: e.ray,
                medium: scene.light_media.get(k).copied().flatten(),
                beta: e.weight,
                in_volume: false,
            }
        } else {
            let v = Vec2::new(sampler.next_1d(), sampler.next_1d());
            self.volumes[k - n].start(scene, u_pos, v, u_dir, mode)?
        };
        s.beta /= pmf;
        Some(s)
    }
}
