//! CIE colorimetry on the 1 nm tables of `base::cie_data`: the CIE 1931 2° colour-matching
//! functions x̄, ȳ, z̄ and the standard illuminant D65, 360–830 nm.
//!
//! Lookups between the 1 nm samples interpolate linearly and are zero outside [360, 830] nm.
//! "The integral over the table" is the plain sum of the 1 nm samples (Σ f(λ)·1 nm, as pbrt-v4
//! integrates): ∫ȳ = [`CIE_Y_INTEGRAL`] ≈ 106.857. Quantities meant to be colorimetric (the
//! upsampling tables, the round-trip tests) use that same rule.

use crate::math::{Vec3, Vec4};
use base::cie_data;

pub use cie_data::{CIE_D65, CIE_X, CIE_Y, CIE_Z};

/// Shortest wavelength of the tables and of wavelength sampling (nm).
pub const LAMBDA_MIN: f32 = 360.0;
/// Longest wavelength of the tables and of wavelength sampling (nm).
pub const LAMBDA_MAX: f32 = 830.0;
/// Number of 1 nm samples: 360, 361, ..., 830 nm.
pub const CIE_SAMPLES: usize = cie_data::N;

/// Σ ȳ(λ)·1 nm over the table (the CIE's 1 nm ȳ sums to 106.856 917 1…; pbrt-v4's
/// `CIE_Y_integral`, summed in single precision, is 106.856 895).
pub const CIE_Y_INTEGRAL: f64 = 106.856_917_101_172;

/// Σ D65(λ)·ȳ(λ)·1 nm over the table: the luminance of the tabulated D65 (relative units,
/// D65(560 nm) = 100).
pub const D65_Y_INTEGRAL: f64 = 10_567.081_666_988_128;

/// The wavelength (nm) of table sample `i`.
#[inline]
pub fn table_lambda(i: usize) -> f64 {
    LAMBDA_MIN as f64 + i as f64
}

/// Index and weight of the sample before `lambda` for linear interpolation, or `None` outside
/// the table.
#[inline]
fn locate(lambda: f32) -> Option<(usize, f32)> {
    // Also rejects NaN.
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return None;
    }
    let x = lambda - LAMBDA_MIN;
    let i = (x as usize).min(CIE_SAMPLES - 2);
    Some((i, x - i as f32))
}

#[inline]
fn lerp_table(table: &[f64; CIE_SAMPLES], i: usize, t: f32) -> f32 {
    let (a, b) = (table[i] as f32, table[i + 1] as f32);
    a + (b - a) * t
}

/// A tabulated function at `lambda` (nm), linearly interpolated, 0 outside [360, 830] nm.
#[inline]
pub fn lookup(table: &[f64; CIE_SAMPLES], lambda: f32) -> f32 {
    match locate(lambda) {
        Some((i, t)) => lerp_table(table, i, t),
        None => 0.0,
    }
}

/// x̄(λ).
#[inline]
pub fn x_bar(lambda: f32) -> f32 {
    lookup(&CIE_X, lambda)
}

/// ȳ(λ).
#[inline]
pub fn y_bar(lambda: f32) -> f32 {
    lookup(&CIE_Y, lambda)
}

/// z̄(λ).
#[inline]
pub fn z_bar(lambda: f32) -> f32 {
    lookup(&CIE_Z, lambda)
}

/// (x̄, ȳ, z̄)(λ) with one interval search.
#[inline]
pub fn xyz_bar(lambda: f32) -> Vec3 {
    match locate(lambda) {
        Some((i, t)) => Vec3::new(
            lerp_table(&CIE_X, i, t),
            lerp_table(&CIE_Y, i, t),
            lerp_table(&CIE_Z, i, t),
        ),
        None => Vec3::ZERO,
    }
}

/// The tabulated D65 (relative, 100 at 560 nm).
#[inline]
pub fn d65(lambda: f32) -> f32 {
    lookup(&CIE_D65, lambda)
}

/// Scale from the tabulated D65 to D65 of unit luminance in the sense of
/// `SampledSpectrum::to_xyz`: Σ D65·ȳ / Σ ȳ = 1.
pub const D65_TO_UNIT_Y: f64 = CIE_Y_INTEGRAL / D65_Y_INTEGRAL;

/// D65 scaled to unit luminance (Y = 1 by the table's own rule): the emission spectrum of the
/// sRGB white.
#[inline]
pub fn d65_unit_y(lambda: f32) -> f32 {
    d65(lambda) * D65_TO_UNIT_Y as f32
}

/// Σ f(λ)·(x̄, ȳ, z̄)(λ)·1 nm over the table's wavelengths, in double precision: the
/// deterministic quadrature the colorimetric tests and tools use.
pub fn integrate_xyz(f: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for i in 0..CIE_SAMPLES {
        let v = f(table_lambda(i));
        xyz[0] += v * CIE_X[i];
        xyz[1] += v * CIE_Y[i];
        xyz[2] += v * CIE_Z[i];
    }
    xyz
}

/// Per 1 nm sample, interleaved in f32: the CIE observer in linear sRGB divided by ∫ȳ
/// (r̄, ḡ, b̄ = `XYZ_TO_SRGB` · (x̄, ȳ, z̄) / ∫ȳ) and D65 of unit luminance. What a spectral path
/// needs at each of its wavelengths, once: its light's white and the weights that turn its
/// estimate into the film's colour (interpolation commutes with the linear map, so
/// Σ wᵢ·(r̄, ḡ, b̄)(λᵢ) is `xyz_to_srgb` of the XYZ estimate, to rounding). Four 16-byte loads
/// per path instead of twelve lookups in three f64 tables, built at compile time.
pub static SRGB_BAR_D65: [[f32; 4]; CIE_SAMPLES] = srgb_bar_d65();

const fn srgb_bar_d65() -> [[f32; 4]; CIE_SAMPLES] {
    let m = cie_data::XYZ_TO_SRGB;
    let mut t = [[0.0f32; 4]; CIE_SAMPLES];
    let mut i = 0;
    while i < CIE_SAMPLES {
        let xyz = [CIE_X[i], CIE_Y[i], CIE_Z[i]];
        let mut r = 0;
        while r < 3 {
            let v = m[r][0] * xyz[0] + m[r][1] * xyz[1] + m[r][2] * xyz[2];
            t[i][r] = (v / CIE_Y_INTEGRAL) as f32;
            r += 1;
        }
        t[i][3] = (CIE_D65[i] * D65_TO_UNIT_Y) as f32;
        i += 1;
    }
    t
}

/// [`SRGB_BAR_D65`] at `lambda` (nm), linearly interpolated, 0 outside [360, 830] nm.
#[inline]
pub fn srgb_bar_d65_at(lambda: f32) -> Vec4 {
    match locate(lambda) {
        Some((i, t)) => {
            let a = Vec4::from_array(SRGB_BAR_D65[i]);
            let b = Vec4::from_array(SRGB_BAR_D65[i + 1]);
            a + (b - a) * t
        }
        None => Vec4::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(table: &[f64; CIE_SAMPLES], nm: usize) -> f64 {
        table[nm - 360]
    }

    #[test]
    fn published_values() {
        // CIE 015:2004 Table T.4 / the CIE's 1 nm table.
        assert!((at(&CIE_Y, 555) - 1.0).abs() < 1e-4);
        assert_eq!(at(&CIE_X, 600), 1.0622);
        assert_eq!(at(&CIE_Y, 600), 0.631);
        assert_eq!(at(&CIE_Z, 450), 1.77211);
        assert_eq!(at(&CIE_X, 360), 0.0001299);
        assert_eq!(at(&CIE_Z, 830), 0.0);
        // CIE 015:2004 Table T.1: D65.
        assert_eq!(at(&CIE_D65, 560), 100.0);
        assert_eq!(at(&CIE_D65, 360), 46.6383);
        assert_eq!(at(&CIE_D65, 460), 117.812);
        assert_eq!(at(&CIE_D65, 780), 63.3828);
    }

    #[test]
    fn integrals_are_the_table_sums() {
        let sy: f64 = CIE_Y.iter().sum();
        assert!((sy - CIE_Y_INTEGRAL).abs() < 1e-9, "Σȳ = {sy}");
        assert!((sy - 106.857).abs() < 1e-3);
        let [_, y, _] = integrate_xyz(|_| 1.0);
        assert!((y - CIE_Y_INTEGRAL).abs() < 1e-9);
        let [_, yd, _] = integrate_xyz(|l| lookup(&CIE_D65, l as f32) as f64);
        // f32 lookups of integer wavelengths are the f32 table values.
        assert!(
            (yd - D65_Y_INTEGRAL).abs() / D65_Y_INTEGRAL < 1e-6,
            "ΣD65·ȳ = {yd}"
        );
        let exact: f64 = (0..CIE_SAMPLES).map(|i| CIE_D65[i] * CIE_Y[i]).sum();
        assert!((exact - D65_Y_INTEGRAL).abs() < 1e-6, "ΣD65·ȳ = {exact}");
    }

    #[test]
    fn lookups_interpolate_and_vanish_outside() {
        assert_eq!(y_bar(555.0), 1.0);
        let mid = y_bar(555.5);
        let expect = 0.5 * (at(&CIE_Y, 555) + at(&CIE_Y, 556)) as f32;
        assert!((mid - expect).abs() < 1e-6);
        assert_eq!(y_bar(359.9), 0.0);
        assert_eq!(y_bar(830.1), 0.0);
        assert_eq!(x_bar(f32::NAN), 0.0);
        assert_eq!(z_bar(830.0), 0.0);
        assert!((x_bar(830.0) as f64 - at(&CIE_X, 830)).abs() < 1e-9);
        let v = xyz_bar(612.3);
        assert_eq!(v, Vec3::new(x_bar(612.3), y_bar(612.3), z_bar(612.3)));
        assert!((d65_unit_y(560.0) as f64 - 100.0 * D65_TO_UNIT_Y).abs() < 1e-4);
    }

    /// The interleaved table is the sRGB observer and unit-luminance D65 of the separate
    /// lookups (f32 rounding apart), and vanishes outside the tables like them.
    #[test]
    fn interleaved_table_matches_the_lookups() {
        let m = super::super::colorspace::XYZ_TO_SRGB_F32;
        for k in 0..=4700 {
            let l = 360.0 + k as f32 * 0.1;
            let v = srgb_bar_d65_at(l);
            let rgb = m.mul_vec3a(xyz_bar(l)) / CIE_Y_INTEGRAL as f32;
            let d = d65_unit_y(l);
            for (got, want) in [(v.x, rgb.x), (v.y, rgb.y), (v.z, rgb.z), (v.w, d)] {
                assert!(
                    (got - want).abs() <= 1e-6 * (1.0 + want.abs()),
                    "{l}: {v} vs {rgb}, {d}"
                );
            }
        }
        assert_eq!(srgb_bar_d65_at(359.9), Vec4::ZERO);
        assert_eq!(srgb_bar_d65_at(f32::NAN), Vec4::ZERO);
    }
}
