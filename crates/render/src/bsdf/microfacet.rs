//! Microfacet normal distributions (Beckmann and GGX, isotropic or anisotropic) with Smith
//! shadowing–masking and sampling of the distribution of visible normals, after Mitsuba 3's
//! `include/mitsuba/render/microfacet.h`.
//!
//! - D(m): Beckmann `exp(-((mx/αu)² + (my/αv)²)/mz²) / (π αu αv mz⁴)`, GGX
//!   `1 / (π αu αv ((mx/αu)² + (my/αv)² + mz²)²)`.
//! - G1: exact Smith for GGX, the rational approximation of Walter et al. 2007 for Beckmann
//!   (< 0.35 % error, as Mitsuba uses); G = G1(wi)·G1(wo) (separable form).
//! - Visible normals D_wi(m) = G1(wi, m)·max(0, wi·m)·D(m)/cos θi are sampled with Heitz 2018
//!   ("Sampling the GGX Distribution of Visible Normals", JCGT 7(4)) for GGX, and for Beckmann
//!   with the stretch / sample-the-α=1-slopes / unstretch scheme of Heitz & d'Eon 2014, where
//!   the α=1 slope distribution is inverted numerically in the erf domain (Jakob's
//!   bisection–Newton variant, as Mitsuba does).
//!
//! Roughness values are clamped to ≥ 1e-4 like Mitsuba.

use crate::math::{PI, Vec2, Vec3};
use crate::sampling::warp;

use super::fresnel::{fresnel_dielectric, refract_m};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MicrofacetType {
    /// Beckmann (Gaussian random surface); Mitsuba's default.
    #[default]
    Beckmann,
    /// GGX / Trowbridge–Reitz.
    Ggx,
}

impl From<base::MicrofacetDistribution> for MicrofacetType {
    fn from(d: base::MicrofacetDistribution) -> Self {
        match d {
            base::MicrofacetDistribution::Ggx => MicrofacetType::Ggx,
            base::MicrofacetDistribution::Beckmann => MicrofacetType::Beckmann,
        }
    }
}

/// A microfacet distribution with roughness `alpha_u` (along the tangent, x) and `alpha_v`
/// (along the bitangent, y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub kind: MicrofacetType,
    pub alpha_u: f32,
    pub alpha_v: f32,
}

const INV_SQRT_PI: f64 = 0.564_189_583_547_756_3;

impl Microfacet {
    pub fn new(kind: MicrofacetType, alpha_u: f32, alpha_v: f32) -> Microfacet {
        let fix = |a: f32| if a.is_finite() { a.max(1e-4) } else { 1e-4 };
        Microfacet {
            kind,
            alpha_u: fix(alpha_u),
            alpha_v: fix(alpha_v),
        }
    }

    pub fn isotropic(kind: MicrofacetType, alpha: f32) -> Microfacet {
        Microfacet::new(kind, alpha, alpha)
    }

    pub fn is_isotropic(&self) -> bool {
        self.alpha_u == self.alpha_v
    }

    /// The normal distribution D(m) (density of microfacet normals per projected area).
    #[inline]
    pub fn eval(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (au, av) = (self.alpha_u, self.alpha_v);
        let cos2 = m.z * m.z;
        let r = match self.kind {
            MicrofacetType::Beckmann => {
                let e = ((m.x / au).powi(2) + (m.y / av).powi(2)) / cos2;
                (-e).exp() / (PI * au * av * cos2 * cos2)
            }
            MicrofacetType::Ggx => {
                let d = (m.x / au).powi(2) + (m.y / av).powi(2) + cos2;
                1.0 / (PI * au * av * d * d)
            }
        };
        // Prune tiny values (as Mitsuba) so that a zero density never meets a huge weight.
        if r * m.z > 1e-20 && r.is_finite() {
            r
        } else {
            0.0
        }
    }

    /// Smith's shadowing–masking for one direction `v` and microfacet normal `m`.
    #[inline]
    pub fn smith_g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let xy_alpha_2 = (self.alpha_u * v.x).powi(2) + (self.alpha_v * v.y).powi(2);
        if xy_alpha_2 == 0.0 {
            return 1.0;
        }
        let tan_theta_alpha_2 = xy_alpha_2 / (v.z * v.z);
        match self.kind {
            MicrofacetType::Beckmann => {
                let a = 1.0 / tan_theta_alpha_2.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    let a2 = a * a;
                    (3.535 * a + 2.181 * a2) / (1.0 + 2.276 * a + 2.577 * a2)
                }
            }
            MicrofacetType::Ggx => 2.0 / (1.0 + (1.0 + tan_theta_alpha_2).sqrt()),
        }
    }

    /// Separable Smith shadowing–masking G1(wi)·G1(wo).
    #[inline]
    pub fn g(&self, wi: Vec3, wo: Vec3, m: Vec3) -> f32 {
        self.smith_g1(wi, m) * self.smith_g1(wo, m)
    }

    /// Density of visible normals D_wi(m) = D(m)·G1(wi, m)·|wi·m| / |cos θi| (`wi.z > 0`).
    #[inline]
    pub fn pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        if wi.z == 0.0 {
            return 0.0;
        }
        self.eval(m) * self.smith_g1(wi, m) * wi.dot(m).abs() / wi.z.abs()
    }

    /// Sample a visible normal for `wi` (which must have `wi.z > 0`); returns the normal and
    /// its density [`Microfacet::pdf`].
    #[inline]
    pub fn sample(&self, wi: Vec3, u: Vec2) -> (Vec3, f32) {
        let m = match self.kind {
            MicrofacetType::Ggx => self.sample_ggx_visible(wi, u),
            MicrofacetType::Beckmann => self.sample_beckmann_visible(wi, u),
        };
        (m, self.pdf(wi, m))
    }

    /// Heitz 2018: sample the projected area of a hemisphere in the stretched configuration.
    fn sample_ggx_visible(&self, wi: Vec3, u: Vec2) -> Vec3 {
        let vh = Vec3::new(self.alpha_u * wi.x, self.alpha_v * wi.y, wi.z).normalize();
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        let r = u.x.sqrt();
        let (sp, cp) = warp::sin_cos_2pi(u.y);
        let p1 = r * cp;
        let mut p2 = r * sp;
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3::new(self.alpha_u * nh.x, self.alpha_v * nh.y, nh.z.max(1e-7)).normalize()
    }

    /// Heitz & d'Eon 2014 with a numerical inversion of the α = 1 slope CDF.
    fn sample_beckmann_visible(&self, wi: Vec3, u: Vec2) -> Vec3 {
        // Step 1: stretch wi.
        let wp = Vec3::new(self.alpha_u * wi.x, self.alpha_v * wi.y, wi.z).normalize();
        let sin_t = (wp.x * wp.x + wp.y * wp.y).sqrt();
        let (cos_phi, sin_phi) = if sin_t > 0.0 {
            (wp.x / sin_t, wp.y / sin_t)
        } else {
            (1.0, 0.0)
        };
        // Step 2: slopes of visible normals for α = 1.
        let (sx, sy) = beckmann_visible_slopes_11(wp.z as f64, u.x as f64, u.y as f64);
        let (sx, sy) = (sx as f32, sy as f32);
        // Step 3: rotate and unstretch.
        let slope_x = (cos_phi * sx - sin_phi * sy) * self.alpha_u;
        let slope_y = (sin_phi * sx + cos_phi * sy) * self.alpha_v;
        Vec3::new(-slope_x, -slope_y, 1.0).normalize()
    }

    /// Sample D(m)·cos θm (all normals, not just the visible ones) — used by Nori's model.
    pub fn sample_all(&self, u: Vec2) -> Vec3 {
        let phi = 2.0 * PI * u.y;
        let (sp, cp) = phi.sin_cos();
        // Azimuth-dependent roughness for anisotropic distributions is not needed here: the
        // only user (Nori) is isotropic.
        let a2 = self.alpha_u * self.alpha_v;
        let one_minus = (1.0 - u.x).max(1e-12);
        let tan2 = match self.kind {
            MicrofacetType::Beckmann => -a2 * one_minus.ln(),
            MicrofacetType::Ggx => a2 * u.x / one_minus,
        };
        let cos_t = 1.0 / (1.0 + tan2).sqrt();
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        Vec3::new(sin_t * cp, sin_t * sp, cos_t)
    }
}

/// Slopes (x̃, ỹ) of a visible Beckmann normal with α = 1 for an incident direction in the
/// xz-plane with cosine `cos_theta_i` (m ∝ (−x̃, −ỹ, 1)). The x-slope CDF, written in the
/// erf domain b = erf(x̃), is (1 + b + tan θ/√π · exp(−x̃²)) / (1 + erf(cot θ) + tan θ/√π ·
/// exp(−cot²θ)); it is inverted with safeguarded Newton iterations.
fn beckmann_visible_slopes_11(cos_theta_i: f64, u1: f64, u2: f64) -> (f64, f64) {
    use statrs::function::erf::{erf, erf_inv};
    let u1 = u1.clamp(1e-7, 1.0 - 1e-7);
    let u2 = u2.clamp(1e-7, 1.0 - 1e-7);
    let sy = erf_inv(2.0 * u2 - 1.0);
    let cos_theta_i = cos_theta_i.clamp(-1.0, 1.0);
    if cos_theta_i >= 0.999_999 {
        return (erf_inv(2.0 * u1 - 1.0), sy);
    }
    let tan_t = (1.0 - cos_theta_i * cos_theta_i).max(0.0).sqrt() / cos_theta_i.max(1e-9);
    let cot_t = 1.0 / tan_t;
    let c = erf(cot_t);
    let target = u1 * (1.0 + c + INV_SQRT_PI * tan_t * (-cot_t * cot_t).exp());

    // Initial guess (Jakob's fit, exact for θ = π/2 up to the fit), then safeguarded Newton.
    let theta = cos_theta_i.acos();
    let fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
    let mut b = c - (1.0 + c) * (1.0 - u1).powf(fit);
    let (mut lo, mut hi) = (-1.0f64, c);
    for _ in 0..64 {
        if !(b > lo && b < hi) {
            b = 0.5 * (lo + hi);
        }
        let s = erf_inv(b);
        let value = 1.0 + b + INV_SQRT_PI * tan_t * (-s * s).exp() - target;
        if value.abs() < 1e-10 {
            break;
        }
        if value > 0.0 {
            hi = b;
        } else {
            lo = b;
        }
        if hi - lo < 1e-15 {
            break;
        }
        let derivative = 1.0 - s * tan_t;
        b -= value / derivative;
    }
    (erf_inv(b), sy)
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton iteration on P_n).
pub(crate) fn gauss_legendre(n: usize, nodes: &mut [f64], weights: &mut [f64]) {
    for i in 0..n {
        let mut x = (PI as f64 * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0f64, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else { p1 };
            let pn1 = if n == 0 { 0.0 } else { p0 };
            dp = n as f64 * (x * pn - pn1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
}

/// Integrate `f(m)` against the visible-normal density for `wi` with a tensor Gauss–Legendre
/// rule over the sampling routine's unit square (Mitsuba's `eval_reflectance` scheme).
fn integrate_visible(distr: &Microfacet, wi: Vec3, res: usize, f: impl Fn(Vec3) -> f64) -> f64 {
    let mut nodes = [0.0f64; 128];
    let mut weights = [0.0f64; 128];
    let res = res.min(128);
    gauss_legendre(res, &mut nodes, &mut weights);
    let mut acc = 0.0;
    for i in 0..res {
        for j in 0..res {
            let u = Vec2::new((0.5 * nodes[i] + 0.5) as f32, (0.5 * nodes[j] + 0.5) as f32);
            let (m, _) = distr.sample(wi, u);
            acc += weights[i] * weights[j] * f(m);
        }
    }
    acc * 0.25
}

/// Directional albedo of a rough dielectric interface's single-scattering *reflection* for an
/// incident direction with cosine `mu` (> 0) and relative index `eta`.
pub fn eval_reflectance(distr: &Microfacet, mu: f32, eta: f32) -> f32 {
    let mu = mu.clamp(1e-6, 1.0);
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let res = if eta > 1.0 { 32 } else { 128 };
    integrate_visible(distr, wi, res, |m| {
        let wo = super::reflect_z_about(wi, m);
        if wo.z <= 0.0 {
            return 0.0;
        }
        let f = fresnel_dielectric(wi.dot(m), eta).0;
        (f * distr.smith_g1(wo, m)) as f64
    }) as f32
}

/// Directional albedo of a rough dielectric interface's single-scattering *transmission*.
pub fn eval_transmittance(distr: &Microfacet, mu: f32, eta: f32) -> f32 {
    let mu = mu.clamp(1e-6, 1.0);
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let res = if eta > 1.0 { 32 } else { 128 };
    integrate_visible(distr, wi, res, |m| {
        let (f, cos_t, _, eta_ti) = fresnel_dielectric(wi.dot(m), eta);
        let wo = refract_m(wi, m, cos_t, eta_ti);
        if wo.z >= 0.0 {
            return 0.0;
        }
        ((1.0 - f) * distr.smith_g1(wo, m)) as f64
    }) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dirs() -> impl Iterator<Item = Vec3> {
        (0..16).flat_map(|i| {
            (0..32).map(move |j| {
                let z = (i as f32 + 0.5) / 16.0;
                let phi = 2.0 * PI * (j as f32 + 0.5) / 32.0;
                let r = (1.0 - z * z).sqrt();
                Vec3::new(r * phi.cos(), r * phi.sin(), z)
            })
        })
    }

    /// ∫ D(m) cos θm dω = 1 (projected area normalisation), by midpoint rule in (cos θ, φ)
    /// after the substitution tan θ = α·t that resolves narrow lobes.
    #[test]
    fn distributions_are_normalised() {
        for kind in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for (au, av) in [(0.05, 0.05), (0.3, 0.3), (0.8, 0.8), (0.1, 0.4)] {
                let d = Microfacet::new(kind, au, av);
                let (nt, np) = (4000, 256);
                let mut s = 0.0f64;
                let tmax = 60.0f64;
                for i in 0..nt {
                    // θ = atan(α·t), t ∈ [0, tmax]: dθ = α/(1+α²t²) dt.
                    let t = (i as f64 + 0.5) / nt as f64 * tmax;
                    let a = au.max(av) as f64;
                    let theta = (a * t).atan();
                    let dtheta = a / (1.0 + a * a * t * t) * tmax / nt as f64;
                    for j in 0..np {
                        let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                        let m = Vec3::new(
                            (theta.sin() * phi.cos()) as f32,
                            (theta.sin() * phi.sin()) as f32,
                            theta.cos() as f32,
                        );
                        s += d.eval(m) as f64
                            * theta.cos()
                            * theta.sin()
                            * dtheta
                            * (2.0 * std::f64::consts::PI / np as f64);
                    }
                }
                let tol = if kind == MicrofacetType::Ggx {
                    2e-2
                } else {
                    2e-3
                };
                assert!((s - 1.0).abs() < tol, "{kind:?} {au} {av}: {s}");
            }
        }
    }

    #[test]
    fn visible_normals_are_in_front_and_pdf_positive() {
        for kind in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            let d = Microfacet::new(kind, 0.3, 0.15);
            for wi in dirs() {
                for k in 0..16 {
                    let u = Vec2::new((k as f32 + 0.5) / 16.0, ((k * 7 % 16) as f32 + 0.5) / 16.0);
                    let (m, pdf) = d.sample(wi, u);
                    assert!((m.length() - 1.0).abs() < 1e-4 && m.z > 0.0);
                    assert!(pdf > 0.0 && pdf.is_finite(), "{kind:?} {wi} {m} {pdf}");
                }
            }
        }
    }

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let mut x = [0.0; 8];
        let mut w = [0.0; 8];
        gauss_legendre(8, &mut x, &mut w);
        let s: f64 = (0..8).map(|i| w[i] * x[i].powi(14)).sum();
        assert!((s - 2.0 / 15.0).abs() < 1e-12);
    }

    #[test]
    fn rough_interface_albedos_are_sane() {
        let d = Microfacet::isotropic(MicrofacetType::Beckmann, 0.01);
        // Nearly smooth: matches the smooth Fresnel reflectance.
        let r = eval_reflectance(&d, 1.0, 1.5);
        assert!((r - 0.04).abs() < 1e-3, "{r}");
        let t = eval_transmittance(&d, 1.0, 1.5);
        assert!((t - 0.96).abs() < 1e-3, "{t}");
        let d = Microfacet::isotropic(MicrofacetType::Ggx, 0.5);
        for mu in [0.1, 0.5, 1.0] {
            let r = eval_reflectance(&d, mu, 1.5);
            let t = eval_transmittance(&d, mu, 1.5);
            assert!(r > 0.0 && t > 0.0 && r + t <= 1.0 + 1e-4, "{mu}: {r} {t}");
        }
    }
}
