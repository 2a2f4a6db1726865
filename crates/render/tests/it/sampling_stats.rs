//! Statistical tests of `sampling::distrib` and `sampling::sampler`.
//!
//! Significance: every χ² test is one-sided (upper tail) at a family-wise level α = 0.01 per
//! test function, split over its cases with the Šidák correction
//! (α_case = 1 − (1 − α)^(1/cases)). All seeds are fixed, so the outcome is deterministic; the
//! level says how unlikely a correct implementation is to fail with an arbitrary seed.
//!
//! Low-discrepancy samplers give histograms *more* uniform than independent samples, i.e. small
//! χ² values; the tests only reject too large ones (non-uniformity, or structure between
//! dimensions that a correct randomisation would not show).

use crate::sampling_common::{Rng, assert_chi2, sidak};
use base::SamplerKind;
use glam::{UVec2, Vec2};
use render::sampling::{AliasTable, Distribution1D, Distribution2D, Sampler};

const ALPHA: f64 = 0.01;

fn test_function_1d() -> Vec<f32> {
    // Zeros, a spike, a wide dynamic range.
    (0..50)
        .map(|i| match i {
            3 | 17 | 18 | 49 => 0.0,
            25 => 40.0,
            _ => 0.05 + ((i as f32) * 0.7).sin().abs() * (i % 7) as f32,
        })
        .collect()
}

#[test]
fn distribution1d_matches_its_pmf_and_pdf() {
    let f = test_function_1d();
    let d = Distribution1D::new(&f);
    let n = 200_000;
    let bins = 200; // 4 bins per cell: also checks uniformity inside cells
    let (mut cont, mut disc) = (vec![0.0; bins], vec![0.0; f.len()]);
    let mut rng = Rng(1);
    for _ in 0..n {
        let (x, pdf, cell) = d.sample_continuous(rng.next_f32());
        assert!((0.0..1.0).contains(&x) && pdf > 0.0 && f[cell] > 0.0);
        assert_eq!(pdf, d.pdf(x));
        cont[(x * bins as f32) as usize] += 1.0;
        let (cell, pmf, u2) = d.sample_discrete(rng.next_f32());
        assert!((0.0..1.0).contains(&u2));
        assert_eq!(pmf, d.pmf(cell));
        disc[cell] += 1.0;
    }
    // Expected counts from the input function itself, not from the code under test.
    let total: f64 = f.iter().map(|&v| v as f64).sum();
    let exp_disc: Vec<f64> = f.iter().map(|&v| n as f64 * v as f64 / total).collect();
    let exp_cont: Vec<f64> = (0..bins).map(|b| exp_disc[b / 4] / 4.0).collect();
    let a = sidak(ALPHA, 2);
    assert_chi2("Distribution1D::sample_continuous", &cont, &exp_cont, a);
    assert_chi2("Distribution1D::sample_discrete", &disc, &exp_disc, a);
}

#[test]
fn distribution1d_remapped_u_is_uniform_and_independent_of_the_cell() {
    let d = Distribution1D::new(&[1.0, 2.0, 3.0]);
    let n = 60_000;
    let mut hist = vec![0.0; 3 * 10];
    let mut rng = Rng(2);
    for _ in 0..n {
        let (cell, _, u2) = d.sample_discrete(rng.next_f32());
        hist[cell * 10 + (u2 * 10.0) as usize] += 1.0;
    }
    let exp: Vec<f64> = (0..30)
        .map(|k| n as f64 * [1.0, 2.0, 3.0][k / 10] / 6.0 / 10.0)
        .collect();
    assert_chi2("remapped u", &hist, &exp, ALPHA);
}

#[test]
fn distribution2d_matches_its_pdf() {
    let (w, h) = (13, 7);
    let f: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if y == 3 || (x + y) % 5 == 0 {
                0.0
            } else {
                1.0 + (x * y) as f32 * 0.3
            }
        })
        .collect();
    let d = Distribution2D::new(&f, w, h);
    let total: f64 = f.iter().map(|&v| v as f64).sum();
    let (bw, bh) = (2 * w, 2 * h);
    let n = 200_000;
    let mut hist = vec![0.0; bw * bh];
    let mut rng = Rng(3);
    for _ in 0..n {
        let (p, pdf) = d.sample(Vec2::new(rng.next_f32(), rng.next_f32()));
        assert!(pdf > 0.0 && (pdf - d.pdf(p)).abs() <= 1e-5 * pdf);
        hist[(p.y * bh as f32) as usize * bw + (p.x * bw as f32) as usize] += 1.0;
    }
    let exp: Vec<f64> = (0..bw * bh)
        .map(|k| {
            let (x, y) = ((k % bw) / 2, (k / bw) / 2);
            n as f64 * f[y * w + x] as f64 / total / 4.0
        })
        .collect();
    assert_chi2("Distribution2D::sample", &hist, &exp, ALPHA);
    // The pdf integrates to 1.
    let mut integral = 0.0f64;
    for k in 0..bw * bh {
        let p = Vec2::new(
            ((k % bw) as f32 + 0.5) / bw as f32,
            ((k / bw) as f32 + 0.5) / bh as f32,
        );
        integral += d.pdf(p) as f64 / (bw * bh) as f64;
    }
    assert!((integral - 1.0).abs() < 1e-5, "{integral}");
}

#[test]
fn alias_table_matches_its_pmf() {
    let w: Vec<f32> = (0..40)
        .map(|i| {
            if i % 9 == 4 {
                0.0
            } else {
                1.0 + (i * i % 17) as f32
            }
        })
        .collect();
    let a = AliasTable::new(&w);
    let total: f64 = w.iter().map(|&v| v as f64).sum();
    let n = 200_000;
    let mut hist = vec![0.0; w.len()];
    let mut rng = Rng(4);
    for _ in 0..n {
        let (i, pmf) = a.sample(rng.next_f32());
        assert_eq!(pmf, a.pmf(i));
        hist[i] += 1.0;
    }
    let exp: Vec<f64> = w.iter().map(|&v| n as f64 * v as f64 / total).collect();
    for (i, &v) in w.iter().enumerate() {
        assert!((a.pmf(i) as f64 - v as f64 / total).abs() < 1e-7);
    }
    assert_chi2("AliasTable::sample", &hist, &exp, ALPHA);
}

// ---------------------------------------------------------------------------------------------
// Samplers

const KINDS: [SamplerKind; 5] = [
    SamplerKind::Independent,
    SamplerKind::Stratified,
    SamplerKind::Halton,
    SamplerKind::Sobol,
    SamplerKind::MultiJitter { jitter: true },
];

/// (kind, spp, sample indices drawn per pixel, pixels).
fn uniformity_configs() -> Vec<(SamplerKind, u32, u32, u32)> {
    vec![
        (SamplerKind::Independent, 64, 64, 128),
        (SamplerKind::Stratified, 64, 64, 128),
        // Non-square spp, and indices past spp (independent continuation).
        (SamplerKind::Stratified, 12, 24, 342),
        (SamplerKind::Halton, 64, 64, 128),
        (SamplerKind::Halton, 10, 10, 820),
        (SamplerKind::Sobol, 64, 64, 128),
        (SamplerKind::Sobol, 13, 13, 630),
        (SamplerKind::MultiJitter { jitter: true }, 64, 64, 128),
        (SamplerKind::MultiJitter { jitter: true }, 12, 24, 342),
    ]
}

/// The first 8 coordinates of every (pixel, index), drawn as 8 × next_1d or as 4 × next_2d.
fn draw(kind: SamplerKind, spp: u32, indices: u32, pixels: u32, two_d: bool) -> Vec<[f32; 8]> {
    let mut s = Sampler::new(kind, spp, 0xC0FFEE);
    let mut out = Vec::with_capacity((indices * pixels) as usize);
    for p in 0..pixels {
        let pixel = UVec2::new(p % 37, p / 37);
        for i in 0..indices {
            s.start_pixel_sample(pixel, i);
            let mut v = [0.0f32; 8];
            if two_d {
                for k in 0..4 {
                    let u = s.next_2d();
                    (v[2 * k], v[2 * k + 1]) = (u.x, u.y);
                }
            } else {
                for x in v.iter_mut() {
                    *x = s.next_1d();
                }
            }
            assert!(v.iter().all(|x| (0.0..1.0).contains(x)), "{kind:?}: {v:?}");
            out.push(v);
        }
    }
    out
}

#[test]
fn samplers_are_uniform_in_each_dimension_and_each_pair() {
    let configs = uniformity_configs();
    // Per config and draw pattern: 8 one-dimensional histograms and 28 pair histograms.
    let cases = configs.len() * 2 * (8 + 28);
    let a = sidak(ALPHA, cases);
    for (kind, spp, indices, pixels) in configs {
        for two_d in [false, true] {
            let pts = draw(kind, spp, indices, pixels, two_d);
            let n = pts.len() as f64;
            let name = |what: String| {
                format!(
                    "{kind:?} spp={spp} {} {what}",
                    if two_d { "next_2d" } else { "next_1d" }
                )
            };
            let bins1 = 16;
            for d in 0..8 {
                let mut h = vec![0.0; bins1];
                for v in &pts {
                    h[(v[d] * bins1 as f32) as usize] += 1.0;
                }
                assert_chi2(
                    &name(format!("dim {d}")),
                    &h,
                    &vec![n / bins1 as f64; bins1],
                    a,
                );
            }
            let g = 8;
            for d0 in 0..8 {
                for d1 in d0 + 1..8 {
                    let mut h = vec![0.0; g * g];
                    for v in &pts {
                        h[(v[d1] * g as f32) as usize * g + (v[d0] * g as f32) as usize] += 1.0;
                    }
                    let exp = vec![n / (g * g) as f64; g * g];
                    assert_chi2(&name(format!("dims ({d0}, {d1})")), &h, &exp, a);
                }
            }
        }
    }
}

/// A smooth, non-separable integrand on the unit square.
fn smooth(x: f64, y: f64) -> f64 {
    (-((x - 0.4).powi(2) + (y - 0.6).powi(2)) / 0.1).exp() + 0.5 * x * y + (3.0 * x + y).sin()
}

/// (∫ smooth, ∫ smooth²) by a 1500² midpoint rule (accurate to ~1e-7 here).
fn reference_moments() -> (f64, f64) {
    let m = 1500;
    let (mut s, mut s2) = (0.0, 0.0);
    for i in 0..m {
        for j in 0..m {
            let v = smooth((i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64);
            s += v;
            s2 += v * v;
        }
    }
    let n = (m * m) as f64;
    (s / n, s2 / n)
}

/// Mean squared error of the per-pixel estimate of ∫ smooth with `spp` samples from the 2D draw
/// number `draw_index` (0 → dims (0,1), 2 → dims (4,5)), over `pixels` pixels.
fn integration_mse(kind: SamplerKind, spp: u32, draw_index: u32, pixels: u32, exact: f64) -> f64 {
    let mut s = Sampler::new(kind, spp, 42);
    let mut mse = 0.0;
    for p in 0..pixels {
        let pixel = UVec2::new(p, 7 * p + 1);
        let mut est = 0.0;
        for i in 0..spp {
            s.start_pixel_sample(pixel, i);
            let mut u = s.next_2d();
            for _ in 0..draw_index {
                u = s.next_2d();
            }
            est += smooth(u.x as f64, u.y as f64);
        }
        est /= spp as f64;
        mse += (est - exact).powi(2);
    }
    mse / pixels as f64
}

#[test]
fn stratified_and_quasi_random_samplers_beat_independent_on_smooth_integrands() {
    // MSE over 400 pixels has a relative standard deviation of about √(2/400) ≈ 7%, so the
    // bounds below (far from the theoretical values) cannot fail by chance.
    let (exact, second) = reference_moments();
    let var = second - exact * exact;
    let pixels = 400;
    for draw_index in [0, 2] {
        let mut mse_ind = [0.0; 2];
        for (k, spp) in [64, 256].into_iter().enumerate() {
            mse_ind[k] = integration_mse(SamplerKind::Independent, spp, draw_index, pixels, exact);
            // The independent sampler's MSE is Var(f)/spp: unbiased, right order of magnitude.
            let rel = mse_ind[k] * spp as f64 / var;
            assert!(
                (0.7..1.3).contains(&rel),
                "independent: MSE·spp/Var = {rel}"
            );
        }
        // (kind, minimum variance reduction at 64 spp, minimum MSE(64)/MSE(256)). Theory for
        // the rate: jittered O(N⁻²) → 16, Owen-scrambled (0,2)-net O(N⁻³) → 64; Halton's
        // scrambled digits in bases 2,3 (or 5,7 for draw 2) sit in between.
        for (kind, min_ratio, min_rate) in [
            (SamplerKind::Stratified, 20.0, 10.0),
            // Kensler's correlated offsets (one permutation for all rows) measure 68–71× and
            // a rate of 8.8–9.1 here, half the uncorrelated multi-jittering's on this smooth
            // integrand: the bounds are below those, not at the jittered theory.
            (SamplerKind::MultiJitter { jitter: true }, 20.0, 6.0),
            (SamplerKind::Halton, 4.0, 6.0),
            (SamplerKind::Sobol, 50.0, 25.0),
        ] {
            let mse = [64, 256].map(|spp| integration_mse(kind, spp, draw_index, pixels, exact));
            let (r64, r256) = (mse_ind[0] / mse[0], mse_ind[1] / mse[1]);
            let rate = mse[0] / mse[1];
            println!(
                "independent / {kind:?} MSE ratio, 2D draw {draw_index}: {r64:.1} at 64 spp, \
                 {r256:.1} at 256 spp; MSE(64)/MSE(256) = {rate:.1}"
            );
            assert!(r64 > min_ratio, "{kind:?} draw {draw_index}: ratio {r64}");
            assert!(rate > min_rate, "{kind:?} draw {draw_index}: rate {rate}");
        }
    }
}

/// Kensler's correlated multi-jittering: the `spp` samples of a pixel's 2D draw put one point
/// in each of the m × n cells and one in each of the `spp` columns and rows of width 1/spp
/// (n-rooks), for any pixel and draw; without jitter every point is at its sub-cell's centre;
/// 1D draws are stratified.
#[test]
fn multi_jittered_draws_fill_the_cells_and_the_rooks_rows() {
    for (spp, jitter) in [(16, true), (12, true), (7, true), (64, false), (6, false)] {
        let mut s = Sampler::new(SamplerKind::MultiJitter { jitter }, spp, 5);
        let (mut m, n) = ((spp as f64).sqrt() as u32, 0);
        while m > 1 && spp % m != 0 {
            m -= 1;
        }
        let (m, n) = (m.max(1), n.max(spp / m.max(1)));
        for pixel in [UVec2::new(0, 0), UVec2::new(3, 9)] {
            for draw in 0..3 {
                let pts: Vec<Vec2> = (0..spp)
                    .map(|i| {
                        s.start_pixel_sample(pixel, i);
                        s.set_dimension(2 * draw);
                        s.next_2d()
                    })
                    .collect();
                let mut cells = vec![0; spp as usize];
                let (mut cols, mut rows) = (vec![0; spp as usize], vec![0; spp as usize]);
                for p in &pts {
                    let c = ((p.x * m as f32) as u32, (p.y * n as f32) as u32);
                    cells[(c.1 * m + c.0) as usize] += 1;
                    cols[(p.x * spp as f32) as usize] += 1;
                    rows[(p.y * spp as f32) as usize] += 1;
                    if !jitter {
                        let off = (p.x * spp as f32).fract();
                        assert!((off - 0.5).abs() < 1e-3, "spp {spp}: x offset {off}");
                    }
                }
                assert!(
                    cells.iter().all(|&k| k == 1),
                    "spp {spp} draw {draw}: cells {cells:?}"
                );
                assert!(
                    cols.iter().all(|&k| k == 1),
                    "spp {spp} draw {draw}: columns {cols:?}"
                );
                assert!(
                    rows.iter().all(|&k| k == 1),
                    "spp {spp} draw {draw}: rows {rows:?}"
                );
                let mut strata = vec![0; spp as usize];
                for i in 0..spp {
                    s.start_pixel_sample(pixel, i);
                    s.set_dimension(2 * draw);
                    strata[(s.next_1d() * spp as f32) as usize] += 1;
                }
                assert!(
                    strata.iter().all(|&k| k == 1),
                    "spp {spp}: 1D strata {strata:?}"
                );
            }
        }
    }
}

#[test]
fn streams_are_pure_functions_of_seed_pixel_index_dimension() {
    for kind in KINDS {
        let run = |s: &mut Sampler, pixel: UVec2, index: u32| -> Vec<f32> {
            s.start_pixel_sample(pixel, index);
            let mut v = vec![s.next_1d()];
            let u = s.next_2d();
            v.extend([u.x, u.y, s.next_1d(), s.next_1d()]);
            v
        };
        let (p, q) = (UVec2::new(10, 20), UVec2::new(11, 20));
        let mut a = Sampler::new(kind, 16, 5);
        let first = run(&mut a, p, 3);
        // Interleaving other pixels and indices does not change the stream.
        let _ = run(&mut a, q, 0);
        let _ = run(&mut a, p, 4);
        assert_eq!(run(&mut a, p, 3), first, "{kind:?}");
        // Nor does starting mid-stream at the same dimension.
        a.start_pixel_sample_at(p, 3, 3);
        assert_eq!(a.next_1d(), first[3], "{kind:?}");
        // A fresh sampler on another thread agrees.
        let other = std::thread::spawn(move || run(&mut Sampler::new(kind, 16, 5), p, 3))
            .join()
            .unwrap();
        assert_eq!(other, first, "{kind:?}");
        // A clone continues identically.
        a.start_pixel_sample(p, 3);
        a.next_1d();
        let mut b = a.clone();
        assert_eq!(a.next_2d(), b.next_2d());
        // Different pixels, indices and seeds give different streams.
        assert_ne!(run(&mut a, q, 3), first, "{kind:?}");
        assert_ne!(run(&mut a, p, 2), first, "{kind:?}");
        assert_ne!(run(&mut Sampler::new(kind, 16, 6), p, 3), first, "{kind:?}");
    }
}

#[test]
fn neighbouring_pixels_are_decorrelated() {
    // Pearson correlation of dimension d between horizontally adjacent pixels, over many
    // pixels and indices: |r| must be within a 99.9% band of 0 (n ≈ 8192 → 3.3/√n).
    for kind in KINDS {
        let mut s = Sampler::new(kind, 16, 9);
        let (mut sx, mut sy, mut sxx, mut syy, mut sxy, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for p in 0..512u32 {
            for i in 0..16 {
                s.start_pixel_sample(UVec2::new(2 * p, 3), i);
                s.set_dimension(2);
                let x = s.next_1d() as f64;
                s.start_pixel_sample(UVec2::new(2 * p + 1, 3), i);
                s.set_dimension(2);
                let y = s.next_1d() as f64;
                sx += x;
                sy += y;
                sxx += x * x;
                syy += y * y;
                sxy += x * y;
                n += 1.0;
            }
        }
        let cov = sxy / n - sx / n * sy / n;
        let r = cov / ((sxx / n - (sx / n).powi(2)) * (syy / n - (sy / n).powi(2))).sqrt();
        assert!(r.abs() < 3.3 / n.sqrt(), "{kind:?}: r = {r}");
    }
}
