//! Spectral data → linear Rec.709 ("sRGB") RGB, the way Mitsuba 3 does it in its RGB variants.
//!
//! Our reference images come from Mitsuba 3 `llvm_ad_rgb`. In RGB variants Mitsuba never
//! renders spectra: a `<spectrum>` given as `wavelength:value` pairs is integrated against the
//! CIE 1931 2° colour-matching functions once, at load time, and replaced by an RGB colour.
//! To match those renders we reproduce that conversion, not the "ideal" colorimetric one:
//!
//! - **Colour-matching functions**: the CIE 1931 2° observer tabulated every 5 nm over
//!   360–830 nm (95 samples; CIE 015:2004, the same table Mitsuba ships), linearly interpolated
//!   and zero outside the range. We use the table rather than an analytic fit (e.g. Wyman et
//!   al. 2013, whose multi-lobe Gaussian fit is off by up to ~1 % of the peak) because the table
//!   *is* what Mitsuba integrates against: with it the conversion is exact up to float rounding
//!   (f64 here, f32 in Mitsuba: differences are below 1e-5 relative).
//! - **Quadrature**: Mitsuba's own rule: 1000 equally spaced wavelengths from 360 to 830 nm
//!   inclusive, each weighted by (830 − 360) / 1000 nm; samples outside the spectrum's first and
//!   last wavelength contribute nothing; the spectrum is linearly interpolated in between.
//! - **Normalisation**: values are scaled by 1 / 106.7502593994140625 (Mitsuba's
//!   `MI_CIE_Y_NORMALIZATION`, the integral of ȳ with this rule), so a flat unit spectrum has
//!   luminance Y = 1.
//! - **Reflectances** (and other non-emitted quantities) are integrated against the product of
//!   the CMFs and the CIE D65 illuminant (normalised to unit luminance), so a flat unit
//!   reflectance maps to RGB ≈ (1, 1, 1) — sRGB's white point is D65. **Emission** spectra and
//!   tabulated complex IORs are integrated without D65 (a flat unit emitter is the slightly
//!   purple `xyz_to_srgb(1, 1, 1)`, as in Mitsuba).
//! - **XYZ → linear sRGB**: Mitsuba's matrix (the classic Rec.709/D65 matrix to 6 digits).
//! - **Clamping**: bounded quantities (reflectances) are clamped to [0, 1]; unbounded ones
//!   (emission, `eta`, `k`, `int_ior`, `ext_ior`) to ≥ 0.

use glam::Vec3;

/// First wavelength of the CIE tables (nm).
pub const CIE_MIN: f64 = 360.0;
/// Last wavelength of the CIE tables (nm).
pub const CIE_MAX: f64 = 830.0;
/// Number of samples of the CIE tables (5 nm spacing).
pub const CIE_SAMPLES: usize = 95;
/// Scale making a flat unit spectrum integrate to luminance 1 (Mitsuba `MI_CIE_Y_NORMALIZATION`).
pub const CIE_Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
/// Scale making the tabulated D65 illuminant integrate to luminance 1 (Mitsuba
/// `MI_CIE_D65_NORMALIZATION`).
pub const D65_NORMALIZATION: f64 = 1.0 / 98.997_417_518_762_55;

/// How a spectrum is used; decides D65 weighting and clamping (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpectrumUse {
    /// A reflectance or transmittance: D65-weighted, clamped to [0, 1].
    Reflectance,
    /// An unbounded non-emitted quantity given in a scene (`eta`, `k`, `int_ior`, `ext_ior`):
    /// D65-weighted, clamped to ≥ 0.
    Unbounded,
    /// Emitted radiance / intensity / irradiance: no D65 weighting, clamped to ≥ 0.
    Emission,
    /// Tabulated complex IOR data (Mitsuba's `ior_from_file`): no D65 weighting, ≥ 0.
    IorData,
}

impl SpectrumUse {
    fn d65(self) -> bool {
        matches!(self, SpectrumUse::Reflectance | SpectrumUse::Unbounded)
    }
    fn bounded(self) -> bool {
        matches!(self, SpectrumUse::Reflectance)
    }
}

/// The 5 nm nodes (360, 365, ..., 830 nm) of a 1 nm table of `base::cie_data`, in f32 as
/// Mitsuba stores them: CIE 015:2004's 5 nm tables are exactly every fifth value of the CIE's
/// 1 nm tables, so these are Mitsuba's tables.
const fn every_fifth(t: &[f64; base::cie_data::N]) -> [f32; CIE_SAMPLES] {
    let mut out = [0.0f32; CIE_SAMPLES];
    let mut i = 0;
    while i < CIE_SAMPLES {
        out[i] = t[5 * i] as f32;
        i += 1;
    }
    out
}

/// CIE 1931 2° colour-matching functions x̄, ȳ, z̄ at 360, 365, ..., 830 nm (CIE 015:2004).
static CIE_X: [f32; CIE_SAMPLES] = every_fifth(&base::cie_data::CIE_X);
static CIE_Y: [f32; CIE_SAMPLES] = every_fifth(&base::cie_data::CIE_Y);
static CIE_Z: [f32; CIE_SAMPLES] = every_fifth(&base::cie_data::CIE_Z);

/// CIE standard illuminant D65, relative spectral power (100 at 560 nm), 360–830 nm every 5 nm.
static D65: [f32; CIE_SAMPLES] = every_fifth(&base::cie_data::CIE_D65);

/// Linear interpolation into a 5 nm CIE table; zero outside [360, 830] nm.
fn lookup(table: &[f32; CIE_SAMPLES], lambda: f64) -> f64 {
    if !(CIE_MIN..=CIE_MAX).contains(&lambda) {
        return 0.0;
    }
    let t = (lambda - CIE_MIN) * ((CIE_SAMPLES - 1) as f64 / (CIE_MAX - CIE_MIN));
    let i0 = (t as usize).min(CIE_SAMPLES - 2);
    let w1 = t - i0 as f64;
    (1.0 - w1) * f64::from(table[i0]) + w1 * f64::from(table[i0 + 1])
}

/// CIE 1931 2° colour-matching functions (x̄, ȳ, z̄) at `lambda` nm (unnormalised, ȳ(555) = 1).
pub fn cie1931_xyz(lambda: f64) -> [f64; 3] {
    [
        lookup(&CIE_X, lambda),
        lookup(&CIE_Y, lambda),
        lookup(&CIE_Z, lambda),
    ]
}

/// CIE D65 illuminant at `lambda` nm, normalised to unit luminance.
pub fn cie_d65(lambda: f64) -> f64 {
    lookup(&D65, lambda) * D65_NORMALIZATION
}

/// The nodes of the CIE D65 table (360, 365, ..., 830 nm) and its values normalised to unit
/// luminance: Mitsuba 3's `d65` spectrum, linear in between.
pub fn d65_nodes() -> (Vec<f64>, Vec<f64>) {
    let w: Vec<f64> = (0..CIE_SAMPLES).map(|i| CIE_MIN + 5.0 * i as f64).collect();
    let v = D65
        .iter()
        .map(|&d| f64::from(d) * D65_NORMALIZATION)
        .collect();
    (w, v)
}

/// A piecewise-linear spectrum through (`wavelengths`, `values`) at `lambda`: zero outside
/// the first and last wavelength (Mitsuba's `irregular` spectrum). `wavelengths` increase.
pub fn interpolate(wavelengths: &[f64], values: &[f64], lambda: f64) -> f64 {
    let n = wavelengths.len();
    if n < 2 || !(wavelengths[0]..=wavelengths[n - 1]).contains(&lambda) {
        return 0.0;
    }
    let i = wavelengths
        .partition_point(|&x| x <= lambda)
        .saturating_sub(1)
        .min(n - 2);
    let t = (lambda - wavelengths[i]) / (wavelengths[i + 1] - wavelengths[i]);
    values[i] + (values[i + 1] - values[i]) * t
}

/// Planck's law: the spectral radiance of a black body at `kelvin`, in W/(m²·sr·nm) at
/// `lambda` nm (Mitsuba's `blackbody` units).
pub fn planck(lambda: f64, kelvin: f64) -> f64 {
    const H: f64 = 6.626_070_15e-34;
    const C: f64 = 2.997_924_58e8;
    const K: f64 = 1.380_649e-23;
    let l = lambda * 1e-9;
    let c0 = 2.0 * H * C * C;
    let c1 = H * C / K;
    // Per metre of wavelength → per nanometre.
    1e-9 * c0 / (l.powi(5) * ((c1 / (l * kelvin)).exp_m1()))
}

/// CIE XYZ → linear Rec.709 RGB (D65 white), Mitsuba's matrix.
pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = xyz;
    [
        3.240_479 * x - 1.537_150 * y - 0.498_535 * z,
        -0.969_256 * x + 1.875_991 * y + 0.041_556 * z,
        0.055_648 * x - 0.204_043 * y + 1.057_311 * z,
    ]
}

fn finish(rgb: [f64; 3], usage: SpectrumUse) -> Vec3 {
    let clamp = |v: f64| {
        if usage.bounded() {
            v.clamp(0.0, 1.0)
        } else {
            v.max(0.0)
        }
    };
    Vec3::new(
        clamp(rgb[0]) as f32,
        clamp(rgb[1]) as f32,
        clamp(rgb[2]) as f32,
    )
}

/// RGB of a uniform (wavelength-independent) spectrum of value `v`.
///
/// Mitsuba keeps uniform non-emitted spectra grey, but turns a uniform *emission* spectrum into
/// `v · xyz_to_srgb(1, 1, 1)` so that RGB renders match spectral ones.
pub fn uniform_to_rgb(v: f64, usage: SpectrumUse) -> Vec3 {
    match usage {
        SpectrumUse::Emission => {
            let c = xyz_to_linear_srgb([v, v, v]);
            Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)
        }
        _ => Vec3::splat(v as f32),
    }
}

/// Why a sampled spectrum was rejected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SpectrumError {
    TooFewSamples,
    LengthMismatch,
    NotIncreasing,
    NonFinite,
}

impl std::fmt::Display for SpectrumError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SpectrumError::TooFewSamples => "a sampled spectrum needs at least two samples",
            SpectrumError::LengthMismatch => "wavelength and value lists differ in length",
            SpectrumError::NotIncreasing => "wavelengths must be strictly increasing",
            SpectrumError::NonFinite => "spectrum contains a non-finite number",
        })
    }
}

/// Convert a piecewise-linear sampled spectrum (`wavelengths` in nm, strictly increasing) to
/// linear Rec.709 RGB exactly as Mitsuba 3's `spectrum_list_to_srgb` does in RGB variants
/// (see the module docs for the method).
pub fn sampled_to_rgb(
    wavelengths: &[f64],
    values: &[f64],
    usage: SpectrumUse,
) -> Result<Vec3, SpectrumError> {
    if wavelengths.len() != values.len() {
        return Err(SpectrumError::LengthMismatch);
    }
    if wavelengths.len() < 2 {
        return Err(SpectrumError::TooFewSamples);
    }
    if wavelengths.iter().chain(values).any(|v| !v.is_finite()) {
        return Err(SpectrumError::NonFinite);
    }
    if wavelengths.windows(2).any(|w| w[1] <= w[0]) {
        return Err(SpectrumError::NotIncreasing);
    }
    const STEPS: usize = 1000;
    let (first, last) = (wavelengths[0], wavelengths[wavelengths.len() - 1]);
    let mut xyz = [0.0f64; 3];
    for i in 0..STEPS {
        let w = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        if w < first || w > last {
            continue;
        }
        // Largest interval start with wavelengths[idx] <= w, clamped to a valid interval.
        let idx = wavelengths
            .partition_point(|&x| x <= w)
            .saturating_sub(1)
            .min(wavelengths.len() - 2);
        let (w0, w1) = (wavelengths[idx], wavelengths[idx + 1]);
        let (v0, v1) = (values[idx], values[idx + 1]);
        let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        let weight = if usage.d65() { cie_d65(w) } else { 1.0 };
        let cmf = cie1931_xyz(w);
        for c in 0..3 {
            xyz[c] += cmf[c] * v * weight;
        }
    }
    let scale = (CIE_MAX - CIE_MIN) / STEPS as f64 * CIE_Y_NORMALIZATION;
    let xyz = xyz.map(|c| c * scale);
    Ok(finish(xyz_to_linear_srgb(xyz), usage))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Planck's law integrates to σT⁴/π (Stefan–Boltzmann) and peaks at Wien's wavelength.
    #[test]
    fn planck_obeys_stefan_boltzmann_and_wien() {
        let t = 3000.0;
        let sigma = 5.670_374_419e-8;
        let mut total = 0.0;
        let mut lambda = 10.0;
        while lambda < 200_000.0 {
            total += planck(lambda + 0.05, t) * 0.1;
            lambda += 0.1;
        }
        let expected = sigma * t.powi(4) / std::f64::consts::PI;
        assert!(
            (total / expected - 1.0).abs() < 1e-3,
            "{total} vs {expected}"
        );
        let peak = 2.897_771_955e6 / t;
        assert!(planck(peak, t) > planck(peak - 5.0, t) && planck(peak, t) > planck(peak + 5.0, t));
    }

    fn flat(v: f64) -> (Vec<f64>, Vec<f64>) {
        (vec![CIE_MIN, CIE_MAX], vec![v, v])
    }

    #[test]
    fn flat_reflectance_is_white() {
        let (w, v) = flat(1.0);
        let rgb = sampled_to_rgb(&w, &v, SpectrumUse::Unbounded).unwrap();
        assert!((rgb - Vec3::ONE).abs().max_element() < 2e-3, "{rgb}");
    }

    #[test]
    fn flat_emission_has_unit_luminance_and_matches_uniform() {
        let (w, v) = flat(2.0);
        let rgb = sampled_to_rgb(&w, &v, SpectrumUse::Emission).unwrap();
        let u = uniform_to_rgb(2.0, SpectrumUse::Emission);
        assert!((rgb - u).abs().max_element() < 2e-3, "{rgb} vs {u}");
        let y = 0.212_671 * rgb.x + 0.715_160 * rgb.y + 0.072_169 * rgb.z;
        assert!((y - 2.0).abs() < 3e-3, "{y}");
    }

    #[test]
    fn reflectance_is_clamped_but_emission_is_not() {
        let (w, v) = flat(3.0);
        let r = sampled_to_rgb(&w, &v, SpectrumUse::Reflectance).unwrap();
        assert_eq!(r, Vec3::ONE);
        let e = sampled_to_rgb(&w, &v, SpectrumUse::Unbounded).unwrap();
        assert!(e.min_element() > 2.9);
    }

    #[test]
    fn narrow_band_outside_visible_is_black() {
        let rgb = sampled_to_rgb(&[900.0, 1000.0], &[5.0, 5.0], SpectrumUse::Emission).unwrap();
        assert_eq!(rgb, Vec3::ZERO);
    }

    #[test]
    fn rejects_bad_input() {
        use SpectrumError::*;
        let u = SpectrumUse::Reflectance;
        assert_eq!(sampled_to_rgb(&[500.0], &[1.0], u), Err(TooFewSamples));
        assert_eq!(
            sampled_to_rgb(&[500.0, 400.0], &[1.0, 1.0], u),
            Err(NotIncreasing)
        );
        assert_eq!(
            sampled_to_rgb(&[400.0, 500.0], &[1.0], u),
            Err(LengthMismatch)
        );
        assert_eq!(
            sampled_to_rgb(&[400.0, 500.0], &[f64::NAN, 1.0], u),
            Err(NonFinite)
        );
    }
}
