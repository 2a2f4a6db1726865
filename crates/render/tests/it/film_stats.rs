//! Tests of `film`: splatting converges to the filtered image (z-tests against quadrature,
//! image edges included), the standard error is calibrated, and the accumulation is exact where
//! it must be (tiling, threads, crop window, constant radiance, non-finite samples).
//!
//! Significance: α = 0.01 per test function, split over its cases with the Šidák correction;
//! fixed seeds.

use crate::sampling_common::{Rng, sidak};
use base::{CropWindow, FilterDesc, SamplerKind};
use glam::{UVec2, Vec2};
use rayon::prelude::*;
use render::film::{Film, Filter};
use render::math::Vec3;
use render::sampling::Sampler;
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

fn z_crit(alpha: f64) -> f64 {
    Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0)
}

/// Renders every pixel of `film` with `spp` samples at `pixel + u` (u from `sampler`, then one
/// more dimension for `radiance`), tile by tile (in parallel when asked), and merges the tiles
/// in tile order as the render driver does.
fn render(
    film: &mut Film,
    tile_size: u32,
    parallel: bool,
    spp: u32,
    kind: SamplerKind,
    radiance: impl Fn(Vec2, f32) -> Vec3 + Sync,
) {
    let bounds = film.tile_bounds(tile_size);
    let work = |&(a, b): &(UVec2, UVec2)| {
        let mut tile = film.tile(a, b);
        let mut s = Sampler::new(kind, spp, 7);
        for y in a.y..b.y {
            for x in a.x..b.x {
                let p = UVec2::new(x, y);
                for i in 0..spp {
                    s.start_pixel_sample(p, i);
                    let p_film = p.as_vec2() + s.next_2d();
                    let l = radiance(p_film, s.next_1d());
                    tile.add_sample(p_film, l);
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
    for t in tiles {
        film.merge(&t);
    }
}

/// A smooth image `h` and a noisy radiance with mean `h` in its first channel, `h` itself in
/// the second.
fn h(p: Vec2) -> f64 {
    let (x, y) = (p.x as f64, p.y as f64);
    1.0 + 0.5 * (0.8 * x + 0.3 * y).sin() + 0.01 * x * y
}

fn noisy(p: Vec2, u: f32) -> Vec3 {
    let v = h(p) as f32;
    Vec3::new(v * (0.5 + u), v, 1.0)
}

/// `∫ f(c − p) h(p) dp / ∫ f(c − p) dp` over the film `[0, w) × [0, h)`, `c` the centre of
/// `pixel` (midpoint rule, 240² cells over the filter support).
fn filtered(filter: &Filter, pixel: UVec2, size: UVec2) -> f64 {
    let r = filter.radius();
    let c = pixel.as_vec2() + 0.5;
    let m = 240;
    let d = 2.0 * r / m as f32;
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for j in 0..m {
        let y = c.y - r + (j as f32 + 0.5) * d;
        if y < 0.0 || y >= size.y as f32 {
            continue;
        }
        for i in 0..m {
            let x = c.x - r + (i as f32 + 0.5) * d;
            if x < 0.0 || x >= size.x as f32 {
                continue;
            }
            let p = Vec2::new(x, y);
            let f = filter.eval(c - p) as f64;
            num += f * h(p);
            den += f;
        }
    }
    num / den
}

#[test]
fn splatting_converges_to_the_filtered_image() {
    // Pixels far enough apart (≥ 5 for r ≤ 2) to share no sample: independent z-tests. (0, 0)
    // checks the image corner, where the filter is truncated to the sampled region.
    let size = UVec2::new(26, 26);
    let pixels = [(0, 0), (6, 13), (13, 6), (19, 19), (25, 25)].map(|(x, y)| UVec2::new(x, y));
    let all = filters();
    let a = sidak(ALPHA, all.len() * pixels.len() * 2);
    for (name, filter) in &all {
        let mut film = Film::new(size.x, size.y, None, *filter);
        render(&mut film, 8, true, 64, SamplerKind::Independent, noisy);
        let (img, err) = (film.develop(), film.develop_stderr());
        for &p in &pixels {
            let expected = filtered(filter, p, size);
            let (v, e) = (img.get(p.x, p.y), err.get(p.x, p.y));
            for (c, (v, e)) in [(v.x, e.x), (v.y, e.y)].into_iter().enumerate() {
                let z = (v as f64 - expected) / e as f64;
                assert!(
                    z.abs() < z_crit(a),
                    "{name} pixel {p} channel {c}: {v} vs filtered {expected}, z = {z:.2}"
                );
            }
        }
    }
}

fn bits(v: &[Vec3]) -> Vec<[u32; 3]> {
    v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

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

#[test]
fn tiles_merge_deterministically_and_match_a_single_tile() {
    let filter = Filter::new(&FilterDesc::Mitchell {
        b: 1.0 / 3.0,
        c: 1.0 / 3.0,
        radius: 2.0,
    });
    let (w, h, spp) = (23, 17, 8);
    let kind = SamplerKind::Sobol;
    let mut one = Film::new(w, h, None, filter);
    render(&mut one, 1 << 20, false, spp, kind, radiance);
    let mut seq = Film::new(w, h, None, filter);
    render(&mut seq, 5, false, spp, kind, radiance);
    let mut par = Film::new(w, h, None, filter);
    render(&mut par, 5, true, spp, kind, radiance);
    // Same tiling, merged in the same order: identical for any number of threads.
    assert_eq!(bits(&seq.develop().pixels), bits(&par.develop().pixels));
    assert_eq!(
        bits(&seq.develop_stderr().pixels),
        bits(&par.develop_stderr().pixels)
    );
    // Another tiling adds the same terms in another order and rounds other partial sums
    // into the film: equal up to f64 rounding and the film's resolution (2⁻⁴⁰ a rounding).
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (
                one.pixel(UVec2::new(x, y)).unwrap(),
                seq.pixel(UVec2::new(x, y)).unwrap(),
            );
            assert_eq!(a.count, b.count);
            let close = |u: f64, v: f64| (u - v).abs() <= 1e-12 * u.abs().max(v.abs()) + 1e-10;
            assert!(close(a.weight, b.weight) && close(a.weight_sq, b.weight_sq));
            for c in 0..3 {
                assert!(close(a.weighted[c], b.weighted[c]), "({x}, {y})");
                assert!(close(a.weighted_sq[c], b.weighted_sq[c]));
                assert!(close(a.cross[c], b.cross[c]));
            }
        }
    }
    assert_eq!(one.sample_count(), seq.sample_count());
    assert!(
        one.nonfinite_count() > 0,
        "the scene emits some NaN samples"
    );
    assert_eq!(one.nonfinite_count(), par.nonfinite_count());
    assert_eq!(
        one.sample_count() + one.nonfinite_count(),
        (w * h * spp) as u64,
        "every sample is either accepted or counted once as rejected"
    );
    // Adding a whole film to an empty one is exact.
    let mut copy = Film::new(w, h, None, filter);
    copy.add_film(&one);
    assert_eq!(bits(&one.develop().pixels), bits(&copy.develop().pixels));
    assert_eq!(copy.sample_count(), one.sample_count());
}

#[test]
fn crop_window_samples_only_its_pixels() {
    let filter = Filter::default_gaussian();
    let crop = CropWindow {
        offset_x: 5,
        offset_y: 3,
        width: 9,
        height: 6,
    };
    let kind = SamplerKind::Sobol;
    let mut cropped = Film::new(24, 16, Some(crop), filter);
    assert_eq!(cropped.full_resolution(), UVec2::new(24, 16));
    assert_eq!(
        cropped.pixel_bounds(),
        (UVec2::new(5, 3), UVec2::new(14, 9))
    );
    render(&mut cropped, 4, true, 4, kind, radiance);
    let mut full = Film::new(24, 16, None, filter);
    render(&mut full, 8, true, 4, kind, radiance);
    let (c, f) = (cropped.develop(), full.develop());
    assert_eq!((c.width, c.height), (9, 6));
    // Pixels farther than the filter's reach (2) from the crop's edges see the same samples
    // as in the full render; the others lack the samples outside the crop (as in Mitsuba).
    for y in 0..6 {
        for x in 0..9 {
            let p = UVec2::new(x + 5, y + 3);
            let (sc, sf) = (cropped.pixel(p).unwrap(), full.pixel(p).unwrap());
            if (2..7).contains(&x) && (2..4).contains(&y) {
                assert_eq!(sc.count, sf.count);
                assert!((sc.weight - sf.weight).abs() <= 1e-12 * sf.weight);
                let (vc, vf) = (c.get(x, y), f.get(p.x, p.y));
                assert!((vc - vf).abs().max_element() <= 1e-6 * vf.abs().max_element());
            } else {
                assert!(sc.count < sf.count && sc.weight < sf.weight, "{p}");
            }
        }
    }
    assert_eq!(cropped.sample_count() + cropped.nonfinite_count(), 54 * 4);
    assert_eq!(cropped.spp_added(), cropped.sample_count() as f64 / 54.0);
    // Tiles requested outside the crop are clipped to it.
    let t = cropped.tile(UVec2::ZERO, UVec2::new(100, 4));
    assert_eq!(t.sample_bounds(), (UVec2::new(5, 3), UVec2::new(14, 4)));
    assert_eq!(t.bounds(), (UVec2::new(5, 3), UVec2::new(14, 6)));
}

#[test]
fn constant_radiance_develops_to_itself_with_any_filter() {
    // Σ w c / Σ w: each w·c is exact in f64 and the sums carry relative errors ~1e-16, so the
    // f32 result rounds to c itself.
    let c = Vec3::new(0.25, 1.0, 4.0);
    for (name, filter) in filters() {
        let mut film = Film::new(6, 5, None, filter);
        render(&mut film, 4, false, 16, SamplerKind::Independent, |_, _| c);
        let (img, err) = (film.develop(), film.develop_stderr());
        for (v, e) in img.pixels.iter().zip(&err.pixels) {
            assert_eq!(*v, c, "{name}");
            assert!((*e / c).max_element() < 1e-5, "{name}: stderr {e}");
        }
    }
}

/// A `w × h` film of `n` samples per pixel at uniform positions with radiance L ~ U[0,1)
/// (σ² = 1/12), independent of the position.
fn uniform_noise_film(filter: Filter, w: u32, h: u32, n: u32, seed: u64) -> Film {
    let mut film = Film::new(w, h, None, filter);
    let (lo, hi) = film.pixel_bounds();
    let mut tile = film.tile(lo, hi);
    let mut rng = Rng(seed);
    for y in 0..h {
        for x in 0..w {
            for _ in 0..n {
                let p = Vec2::new(x as f32 + rng.next_f32(), y as f32 + rng.next_f32());
                tile.add_sample(p, Vec3::splat(rng.next_f32()));
            }
        }
    }
    film.merge(&tile);
    film
}

#[test]
fn stderr_matches_a_known_variance() {
    // Box filter (unit weights, one pixel per sample): over M pixels of n samples, the mean of
    // stderr² = s²/n estimates σ²/n; z-test with Var(s²) = (μ₄ − σ⁴(n−3)/(n−1))/n, μ₄ = 1/80.
    // Coverage of the ±1.96·stderr interval around the true mean 0.5: ≈ 94% for n = 32
    // (Student t with 31 dof), binomial z-test.
    let (w, h, n) = (64u32, 32u32, 32u32);
    let a = sidak(ALPHA, 2);
    let film = uniform_noise_film(Filter::new(&FilterDesc::Box { radius: 0.5 }), w, h, n, 21);
    let (img, err) = (film.develop(), film.develop_stderr());
    let m = (w * h) as f64;
    let nf = n as f64;
    let mean_var: f64 = err.pixels.iter().map(|e| (e.x as f64).powi(2)).sum::<f64>() / m;
    let sigma2 = 1.0 / 12.0;
    let var_s2 = (1.0 / 80.0 - sigma2 * sigma2 * (nf - 3.0) / (nf - 1.0)) / nf;
    let z = (mean_var - sigma2 / nf) / (var_s2.sqrt() / nf / m.sqrt());
    assert!(z.abs() < z_crit(a), "mean stderr² {mean_var}, z = {z:.2}");
    let covered = img
        .pixels
        .iter()
        .zip(&err.pixels)
        .filter(|(v, e)| (v.x - 0.5).abs() <= 1.96 * e.x)
        .count() as f64
        / m;
    let sd = (0.94f64 * 0.06 / m).sqrt();
    assert!(
        (covered - 0.94).abs() < z_crit(a) * sd,
        "coverage {covered:.4}"
    );
}

#[test]
fn film_stderr_adds_up_over_pixels() {
    // Splatted pixels are correlated; develop_stderr² must still add up to the variance of a
    // sum of pixels. K independent films of uniform noise: the spread of the means of their
    // interior (pixels ≥ 3 from the image edges, where develop_stderr underestimates, see the
    // film docs) against the variance predicted from Σ stderr² / N² (two-sided χ² test, K − 1
    // dof). With the per-pixel errors alone the prediction would be F times too small (F = π
    // for the default gaussian, 9 for the r = 1.5 box).
    let (w, h, n, k, margin) = (64u32, 64u32, 4u32, 64usize, 3u32);
    let cases = [
        ("gaussian", Filter::default_gaussian()),
        ("box r=1.5", Filter::new(&FilterDesc::Box { radius: 1.5 })),
        (
            "mitchell",
            Filter::new(&FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
                radius: 2.0,
            }),
        ),
    ];
    let a = sidak(ALPHA, cases.len());
    let chi2 = statrs::distribution::ChiSquared::new((k - 1) as f64).unwrap();
    let (lo, hi) = (chi2.inverse_cdf(a / 2.0), chi2.inverse_cdf(1.0 - a / 2.0));
    let npix = ((w - 2 * margin) * (h - 2 * margin)) as f64;
    let interior = |img: &render::film::Image, f: fn(Vec3) -> f64| -> f64 {
        let mut s = 0.0;
        for y in margin..h - margin {
            for x in margin..w - margin {
                s += f(img.get(x, y));
            }
        }
        s
    };
    for (name, filter) in cases {
        let (mut means, mut predicted) = (Vec::new(), 0.0f64);
        for seed in 0..k {
            let film = uniform_noise_film(filter, w, h, n, 100 + seed as u64);
            means.push(interior(&film.develop(), |v| v.x as f64) / npix);
            let se2 = interior(&film.develop_stderr(), |e| (e.x as f64).powi(2));
            predicted += se2 / (npix * npix) / k as f64;
        }
        let mean = means.iter().sum::<f64>() / k as f64;
        let ss: f64 = means.iter().map(|m| (m - mean).powi(2)).sum();
        let stat = ss / predicted;
        let ratio = stat / (k - 1) as f64;
        println!("{name}: spread/predicted = {ratio:.3}");
        assert!(
            (lo..hi).contains(&stat),
            "{name}: χ² = {stat:.1} outside [{lo:.1}, {hi:.1}] (spread/predicted {ratio:.3})"
        );
    }
}

#[test]
fn nonfinite_samples_are_rejected_and_counted_once() {
    let mut film = Film::new(6, 6, None, Filter::default_gaussian());
    let mut tile = film.tile(UVec2::new(2, 1), UVec2::new(4, 3));
    let p = Vec2::new(2.5, 1.5);
    tile.add_sample(p, Vec3::new(f32::NAN, 0.0, 0.0));
    tile.add_sample(p, Vec3::new(1.0, f32::NEG_INFINITY, 1.0));
    tile.add_sample(Vec2::new(f32::NAN, 1.5), Vec3::ONE);
    tile.add_sample(Vec2::new(2.5, f32::INFINITY), Vec3::ONE);
    tile.add_sample(p, Vec3::new(0.5, 2.0, 3.0));
    assert_eq!((tile.nonfinite_count(), tile.sample_count()), (4, 1));
    film.merge(&tile);
    let mut tile = film.tile(UVec2::ZERO, UVec2::new(1, 1));
    tile.add_sample(Vec2::splat(0.5), Vec3::splat(f32::INFINITY));
    film.merge(&tile);
    assert_eq!(film.nonfinite_count(), 5);
    assert_eq!(film.sample_count(), 1);
    let img = film.develop();
    // The one valid sample reaches the pixels with centres within (−2, 2] of (2.5, 1.5), with
    // weight 0 at offset 2.
    for y in 0..6 {
        for x in 0..6 {
            let reached = (1..=3).contains(&x) && y <= 2;
            let expected = if reached {
                Vec3::new(0.5, 2.0, 3.0)
            } else {
                Vec3::ZERO
            };
            assert_eq!(img.get(x, y), expected, "({x}, {y})");
        }
    }
    assert!(film.develop_stderr().pixels.iter().all(|v| v.is_finite()));
}
