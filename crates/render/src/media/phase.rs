//! Phase functions: isotropic, Henyey–Greenstein, Rayleigh, tabulated (Mitsuba 3's
//! `tabphase`), blends of two (`blendphase`) and the specular SGGX microflake phase function
//! of a constant S (Mitsuba 3's `sggx`), with Mitsuba 3's conventions.
//!
//! Directions point away from the scattering point: `wo` towards where the path came from
//! (Mitsuba's `mi.wi`), `wi` the new direction. The scattering angle θ is between the
//! incident travel direction `-wo` and `wi`, so forward scattering (g > 0) favours `wi ≈ -wo`.
//! Every one is sampled exactly: `sample` returns a direction whose weight (value / pdf)
//! is 1. A blend picks its component with the first random number, rescaled for reuse.

use std::sync::Arc;

use crate::math::{Frame, INV_2PI, INV_4PI, PI, Vec2, Vec3, safe_sqrt, spherical_direction};
use crate::sampling::warp;

#[derive(Clone, Debug, PartialEq)]
pub enum Phase {
    Isotropic,
    /// Henyey–Greenstein with mean cosine `g` ∈ (−1, 1).
    HenyeyGreenstein {
        g: f32,
    },
    /// Rayleigh scattering, 3/(16π)·(1 + cos²θ) (unpolarised).
    Rayleigh,
    /// A table over the scattering cosine (Mitsuba's `tabphase`).
    Tabulated(Arc<TabulatedPhase>),
    /// `(1 − w)·first + w·second` (Mitsuba's `blendphase`).
    Blend(Arc<BlendPhase>),
    /// The specular SGGX microflake phase function (Mitsuba's `sggx`).
    Sggx(Arc<SggxPhase>),
}

/// Mitsuba 3's `sggx`: specular microflakes whose normals follow the SGGX distribution of
/// the symmetric positive definite matrix S (Heitz, Dupuy, Crassin and Dachsbacher 2015,
/// "The SGGX microflake distribution"). Its value for scattering from `-wo` into `wi` is
/// D(h)/(4·σ(wo)), h the half vector of `wo` and `wi`, D(m) = 1/(π·√|S|·(mᵀS⁻¹m)²) and
/// σ(w) = √(wᵀSw) the projected area; a sample reflects `wo` about a visible normal drawn
/// from ⟨wo, m⟩·D(m)/σ(wo), so its density is the value. S is constant here (Mitsuba lets a
/// 6-channel volume vary it over space).
#[derive(Clone, Debug, PartialEq)]
pub struct SggxPhase {
    /// S_xx, S_yy, S_zz, S_xy, S_xz, S_yz (Mitsuba's order).
    s: [f32; 6],
    /// The adjugate's entries in the same order (S⁻¹ = adj / det), for D.
    adj: [f32; 6],
    /// |S|.
    det: f32,
}

impl SggxPhase {
    /// From S_xx, S_yy, S_zz, S_xy, S_xz, S_yz; `None` unless finite and positive definite.
    pub fn new(s: [f32; 6]) -> Option<SggxPhase> {
        let [xx, yy, zz, xy, xz, yz] = s;
        let adj = [
            yy * zz - yz * yz,
            xx * zz - xz * xz,
            xx * yy - xy * xy,
            xz * yz - zz * xy,
            xy * yz - yy * xz,
            xy * xz - xx * yz,
        ];
        let det = xx * adj[0] + xy * adj[3] + xz * adj[4];
        // Sylvester's criterion: the leading minors are positive.
        let ok = s.iter().all(|v| v.is_finite()) && xx > 0.0 && adj[2] > 0.0 && det > 0.0;
        ok.then_some(SggxPhase { s, adj, det })
    }

    /// wᵀ·M·w for a symmetric M given as its six entries.
    #[inline]
    fn quad(m: &[f32; 6], w: Vec3) -> f32 {
        w.x * w.x * m[0]
            + w.y * w.y * m[1]
            + w.z * w.z * m[2]
            + 2.0 * (w.x * w.y * m[3] + w.x * w.z * m[4] + w.y * w.z * m[5])
    }

    /// The microflake normal density D(m) (per steradian; `sggx_pdf` in Mitsuba).
    #[inline]
    fn ndf(&self, m: Vec3) -> f32 {
        let den = Self::quad(&self.adj, m);
        self.det * self.det.sqrt() / (PI * den * den)
    }

    /// The projected area σ(w) = √(wᵀSw).
    #[inline]
    fn projected_area(&self, w: Vec3) -> f32 {
        safe_sqrt(Self::quad(&self.s, w))
    }

    fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        let h = wo + wi;
        let len2 = h.length_squared();
        let sigma = self.projected_area(wo);
        if !(len2 > 0.0 && sigma > 0.0) {
            return 0.0;
        }
        0.25 * self.ndf(h / len2.sqrt()) / sigma
    }

    /// A visible normal for `wo` (Heitz et al.'s `sample_VNDF`, as Mitsuba's `sggx_sample`:
    /// S in a frame whose third axis is `wo`, a cosine-distributed point of the unit disk
    /// mapped by the factor of that matrix).
    fn sample_normal(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let f = Frame::from_normal(wo);
        let (k, j, i) = (f.s, f.t, f.n);
        let [xx, yy, zz, xy, xz, yz] = self.s;
        let bil = |a: Vec3, b: Vec3| {
            a.x * b.x * xx
                + a.y * b.y * yy
                + a.z * b.z * zz
                + (a.x * b.y + a.y * b.x) * xy
                + (a.x * b.z + a.z * b.x) * xz
                + (a.y * b.z + a.z * b.y) * yz
        };
        let (s_kk, s_jj, s_ii) = (bil(k, k), bil(j, j), bil(i, i));
        let (s_kj, s_ki, s_ji) = (bil(k, j), bil(k, i), bil(j, i));
        let det = s_kk * s_jj * s_ii - s_kj * s_kj * s_ii - s_ki * s_ki * s_jj - s_ji * s_ji * s_kk
            + 2.0 * s_kj * s_ki * s_ji;
        let inv_sqrt_ii = 1.0 / s_ii.max(f32::MIN_POSITIVE).sqrt();
        let tmp = safe_sqrt(s_jj * s_ii - s_ji * s_ji).max(f32::MIN_POSITIVE);
        let m_k = Vec3::new(det.abs().sqrt() / tmp, 0.0, 0.0);
        let m_j = Vec3::new(
            -inv_sqrt_ii * (s_ki * s_ji - s_kj * s_ii) / tmp,
            inv_sqrt_ii * tmp,
            0.0,
        );
        let m_i = inv_sqrt_ii * Vec3::new(s_ki, s_ji, s_ii);
        let w = warp::square_to_cosine_hemisphere(u);
        let m = (w.x * m_k + w.y * m_j + w.z * m_i).normalize();
        m.x * k + m.y * j + m.z * i
    }

    fn sample(&self, wo: Vec3, u: Vec2) -> (Vec3, f32) {
        let m = self.sample_normal(wo, u);
        let wi = (2.0 * wo.dot(m) * m - wo).normalize();
        (wi, self.eval(wo, wi))
    }
}

/// A phase function tabulated at cosines of the scattering angle spaced evenly over
/// [−1, 1] (cos θ = 1 forward), linear in between and normalised, as Mitsuba 3's `tabphase`.
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedPhase {
    /// The values, normalised to a density over cos θ (∫ = 1 over [−1, 1]).
    pdf: Vec<f32>,
    /// The mass of each interval's trapezoid, accumulated (`cdf[0] = 0`, last = 1).
    cdf: Vec<f32>,
}

impl TabulatedPhase {
    /// From at least two non-negative finite values with a positive integral; `None`
    /// otherwise.
    pub fn new(values: &[f32]) -> Option<TabulatedPhase> {
        if values.len() < 2 || values.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return None;
        }
        let h = 2.0 / (values.len() - 1) as f64;
        let mut cdf = Vec::with_capacity(values.len());
        let mut sum = 0.0f64;
        cdf.push(0.0);
        for w in values.windows(2) {
            sum += 0.5 * h * (w[0] as f64 + w[1] as f64);
            cdf.push(sum);
        }
        if !(sum > 0.0 && sum.is_finite()) {
            return None;
        }
        Some(TabulatedPhase {
            pdf: values.iter().map(|&v| (v as f64 / sum) as f32).collect(),
            cdf: cdf.into_iter().map(|c| (c / sum) as f32).collect(),
        })
    }

    /// The density over cos θ at `c` (linear between the nodes).
    fn pdf_cos(&self, c: f32) -> f32 {
        let n = self.pdf.len() - 1;
        let x = ((c.clamp(-1.0, 1.0) + 1.0) * 0.5 * n as f32).min(n as f32);
        let i = (x as usize).min(n - 1);
        let t = x - i as f32;
        (1.0 - t) * self.pdf[i] + t * self.pdf[i + 1]
    }

    /// A cosine with density [`Self::pdf_cos`]: the interval by its mass, then the inverse of
    /// the linear density's CDF within it.
    fn sample_cos(&self, u: f32) -> f32 {
        let n = self.pdf.len() - 1;
        let i = self.cdf.partition_point(|&c| c <= u).clamp(1, n) - 1;
        let mass = self.cdf[i + 1] - self.cdf[i];
        let r = if mass > 0.0 {
            ((u - self.cdf[i]) / mass).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let (a, b) = (self.pdf[i], self.pdf[i + 1]);
        // Solve ((b − a)/2)·t² + a·t = r·(a + b)/2 for t in [0, 1], in the form that stays
        // exact as b → a.
        let t = if a + b > 0.0 {
            r * (a + b) / (a + (a * a + r * (b * b - a * a)).max(0.0).sqrt())
        } else {
            r
        };
        let h = 2.0 / n as f32;
        (-1.0 + (i as f32 + t.clamp(0.0, 1.0)) * h).clamp(-1.0, 1.0)
    }
}

/// Two phase functions mixed with weight `weight` ∈ [0, 1] on the second.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendPhase {
    pub weight: f32,
    pub first: Phase,
    pub second: Phase,
}

/// The Rayleigh density of the scattering-angle cosine (per steradian).
#[inline]
fn rayleigh(cos_theta: f32) -> f32 {
    3.0 / (16.0 * PI) * (1.0 + cos_theta * cos_theta)
}

/// The Henyey–Greenstein density of the scattering-angle cosine `cos_theta` (per steradian).
#[inline]
pub fn hg(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    INV_4PI * (1.0 - g * g) / (denom * safe_sqrt(denom))
}

/// The direction at angle θ (cosine `cos_theta`) from the unit `axis`, at azimuth 2π·`u`.
fn around(axis: Vec3, cos_theta: f32, u: f32) -> Vec3 {
    let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
    let local = spherical_direction(sin_theta, cos_theta, 2.0 * PI * u);
    Frame::from_normal(axis).to_world(local)
}

impl Phase {
    /// For a microflake phase function (`Sggx`), the factor σ(ω) by which Mitsuba 3 scales a
    /// medium's extinction along direction `d` (its projected area; even in `d`); `None` for
    /// the others, whose media do not depend on the direction.
    #[inline]
    pub fn extinction_scale(&self, d: Vec3) -> Option<f32> {
        match self {
            Phase::Sggx(p) => Some(p.projected_area(d)),
            _ => None,
        }
    }

    /// Whether it is a microflake phase function (see [`Self::extinction_scale`]).
    pub fn is_microflake(&self) -> bool {
        matches!(self, Phase::Sggx(_))
    }

    /// The phase function's value for scattering from `-wo` into `wi`; it is also the
    /// density `sample` gives `wi`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Phase::Isotropic => INV_4PI,
            &Phase::HenyeyGreenstein { g } => hg(-wo.dot(wi), g),
            Phase::Rayleigh => rayleigh(wo.dot(wi)),
            Phase::Tabulated(t) => t.pdf_cos(-wo.dot(wi)) * INV_2PI,
            Phase::Blend(b) => {
                (1.0 - b.weight) * b.first.eval(wo, wi) + b.weight * b.second.eval(wo, wi)
            }
            Phase::Sggx(p) => p.eval(wo, wi),
        }
    }

    /// A direction with density [`Phase::eval`], and that density.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> (Vec3, f32) {
        match self {
            Phase::Isotropic => (warp::square_to_uniform_sphere(u), INV_4PI),
            &Phase::HenyeyGreenstein { g } => {
                // Inversion of the cosine's CDF (pbrt-v4's form, stable near g = 0).
                let cos_theta = if g.abs() < 1e-3 {
                    1.0 - 2.0 * u.x
                } else {
                    let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
                    -(1.0 + g * g - s * s) / (2.0 * g)
                };
                // pbrt-v4 measures θ from `wo`; flip to measure it from the travel direction.
                let cos_theta = (-cos_theta).clamp(-1.0, 1.0);
                let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
                let phi = 2.0 * std::f32::consts::PI * u.y;
                let local = spherical_direction(sin_theta, cos_theta, phi);
                let wi = Frame::from_normal(-wo).to_world(local);
                (wi, hg(cos_theta, g))
            }
            Phase::Rayleigh => {
                // The cosine's CDF (cos³ + 3 cos + 4)/8 inverted by Cardano's formula.
                let z = 2.0 * (2.0 * u.x - 1.0);
                let s = (z * z + 1.0).sqrt();
                let cos_theta = ((z + s).cbrt() + (z - s).cbrt()).clamp(-1.0, 1.0);
                let wi = around(-wo, cos_theta, u.y);
                (wi, rayleigh(cos_theta))
            }
            Phase::Tabulated(t) => {
                let cos_theta = t.sample_cos(u.x);
                let wi = around(-wo, cos_theta, u.y);
                (wi, t.pdf_cos(cos_theta) * INV_2PI)
            }
            Phase::Blend(b) => {
                let w = b.weight;
                // The component by u.x, and u.x rescaled to [0, 1) for it.
                let (wi, _) = if u.x < w {
                    b.second.sample(wo, Vec2::new(u.x / w, u.y))
                } else {
                    b.first
                        .sample(wo, Vec2::new(((u.x - w) / (1.0 - w)).min(1.0), u.y))
                };
                (wi, self.eval(wo, wi))
            }
            Phase::Sggx(p) => p.sample(wo, u),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numerical integral of the value over the sphere is 1, and its mean cosine is g.
    #[test]
    fn hg_integrates_to_one_with_mean_cosine_g() {
        for g in [-0.9f32, -0.5, 0.0, 0.3, 0.9] {
            let n = 200_000;
            let (mut sum, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                let v = hg(c as f32, g) as f64 * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
                sum += v;
                mean += v * c;
            }
            assert!((sum - 1.0).abs() < 1e-3, "g={g}: ∫p = {sum}");
            assert!((mean - g as f64).abs() < 2e-3, "g={g}: mean cosine {mean}");
        }
    }

    /// Mitsuba's table is in the physics convention: its last value is forward scattering
    /// (`wi = −wo`), normalised so that 2π·∫ p d(cos θ) = 1; Rayleigh integrates to 1.
    #[test]
    fn tables_read_forward_last_and_integrate_to_one() {
        let t = Phase::Tabulated(Arc::new(TabulatedPhase::new(&[1.0, 3.0]).unwrap()));
        let wo = Vec3::Z;
        // p(cos θ) ∝ 2 + cos θ: 1/(4π)·(2 + c)/2 per steradian.
        assert!((t.eval(wo, -wo) - 3.0 / 2.0 * INV_4PI).abs() < 1e-6);
        assert!((t.eval(wo, wo) - 1.0 / 2.0 * INV_4PI).abs() < 1e-6);
        for phase in [t, Phase::Rayleigh] {
            let n = 100_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
                    let wi = Vec3::new(safe_sqrt(1.0 - c * c), 0.0, -c);
                    phase.eval(wo, wi) as f64 * 2.0 * std::f64::consts::PI * 2.0 / n as f64
                })
                .sum();
            assert!((sum - 1.0).abs() < 1e-4, "{phase:?}: {sum}");
        }
        assert!(TabulatedPhase::new(&[0.0, 0.0]).is_none());
        assert!(TabulatedPhase::new(&[1.0]).is_none());
        assert!(TabulatedPhase::new(&[1.0, -1.0]).is_none());
    }

    /// Values Mitsuba 3.9.1's `sggx` returns (`eval_pdf`, scalar_rgb) for S = (1, 0.5, 0.2,
    /// 0.1, 0.05, 0), mi.wi = +z; and S = I is isotropic.
    #[test]
    fn sggx_matches_mitsuba_values() {
        let p = SggxPhase::new([1.0, 0.5, 0.2, 0.1, 0.05, 0.0]).unwrap();
        for (wi, want) in [
            (Vec3::new(0.6, 0.0, 0.8), 0.0281695f32),
            (Vec3::new(-0.856509, 0.479107, -0.191964), 0.0574206),
        ] {
            let v = p.eval(Vec3::Z, wi);
            assert!((v - want).abs() < 2e-6, "{v} vs {want}");
        }
        let iso = SggxPhase::new([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]).unwrap();
        let wo = Vec3::new(0.3, -0.5, 0.8).normalize();
        for wi in [Vec3::X, wo, Vec3::new(0.1, 0.7, -0.2).normalize()] {
            assert!((iso.eval(wo, wi) - INV_4PI).abs() < 1e-6);
        }
        assert!(SggxPhase::new([1.0, 1.0, -1.0, 0.0, 0.0, 0.0]).is_none());
        assert!(SggxPhase::new([1.0, 1.0, 1.0, 2.0, 0.0, 0.0]).is_none());
    }

    #[test]
    fn samples_have_the_density_eval_reports() {
        let wo = Vec3::new(0.3, -0.5, 0.8).normalize();
        let table = Phase::Tabulated(Arc::new(
            TabulatedPhase::new(&[0.0, 0.2, 1.0, 0.0, 4.0]).unwrap(),
        ));
        let blend = Phase::Blend(Arc::new(BlendPhase {
            weight: 0.4,
            first: Phase::Rayleigh,
            second: table.clone(),
        }));
        for phase in [
            Phase::Isotropic,
            Phase::HenyeyGreenstein { g: 0.7 },
            Phase::Rayleigh,
            table,
            blend,
            Phase::Sggx(Arc::new(
                SggxPhase::new([1.0, 0.5, 0.2, 0.1, 0.05, 0.0]).unwrap(),
            )),
        ] {
            for u in [
                Vec2::new(0.1, 0.2),
                Vec2::new(0.9, 0.7),
                Vec2::new(0.5, 0.5),
            ] {
                let (wi, pdf) = phase.sample(wo, u);
                assert!((wi.length() - 1.0).abs() < 1e-5);
                assert!(
                    (pdf - phase.eval(wo, wi)).abs() < 1e-4 * pdf.max(1.0),
                    "{phase:?}"
                );
            }
        }
    }
}
