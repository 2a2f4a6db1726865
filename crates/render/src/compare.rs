//! Image comparison against a reference render: relMSE and the block t-test of
//! `shared/references/README.md`, whose executable definition is `shared/references/imgcmp.py`.
//! This module computes the same figures as that script (checked to 4+ significant digits by
//! `tests/it/compare.rs`).
//!
//! A **reference** is a mean image and its per-pixel standard error (`NAME.exr`,
//! `NAME.stderr.exr`), made from [`CompareOptions::reference_batches`] (32) independent batches.
//! A **test render** is either K ≥ 2 independent batch images of equal spp (different seeds), or
//! one mean image with its per-pixel standard error (from per-sample second moments).
//!
//! 1. **relMSE** of the test mean: the mean over pixels and channels of
//!    (test − ref)² / (ref² + 0.01).
//! 2. **Block t-test** (bias). Both images are averaged over `block`×`block` pixel blocks; when
//!    the size is not a multiple of the block size the incomplete blocks at the right and
//!    bottom edges are dropped (as imgcmp.py's reshape does). Per block and channel:
//!    - test variance v₁ = se_test²: with K batches, the sample variance (K − 1 denominator) of
//!      the K per-batch block means divided by K; with a stderr image, the mean of the pixel
//!      stderr² over the block divided by block² (pixel errors taken as independent, exactly
//!      as on the reference side);
//!    - reference variance v₂ = (mean of pixel stderr² over the block) / block² plus the
//!      floor (0.001·|ref block|)² + (1e-5)², so that float rounding in near-constant regions
//!      is never a finding;
//!    - t = (test − ref) / √(v₁ + v₂), with Welch–Satterthwaite degrees of freedom
//!      ν = (v₁ + v₂)² / (v₁²/ν₁ + v₂²/ν₂ + 1e-300), ν₁ = max(K − 1, 1), ν₂ = 31 (reference
//!      batches − 1), and the two-sided p = 2·P(T_max(ν, 1) > |t|).
//!
//!    imgcmp.py has no one-image-with-stderr case. We define it consistently: the test
//!    variance comes from the stderr image as above and the test side has infinite degrees of
//!    freedom (ν₁ = ∞, so its term vanishes from the denominator): a per-pixel second-moment
//!    estimate pools every sample of the block's pixels (block² × spp − 1 degrees of freedom),
//!    which is effectively infinite next to the reference's 31.
//!
//!    The test **passes** when the smallest p-value over all block-channels is at least the
//!    Šidák-corrected level 1 − (1 − α)^(1/m), α = 0.01, m = number of block-channels; i.e.
//!    a correct renderer fails with probability α per comparison.
//! 3. Noise parity (relMSE at 256 spp against Mitsuba's figure) is the caller's business: it
//!    needs only [`rel_mse`] / [`Comparison::rel_mse`].

use std::ffi::OsString;
use std::fmt;
use std::path::{Path, PathBuf};

use statrs::distribution::{ContinuousCDF, StudentsT};

use crate::film::Image;
use crate::image_io::{ImageError, read_image};

/// Parameters of the comparison (imgcmp.py's `--block`, `--alpha` and `REF_BATCHES`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompareOptions {
    /// Block edge in pixels (8).
    pub block: u32,
    /// Family-wise significance level (0.01).
    pub alpha: f64,
    /// Independent batches behind the reference's stderr (32), giving it 31 degrees of freedom.
    pub reference_batches: u32,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            block: 8,
            alpha: 0.01,
            reference_batches: 32,
        }
    }
}

/// Why a comparison could not be made. (A render that merely differs is not an error: it is a
/// [`Comparison`] with `passed == false`.)
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Image(#[from] ImageError),
    #[error(
        "{what} is {width}x{height} ({pixels} pixels stored), expected {expected_width}x{expected_height}"
    )]
    SizeMismatch {
        what: String,
        width: u32,
        height: u32,
        pixels: usize,
        expected_width: u32,
        expected_height: u32,
    },
    #[error("{what} has a non-finite value at pixel ({x}, {y})")]
    NonFinite { what: String, x: u32, y: u32 },
    #[error("the test needs at least 2 independent batch images, got {0}")]
    TooFewBatches(usize),
    #[error("a {width}x{height} image has no complete {block}x{block} block")]
    TooSmall { width: u32, height: u32, block: u32 },
    #[error("invalid comparison options: {0}")]
    Options(&'static str),
}

/// A reference render: mean image and per-pixel standard error of that mean.
#[derive(Clone, Debug)]
pub struct Reference {
    pub mean: Image,
    pub stderr: Image,
}

impl Reference {
    /// The mean of K ≥ 2 independent batch images of equal spp and the standard error of
    /// that mean (spread of the batch means / √K), as the shared references were made.
    pub fn from_batches(batches: &[Image]) -> Result<Reference, CompareError> {
        if batches.len() < 2 {
            return Err(CompareError::TooFewBatches(batches.len()));
        }
        let (w, h) = (batches[0].width, batches[0].height);
        for (i, b) in batches.iter().enumerate() {
            check_image(b, &format!("batch {i}"), w, h)?;
        }
        let k = batches.len() as f64;
        let mut mean = Image::new(w, h);
        let mut stderr = Image::new(w, h);
        for i in 0..mean.pixels.len() {
            for c in 0..3 {
                let m = batches.iter().map(|b| b.pixels[i][c] as f64).sum::<f64>() / k;
                let var = batches
                    .iter()
                    .map(|b| (b.pixels[i][c] as f64 - m).powi(2))
                    .sum::<f64>()
                    / (k - 1.0);
                mean.pixels[i][c] = m as f32;
                stderr.pixels[i][c] = (var / k).sqrt() as f32;
            }
        }
        Ok(Reference { mean, stderr })
    }

    /// Checks that both images have the same consistent size and only finite values.
    pub fn validate(&self) -> Result<(), CompareError> {
        check_image(
            &self.mean,
            "reference mean",
            self.mean.width,
            self.mean.height,
        )?;
        check_image(
            &self.stderr,
            "reference stderr",
            self.mean.width,
            self.mean.height,
        )
    }
}

/// Loads `PREFIX.exr` and `PREFIX.stderr.exr`. `prefix_or_path` may be the prefix itself
/// (`refs/lights`) or the path of either file (`refs/lights.exr`, `refs/lights.stderr.exr`).
pub fn load_reference(prefix_or_path: &Path) -> Result<Reference, CompareError> {
    let s = prefix_or_path.as_os_str().to_string_lossy();
    let prefix: PathBuf = match s
        .strip_suffix(".stderr.exr")
        .or_else(|| s.strip_suffix(".exr"))
    {
        Some(p) => PathBuf::from(p),
        None => prefix_or_path.to_path_buf(),
    };
    let with = |suffix: &str| {
        let mut p = OsString::from(prefix.as_os_str());
        p.push(suffix);
        PathBuf::from(p)
    };
    let reference = Reference {
        mean: read_image(&with(".exr"))?,
        stderr: read_image(&with(".stderr.exr"))?,
    };
    reference.validate()?;
    Ok(reference)
}

/// The render under test.
#[derive(Clone, Debug)]
pub enum TestImages {
    /// K ≥ 2 independent renders (different seeds, equal spp) of the same scene.
    Batches(Vec<Image>),
    /// One render and the per-pixel standard error of its mean (from per-sample second
    /// moments); its test side has infinite degrees of freedom (see the module docs).
    MeanStderr { mean: Image, stderr: Image },
}

impl TestImages {
    /// Reads K batch images.
    pub fn load_batches<P: AsRef<Path>>(paths: &[P]) -> Result<TestImages, CompareError> {
        let images = paths
            .iter()
            .map(|p| read_image(p.as_ref()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(TestImages::Batches(images))
    }
}

/// The block-channel with the smallest p-value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorstBlock {
    /// Top-left pixel of the block.
    pub x: u32,
    pub y: u32,
    /// 0, 1, 2 = R, G, B.
    pub channel: usize,
    /// Block means of the test and the reference.
    pub test: f64,
    pub reference: f64,
    /// Welch's t statistic, its degrees of freedom and two-sided p-value.
    pub t: f64,
    pub dof: f64,
    pub p: f64,
}

/// The outcome of [`compare`].
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// relMSE of the test mean image against the reference mean.
    pub rel_mse: f64,
    /// Per-channel image mean of the test over that of the reference (denominator ≥ 1e-9).
    pub mean_ratio: [f64; 3],
    /// Smallest p-value over all block-channels (= `worst.p`).
    pub min_p: f64,
    /// The Šidák-corrected per-test level 1 − (1 − α)^(1/block_channels).
    pub threshold: f64,
    /// `min_p >= threshold`.
    pub passed: bool,
    /// Number of block-channel t-tests.
    pub block_channels: usize,
    pub worst: WorstBlock,
    /// Degrees of freedom of the test side: K − 1, or ∞ for a mean + stderr input.
    pub test_dof: f64,
}

impl fmt::Display for Comparison {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = &self.worst;
        write!(
            f,
            "{} relMSE={:.4e} worst |t|={:.2} at block ({}, {}) {} (dof {:.1}) \
             p_min={:.2e} (Šidák threshold {:.2e}, {} block-channels) \
             mean ratio RGB=[{:.4}, {:.4}, {:.4}]",
            if self.passed { "PASS" } else { "FAIL" },
            self.rel_mse,
            w.t.abs(),
            w.x,
            w.y,
            ["R", "G", "B"][w.channel.min(2)],
            w.dof,
            self.min_p,
            self.threshold,
            self.block_channels,
            self.mean_ratio[0],
            self.mean_ratio[1],
            self.mean_ratio[2],
        )
    }
}

/// relMSE of `test` against `reference`: mean over pixels and channels of
/// (test − ref)² / (ref² + 0.01), in f64.
pub fn rel_mse(test: &Image, reference: &Image) -> Result<f64, CompareError> {
    check_image(reference, "reference", reference.width, reference.height)?;
    check_image(test, "test image", reference.width, reference.height)?;
    let mean: Vec<[f64; 3]> = test.pixels.iter().map(|p| widen(p.to_array())).collect();
    Ok(rel_mse_f64(&mean, reference))
}

/// Mean of `image` over pixels and channels, and its standard error from the film's
/// standard-error image (`Film::develop_stderr`, scaled so that squares add over pixels).
/// For analytic checks of a whole image (furnaces, cut-outs).
pub fn image_mean(image: &Image, stderr: &Image) -> (f64, f64) {
    let n = image.pixels.len().max(1) as f64;
    let channel_mean = |p: &crate::math::Vec3| p.element_sum() as f64 / 3.0;
    let mean = image.pixels.iter().map(channel_mean).sum::<f64>() / n;
    let var = stderr
        .pixels
        .iter()
        .map(|s| channel_mean(s).powi(2))
        .sum::<f64>()
        / (n * n);
    (mean, var.sqrt())
}

/// Compares a test render with a reference using the default options.
pub fn compare(reference: &Reference, test: &TestImages) -> Result<Comparison, CompareError> {
    compare_with(reference, test, &CompareOptions::default())
}

/// Compares a test render with a reference.
pub fn compare_with(
    reference: &Reference,
    test: &TestImages,
    options: &CompareOptions,
) -> Result<Comparison, CompareError> {
    let bs = options.block;
    if bs == 0 {
        return Err(CompareError::Options("block size must be at least 1"));
    }
    if !(options.alpha > 0.0 && options.alpha < 1.0) {
        return Err(CompareError::Options("alpha must be in (0, 1)"));
    }
    if options.reference_batches < 2 {
        return Err(CompareError::Options(
            "reference_batches must be at least 2",
        ));
    }
    reference.validate()?;
    let (w, h) = (reference.mean.width, reference.mean.height);
    let (bw, bh) = (w / bs, h / bs);
    if bw == 0 || bh == 0 {
        return Err(CompareError::TooSmall {
            width: w,
            height: h,
            block: bs,
        });
    }
    let n_pix = w as usize * h as usize;
    let inv_b2 = 1.0 / (bs as f64 * bs as f64);

    // Test mean image, block means and block variances of the mean.
    let (mean, m_blk, v_test, test_dof) = match test {
        TestImages::Batches(batches) => {
            let k = batches.len();
            if k < 2 {
                return Err(CompareError::TooFewBatches(k));
            }
            for (i, b) in batches.iter().enumerate() {
                check_image(b, &format!("test batch {i}"), w, h)?;
            }
            let mut mean = vec![[0.0f64; 3]; n_pix];
            for b in batches {
                for (m, p) in mean.iter_mut().zip(&b.pixels) {
                    for c in 0..3 {
                        m[c] += p[c] as f64;
                    }
                }
            }
            for m in &mut mean {
                *m = m.map(|v| v / k as f64);
            }
            let per_batch: Vec<Vec<[f64; 3]>> = batches
                .iter()
                .map(|b| block_mean(w, h, bs, |i| widen(b.pixels[i].to_array())))
                .collect();
            let nb = per_batch[0].len();
            let mut m_blk = vec![[0.0; 3]; nb];
            let mut v_test = vec![[0.0; 3]; nb];
            for j in 0..nb {
                for c in 0..3 {
                    let mu = per_batch.iter().map(|b| b[j][c]).sum::<f64>() / k as f64;
                    let ss = per_batch
                        .iter()
                        .map(|b| (b[j][c] - mu) * (b[j][c] - mu))
                        .sum::<f64>();
                    m_blk[j][c] = mu;
                    // (sample std / √K)², sample std with K − 1 in the denominator.
                    v_test[j][c] = ss / (k - 1) as f64 / k as f64;
                }
            }
            (mean, m_blk, v_test, (k - 1) as f64)
        }
        TestImages::MeanStderr {
            mean: m,
            stderr: se,
        } => {
            check_image(m, "test mean", w, h)?;
            check_image(se, "test stderr", w, h)?;
            let mean: Vec<[f64; 3]> = m.pixels.iter().map(|p| widen(p.to_array())).collect();
            let m_blk = block_mean(w, h, bs, |i| mean[i]);
            let v_test = block_mean(w, h, bs, |i| widen(se.pixels[i].to_array()).map(|s| s * s))
                .into_iter()
                .map(|v| v.map(|v| v * inv_b2))
                .collect();
            (mean, m_blk, v_test, f64::INFINITY)
        }
    };

    let rel_mse = rel_mse_f64(&mean, &reference.mean);

    let r_blk = block_mean(w, h, bs, |i| widen(reference.mean.pixels[i].to_array()));
    let r_var = block_mean(w, h, bs, |i| {
        widen(reference.stderr.pixels[i].to_array()).map(|s| s * s)
    });
    let ref_dof = (options.reference_batches - 1) as f64;
    let test_dof_term = test_dof.max(1.0);

    let mut worst: Option<WorstBlock> = None;
    for (j, ((m, r), (vt, vr))) in m_blk
        .iter()
        .zip(&r_blk)
        .zip(v_test.iter().zip(&r_var))
        .enumerate()
    {
        for c in 0..3 {
            let v1 = vt[c];
            let floor = 1e-3 * r[c].abs();
            let v2 = vr[c] * inv_b2 + floor * floor + 1e-10;
            let t = (m[c] - r[c]) / (v1 + v2).sqrt();
            let dof =
                (v1 + v2) * (v1 + v2) / (v1 * v1 / test_dof_term + v2 * v2 / ref_dof + 1e-300);
            let p = two_sided_p(t, dof.max(1.0));
            // Strictly smaller: the first minimum in row-major block order, as numpy's argmin.
            if worst.is_none_or(|wb| p < wb.p) {
                worst = Some(WorstBlock {
                    x: (j as u32 % bw) * bs,
                    y: (j as u32 / bw) * bs,
                    channel: c,
                    test: m[c],
                    reference: r[c],
                    t,
                    dof,
                    p,
                });
            }
        }
    }
    let worst = worst.ok_or(CompareError::TooSmall {
        width: w,
        height: h,
        block: bs,
    })?;

    let block_channels = m_blk.len() * 3;
    // 1 − (1 − α)^(1/m) without cancellation.
    let threshold = -((1.0 - options.alpha).ln() / block_channels as f64).exp_m1();

    let mut test_sum = [0.0f64; 3];
    let mut ref_sum = [0.0f64; 3];
    for (m, r) in mean.iter().zip(&reference.mean.pixels) {
        for c in 0..3 {
            test_sum[c] += m[c];
            ref_sum[c] += r[c] as f64;
        }
    }
    let mean_ratio = std::array::from_fn(|c| {
        (test_sum[c] / n_pix as f64) / (ref_sum[c] / n_pix as f64).max(1e-9)
    });

    Ok(Comparison {
        rel_mse,
        mean_ratio,
        min_p: worst.p,
        threshold,
        passed: worst.p >= threshold,
        block_channels,
        worst,
        test_dof,
    })
}

/// Above this many degrees of freedom Student's t is replaced by the normal distribution.
/// statrs evaluates the t tail as I_h(ν/2, 1/2) with h = ν/(ν + t²) rounded to f64, which loses
/// about ν·ε relative precision (2e-3 at ν = 1e12); the normal tail differs from the t tail by
/// about t⁴/(4ν) relatively. At the cut-off both are ≲ 3e-7 for the |t| ≲ 8 that decide
/// a test. Only the mean + stderr input reaches such ν: with K batches ν ≤ K − 1 + 31.
const NORMAL_DOF: f64 = 2e9;

/// Two-sided p-value of Student's t with `dof` ≥ 1 degrees of freedom (∞ allowed).
fn two_sided_p(t: f64, dof: f64) -> f64 {
    let dof = if dof > NORMAL_DOF { f64::INFINITY } else { dof };
    match StudentsT::new(0.0, 1.0, dof) {
        Ok(d) if t.is_finite() => (2.0 * d.sf(t.abs())).min(1.0),
        // Unreachable for validated (finite) inputs; a malformed statistic is a finding.
        _ => 0.0,
    }
}

fn widen(p: [f32; 3]) -> [f64; 3] {
    p.map(f64::from)
}

fn rel_mse_f64(test: &[[f64; 3]], reference: &Image) -> f64 {
    let sum: f64 = test
        .iter()
        .zip(&reference.pixels)
        .map(|(t, r)| {
            (0..3)
                .map(|c| {
                    let r = r[c] as f64;
                    (t[c] - r) * (t[c] - r) / (r * r + 0.01)
                })
                .sum::<f64>()
        })
        .sum();
    sum / (3 * test.len()) as f64
}

/// Means over complete `bs`×`bs` blocks (row-major over blocks); partial blocks at the right
/// and bottom edges are dropped. `px(i)` gives the value of pixel `i = y·w + x`.
fn block_mean(w: u32, h: u32, bs: u32, px: impl Fn(usize) -> [f64; 3]) -> Vec<[f64; 3]> {
    let (bw, bh, bs) = ((w / bs) as usize, (h / bs) as usize, bs as usize);
    let inv = 1.0 / (bs * bs) as f64;
    let mut out = vec![[0.0; 3]; bw * bh];
    for (j, o) in out.iter_mut().enumerate() {
        let (x0, y0) = ((j % bw) * bs, (j / bw) * bs);
        for y in y0..y0 + bs {
            for x in x0..x0 + bs {
                let v = px(y * w as usize + x);
                for c in 0..3 {
                    o[c] += v[c];
                }
            }
        }
        *o = o.map(|v| v * inv);
    }
    out
}

fn check_image(img: &Image, what: &str, width: u32, height: u32) -> Result<(), CompareError> {
    if img.width != width
        || img.height != height
        || img.pixels.len() != width as usize * height as usize
    {
        return Err(CompareError::SizeMismatch {
            what: what.to_string(),
            width: img.width,
            height: img.height,
            pixels: img.pixels.len(),
            expected_width: width,
            expected_height: height,
        });
    }
    if let Some(i) = img.pixels.iter().position(|p| !p.is_finite()) {
        return Err(CompareError::NonFinite {
            what: what.to_string(),
            x: (i % width as usize) as u32,
            y: (i / width as usize) as u32,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    #[test]
    fn reference_from_batches_is_mean_and_stderr_of_the_mean() {
        // Batch values 1, 2, 6: mean 3, sample variance 7, stderr √(7/3).
        let batches: Vec<Image> = [1.0, 2.0, 6.0].map(|v| constant(8, 8, v)).into();
        let r = Reference::from_batches(&batches).unwrap();
        assert!((r.mean.pixels[0].x - 3.0).abs() < 1e-6);
        assert!((r.stderr.pixels[63].z - (7.0f32 / 3.0).sqrt()).abs() < 1e-6);
        assert!(matches!(
            Reference::from_batches(&batches[..1]),
            Err(CompareError::TooFewBatches(1))
        ));
    }

    fn constant(w: u32, h: u32, v: f32) -> Image {
        let mut img = Image::new(w, h);
        img.pixels.fill(Vec3::splat(v));
        img
    }

    #[test]
    fn block_mean_drops_partial_blocks() {
        // 10×9 image, 4×4 blocks: 2×2 complete blocks; the value is x + 100 y.
        let b = block_mean(10, 9, 4, |i| [(i % 10) as f64 + 100.0 * (i / 10) as f64; 3]);
        assert_eq!(b.len(), 4);
        assert_eq!(b[0][0], 1.5 + 150.0);
        assert_eq!(b[1][0], 5.5 + 150.0);
        assert_eq!(b[2][0], 1.5 + 550.0);
    }

    #[test]
    fn p_values_match_closed_forms() {
        // ν = 1 is Cauchy: p = 1 − 2 atan(t)/π.
        for t in [0.5, 1.0, 3.0, 100.0] {
            let p = 1.0 - 2.0 * f64::atan(t) / std::f64::consts::PI;
            assert!((two_sided_p(t, 1.0) - p).abs() < 1e-12 * p.max(1e-3));
        }
        // ν = 2: p = 1 − t/√(2 + t²).
        for t in [0.5f64, 2.0, 10.0] {
            let p = 1.0 - t / (2.0 + t * t).sqrt();
            assert!((two_sided_p(-t, 2.0) - p).abs() < 1e-12);
        }
        assert_eq!(two_sided_p(0.0, 5.0), 1.0);
    }

    #[test]
    fn p_values_match_scipy_including_huge_dof() {
        // 2·scipy.stats.t.sf(t, ν) (scipy 1.17.1).
        let table = [
            (0.3, 1.0, 8.144528418445154e-01),
            (2.5, 1.0, 2.422378831816868e-01),
            (25.0, 1.0, 2.545122269598366e-02),
            (0.3, 3.5, 7.811334098398895e-01),
            (7.0, 3.5, 3.552836199804264e-03),
            (25.0, 3.5, 4.519902762129363e-05),
            (2.5, 31.0, 1.792022681338621e-02),
            (7.0, 31.0, 7.40344257184903e-8),
            (25.0, 31.0, 4.137286666288182e-22),
            (0.3, 1e4, 7.641833912293323e-01),
            (7.0, 1e4, 2.724031560679831e-12),
            (25.0, 1e4, 7.443343762919511e-134),
            (2.5, 1e8, 1.241933224005455e-02),
            (7.0, 1e8, 2.559641073577134e-12),
            (25.0, 1e8, 6.11938552254733e-138),
            (0.3, 1e12, 7.641771556221572e-01),
            (7.0, 1e12, 2.559625089370258e-12),
            (25.0, 1e12, 6.113394011684949e-138),
        ];
        for (t, dof, p) in table {
            let ours = two_sided_p(t, dof);
            // Exact to rounding where batch inputs can reach (ν ≤ K + 30); see NORMAL_DOF.
            let tol = if dof <= 1e4 { 1e-11 } else { 1e-6 };
            assert!(
                (ours - p).abs() <= tol * p,
                "t={t} ν={dof}: {ours:e} vs {p:e}"
            );
        }
    }

    #[test]
    fn sidak_threshold_matches_the_direct_formula() {
        let r = Reference {
            mean: constant(16, 16, 0.5),
            stderr: constant(16, 16, 0.01),
        };
        let c = compare(
            &r,
            &TestImages::Batches(vec![r.mean.clone(), r.mean.clone()]),
        )
        .unwrap();
        assert_eq!(c.block_channels, 12);
        let direct = 1.0 - 0.99f64.powf(1.0 / 12.0);
        assert!((c.threshold - direct).abs() < 1e-15);
        assert!(c.passed && c.min_p == 1.0 && c.rel_mse == 0.0);
    }

    #[test]
    fn malformed_inputs_are_errors() {
        let r = Reference {
            mean: constant(16, 16, 0.5),
            stderr: constant(16, 16, 0.01),
        };
        let one = TestImages::Batches(vec![r.mean.clone()]);
        assert!(matches!(
            compare(&r, &one),
            Err(CompareError::TooFewBatches(1))
        ));
        let wrong = TestImages::Batches(vec![constant(8, 16, 0.5), constant(8, 16, 0.5)]);
        assert!(matches!(
            compare(&r, &wrong),
            Err(CompareError::SizeMismatch { .. })
        ));
        let mut nan = r.mean.clone();
        nan.set(3, 2, Vec3::new(0.0, f32::NAN, 0.0));
        let e = compare(&r, &TestImages::Batches(vec![nan, r.mean.clone()])).unwrap_err();
        assert!(e.to_string().contains("(3, 2)"), "{e}");
        let tiny = Reference {
            mean: constant(7, 7, 0.5),
            stderr: constant(7, 7, 0.01),
        };
        let t = TestImages::Batches(vec![tiny.mean.clone(), tiny.mean.clone()]);
        assert!(matches!(
            compare(&tiny, &t),
            Err(CompareError::TooSmall { .. })
        ));
        assert!(rel_mse(&constant(2, 2, 1.0), &constant(2, 3, 1.0)).is_err());
    }
}
