//! Helpers shared by the `sampling_*` and `film_*` integration tests: Pearson's χ² test with
//! pooling of sparse cells, the Šidák correction and a small independent RNG (so the tests do
//! not depend on the samplers under test for their own randomness).

use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Per-case significance level keeping the family-wise error rate at `alpha` over `cases`
/// independent tests (Šidák).
pub fn sidak(alpha: f64, cases: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / cases as f64)
}

/// Pearson's χ² goodness of fit of `observed` counts against `expected` counts. Cells with an
/// expected count below 5 are pooled into one cell (merged into the smallest regular cell if the
/// pool itself stays below 5). Returns `(statistic, degrees of freedom, p-value)`; an
/// observation in a cell of expected count 0 gives p = 0.
pub fn chi2(observed: &[f64], expected: &[f64]) -> (f64, usize, f64) {
    assert_eq!(observed.len(), expected.len());
    let mut cells: Vec<(f64, f64)> = Vec::new();
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e <= 0.0 {
            if o > 0.0 {
                return (f64::INFINITY, 0, 0.0);
            }
            continue;
        }
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            cells.push((o, e));
        }
    }
    if pool_e > 0.0 {
        if pool_e >= 5.0 || cells.is_empty() {
            cells.push((pool_o, pool_e));
        } else {
            let k = (0..cells.len())
                .min_by(|&a, &b| cells[a].1.total_cmp(&cells[b].1))
                .unwrap();
            cells[k].0 += pool_o;
            cells[k].1 += pool_e;
        }
    }
    if cells.len() < 2 {
        return (0.0, 0, 1.0);
    }
    let stat: f64 = cells.iter().map(|&(o, e)| (o - e) * (o - e) / e).sum();
    let dof = cells.len() - 1;
    let p = 1.0 - ChiSquared::new(dof as f64).unwrap().cdf(stat);
    (stat, dof, p)
}

/// Fails with a readable message when the χ² p-value is below `alpha`.
pub fn assert_chi2(name: &str, observed: &[f64], expected: &[f64], alpha: f64) {
    let (stat, dof, p) = chi2(observed, expected);
    assert!(
        p >= alpha,
        "{name}: χ² = {stat:.2} with {dof} dof, p = {p:.3e} < α = {alpha:.3e}"
    );
}

/// SplitMix64: a tiny, good-enough generator for test inputs.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 24 bits.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

#[test]
fn chi2_helper_accepts_a_fair_die_and_rejects_a_loaded_one() {
    let exp = vec![1000.0; 6];
    let fair = vec![1010.0, 990.0, 1005.0, 995.0, 1000.0, 1000.0];
    assert!(chi2(&fair, &exp).2 > 0.5);
    let loaded = vec![1200.0, 800.0, 1000.0, 1000.0, 1000.0, 1000.0];
    assert!(chi2(&loaded, &exp).2 < 1e-6);
    assert_eq!(chi2(&[1.0, 0.0], &[0.0, 1.0]).2, 0.0);
    assert!((sidak(0.01, 1) - 0.01).abs() < 1e-12);
}
