//! Black-body emission: Planck's law, and the normalised spectrum emitters use.
//!
//! [`planck`] is the spectral radiance of a black body in W·sr⁻¹·m⁻³ (per metre of wavelength;
//! multiply by 1e-9 for per nm), with the exact SI (2019) values of h, c and k.
//! [`BlackbodySpectrum`] is that curve divided by its value at the peak given by Wien's
//! displacement law (b = 2.897 771 955e-3 m·K), so that its maximum is 1 whatever the
//! temperature: pbrt-v4's `BlackbodySpectrum` normalisation; a scene's emitter scale then sets
//! the brightness and the temperature only the colour. [`BlackbodySpectrum::normalization`]
//! gives the factor back for physically scaled radiance.

use super::sampled::Spectrum;

/// Planck constant (J·s).
pub const PLANCK_H: f64 = 6.626_070_15e-34;
/// Speed of light in vacuum (m/s).
pub const SPEED_OF_LIGHT: f64 = 299_792_458.0;
/// Boltzmann constant (J/K).
pub const BOLTZMANN_K: f64 = 1.380_649e-23;
/// Wien's displacement constant (m·K): λ_max = b / T.
pub const WIEN_B: f64 = 2.897_771_955e-3;

/// Spectral radiance of a black body at temperature `t` (K), wavelength `lambda_nm` (nm), in
/// W·sr⁻¹·m⁻³. 0 for non-positive temperatures.
pub fn planck(lambda_nm: f64, t: f64) -> f64 {
    if t <= 0.0 || lambda_nm <= 0.0 {
        return 0.0;
    }
    let l = lambda_nm * 1e-9;
    let c1 = 2.0 * PLANCK_H * SPEED_OF_LIGHT * SPEED_OF_LIGHT;
    let c2 = PLANCK_H * SPEED_OF_LIGHT / BOLTZMANN_K;
    c1 / (l.powi(5) * (c2 / (l * t)).exp_m1())
}

/// [`planck`] at four wavelengths at once (4-wide double precision: the same formula, the
/// scalar `exp_m1` replaced by `wide`'s, equal to 1e-12 relative).
pub fn planck4(lambda_nm: [f64; 4], t: f64) -> [f64; 4] {
    if t <= 0.0 || lambda_nm.iter().any(|&l| l <= 0.0) {
        return lambda_nm.map(|l| planck(l, t));
    }
    let l = wide::f64x4::from(lambda_nm) * 1e-9;
    let c1 = 2.0 * PLANCK_H * SPEED_OF_LIGHT * SPEED_OF_LIGHT;
    let c2 = PLANCK_H * SPEED_OF_LIGHT / BOLTZMANN_K;
    let l2 = l * l;
    (wide::f64x4::splat(c1) / (l2 * l2 * l * (wide::f64x4::splat(c2) / (l * t)).exp_m1()))
        .to_array()
}

/// A black body's spectrum scaled to a maximum of 1 (pbrt-v4's normalisation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlackbodySpectrum {
    temperature: f64,
    normalization: f64,
}

impl BlackbodySpectrum {
    /// The spectrum of a black body at `temperature` K (> 0).
    pub fn new(temperature: f32) -> BlackbodySpectrum {
        let t = temperature as f64;
        let peak = planck(WIEN_B / t * 1e9, t);
        let normalization = if peak > 0.0 { 1.0 / peak } else { 0.0 };
        BlackbodySpectrum {
            temperature: t,
            normalization,
        }
    }

    pub fn temperature(&self) -> f32 {
        self.temperature as f32
    }

    /// The factor (m³·sr/W) this spectrum applies to [`planck`].
    pub fn normalization(&self) -> f64 {
        self.normalization
    }
}

impl Spectrum for BlackbodySpectrum {
    #[inline]
    fn eval(&self, lambda: f32) -> f32 {
        (planck(lambda as f64, self.temperature) * self.normalization) as f32
    }
}

#[cfg(test)]
mod tests {
    /// The 4-wide Planck's law is the scalar one, over the temperatures and wavelengths a
    /// scene can declare.
    #[test]
    fn planck4_is_planck() {
        for t in [1.0, 300.0, 1000.0, 3000.0, 6504.0, 1e5, 1e8] {
            for l0 in [360.0, 412.5, 555.0, 700.0, 829.9] {
                let ls = [l0, l0 + 0.3, l0 * 0.5, l0 * 2.0];
                let got = planck4(ls, t);
                for (g, &l) in got.iter().zip(&ls) {
                    let want = planck(l, t);
                    assert!(
                        (g - want).abs() <= 1e-12 * want,
                        "{t} K, {l} nm: {g} vs {want}"
                    );
                }
            }
        }
        assert_eq!(planck4([500.0; 4], 0.0), [0.0; 4]);
    }

    use super::*;

    #[test]
    fn planck_matches_an_independent_value_and_stefan_boltzmann() {
        // A 5778 K black body at 500 nm: 2hc²/λ⁵ / (eˣ − 1), x = hc/λkT = 4.980 19…, is
        // 2.637 567e13 W·sr⁻¹·m⁻³ (computed separately, in Python).
        let v = planck(500.0, 5778.0);
        assert!((v / 2.637_567e13 - 1.0).abs() < 1e-6, "{v:e}");
        // Stefan–Boltzmann: π∫B dλ = σT⁴ (σ = 5.670 374 419e-8 W·m⁻²·K⁻⁴).
        let t = 3000.0;
        let n = 200_000;
        let (a, b) = (50.0f64, 100_000.0f64); // nm
        let h = (b - a) / n as f64;
        let integral: f64 = (0..n)
            .map(|k| planck(a + (k as f64 + 0.5) * h, t) * h * 1e-9)
            .sum();
        let sigma = 5.670_374_419e-8;
        let rel = (std::f64::consts::PI * integral / (sigma * t.powi(4)) - 1.0).abs();
        assert!(rel < 1e-4, "Stefan–Boltzmann off by {rel:e}");
        assert_eq!(planck(500.0, 0.0), 0.0);
    }

    #[test]
    fn normalised_peak_is_one() {
        for t in [1000.0f32, 2700.0, 6500.0, 10_000.0] {
            let s = BlackbodySpectrum::new(t);
            let peak_nm = (WIEN_B / t as f64 * 1e9) as f32;
            assert!((s.eval(peak_nm) - 1.0).abs() < 1e-6);
            for d in [-5.0, 5.0] {
                assert!(s.eval(peak_nm + d) < 1.0);
            }
        }
        // Hotter is bluer.
        let warm = BlackbodySpectrum::new(2700.0);
        let cold = BlackbodySpectrum::new(9000.0);
        assert!(warm.eval(450.0) / warm.eval(650.0) < cold.eval(450.0) / cold.eval(650.0));
    }
}
