//! Wavelength-dependent indices of refraction (dispersion): Sellmeier's and Cauchy's
//! equations, and named optical glasses.
//!
//! - Sellmeier: n²(λ) = 1 + Σᵢ Bᵢ·λ² / (λ² − Cᵢ), λ in µm, Cᵢ in µm² (the form of glass
//!   catalogues).
//! - Cauchy: n(λ) = A + B / λ², λ in µm, B in µm².
//!
//! The named glasses are pbrt-v4's `glass-*` names (its named spectra for dielectric `eta`)
//! and a few common materials, with the Sellmeier coefficients their makers publish: SCHOTT's
//! catalogue for the glasses (N-BK7, N-BAF10, N-FK51A, N-LASF9, and SF5, SF10, SF11 behind
//! pbrt-v4's `glass-F5`, `glass-F10`, `glass-F11`), Malitson (1965) for fused silica, Peter
//! (1923) for diamond. Each is checked against its catalogue
//! refractive index n_d at the helium d line (587.56 nm) in the tests.
//!
//! An RGB render has one index per material: the index at the d line, the reference
//! wavelength of glass catalogues ([`D_LINE_NM`]).

/// The helium d line, the wavelength at which glass catalogues give n_d (nm).
pub const D_LINE_NM: f64 = 587.5618;

/// An index of refraction that depends on the wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dispersion {
    /// n²(λ) = 1 + Σ Bᵢ·λ²/(λ² − Cᵢ), λ in µm, `c` in µm².
    Sellmeier { b: [f64; 3], c: [f64; 3] },
    /// n(λ) = A + B/λ², λ in µm, `b` in µm².
    Cauchy { a: f64, b: f64 },
}

/// How a rough dielectric with a dispersive index treats the four wavelengths of a spectral
/// path (smooth dielectrics always keep only the hero; thin sheets always keep all four).
/// Mitsuba-XML spelling: `<string name="dispersion_sampling" value="mis|terminate"/>` on
/// `roughdielectric`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DispersionSampling {
    /// Keep all four: one-sample MIS over the wavelengths' sampling densities (issue 21's
    /// choice, after the extended-Nori write-up's hero-wavelength sampling).
    #[default]
    Mis,
    /// Keep only the hero wavelength, as a smooth dielectric does (pbrt-v4's scheme; the
    /// comparison strategy of issue 21's colour-noise measurement).
    Terminate,
}

impl DispersionSampling {
    /// From its scene-file name: `mis` (also `hero`) or `terminate`.
    pub fn parse(s: &str) -> Option<DispersionSampling> {
        match s.to_ascii_lowercase().as_str() {
            "mis" | "hero" => Some(DispersionSampling::Mis),
            "terminate" => Some(DispersionSampling::Terminate),
            _ => None,
        }
    }
}

/// Named dispersive materials: the name, its Sellmeier B₁..B₃ and C₁..C₃ (µm²).
const NAMED: &[(&str, [f64; 3], [f64; 3])] = &[
    (
        "glass-bk7",
        [1.039_612_12, 0.231_792_344, 1.010_469_45],
        [0.006_000_698_67, 0.020_017_914_4, 103.560_653],
    ),
    (
        "glass-baf10",
        [1.585_149_5, 0.143_559_385, 1.085_212_69],
        [0.009_266_812_82, 0.042_448_980_5, 105.613_573],
    ),
    (
        "glass-fk51a",
        [0.971_247_817, 0.216_901_417, 0.904_651_666],
        [0.004_723_019_95, 0.015_357_561_2, 168.681_33],
    ),
    (
        "glass-lasf9",
        [2.000_295_47, 0.298_926_886, 1.806_918_43],
        [0.012_142_601_7, 0.053_873_623_6, 156.530_829],
    ),
    (
        "glass-f5",
        [1.524_818_89, 0.187_085_527, 1.427_290_15],
        [0.011_254_756, 0.058_899_539_2, 129.141_675],
    ),
    (
        "glass-f10",
        [1.621_539_02, 0.256_287_842, 1.644_475_52],
        [0.012_224_145_7, 0.059_573_677_5, 147.468_793],
    ),
    (
        "glass-f11",
        [1.737_596_95, 0.313_747_346, 1.898_781_01],
        [0.013_188_707, 0.062_306_814_2, 155.236_29],
    ),
    (
        "fused-silica",
        [0.696_166_3, 0.407_942_6, 0.897_479_4],
        [0.004_679_148_26, 0.013_512_063_1, 97.934_002_5],
    ),
    (
        "diamond",
        [0.330_6, 4.335_6, 0.0],
        [0.030_625, 0.011_236, 0.0],
    ),
];

impl Dispersion {
    /// The named dispersive material (case-insensitive; pbrt-v4's `glass-BK7`, `glass-BAF10`,
    /// `glass-FK51A`, `glass-LASF9`, `glass-F5`, `glass-F10`, `glass-F11`, and
    /// `fused-silica`, `diamond`).
    pub fn named(name: &str) -> Option<Dispersion> {
        let name = name.to_ascii_lowercase();
        NAMED
            .iter()
            .find(|(n, ..)| *n == name)
            .map(|&(_, b, c)| Dispersion::Sellmeier { b, c })
    }

    /// The names [`Dispersion::named`] knows, for messages.
    pub fn names() -> impl Iterator<Item = &'static str> {
        NAMED.iter().map(|(n, ..)| *n)
    }

    /// The index of refraction at `lambda_nm` (nanometres).
    pub fn ior(&self, lambda_nm: f64) -> f64 {
        let l = lambda_nm * 1e-3;
        let l2 = l * l;
        match *self {
            Dispersion::Sellmeier { b, c } => {
                let s: f64 = (0..3).map(|i| b[i] * l2 / (l2 - c[i])).sum();
                (1.0 + s).max(1.0).sqrt()
            }
            Dispersion::Cauchy { a, b } => a + b / l2,
        }
    }

    /// The index an RGB render uses: the one at the d line.
    pub fn ior_rgb(&self) -> f64 {
        self.ior(D_LINE_NM)
    }

    /// Whether the index is a valid one (finite and ≥ 1) over the visible range, 360–830 nm:
    /// a Sellmeier pole or a negative Cauchy term there is an input error.
    pub fn is_valid_visible(&self) -> bool {
        (360..=830).step_by(5).all(|l| {
            let n = self.ior(f64::from(l));
            n.is_finite() && n >= 1.0
        }) && match *self {
            // A pole Cᵢ inside the visible range makes n² jump through infinity.
            Dispersion::Sellmeier { c, .. } => {
                c.iter().all(|&c| !(0.36 * 0.36..=0.83 * 0.83).contains(&c))
            }
            Dispersion::Cauchy { .. } => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each named glass gives its catalogue n_d (to the catalogue's 4–5 digits) and is normal
    /// dispersive (n falls with λ) over the visible range.
    #[test]
    fn named_glasses_match_their_catalogue_indices() {
        for (name, n_d) in [
            ("glass-BK7", 1.5168),
            ("glass-BAF10", 1.6700),
            ("glass-FK51A", 1.4866),
            ("glass-LASF9", 1.8503),
            ("glass-F5", 1.6727),
            ("glass-F10", 1.7283),
            ("glass-F11", 1.7847),
            ("fused-silica", 1.4585),
            ("diamond", 2.4175),
        ] {
            let d = Dispersion::named(name).unwrap();
            let n = d.ior_rgb();
            assert!((n - n_d).abs() < 1.5e-4, "{name}: n_d {n} vs {n_d}");
            assert!(d.is_valid_visible(), "{name}");
            let mut prev = f64::INFINITY;
            for l in (360..=830).step_by(10) {
                let n = d.ior(f64::from(l));
                assert!(n < prev, "{name} at {l} nm");
                prev = n;
            }
        }
        assert_eq!(Dispersion::named("glass-unobtainium"), None);
        assert_eq!(Dispersion::names().count(), NAMED.len());
    }

    /// BK7's Abbe number (n_d − 1)/(n_F − n_C) is SCHOTT's 64.17.
    #[test]
    fn bk7_abbe_number() {
        let d = Dispersion::named("glass-bk7").unwrap();
        let abbe = (d.ior(587.5618) - 1.0) / (d.ior(486.1327) - d.ior(656.2725));
        assert!((abbe - 64.17).abs() < 0.05, "{abbe}");
    }

    #[test]
    fn cauchy_and_validity() {
        let d = Dispersion::Cauchy { a: 1.5, b: 0.0042 };
        assert!((d.ior(500.0) - (1.5 + 0.0042 / 0.25)).abs() < 1e-12);
        assert!(d.is_valid_visible());
        assert!(!Dispersion::Cauchy { a: 0.5, b: 0.0 }.is_valid_visible());
        // A Sellmeier pole at 500 nm.
        let pole = Dispersion::Sellmeier {
            b: [1.0, 0.0, 0.0],
            c: [0.25, 0.0, 0.0],
        };
        assert!(!pole.is_valid_visible());
    }
}
