//! Spectra as a scene declared them, at run time: what spectral mode samples instead of
//! upsampling an RGB value, when the scene gave a spectrum (Mitsuba's `<spectrum>` lists and
//! files, `uniform`, `blackbody`, `d65`, the measured η and k of named conductors).
//!
//! `build` makes them from the scene model in spectral mode only; RGB mode renders the RGB
//! value the loader converted each one to and never sees them. The type is `base`'s (the
//! renderer's parameters hold it, `crate::textures`); its evaluation is here. Units are Mitsuba 3's
//! spectral variants' (`llvm_ad_spectral`), checked against its values in this module's tests:
//! - tabulated spectra are linear between their nodes and 0 outside the first and last
//!   wavelength (Mitsuba's `irregular`/`regular`); D65 is the CIE 5 nm table times 1/98.997…
//!   (unit luminance), tabulated by `build`;
//! - [`DeclaredSpectrum::Blackbody`] is Planck's law in W·m⁻²·sr⁻¹·nm⁻¹, *not* normalised
//!   (Mitsuba's `blackbody`; pbrt-v4 normalises its peak to 1 instead,
//!   [`super::BlackbodySpectrum`]), times the scene's scale;
//! - a uniform spectrum is its value at every wavelength (an emitter's too: no D65 factor).
//!
//! Values are as declared: a reflectance above 1 is not clamped (Mitsuba's spectral variants
//! do not clamp either; its RGB variants clamp the converted RGB, which RGB mode renders).

use super::blackbody::{planck, planck4};
use super::sampled::{SampledSpectrum, SampledWavelengths, Spectrum};
pub use base::spectrum::DeclaredSpectrum;

/// A tabulated spectrum at `lambda`: linear between the nodes, 0 outside.
#[inline(always)]
fn tabulated(
    wavelengths: &[f32],
    values: &[f32],
    cells: &[u32],
    cells_per_nm: f32,
    lambda: f32,
) -> f32 {
    let n = wavelengths.len();
    if !(wavelengths[0]..=wavelengths[n - 1]).contains(&lambda) {
        return 0.0;
    }
    let i = DeclaredSpectrum::interval(wavelengths, cells, cells_per_nm, lambda);
    let t = (lambda - wavelengths[i]) / (wavelengths[i + 1] - wavelengths[i]);
    values[i] + (values[i + 1] - values[i]) * t
}

impl Spectrum for DeclaredSpectrum {
    fn eval(&self, lambda: f32) -> f32 {
        match self {
            DeclaredSpectrum::Tabulated {
                wavelengths,
                values,
                cells,
                cells_per_nm,
            } => tabulated(wavelengths, values, cells, *cells_per_nm, lambda),
            DeclaredSpectrum::Constant(v) => *v,
            DeclaredSpectrum::Blackbody { temperature, scale } => {
                (planck(lambda as f64, *temperature) * 1e-9 * scale) as f32
            }
        }
    }

    /// One dispatch for the four wavelengths.
    #[inline]
    fn sample(&self, wavelengths: &SampledWavelengths) -> SampledSpectrum {
        match self {
            DeclaredSpectrum::Constant(v) => SampledSpectrum::splat(*v),
            DeclaredSpectrum::Blackbody { temperature, scale } => {
                let l = wavelengths.lambdas().map(f64::from);
                let p = planck4(l, *temperature);
                SampledSpectrum::from_fn(|i| (p[i] * 1e-9 * scale) as f32)
            }
            DeclaredSpectrum::Tabulated {
                wavelengths: w,
                values,
                cells,
                cells_per_nm,
            } => SampledSpectrum::from_fn(|i| {
                tabulated(w, values, cells, *cells_per_nm, wavelengths.lambda(i))
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tabulated_is_linear_inside_and_zero_outside() {
        let s = DeclaredSpectrum::tabulated(&[400.0, 500.0, 540.0], &[0.1, 0.1, 0.9]).unwrap();
        assert_eq!(s.eval(399.9), 0.0);
        assert_eq!(s.eval(400.0), 0.1);
        assert!((s.eval(520.0) - 0.5).abs() < 1e-6);
        assert_eq!(s.eval(540.0), 0.9);
        assert_eq!(s.eval(540.1), 0.0);
        assert!(DeclaredSpectrum::tabulated(&[400.0], &[1.0]).is_none());
        assert!(DeclaredSpectrum::tabulated(&[500.0, 400.0], &[1.0, 1.0]).is_none());
        assert!(DeclaredSpectrum::tabulated(&[400.0, 500.0], &[1.0]).is_none());
        assert!(DeclaredSpectrum::tabulated(&[400.0, 500.0], &[f32::NAN, 1.0]).is_none());
    }
}
