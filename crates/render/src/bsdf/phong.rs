//! The CENG795 Phong family of BRDFs and Torrance–Sparrow, as defined in the course
//! (Akyüz, METU CENG795 "BRDFs" lecture). With cos α = wi·reflect(wo) (Phong) or
//! cos α = n·h, h = normalize(wo + wi) (Blinn–Phong), p the exponent:
//!
//! | model                       | f(wo, wi)                                         |
//! |-----------------------------|---------------------------------------------------|
//! | original Phong              | kd + ks cosᵖα / cos θi                            |
//! | modified Phong              | kd + ks cosᵖα                                     |
//! | modified Phong, normalised  | kd/π + ks (p+2)/(2π) cosᵖα                        |
//! | original Blinn–Phong        | kd + ks cosᵖα / cos θi                            |
//! | modified Blinn–Phong        | kd + ks cosᵖα                                     |
//! | modified Blinn–Phong, norm. | kd/π + ks (p+8)/(8π) cosᵖα                        |
//! | Torrance–Sparrow            | kd/π·(1−F if kdfresnel) + ks D F G / (4 cos θi cos θo) |
//!
//! Torrance–Sparrow uses the normalised Blinn distribution D = (p+2)/(2π) cosᵖθh, the
//! Cook–Torrance shadowing G = min(1, 2 cos θh cos θo / (wo·h), 2 cos θh cos θi / (wo·h)) and
//! Fresnel F(wo·h): Schlick's with F₀ = ((n−1)/(n+1))² from the refraction index n, or, when
//! the material gives an absorption index k > 0, the exact unpolarised reflectance of a
//! conductor of complex index n + ik (the course's metals: gold is n = 0.37, k = 2.82).
//! The unnormalised models keep the course's convention (no 1/π on kd), so their Whitted
//! renders match the course's reference images; they are not energy conserving.
//! Original Phong/Blinn–Phong are not reciprocal (they divide by cos θi), as in the course.
//!
//! Sampling: a lobe is chosen in proportion to an estimate of its albedo; the diffuse lobe
//! is cosine-weighted; the Phong lobe draws wi with density (p+1)/(2π) cosᵖα around the mirror
//! direction of wo; the Blinn lobes draw h with density (p+1)/(2π) cosᵖθh and reflect wo
//! about it (density / (4 wo·h)). `pdf` is the mixture density, and samples carry eval/pdf.

use super::fresnel::fresnel_conductor_1;
use super::reflect_z_about;
use super::{BsdfModel, BsdfSample, TransportMode, mean, mixture_reflection_sample, reflect_z};
use crate::math::{Frame, INV_PI, Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::spectral::lanes::Color;
use base::PhongModel;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhongFamily<C: Color = Vec3> {
    pub model: PhongModel,
    pub normalized: bool,
    pub kd_fresnel: bool,
    pub exponent: f32,
    pub kd: C,
    pub ks: C,
    /// Schlick's F₀ from the refraction index.
    pub f0: f32,
    /// Complex index (n, k) of a conductor: exact conductor Fresnel instead of Schlick's.
    pub conductor: Option<(f32, f32)>,
    /// Probability of sampling the specular lobe: from the RGB channel means of kd and ks
    /// (fixed 3-channel arithmetic), kept in spectral mode so that the lobe choice does not
    /// depend on the path's wavelengths.
    spec_prob: f32,
}

impl PhongFamily {
    pub fn new(
        model: PhongModel,
        normalized: bool,
        kd_fresnel: bool,
        exponent: f32,
        kd: Vec3,
        ks: Vec3,
        ior: f32,
    ) -> PhongFamily {
        let exponent = exponent.max(0.0);
        let r = (ior - 1.0) / (ior + 1.0);
        let mut b = PhongFamily {
            model,
            normalized,
            kd_fresnel,
            exponent,
            kd: kd.max(Vec3::ZERO),
            ks: ks.max(Vec3::ZERO),
            f0: if r.is_finite() { r * r } else { 0.0 },
            conductor: None,
            spec_prob: 0.0,
        };
        // Albedo estimates at normal incidence: unnormalised kd integrates to π·kd.
        let d = mean(b.kd)
            * if b.diffuse_over_pi() {
                1.0
            } else {
                std::f32::consts::PI
            };
        let s = mean(b.ks);
        b.spec_prob = if d + s > 0.0 { s / (d + s) } else { 0.0 };
        if !b.spec_prob.is_finite() {
            b.spec_prob = 0.0;
        }
        b
    }

    /// The same BSDF with kd and ks converted by `f` (e.g. a `ColorMode`'s albedo
    /// upsampling; negative channels are clamped in RGB first); the lobe probability and the
    /// Fresnel parameters stay the RGB ones.
    pub fn map_lanes<D: Color>(&self, f: impl Fn(Vec3) -> D) -> PhongFamily<D> {
        PhongFamily {
            model: self.model,
            normalized: self.normalized,
            kd_fresnel: self.kd_fresnel,
            exponent: self.exponent,
            kd: f(self.kd),
            ks: f(self.ks),
            f0: self.f0,
            conductor: self.conductor,
            spec_prob: self.spec_prob,
        }
    }
}

impl<C: Color> PhongFamily<C> {
    /// With `k > 0`, Torrance–Sparrow uses the Fresnel reflectance of a conductor of complex
    /// index `eta + i k`; otherwise nothing changes.
    pub fn with_absorption(mut self, eta: f32, k: f32) -> PhongFamily<C> {
        if k > 0.0 && eta.is_finite() && k.is_finite() {
            self.conductor = Some((eta.max(0.0), k));
        }
        self
    }

    fn diffuse_over_pi(&self) -> bool {
        self.normalized || self.model == PhongModel::TorranceSparrow
    }

    fn is_blinn(&self) -> bool {
        !matches!(
            self.model,
            PhongModel::OriginalPhong | PhongModel::ModifiedPhong
        )
    }

    fn fresnel(&self, c: f32) -> f32 {
        if let Some((eta, k)) = self.conductor {
            return fresnel_conductor_1(c.clamp(0.0, 1.0), eta, k);
        }
        let m = (1.0 - c).clamp(0.0, 1.0);
        self.f0 + (1.0 - self.f0) * m * m * m * m * m
    }

    /// Density of the specular lobe's sampling of `wi` (no lobe probability).
    fn spec_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = self.exponent;
        let norm = (p + 1.0) * 0.5 * INV_PI;
        if self.is_blinn() {
            let h = (wo + wi).normalize_or_zero();
            let d = wo.dot(h);
            if h.z <= 0.0 || d <= 0.0 {
                return 0.0;
            }
            norm * h.z.powf(p) / (4.0 * d)
        } else {
            let c = wi.dot(reflect_z(wo));
            if c <= 0.0 {
                return 0.0;
            }
            norm * c.powf(p)
        }
    }
}

impl<C: Color> BsdfModel<C> for PhongFamily<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return C::ZERO;
        }
        let p = self.exponent;
        let cos_i = wi.z;
        let h = (wo + wi).normalize_or_zero();
        let cos_a = if self.is_blinn() {
            h.z
        } else {
            wi.dot(reflect_z(wo))
        }
        .max(0.0);
        let lobe = cos_a.powf(p);
        let (diffuse, spec) = match self.model {
            PhongModel::OriginalPhong | PhongModel::OriginalBlinnPhong => {
                (self.kd, self.ks * (lobe / cos_i))
            }
            PhongModel::ModifiedPhong if self.normalized => (
                self.kd * INV_PI,
                self.ks * ((p + 2.0) * 0.5 * INV_PI * lobe),
            ),
            PhongModel::ModifiedBlinnPhong if self.normalized => (
                self.kd * INV_PI,
                self.ks * ((p + 8.0) * 0.125 * INV_PI * lobe),
            ),
            PhongModel::ModifiedPhong | PhongModel::ModifiedBlinnPhong => (self.kd, self.ks * lobe),
            PhongModel::TorranceSparrow => {
                let cos_o = wo.z;
                let woh = wo.dot(h);
                if woh <= 0.0 {
                    return C::ZERO;
                }
                let d = (p + 2.0) * 0.5 * INV_PI * lobe;
                let g = (2.0 * h.z * cos_o / woh)
                    .min(2.0 * h.z * cos_i / woh)
                    .min(1.0);
                let f = self.fresnel(woh);
                let kd = if self.kd_fresnel {
                    self.kd * (1.0 - f)
                } else {
                    self.kd
                };
                (kd * INV_PI, self.ks * (d * f * g / (4.0 * cos_i * cos_o)))
            }
        };
        (diffuse + spec) * cos_i
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let s = if self.spec_prob > 0.0 {
            self.spec_pdf(wo, wi)
        } else {
            0.0
        };
        self.spec_prob * s + (1.0 - self.spec_prob) * cosine_hemisphere_pdf(wi)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u1 < self.spec_prob {
            // cos = u^(1/(p+1)) around the lobe axis.
            let cos_t = u2.x.powf(1.0 / (self.exponent + 1.0));
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * u2.y;
            let local = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
            if self.is_blinn() {
                let h = local;
                if wo.dot(h) <= 0.0 {
                    return None;
                }
                reflect_z_about(wo, h)
            } else {
                Frame::from_normal(reflect_z(wo)).to_world(local)
            }
        } else {
            square_to_cosine_hemisphere(u2)
        };
        mixture_reflection_sample(self, wo, wi, mode)
    }

    fn has_delta(&self) -> bool {
        false
    }
    fn has_smooth(&self) -> bool {
        true
    }
    fn albedo(&self) -> C {
        self.kd
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::Pcg32;

    /// Normalised modified Phong/Blinn–Phong with kd = 1, ks = 0 is Lambertian of albedo 1,
    /// and a normalised lobe alone reflects about what it receives at normal incidence (the
    /// (p+8)/(8π) Blinn–Phong factor is itself an approximation: ≈ 1.06 at p = 20).
    #[test]
    fn normalised_lobes_conserve_energy() {
        for model in [PhongModel::ModifiedPhong, PhongModel::ModifiedBlinnPhong] {
            for (kd, ks, p) in [(Vec3::ONE, Vec3::ZERO, 1.0), (Vec3::ZERO, Vec3::ONE, 20.0)] {
                let b = PhongFamily::new(model, true, false, p, kd, ks, 1.5);
                let wo = Vec3::Z;
                // Albedo by importance sampling (mean of sample weights).
                let mut rng = Pcg32::new(7, 1);
                let n = 200_000;
                let mut sum = 0.0f64;
                for _ in 0..n {
                    if let Some(s) =
                        b.sample(wo, rng.next_f32(), rng.next_vec2(), TransportMode::Radiance)
                    {
                        sum += s.weight.x as f64;
                    }
                }
                let albedo = sum / n as f64;
                if ks == Vec3::ZERO {
                    assert!((albedo - 1.0).abs() < 0.01, "{model:?}: {albedo}");
                } else {
                    assert!(albedo < 1.08 && albedo > 0.8, "{model:?}: {albedo}");
                }
            }
        }
    }

    /// Gold (n = 0.37, k = 2.82) reflects F = ((n−1)² + k²)/((n+1)² + k²) ≈ 0.849 at normal
    /// incidence, where Schlick's dielectric F₀ from n alone would give 0.211.
    #[test]
    fn torrance_sparrow_conductor_fresnel() {
        let ts = |k| {
            PhongFamily::new(
                PhongModel::TorranceSparrow,
                false,
                false,
                50.0,
                Vec3::ZERO,
                Vec3::ONE,
                0.37,
            )
            .with_absorption(0.37, k)
        };
        let f = |b: PhongFamily| b.eval(Vec3::Z, Vec3::Z, TransportMode::Radiance).x;
        let (n, k) = (0.37f32, 2.82f32);
        let exact = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        let schlick = ((n - 1.0) / (n + 1.0)).powi(2);
        // D, G and the cosines are common: the ratio is that of the Fresnel terms.
        let ratio = f(ts(k)) / f(ts(0.0));
        assert!(
            (ratio - exact / schlick).abs() < 1e-3 * exact / schlick,
            "{ratio}"
        );
        assert!((exact - 0.849).abs() < 1e-3);
        // At grazing incidence a conductor reflects (almost) everything, never more.
        let grazing = ts(k).fresnel(0.01);
        assert!(grazing <= 1.0 && grazing > 0.95, "{grazing}");
    }

    #[test]
    fn below_horizon_is_black() {
        let b = PhongFamily::new(
            PhongModel::TorranceSparrow,
            false,
            true,
            50.0,
            Vec3::splat(0.5),
            Vec3::ONE,
            1.5,
        );
        let wo = Vec3::new(0.3, 0.0, 0.9).normalize();
        assert_eq!(
            b.eval(wo, Vec3::new(0.0, 0.0, -1.0), TransportMode::Radiance),
            Vec3::ZERO
        );
        assert_eq!(b.pdf(-wo, Vec3::Z), 0.0);
    }
}
