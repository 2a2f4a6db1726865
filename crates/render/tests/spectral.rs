//! Statistical and colorimetric tests of `render::spectral` (issue 21's foundations).
//!
//! Significance: χ² tests are one-sided at a family-wise α = 0.01 per test function, Šidák-split
//! over its cases; z-tests are two-sided at the same family-wise level. All seeds are fixed, so
//! the outcome is deterministic.

mod sampling_common;

use render::spectral::{SampledWavelengths, visible_wavelength_pdf};
use sampling_common::{Rng, assert_chi2, sidak};

const ALPHA: f64 = 0.01;

/// ∫ f over [a, b] by composite Simpson with `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for k in 1..n {
        s += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// Each of the four stratified lanes of `SampledWavelengths::sample_visible` is distributed by
/// `visible_wavelength_pdf`: a χ² test per lane over 94 bins of 5 nm, expected counts from the
/// pdf integrated over each bin (Simpson), and the pdf each draw reports is the pdf's value.
#[test]
fn wavelength_sampling_matches_its_pdf() {
    let n = 400_000;
    let bins = 94;
    let width = 470.0 / bins as f64;
    let expected: Vec<f64> = (0..bins)
        .map(|b| {
            let a = 360.0 + b as f64 * width;
            n as f64
                * simpson(
                    |l| visible_wavelength_pdf(l as f32) as f64,
                    a,
                    a + width,
                    64,
                )
        })
        .collect();
    let total: f64 = expected.iter().sum::<f64>() / n as f64;
    assert!((total - 1.0).abs() < 1e-5, "∫p = {total}");
    let mut hist = vec![vec![0.0; bins]; 4];
    let mut rng = Rng(21);
    for _ in 0..n {
        let wl = SampledWavelengths::sample_visible(rng.next_f32());
        for (lane, h) in hist.iter_mut().enumerate() {
            let l = wl.lambda(lane);
            assert!((360.0..=830.0).contains(&l), "λ = {l}");
            assert_eq!(wl.pdf()[lane], visible_wavelength_pdf(l));
            let b = (((l as f64 - 360.0) / width) as usize).min(bins - 1);
            h[b] += 1.0;
        }
    }
    let a = sidak(ALPHA, 4);
    for (lane, h) in hist.iter().enumerate() {
        assert_chi2(
            &format!("visible wavelengths, lane {lane}"),
            h,
            &expected,
            a,
        );
    }
}
