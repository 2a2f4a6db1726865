//! Tests of `film`: filter importance sampling (χ² of the sampled offsets against |f|, z-test of
//! the weights), and the film's accumulation (tiling, crop, develop, standard error, rejection
//! of non-finite samples).
//!
//! Significance: α = 0.01 per test function, split over its cases with the Šidák correction;
//! fixed seeds.

mod sampling_common;

use glam::{UVec2, Vec2, Vec3};
use rayon::prelude::*;
use render::film::{Film, Filter};
use render::sampling::Sampler;
use sampling_common::{Rng, assert_chi2, sidak};
use scene::{CropWindow, FilterDesc, SamplerKind};
use statrs::distribution::{ContinuousCDF, Normal};

const ALPHA: f64 = 0.01;

fn filters() -> Vec<(&'static str, Filter)> {
    vec![
        ("box", Filter::new(&FilterDesc::Box { radius: 0.5 })),
        ("box r=1.5", Filter::new(&FilterDesc::Box { radius: 1.5 })),
        ("tent", Filter::new(&FilterDesc::Tent { radius: 1.0 })),
        ("tent r=2", Filter::new(&FilterDesc::Tent { radius: 2.0 })),
        ("gaussian", Filter::default_gaussian()),
        (
            "gaussian σ=0.3 r=1",
            Filter::new(&FilterDesc::Gaussian {
                stddev: 0.3,
                radius: 1.0,
            }),
        ),
        (
            "mitchell",
            Filter::new(&FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
                radius: 2.0,
            }),
        ),
        (
            "catmull-rom",
            Filter::new(&FilterDesc::Mitchell {
                b: 0.0,
                c: 0.5,
                radius: 2.0,
            }),
        ),
    ]
}

/// ∫ over [a, b] of `h(g(x), x)` by a fine midpoint rule.
fn quad(a: f32, b: f32, h: impl Fn(f64) -> f64) -> f64 {
    let m = 400;
    let dx = (b - a) as f64 / m as f64;
    (0..m)
        .map(|k| h(a as f64 + (k as f64 + 0.5) * dx))
        .sum::<f64>()
        * dx
}

#[test]
fn filter_samples_are_distributed_as_abs_f() {
    let all = filters();
    let a = sidak(ALPHA, all.len());
    let bins = 20;
    let n = 300_000;
    for (name, f) in &all {
        let r = f.radius();
        let edge = |k: usize| -r + 2.0 * r * k as f32 / bins as f32;
        // Expected mass of each 1D bin of |g|; the 2D expectation is their product.
        let g: Vec<f64> = (0..bins)
            .map(|k| quad(edge(k), edge(k + 1), |x| f.eval_1d(x as f32).abs() as f64))
            .collect();
        let total: f64 = g.iter().sum();
        let mut hist = vec![0.0; bins * bins];
        let mut rng = Rng(11);
        for _ in 0..n {
            let s = f.sample(Vec2::new(rng.next_f32(), rng.next_f32()));
            assert!(s.offset.abs().max_element() <= r, "{name}: {:?}", s.offset);
            let cell = |v: f32| (((v + r) / (2.0 * r) * bins as f32) as usize).min(bins - 1);
            hist[cell(s.offset.y) * bins + cell(s.offset.x)] += 1.0;
        }
        let exp: Vec<f64> = (0..bins * bins)
            .map(|k| n as f64 * g[k / bins] * g[k % bins] / (total * total))
            .collect();
        assert_chi2(name, &hist, &exp, a);
    }
}

#[test]
fn filter_weights_give_unbiased_filtered_estimates() {
    // E[w h(offset)] = ∫ f h / ∫ f for a test function h; z-test per filter.
    let all = filters();
    let a = sidak(ALPHA, all.len());
    let z_crit = Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - a / 2.0);
    let h = |x: f64, y: f64| x.cos() + y * y + 0.3 * x;
    let n = 200_000;
    for (name, f) in &all {
        let r = f.radius();
        let g = |x: f64| f.eval_1d(x as f32) as f64;
        let i0 = quad(-r, r, g);
        let (ic, ix, ix2) = (
            quad(-r, r, |x| g(x) * x.cos()),
            quad(-r, r, |x| g(x) * x),
            quad(-r, r, |x| g(x) * x * x),
        );
        // ∫∫ g(x)g(y)(cos x + y² + 0.3x) / (∫g)².
        let expected = (ic * i0 + i0 * ix2 + 0.3 * ix * i0) / (i0 * i0);
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        let mut rng = Rng(12);
        for _ in 0..n {
            let fs = f.sample(Vec2::new(rng.next_f32(), rng.next_f32()));
            let v = fs.weight as f64 * h(fs.offset.x as f64, fs.offset.y as f64);
            s += v;
            s2 += v * v;
        }
        let mean = s / n as f64;
        let se = ((s2 / n as f64 - mean * mean) / (n - 1) as f64).sqrt();
        let z = (mean - expected) / se;
        assert!(
            z.abs() < z_crit,
            "{name}: mean {mean}, expected {expected}, z = {z:.2}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Film

/// A synthetic "scene": radiance at a raster position, NaN for about 1% of the samples.
fn radiance(pos: Vec2, u: f32) -> Vec3 {
    if u < 0.01 {
        return Vec3::NAN;
    }
    Vec3::new(
        (pos.x * 0.7).sin() + 1.0,
        (pos.y * 0.3).cos() * u,
        pos.x * pos.y * 0.01,
    )
}

/// Renders `tiles` (in parallel when asked) with the FIS loop and merges them in reverse order.
fn render(film: &mut Film, tile_size: u32, parallel: bool, spp: u32, filter: &Filter) {
    let bounds = film.tile_bounds(tile_size);
    let work = |&(a, b): &(UVec2, UVec2)| {
        let mut tile = film.tile(a, b);
        let mut s = Sampler::new(SamplerKind::Sobol, spp, 7);
        for y in a.y..b.y {
            for x in a.x..b.x {
                let p = UVec2::new(x, y);
                for i in 0..spp {
                    s.start_pixel_sample(p, i);
                    let fs = filter.sample(s.next_2d());
                    let l = radiance(p.as_vec2() + 0.5 + fs.offset, s.next_1d());
                    tile.add_sample(p, l, fs.weight);
                }
            }
        }
        tile
    };
    let tiles: Vec<_> = if parallel {
        bounds.par_iter().map(work).collect()
    } else {
        bounds.iter().map(work).collect()
    };
    for t in tiles.into_iter().rev() {
        film.merge(t);
    }
}

fn bits(v: &[Vec3]) -> Vec<[u32; 3]> {
    v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

#[test]
fn merged_tiles_equal_a_single_tile_bit_for_bit() {
    let filter = Filter::new(&FilterDesc::Mitchell {
        b: 1.0 / 3.0,
        c: 1.0 / 3.0,
        radius: 2.0,
    });
    let mut one = Film::new(23, 17, None);
    render(&mut one, 1 << 20, false, 8, &filter);
    let mut many = Film::new(23, 17, None);
    render(&mut many, 5, true, 8, &filter);
    assert_eq!(bits(&one.develop().pixels), bits(&many.develop().pixels));
    assert_eq!(
        bits(&one.develop_stderr().pixels),
        bits(&many.develop_stderr().pixels)
    );
    assert_eq!(one.sample_count(), many.sample_count());
    assert!(
        one.nonfinite_count() > 0,
        "the scene emits some NaN samples"
    );
    assert_eq!(one.nonfinite_count(), many.nonfinite_count());
    assert_eq!(
        one.sample_count() + one.nonfinite_count(),
        23 * 17 * 8,
        "every sample is either accepted or counted as rejected"
    );
    // Merging a whole film into an empty one is exact too.
    let mut copy = Film::new(23, 17, None);
    copy.merge(one.clone().into_tile());
    assert_eq!(bits(&one.develop().pixels), bits(&copy.develop().pixels));
}

#[test]
fn crop_window_stores_and_develops_only_its_pixels() {
    let filter = Filter::default_gaussian();
    let crop = CropWindow {
        offset_x: 5,
        offset_y: 3,
        width: 9,
        height: 6,
    };
    let mut cropped = Film::new(24, 16, Some(crop));
    assert_eq!(cropped.full_resolution(), UVec2::new(24, 16));
    assert_eq!(
        cropped.pixel_bounds(),
        (UVec2::new(5, 3), UVec2::new(14, 9))
    );
    render(&mut cropped, 4, true, 4, &filter);
    let mut full = Film::new(24, 16, None);
    render(&mut full, 8, true, 4, &filter);
    let (c, f) = (cropped.develop(), full.develop());
    assert_eq!((c.width, c.height), (9, 6));
    for y in 0..6 {
        for x in 0..9 {
            assert_eq!(
                c.get(x, y).to_array().map(f32::to_bits),
                f.get(x + 5, y + 3).to_array().map(f32::to_bits)
            );
        }
    }
    assert_eq!(cropped.spp_added(), cropped.sample_count() as f64 / 54.0);
    // Tiles requested outside the crop are clipped to it.
    let t = cropped.tile(UVec2::ZERO, UVec2::new(100, 4));
    assert_eq!(t.bounds(), (UVec2::new(5, 3), UVec2::new(14, 4)));
}

#[test]
fn constant_radiance_develops_to_itself_with_any_filter() {
    let c = Vec3::new(0.25, 1.0, 4.0);
    for (name, filter) in filters() {
        let mut film = Film::new(6, 5, None);
        let (a, b) = film.pixel_bounds();
        let mut tile = film.tile(a, b);
        let mut s = Sampler::new(SamplerKind::Independent, 16, 1);
        for y in 0..5 {
            for x in 0..6 {
                for i in 0..16 {
                    let p = UVec2::new(x, y);
                    s.start_pixel_sample(p, i);
                    tile.add_sample(p, c, filter.sample(s.next_2d()).weight);
                }
            }
        }
        film.merge(tile);
        let (img, err) = (film.develop(), film.develop_stderr());
        for (v, e) in img.pixels.iter().zip(&err.pixels) {
            assert!(((*v - c) / c).abs().max_element() < 1e-5, "{name}: {v}");
            assert!((*e / c).max_element() < 1e-5, "{name}: stderr {e}");
        }
    }
}

#[test]
fn stderr_matches_a_known_variance() {
    // Unit weights (box filter), L ~ U[0,1): σ² = 1/12. Over M pixels of n samples, the mean of
    // stderr² = s²/n estimates σ²/n; z-test with Var(s²) = (μ₄ − σ⁴(n−3)/(n−1))/n, μ₄ = 1/80.
    let (w, h, n) = (64u32, 32u32, 32u32);
    let box_filter = Filter::new(&FilterDesc::Box { radius: 0.5 });
    let gauss = Filter::default_gaussian();
    let a = sidak(ALPHA, 2);
    for (name, filter) in [("box", &box_filter), ("gaussian", &gauss)] {
        let mut film = Film::new(w, h, None);
        let (lo, hi) = film.pixel_bounds();
        let mut tile = film.tile(lo, hi);
        let mut rng = Rng(21);
        for y in 0..h {
            for x in 0..w {
                for _ in 0..n {
                    let fs = filter.sample(Vec2::new(rng.next_f32(), rng.next_f32()));
                    tile.add_sample(UVec2::new(x, y), Vec3::splat(rng.next_f32()), fs.weight);
                }
            }
        }
        film.merge(tile);
        let (img, err) = (film.develop(), film.develop_stderr());
        let m = (w * h) as f64;
        let nf = n as f64;
        if name == "box" {
            let mean_var: f64 = err.pixels.iter().map(|e| (e.x as f64).powi(2)).sum::<f64>() / m;
            let sigma2 = 1.0 / 12.0;
            let var_s2 = (1.0 / 80.0 - sigma2 * sigma2 * (nf - 3.0) / (nf - 1.0)) / nf;
            let z = (mean_var - sigma2 / nf) / (var_s2.sqrt() / nf / m.sqrt());
            let z_crit = Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - a / 2.0);
            assert!(z.abs() < z_crit, "mean stderr² {mean_var}, z = {z:.2}");
        }
        // Coverage of the ±1.96·stderr interval around the true mean 0.5: ≈ 94% for n = 32
        // (Student t with 31 dof), also with the gaussian filter's non-unit weights (delta
        // method). Bounds: ±3.5 binomial standard deviations around 0.94.
        let covered = img
            .pixels
            .iter()
            .zip(&err.pixels)
            .filter(|(v, e)| (v.x - 0.5).abs() <= 1.96 * e.x)
            .count() as f64
            / m;
        let sd = (0.94f64 * 0.06 / m).sqrt();
        assert!(
            (covered - 0.94).abs() < 3.5 * sd,
            "{name}: coverage {covered:.4}"
        );
        println!("{name}: 95% interval coverage {covered:.4}");
    }
}

#[test]
fn nonfinite_samples_are_rejected_and_counted() {
    let mut film = Film::new(4, 4, None);
    let p = UVec2::new(2, 1);
    let mut tile = film.tile(UVec2::new(2, 0), UVec2::new(4, 2));
    tile.add_sample(p, Vec3::new(f32::NAN, 0.0, 0.0), 1.0);
    tile.add_sample(p, Vec3::ONE, f32::INFINITY);
    tile.add_sample(p, Vec3::new(1.0, f32::NEG_INFINITY, 1.0), 1.0);
    tile.add_sample(p, Vec3::ONE, f32::NAN);
    tile.add_sample(p, Vec3::new(0.5, 2.0, 3.0), 0.5);
    assert_eq!(tile.nonfinite_count(), 4);
    film.merge(tile);
    let mut tile = film.tile(UVec2::ZERO, UVec2::new(1, 1));
    tile.add_sample(UVec2::ZERO, Vec3::splat(f32::INFINITY), 1.0);
    film.merge(tile);
    assert_eq!(film.nonfinite_count(), 5);
    assert_eq!(film.sample_count(), 1);
    let img = film.develop();
    assert_eq!(img.get(2, 1), Vec3::new(0.5, 2.0, 3.0));
    assert_eq!(img.get(0, 0), Vec3::ZERO);
    assert!(img.pixels.iter().all(|v| v.is_finite()));
    assert!(film.develop_stderr().pixels.iter().all(|v| v.is_finite()));
}
