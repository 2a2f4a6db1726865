//! The CENG795 course's mirror, conductor and dielectric materials, whole: the course shades
//! every material with its ambient/diffuse/specular (Phong family) lobes and adds, for these
//! three types, an ideal lobe traced recursively:
//!
//! - mirror: `MirrorReflectance` in the mirror direction;
//! - conductor: `MirrorReflectance` · F_conductor(cos θo; n = `RefractionIndex`,
//!   k = `AbsorptionIndex`) in the mirror direction;
//! - dielectric: Fresnel reflection and refraction (index `RefractionIndex`; Beer–Lambert
//!   absorption inside is not the BSDF's: the build step makes it the shape's interior
//!   medium, which the integrators apply).
//!
//! `Roughness` r > 0 (homework 3, "glossy reflections") perturbs the ideal direction w as the
//! homework defines: with (u, v) an orthonormal pair perpendicular to w and ξ₁, ξ₂ uniform in
//! [0, 1), w' = normalize(w + r(ξ₁ − ½)u + r(ξ₂ − ½)v): a uniform offset in a square of side r
//! on the plane at unit distance along w. A perturbed direction that ends on the wrong side of
//! the surface carries nothing (the course would trace it into the surface itself).
//!
//! The ideal lobe, perturbed or not, is *sampled only*: like a delta lobe it has no `eval` or
//! `pdf` and emission found through it is not weighted against emitter sampling. That is an
//! unbiased estimator of exactly the course's recursion (which also averages the perturbed
//! lobe over its random directions), and it keeps a Whitted tracer following these bounces.
//! The lobe is chosen against the Phong lobes in proportion to estimates of their albedos, so
//! sample weights are the lobe's value over its probability.

use super::{BsdfModel, BsdfSample, Conductor, Dielectric, PhongFamily, TransportMode, mean};
use crate::math::{Frame, Vec2, Vec3};
use crate::spectral::lanes::Color;

/// The ideal part of a course material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IdealLobe {
    Mirror,
    /// Complex index n + ik, the same for every channel (the course's scalars).
    Conductor {
        eta: f32,
        k: f32,
    },
    /// Relative index int/ext.
    Dielectric {
        eta: f32,
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CourseMaterial<C: Color = Vec3> {
    pub phong: PhongFamily<C>,
    pub ideal: IdealLobe,
    /// `MirrorReflectance` (mirror and conductor).
    pub reflectance: C,
    pub roughness: f32,
    /// Probability of choosing the ideal lobe when the Phong lobes can scatter (wo.z > 0):
    /// from RGB channel means (fixed 3-channel arithmetic), kept in spectral mode so that the
    /// lobe choice does not depend on the path's wavelengths.
    ideal_prob: f32,
}

impl CourseMaterial {
    pub fn new(phong: PhongFamily, ideal: IdealLobe, reflectance: Vec3, roughness: f32) -> Self {
        let mut m = CourseMaterial {
            phong,
            ideal,
            reflectance: reflectance.max(Vec3::ZERO),
            roughness: if roughness.is_finite() {
                roughness.max(0.0)
            } else {
                0.0
            },
            ideal_prob: 1.0,
        };
        let ideal_weight = mean(m.ideal_albedo());
        let phong_weight = mean(phong.kd) + mean(phong.ks);
        if ideal_weight + phong_weight > 0.0 && phong_weight.is_finite() {
            m.ideal_prob = ideal_weight / (ideal_weight + phong_weight);
        }
        m
    }

    /// The same material with its colours (Phong kd, ks and the mirror reflectance)
    /// converted by `f` (e.g. a `ColorMode`'s albedo upsampling); the lobe probabilities stay
    /// the RGB ones.
    pub fn map_lanes<D: Color>(&self, f: impl Fn(Vec3) -> D) -> CourseMaterial<D> {
        CourseMaterial {
            phong: self.phong.map_lanes(&f),
            ideal: self.ideal,
            reflectance: f(self.reflectance),
            roughness: self.roughness,
            ideal_prob: self.ideal_prob,
        }
    }
}

impl<C: Color> CourseMaterial<C> {
    fn ideal_albedo(&self) -> C {
        match self.ideal {
            IdealLobe::Mirror => self.reflectance,
            IdealLobe::Conductor { eta, k } => self.conductor(eta, k).reflectance(1.0),
            IdealLobe::Dielectric { .. } => C::ONE,
        }
    }

    /// The course's scalar n + ik: the same at every lane (a constant spectrum).
    fn conductor(&self, eta: f32, k: f32) -> Conductor<C> {
        Conductor::new(C::splat(eta), C::splat(k), self.reflectance)
    }

    /// Probability of the ideal lobe for this `wo`: below the surface only it scatters.
    fn ideal_prob(&self, wo: Vec3) -> f32 {
        if wo.z > 0.0 { self.ideal_prob } else { 1.0 }
    }

    fn sample_ideal(
        &self,
        wo: Vec3,
        u1: f32,
        u2: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample<C>> {
        let s = match self.ideal {
            IdealLobe::Mirror => Conductor::mirror(self.reflectance).sample(wo, u1, u2, mode),
            IdealLobe::Conductor { eta, k } => self.conductor(eta, k).sample(wo, u1, u2, mode),
            IdealLobe::Dielectric { eta } => {
                Dielectric::with_lanes(eta, 1.0).sample(wo, u1, u2, mode)
            }
        }?;
        if self.roughness <= 0.0 {
            return Some(s);
        }
        let wi = perturb(s.wi, self.roughness, u2);
        // The perturbed direction must stay on the side the ideal one leaves to.
        (wi.z * s.wi.z > 0.0).then_some(BsdfSample { wi, ..s })
    }
}

/// The course's roughness perturbation of the unit direction `w`: a uniform offset in a
/// square of side `r` on the plane perpendicular to `w` at unit distance.
pub fn perturb(w: Vec3, r: f32, u: Vec2) -> Vec3 {
    let f = Frame::from_normal(w);
    (w + r * (u.x - 0.5) * f.s + r * (u.y - 0.5) * f.t).normalize()
}

impl<C: Color> BsdfModel<C> for CourseMaterial<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        self.phong.eval(wo, wi, mode)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        (1.0 - self.ideal_prob(wo)) * self.phong.pdf(wo, wi)
    }

    fn eval_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (C, f32) {
        let (f, p) = self.phong.eval_pdf(wo, wi, mode);
        (f, (1.0 - self.ideal_prob(wo)) * p)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        let p = self.ideal_prob(wo);
        if u1 < p {
            let mut s = self.sample_ideal(wo, u1 / p, u2, mode)?;
            s.weight /= p;
            s.pdf *= p;
            Some(s)
        } else {
            let q = 1.0 - p;
            let mut s = self.phong.sample(wo, ((u1 - p) / q).min(1.0), u2, mode)?;
            s.weight /= q;
            s.pdf *= q;
            Some(s)
        }
    }

    fn has_delta(&self) -> bool {
        true
    }
    fn has_smooth(&self) -> bool {
        self.ideal_prob < 1.0
    }
    fn albedo(&self) -> C {
        self.phong.albedo() + self.ideal_albedo()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::Pcg32;
    use base::PhongModel;

    fn phong(kd: f32, ks: f32) -> PhongFamily {
        PhongFamily::new(
            PhongModel::OriginalBlinnPhong,
            false,
            false,
            20.0,
            Vec3::splat(kd),
            Vec3::splat(ks),
            1.5,
        )
    }

    /// The perturbation is the homework's: projecting w' back onto the plane at unit distance
    /// along w gives offsets uniform in the square [−r/2, r/2]². χ² over an 8×8 grid of that
    /// square, 64 000 samples, 63 degrees of freedom, rejected at α = 1e-3 (χ² > 103.4).
    #[test]
    fn perturbation_is_uniform_on_the_square() {
        let w = Vec3::new(0.3, -0.4, 0.866).normalize();
        let f = Frame::from_normal(w);
        let r = 0.3;
        let mut rng = Pcg32::new(7, 1);
        let mut counts = [0u32; 64];
        let n = 64_000;
        for _ in 0..n {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let p = perturb(w, r, u);
            assert!((p.length() - 1.0).abs() < 1e-5);
            let on_plane = p / p.dot(w);
            let (a, b) = (on_plane.dot(f.s) / r + 0.5, on_plane.dot(f.t) / r + 0.5);
            assert!((-1e-4..1.0001).contains(&a) && (-1e-4..1.0001).contains(&b));
            let (i, j) = (
                (a * 8.0).clamp(0.0, 7.999) as usize,
                (b * 8.0).clamp(0.0, 7.999) as usize,
            );
            counts[i * 8 + j] += 1;
        }
        let e = n as f64 / 64.0;
        let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 103.4, "chi2 = {chi2}");
    }

    /// The ideal lobe's expected weight is its albedo, whatever the lobe probabilities, and
    /// the Phong part keeps its own value: E[weight] = ideal + Phong albedo.
    #[test]
    fn lobes_add_up() {
        let wo = Vec3::new(0.2, 0.1, 0.97).normalize();
        let mirror = CourseMaterial::new(phong(0.4, 0.0), IdealLobe::Mirror, Vec3::splat(0.5), 0.0);
        let mut rng = Pcg32::new(3, 5);
        let n = 200_000;
        let (mut ideal, mut rest) = (Vec3::ZERO, Vec3::ZERO);
        for _ in 0..n {
            let u1 = rng.next_f32();
            let u2 = Vec2::new(rng.next_f32(), rng.next_f32());
            if let Some(s) = mirror.sample(wo, u1, u2, TransportMode::Radiance) {
                if s.delta {
                    assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
                    ideal += s.weight;
                } else {
                    rest += s.weight;
                }
            }
        }
        let ideal = ideal / n as f32;
        // The unnormalised course diffuse lobe integrates kd·cos over the hemisphere: π·kd.
        let rest = rest / n as f32;
        assert!((ideal.x - 0.5).abs() < 0.01, "{ideal}");
        assert!((rest.x - 0.4 * std::f32::consts::PI).abs() < 0.03, "{rest}");
    }

    #[test]
    fn rough_directions_stay_on_their_side() {
        let glass = CourseMaterial::new(
            phong(0.0, 0.0),
            IdealLobe::Dielectric { eta: 1.5 },
            Vec3::ZERO,
            0.5,
        );
        let mut rng = Pcg32::new(11, 2);
        for _ in 0..10_000 {
            let wo = Vec3::new(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
            )
            .normalize();
            let u2 = Vec2::new(rng.next_f32(), rng.next_f32());
            if let Some(s) = glass.sample(wo, rng.next_f32(), u2, TransportMode::Radiance) {
                assert_eq!(s.transmission, s.wi.z * wo.z < 0.0);
                assert!(s.delta);
            }
        }
    }
}
