//! Sampled spectra in the style of pbrt-v4 (§4.5.4): each camera path carries
//! [`N_SPECTRUM_SAMPLES`] = 4 wavelengths ([`SampledWavelengths`]) and every spectral quantity
//! along it is the 4-lane [`SampledSpectrum`] of its values there.
//!
//! Wavelengths are drawn from the visible-XYZ importance density of pbrt-v4 (Radziszewski et
//! al. 2009's fit), p(λ) ∝ 1/cosh²(0.0072·(λ − 538 nm)) on [360, 830] nm, by inverting its CDF
//! F(λ) = (tanh(a(λ − 538)) − t₀)/(t₁ − t₀), a = 0.0072, t₀ = tanh(a(360 − 538)),
//! t₁ = tanh(a(830 − 538)), at the four stratified points (u + i/4) mod 1. Each lane is
//! distributed by p, so [`SampledSpectrum::to_xyz`] (the mean over the lanes of value·CMF/pdf,
//! divided by ∫ȳ) is an unbiased estimate of the spectrum's XYZ, normalised so that a flat unit
//! spectrum has Y = 1.
//!
//! [`SampledWavelengths::terminate_secondary`] keeps only the first ("hero") wavelength when a
//! path meets a wavelength-dependent interface, with pbrt-v4's scheme: the other pdfs become 0
//! (their lanes then contribute 0 to `to_xyz`) and the hero's pdf is divided by 4, so the mean
//! over the lanes is still value/pdf of the hero alone.

use super::cie::{self, LAMBDA_MAX, LAMBDA_MIN};
use crate::math::{Vec3, Vec4};
use std::ops::{
    Add, AddAssign, Div, DivAssign, Index, IndexMut, Mul, MulAssign, Neg, Sub, SubAssign,
};

/// Wavelengths per path.
pub const N_SPECTRUM_SAMPLES: usize = 4;

/// a in p(λ) ∝ 1/cosh²(a(λ − λ₀)) (1/nm).
const VISIBLE_A: f32 = 0.0072;
/// λ₀ (nm).
const VISIBLE_CENTRE: f32 = 538.0;
/// t₀ = tanh(a(360 − 538)).
const VISIBLE_T0: f32 = -0.856_910_6;
/// t₁ − t₀.
const VISIBLE_SPAN: f32 = 1.827_502;
/// a/(t₁ − t₀): the density's normalisation.
const VISIBLE_NORM: f32 = 0.003_939_804;

/// A wavelength (nm) from the visible-XYZ density, by inversion of its CDF at `u` ∈ [0, 1).
#[inline]
pub fn sample_visible_wavelength(u: f32) -> f32 {
    let l = VISIBLE_CENTRE + (VISIBLE_T0 + VISIBLE_SPAN * u).atanh() / VISIBLE_A;
    l.clamp(LAMBDA_MIN, LAMBDA_MAX)
}

/// The visible-XYZ density at `lambda` (1/nm): 0 outside [360, 830] nm.
#[inline]
pub fn visible_wavelength_pdf(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    let c = (VISIBLE_A * (lambda - VISIBLE_CENTRE)).cosh();
    VISIBLE_NORM / (c * c)
}

/// The wavelengths one path carries and their densities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    lambda: Vec4,
    pdf: Vec4,
}

impl SampledWavelengths {
    /// Four wavelengths from the visible-XYZ density, stratified from one `u` ∈ [0, 1):
    /// λᵢ = F⁻¹((u + i/4) mod 1). λ₀ is the hero.
    pub fn sample_visible(u: f32) -> SampledWavelengths {
        let ui = Vec4::splat(u) + Vec4::new(0.0, 0.25, 0.5, 0.75);
        let ui = Vec4::select(ui.cmpge(Vec4::ONE), ui - Vec4::ONE, ui);
        // λ = λ₀ + atanh(t)/a with t = tanh(a(λ − λ₀)), so the density
        // a/(span·cosh²(a(λ − λ₀))) is NORM·(1 − t²): no cosh. The four atanh are one
        // 4-wide logarithm, atanh(t) = ½·ln((1 + t)/(1 − t)) (|t| ≤ 0.98 here): the scalar
        // transcendentals were a tenth of spectral mode's overhead on bench-cbox.
        let t = Vec4::splat(VISIBLE_T0) + VISIBLE_SPAN * ui;
        let ratio = ((Vec4::ONE + t) / (Vec4::ONE - t)).to_array();
        let ln = wide::f32x4::from(ratio).ln().to_array();
        let atanh = 0.5 * Vec4::from_array(ln);
        let lambda = (Vec4::splat(VISIBLE_CENTRE) + atanh / VISIBLE_A)
            .clamp(Vec4::splat(LAMBDA_MIN), Vec4::splat(LAMBDA_MAX));
        let pdf = VISIBLE_NORM * (Vec4::ONE - t * t);
        SampledWavelengths { lambda, pdf }
    }

    /// Four wavelengths uniform on [`lambda_min`, `lambda_max`], stratified like
    /// [`Self::sample_visible`].
    pub fn sample_uniform(u: f32, lambda_min: f32, lambda_max: f32) -> SampledWavelengths {
        let width = lambda_max - lambda_min;
        let mut lambda = Vec4::ZERO;
        for i in 0..N_SPECTRUM_SAMPLES {
            let mut ui = u + i as f32 / N_SPECTRUM_SAMPLES as f32;
            if ui >= 1.0 {
                ui -= 1.0;
            }
            lambda[i] = (lambda_min + ui * width).min(lambda_max);
        }
        SampledWavelengths {
            lambda,
            pdf: Vec4::splat(1.0 / width),
        }
    }

    /// Wavelength `i` (nm); 0 is the hero.
    #[inline]
    pub fn lambda(&self, i: usize) -> f32 {
        self.lambda[i]
    }

    /// All four wavelengths (nm).
    #[inline]
    pub fn lambdas(&self) -> [f32; N_SPECTRUM_SAMPLES] {
        self.lambda.to_array()
    }

    /// All four wavelengths (nm), as a vector.
    #[inline]
    pub fn lambda4(&self) -> Vec4 {
        self.lambda
    }

    /// The density each wavelength was drawn with (0 for terminated ones).
    #[inline]
    pub fn pdf(&self) -> SampledSpectrum {
        SampledSpectrum(self.pdf)
    }

    /// Keep only the hero wavelength (pbrt-v4's scheme: the others' pdfs become 0, the hero's is
    /// divided by 4). Idempotent.
    pub fn terminate_secondary(&mut self) {
        if self.secondary_terminated() {
            return;
        }
        self.pdf = Vec4::new(self.pdf.x / N_SPECTRUM_SAMPLES as f32, 0.0, 0.0, 0.0);
    }

    /// Whether only the hero wavelength is left.
    #[inline]
    pub fn secondary_terminated(&self) -> bool {
        self.pdf.y == 0.0 && self.pdf.z == 0.0 && self.pdf.w == 0.0
    }
}

/// A spectral quantity at the four wavelengths of a [`SampledWavelengths`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampledSpectrum(Vec4);

impl SampledSpectrum {
    pub const ZERO: SampledSpectrum = SampledSpectrum(Vec4::ZERO);
    pub const ONE: SampledSpectrum = SampledSpectrum(Vec4::ONE);

    #[inline]
    pub const fn new(values: [f32; N_SPECTRUM_SAMPLES]) -> SampledSpectrum {
        SampledSpectrum(Vec4::from_array(values))
    }

    #[inline]
    pub const fn splat(v: f32) -> SampledSpectrum {
        SampledSpectrum(Vec4::splat(v))
    }

    /// The spectrum whose lane `i` is `f(i)`.
    #[inline]
    pub fn from_fn(mut f: impl FnMut(usize) -> f32) -> SampledSpectrum {
        SampledSpectrum(Vec4::new(f(0), f(1), f(2), f(3)))
    }

    #[inline]
    pub fn to_array(self) -> [f32; N_SPECTRUM_SAMPLES] {
        self.0.to_array()
    }

    #[inline]
    pub fn as_vec4(self) -> Vec4 {
        self.0
    }

    #[inline]
    pub const fn from_vec4(v: Vec4) -> SampledSpectrum {
        SampledSpectrum(v)
    }

    /// Every lane is zero.
    #[inline]
    pub fn is_black(self) -> bool {
        self.0.cmpeq(Vec4::ZERO).all()
    }

    #[inline]
    pub fn max_component(self) -> f32 {
        self.0.max_element()
    }

    #[inline]
    pub fn min_component(self) -> f32 {
        self.0.min_element()
    }

    #[inline]
    pub fn average(self) -> f32 {
        self.0.element_sum() / N_SPECTRUM_SAMPLES as f32
    }

    /// Lane-wise `self / d`, 0 where `d` is 0.
    #[inline]
    pub fn safe_div(self, d: SampledSpectrum) -> SampledSpectrum {
        SampledSpectrum(Vec4::select(
            d.0.cmpne(Vec4::ZERO),
            self.0 / d.0,
            Vec4::ZERO,
        ))
    }

    #[inline]
    pub fn map(self, mut f: impl FnMut(f32) -> f32) -> SampledSpectrum {
        SampledSpectrum::from_fn(|i| f(self.0[i]))
    }

    #[inline]
    pub fn exp(self) -> SampledSpectrum {
        self.map(f32::exp)
    }

    #[inline]
    pub fn sqrt(self) -> SampledSpectrum {
        self.map(f32::sqrt)
    }

    /// Lane-wise max(·, 0).
    #[inline]
    pub fn clamp_zero(self) -> SampledSpectrum {
        SampledSpectrum(self.0.max(Vec4::ZERO))
    }

    /// Monte Carlo estimate of the XYZ of the spectrum these are samples of: the mean over the
    /// lanes of value·(x̄, ȳ, z̄)(λᵢ)/pdfᵢ (lanes of pdf 0 count as 0), divided by ∫ȳ so that a
    /// flat unit spectrum has Y = 1.
    pub fn to_xyz(self, wavelengths: &SampledWavelengths) -> Vec3 {
        let w = self.safe_div(wavelengths.pdf());
        let mut xyz = Vec3::ZERO;
        for i in 0..N_SPECTRUM_SAMPLES {
            xyz += cie::xyz_bar(wavelengths.lambda(i)) * w.0[i];
        }
        xyz * (1.0 / (N_SPECTRUM_SAMPLES as f64 * cie::CIE_Y_INTEGRAL) as f32)
    }

    /// The Y component of [`Self::to_xyz`].
    pub fn y(self, wavelengths: &SampledWavelengths) -> f32 {
        let w = self.safe_div(wavelengths.pdf());
        let mut y = 0.0;
        for i in 0..N_SPECTRUM_SAMPLES {
            y += cie::y_bar(wavelengths.lambda(i)) * w.0[i];
        }
        y * (1.0 / (N_SPECTRUM_SAMPLES as f64 * cie::CIE_Y_INTEGRAL) as f32)
    }

    /// [`Self::to_xyz`] in linear sRGB.
    pub fn to_srgb(self, wavelengths: &SampledWavelengths) -> Vec3 {
        super::colorspace::xyz_to_srgb(self.to_xyz(wavelengths))
    }
}

impl Index<usize> for SampledSpectrum {
    type Output = f32;
    #[inline]
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}

impl IndexMut<usize> for SampledSpectrum {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut f32 {
        &mut self.0[i]
    }
}

macro_rules! lanewise {
    ($Op:ident, $op:ident, $OpAssign:ident, $op_assign:ident) => {
        impl $Op for SampledSpectrum {
            type Output = SampledSpectrum;
            #[inline]
            fn $op(self, rhs: SampledSpectrum) -> SampledSpectrum {
                SampledSpectrum(self.0.$op(rhs.0))
            }
        }
        impl $Op<f32> for SampledSpectrum {
            type Output = SampledSpectrum;
            #[inline]
            fn $op(self, rhs: f32) -> SampledSpectrum {
                SampledSpectrum(self.0.$op(rhs))
            }
        }
        impl $OpAssign for SampledSpectrum {
            #[inline]
            fn $op_assign(&mut self, rhs: SampledSpectrum) {
                self.0.$op_assign(rhs.0);
            }
        }
        impl $OpAssign<f32> for SampledSpectrum {
            #[inline]
            fn $op_assign(&mut self, rhs: f32) {
                self.0.$op_assign(rhs);
            }
        }
    };
}

lanewise!(Add, add, AddAssign, add_assign);
lanewise!(Sub, sub, SubAssign, sub_assign);
lanewise!(Mul, mul, MulAssign, mul_assign);
lanewise!(Div, div, DivAssign, div_assign);

impl Mul<SampledSpectrum> for f32 {
    type Output = SampledSpectrum;
    #[inline]
    fn mul(self, rhs: SampledSpectrum) -> SampledSpectrum {
        SampledSpectrum(self * rhs.0)
    }
}

impl Neg for SampledSpectrum {
    type Output = SampledSpectrum;
    #[inline]
    fn neg(self) -> SampledSpectrum {
        SampledSpectrum(-self.0)
    }
}

/// A spectrum that can be evaluated at any wavelength.
pub trait Spectrum {
    /// The value at `lambda` (nm).
    fn eval(&self, lambda: f32) -> f32;

    /// The values at the path's wavelengths.
    #[inline]
    fn sample(&self, wavelengths: &SampledWavelengths) -> SampledSpectrum {
        SampledSpectrum::from_fn(|i| self.eval(wavelengths.lambda(i)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visible_density_constants() {
        let a = VISIBLE_A as f64;
        let t0 = (a * (360.0 - 538.0)).tanh();
        let t1 = (a * (830.0 - 538.0)).tanh();
        assert!((VISIBLE_T0 as f64 - t0).abs() < 1e-7);
        assert!((VISIBLE_SPAN as f64 - (t1 - t0)).abs() < 1e-6);
        assert!((VISIBLE_NORM as f64 - a / (t1 - t0)).abs() < 1e-10);
        // The density integrates to 1 (midpoint rule, 0.01 nm).
        let n = 47_000;
        let h = 470.0 / n as f64;
        let s: f64 = (0..n)
            .map(|k| visible_wavelength_pdf((360.0 + (k as f64 + 0.5) * h) as f32) as f64 * h)
            .sum();
        assert!((s - 1.0).abs() < 1e-5, "∫p = {s}");
    }

    #[test]
    fn sampling_inverts_the_cdf() {
        assert!((sample_visible_wavelength(0.0) - 360.0).abs() < 1e-3);
        assert!((sample_visible_wavelength(0.999_999_9) - 830.0).abs() < 0.1);
        let a = VISIBLE_A as f64;
        let t0 = (a * (360.0 - 538.0)).tanh();
        let t1 = (a * (830.0 - 538.0)).tanh();
        for k in 0..100 {
            let u = k as f32 / 100.0;
            let l = sample_visible_wavelength(u) as f64;
            let cdf = ((a * (l - 538.0)).tanh() - t0) / (t1 - t0);
            assert!((cdf - u as f64).abs() < 2e-6, "u = {u}: F(λ) = {cdf}");
        }
        // Monotone.
        let mut prev = 0.0;
        for k in 0..=1000 {
            let l = sample_visible_wavelength(k as f32 / 1001.0);
            assert!(l >= prev);
            prev = l;
        }
    }

    /// The 4-wide sampling (one vector logarithm) is the scalar CDF inversion to within
    /// 2e-3 nm everywhere, its densities the analytic ones to 2e-6 relative.
    #[test]
    fn vector_sampling_matches_the_scalar_inverse() {
        for k in 0..20_000 {
            let u = k as f32 / 20_000.0;
            let wl = SampledWavelengths::sample_visible(u);
            for i in 0..N_SPECTRUM_SAMPLES {
                let ui = (u + i as f32 / 4.0) % 1.0;
                let e = sample_visible_wavelength(ui);
                assert!(
                    (wl.lambda(i) - e).abs() < 2e-3,
                    "u {ui}: {} vs {e}",
                    wl.lambda(i)
                );
                let p = visible_wavelength_pdf(wl.lambda(i));
                assert!(
                    (wl.pdf()[i] - p).abs() <= 2e-6 * p,
                    "u {ui}: {} vs {p}",
                    wl.pdf()[i]
                );
            }
        }
    }

    #[test]
    fn wavelengths_are_stratified_and_terminate_like_pbrt() {
        let mut wl = SampledWavelengths::sample_visible(0.9);
        let expect = [0.9f32, 0.15, 0.4, 0.65].map(sample_visible_wavelength);
        for (i, e) in expect.into_iter().enumerate() {
            assert!((wl.lambda(i) - e).abs() < 1e-3);
            let p = visible_wavelength_pdf(wl.lambda(i));
            assert!(
                (wl.pdf()[i] - p).abs() <= 2e-6 * p,
                "{} vs {p}",
                wl.pdf()[i]
            );
        }
        assert!(!wl.secondary_terminated());
        let hero_pdf = wl.pdf()[0];
        wl.terminate_secondary();
        assert!(wl.secondary_terminated());
        assert_eq!(wl.pdf().to_array(), [hero_pdf / 4.0, 0.0, 0.0, 0.0]);
        wl.terminate_secondary();
        assert_eq!(wl.pdf()[0], hero_pdf / 4.0);
        // A terminated path's estimate is the hero's value/pdf alone.
        let s = SampledSpectrum::new([2.0, 7.0, 7.0, 7.0]);
        let y = s.y(&wl) as f64;
        let hero = 2.0 * cie::y_bar(wl.lambda(0)) as f64 / hero_pdf as f64 / cie::CIE_Y_INTEGRAL;
        assert!((y - hero).abs() < 1e-5 * hero);
        let u = SampledWavelengths::sample_uniform(0.5, 400.0, 700.0);
        assert_eq!(u.lambdas(), [550.0, 625.0, 400.0, 475.0]);
        assert_eq!(u.pdf(), SampledSpectrum::splat(1.0 / 300.0));
    }

    #[test]
    fn arithmetic_is_lanewise() {
        let a = SampledSpectrum::new([1.0, 2.0, 3.0, 4.0]);
        let b = SampledSpectrum::new([2.0, 0.0, 1.0, 8.0]);
        assert_eq!((a + b).to_array(), [3.0, 2.0, 4.0, 12.0]);
        assert_eq!((a - b).to_array(), [-1.0, 2.0, 2.0, -4.0]);
        assert_eq!((a * b).to_array(), [2.0, 0.0, 3.0, 32.0]);
        assert_eq!(a.safe_div(b).to_array(), [0.5, 0.0, 3.0, 0.5]);
        assert_eq!((a * 2.0).to_array(), (2.0 * a).to_array());
        assert_eq!((a / 2.0).to_array(), [0.5, 1.0, 1.5, 2.0]);
        let mut c = a;
        c += b;
        c -= b;
        c *= 3.0;
        c /= 3.0;
        assert_eq!(c, a);
        assert_eq!((-a).clamp_zero(), SampledSpectrum::ZERO);
        assert!(SampledSpectrum::ZERO.is_black() && !a.is_black());
        assert_eq!(a.max_component(), 4.0);
        assert_eq!(a.min_component(), 1.0);
        assert_eq!(a.average(), 2.5);
        assert_eq!(a[2], 3.0);
        assert_eq!(
            SampledSpectrum::splat(4.0).sqrt(),
            SampledSpectrum::splat(2.0)
        );
        assert_eq!(SampledSpectrum::ZERO.exp(), SampledSpectrum::ONE);
    }

    #[test]
    fn flat_spectrum_has_unit_luminance_on_average() {
        // Stratified u over many paths: the estimate of Y for a flat unit spectrum → 1.
        let n = 20_000;
        let mut y = 0.0f64;
        for k in 0..n {
            let wl = SampledWavelengths::sample_visible((k as f32 + 0.5) / n as f32);
            y += SampledSpectrum::ONE.to_xyz(&wl).y as f64;
        }
        let y = y / n as f64;
        assert!((y - 1.0).abs() < 1e-3, "Y = {y}");
    }
}
