//! Statistical tests used by the test suite and by `penumbra test` (Nori's `chi2test` and
//! `ttest` files): a χ² goodness-of-fit test of a sampling routine against its density, over
//! the sphere of directions or over a planar rectangle, and Student's t-test.
//!
//! χ² test, after Nori / Mitsuba: the domain is cut into equal-measure cells (on the sphere:
//! `res` bins in cos θ × `2·res` bins in φ, so every cell has solid angle 2π/res²·…); the
//! expected count of a cell is `sample_count ×` the integral of the density over it, computed
//! by nested adaptive Simpson quadrature; cells whose expected count is below
//! `min_exp_frequency` are pooled (in increasing order of expectation) until the pool reaches
//! it; an observed sample in a cell of zero expectation fails the test outright. The p-value
//! comes from the χ² distribution with (cells − 1) degrees of freedom. The test also checks
//! that the density integrates to the fraction of calls that produced a sample (a sampler
//! that fails silently, or a density that is not normalised, is caught even where χ² is
//! weak).

use crate::math::{Vec2, Vec3};
use statrs::distribution::{ChiSquared, ContinuousCDF, StudentsT};
use std::f64::consts::PI;

/// PCG32 (O'Neill 2014, XSH-RR output): a tiny deterministic generator for the tests.
#[derive(Clone, Copy, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MULT: u64 = 6_364_136_223_846_793_005;

    pub fn new(seed: u64, stream: u64) -> Pcg32 {
        let mut r = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1) with 24 bits of resolution.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in [0, 1) with 53 bits of resolution.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() >> 5) as u64;
        let lo = (self.next_u32() >> 6) as u64;
        ((hi << 26) | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    #[inline]
    pub fn next_vec2(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

/// Parameters of a χ² test.
#[derive(Clone, Debug)]
pub struct Chi2Config {
    /// Cells per unit dimension: `res` × `2·res` on the sphere, `res` × `res` on a rectangle.
    pub res: u32,
    /// Calls of the sampling routine.
    pub sample_count: u64,
    /// Cells with a smaller expected count are pooled (Nori / Mitsuba use 5).
    pub min_exp_frequency: f64,
    /// Rejection level for the null hypothesis (already corrected for multiple tests).
    pub significance: f64,
    pub seed: u64,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Chi2Config {
            res: 10,
            sample_count: 100_000,
            min_exp_frequency: 5.0,
            significance: 0.01,
            seed: 0,
        }
    }
}

/// Outcome of a χ² test.
#[derive(Clone, Debug)]
pub struct Chi2Result {
    pub statistic: f64,
    pub dof: u32,
    pub p_value: f64,
    pub passed: bool,
    /// Human-readable summary (why it failed, or the figures when it passed).
    pub message: String,
}

/// Šidák-corrected per-test significance so that `n_tests` tests together reject a true null
/// hypothesis with probability `alpha`.
pub fn sidak(alpha: f64, n_tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / n_tests.max(1) as f64)
}

/// χ² test of a direction sampler over the sphere. `sample(u2, u1)` maps uniform variates to a
/// unit direction, or `None` when it produces no sample (e.g. a delta lobe or a failure); `pdf`
/// is its solid-angle density. Cells are `res` bins in cos θ × `2·res` bins in φ.
pub fn chi2_test(
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
    cfg: &Chi2Config,
) -> Chi2Result {
    let res = cfg.res.max(1) as usize;
    let grid = Grid {
        nx: res,
        ny: 2 * res,
        x0: -1.0,
        x1: 1.0,
        y0: 0.0,
        y1: 2.0 * PI,
    };
    let mut rng = Pcg32::new(cfg.seed, 0x5eed_c412);
    let sampler = |rng: &mut Pcg32| -> SampleOutcome {
        let u2 = rng.next_vec2();
        let u1 = rng.next_f32();
        match sample(u2, u1) {
            None => SampleOutcome::None,
            Some(w) => {
                let len = w.length();
                if !len.is_finite() || (len - 1.0).abs() > 1e-3 {
                    return SampleOutcome::Invalid(format!("non-unit direction {w}"));
                }
                let z = (w.z as f64 / len as f64).clamp(-1.0, 1.0);
                let mut phi = (w.y as f64).atan2(w.x as f64);
                if phi < 0.0 {
                    phi += 2.0 * PI;
                }
                SampleOutcome::Point(z, phi)
            }
        }
    };
    // Integrate over each cell in (θ, φ) with the Jacobian sin θ: smooth at the poles, where
    // the (cos θ, φ) parametrisation has a square-root singularity that defeats Simpson.
    let density = |theta: f64, phi: f64| -> f64 {
        let (s, z) = theta.sin_cos();
        let w = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
        pdf(w) as f64 * s
    };
    let cell_integral = |ix: usize, iy: usize, eps: f64, depth: u32| -> f64 {
        let (z0, z1) = grid.x_range(ix);
        let (p0, p1) = grid.y_range(iy);
        let (t0, t1) = (z1.clamp(-1.0, 1.0).acos(), z0.clamp(-1.0, 1.0).acos());
        // Stay a hair inside the cell so that a density discontinuous across a cell edge (the
        // horizon) is evaluated on the correct side.
        let inset = 1e-7 * (t1 - t0);
        integrate_2d(&density, t0 + inset, t1 - inset, p0, p1, eps, depth)
    };
    run_chi2(&grid, &mut rng, sampler, cell_integral, cfg)
}

/// χ² test of a sampler of points in the rectangle `[lo, hi]` against its area density, on a
/// `res × res` grid. `sample(u2, u1)` returns a point or `None`.
pub fn chi2_test_2d(
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec2>,
    pdf: impl Fn(Vec2) -> f32,
    lo: Vec2,
    hi: Vec2,
    cfg: &Chi2Config,
) -> Chi2Result {
    let res = cfg.res.max(1) as usize;
    let grid = Grid {
        nx: res,
        ny: res,
        x0: lo.x as f64,
        x1: hi.x as f64,
        y0: lo.y as f64,
        y1: hi.y as f64,
    };
    let mut rng = Pcg32::new(cfg.seed, 0x5eed_2d2d);
    let sampler = |rng: &mut Pcg32| -> SampleOutcome {
        let u2 = rng.next_vec2();
        let u1 = rng.next_f32();
        match sample(u2, u1) {
            None => SampleOutcome::None,
            Some(p) if p.is_finite() => SampleOutcome::Point(p.x as f64, p.y as f64),
            Some(p) => SampleOutcome::Invalid(format!("non-finite point {p}")),
        }
    };
    let density = |x: f64, y: f64| pdf(Vec2::new(x as f32, y as f32)) as f64;
    let cell_integral = |ix: usize, iy: usize, eps: f64, depth: u32| -> f64 {
        let (x0, x1) = grid.x_range(ix);
        let (y0, y1) = grid.y_range(iy);
        let (ix_, iy_) = (1e-7 * (x1 - x0), 1e-7 * (y1 - y0));
        integrate_2d(&density, x0 + ix_, x1 - ix_, y0 + iy_, y1 - iy_, eps, depth)
    };
    run_chi2(&grid, &mut rng, sampler, cell_integral, cfg)
}

enum SampleOutcome {
    None,
    Point(f64, f64),
    Invalid(String),
}

struct Grid {
    nx: usize,
    ny: usize,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Grid {
    fn x_range(&self, ix: usize) -> (f64, f64) {
        let d = (self.x1 - self.x0) / self.nx as f64;
        (self.x0 + ix as f64 * d, self.x0 + (ix + 1) as f64 * d)
    }

    fn y_range(&self, iy: usize) -> (f64, f64) {
        let d = (self.y1 - self.y0) / self.ny as f64;
        (self.y0 + iy as f64 * d, self.y0 + (iy + 1) as f64 * d)
    }

    fn cell(&self, x: f64, y: f64) -> Option<usize> {
        let fx = (x - self.x0) / (self.x1 - self.x0) * self.nx as f64;
        let fy = (y - self.y0) / (self.y1 - self.y0) * self.ny as f64;
        let eps = 1e-6;
        if !(fx >= -eps && fx <= self.nx as f64 + eps && fy >= -eps && fy <= self.ny as f64 + eps) {
            return None;
        }
        let ix = (fx.max(0.0) as usize).min(self.nx - 1);
        let iy = (fy.max(0.0) as usize).min(self.ny - 1);
        Some(iy * self.nx + ix)
    }
}

fn fail(message: String) -> Chi2Result {
    Chi2Result {
        statistic: f64::INFINITY,
        dof: 0,
        p_value: 0.0,
        passed: false,
        message,
    }
}

fn run_chi2(
    grid: &Grid,
    rng: &mut Pcg32,
    mut sampler: impl FnMut(&mut Pcg32) -> SampleOutcome,
    cell_integral: impl Fn(usize, usize, f64, u32) -> f64,
    cfg: &Chi2Config,
) -> Chi2Result {
    let n_cells = grid.nx * grid.ny;
    let n = cfg.sample_count.max(1);
    let mut observed = vec![0u64; n_cells];
    let mut successes = 0u64;
    for _ in 0..n {
        match sampler(rng) {
            SampleOutcome::None => {}
            SampleOutcome::Invalid(msg) => return fail(format!("invalid sample: {msg}")),
            SampleOutcome::Point(x, y) => match grid.cell(x, y) {
                Some(c) => {
                    observed[c] += 1;
                    successes += 1;
                }
                None => return fail(format!("sample ({x}, {y}) outside the domain")),
            },
        }
    }

    // Expected counts by nested adaptive Simpson quadrature over each cell.
    let mut expected = vec![0.0f64; n_cells];
    let mut total = 0.0;
    for iy in 0..grid.ny {
        for ix in 0..grid.nx {
            // Tolerance: 1 % of the Poisson standard deviation of the cell's count, from a
            // coarse estimate of its probability.
            let coarse = cell_integral(ix, iy, 0.0, 0).abs();
            let eps = 0.01 * (coarse.max(1.0 / n as f64) / n as f64).sqrt();
            let integral = cell_integral(ix, iy, eps, 11);
            if !integral.is_finite() || integral < 0.0 {
                return fail(format!(
                    "density integral over cell ({ix}, {iy}) is {integral}"
                ));
            }
            total += integral;
            expected[iy * grid.nx + ix] = integral * n as f64;
        }
    }

    // The density must integrate to the fraction of calls that produced a sample.
    let frac = successes as f64 / n as f64;
    let tol = 5e-3 + 5.0 * (frac * (1.0 - frac) / n as f64).sqrt();
    if (total - frac).abs() > tol {
        return fail(format!(
            "the density integrates to {total:.5} but {frac:.5} of the calls produced a sample"
        ));
    }

    // Pool small cells (in increasing order of expectation) and accumulate the statistic.
    let mut order: Vec<usize> = (0..n_cells).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pool_obs, mut pool_exp) = (0.0f64, 0.0f64);
    let mut statistic = 0.0f64;
    let mut cells = 0u32;
    for &c in &order {
        let (o, e) = (observed[c] as f64, expected[c]);
        if e == 0.0 {
            if o > 0.0 {
                return fail(format!(
                    "{o} samples in cell {c} where the density integrates to zero"
                ));
            }
        } else if e < cfg.min_exp_frequency || (pool_exp > 0.0 && pool_exp < cfg.min_exp_frequency)
        {
            pool_obs += o;
            pool_exp += e;
        } else {
            statistic += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pool_exp > 0.0 {
        statistic += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        cells += 1;
    }
    if cells < 2 {
        return Chi2Result {
            statistic,
            dof: 0,
            p_value: 1.0,
            passed: true,
            message: "fewer than two cells after pooling: nothing to test".into(),
        };
    }
    let dof = cells - 1;
    let p_value = ChiSquared::new(dof as f64)
        .map(|d| d.sf(statistic))
        .unwrap_or(0.0);
    let passed = p_value >= cfg.significance;
    let message = format!(
        "chi2 = {statistic:.2}, dof = {dof}, p = {p_value:.4e} ({} at significance {:.3e}); \
         density integral {total:.5}, sample fraction {frac:.5}",
        if passed { "accepted" } else { "rejected" },
        cfg.significance
    );
    Chi2Result {
        statistic,
        dof,
        p_value,
        passed,
        message,
    }
}

/// ∫∫ f over [x0, x1] × [y0, y1] by two-dimensional adaptive Simpson quadrature (absolute
/// tolerance `eps`): a rectangle's 3×3 tensor Simpson rule is compared with the sum of its
/// four quadrants' rules, and quadrants are refined until they agree. Every cell is split at
/// least twice so that narrow features between the first nodes are seen.
fn integrate_2d(
    f: &impl Fn(f64, f64) -> f64,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    eps: f64,
    max_depth: u32,
) -> f64 {
    let mut v = [[0.0f64; 3]; 3];
    for (j, row) in v.iter_mut().enumerate() {
        for (i, e) in row.iter_mut().enumerate() {
            *e = f(
                x0 + 0.5 * i as f64 * (x1 - x0),
                y0 + 0.5 * j as f64 * (y1 - y0),
            );
        }
    }
    let whole = simpson_3x3(&v, x1 - x0, y1 - y0);
    simpson_2d_rec(
        f,
        x0,
        x1,
        y0,
        y1,
        &v,
        whole,
        eps,
        max_depth,
        2.min(max_depth),
    )
}

/// Tensor Simpson rule from a 3×3 grid of values (`v[j][i]`, j along y).
fn simpson_3x3(v: &[[f64; 3]; 3], wx: f64, wy: f64) -> f64 {
    const W: [f64; 3] = [1.0, 4.0, 1.0];
    let mut s = 0.0;
    for j in 0..3 {
        for i in 0..3 {
            s += W[i] * W[j] * v[j][i];
        }
    }
    s * wx * wy / 36.0
}

#[allow(clippy::too_many_arguments)]
fn simpson_2d_rec(
    f: &impl Fn(f64, f64) -> f64,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    v: &[[f64; 3]; 3],
    whole: f64,
    eps: f64,
    depth: u32,
    min_depth: u32,
) -> f64 {
    // 5×5 grid: even indices are the parent's nodes.
    let mut g = [[0.0f64; 5]; 5];
    let (hx, hy) = (0.25 * (x1 - x0), 0.25 * (y1 - y0));
    for (j, row) in g.iter_mut().enumerate() {
        for (i, e) in row.iter_mut().enumerate() {
            *e = if i % 2 == 0 && j % 2 == 0 {
                v[j / 2][i / 2]
            } else {
                f(x0 + i as f64 * hx, y0 + j as f64 * hy)
            };
        }
    }
    let mut subs = [[[0.0f64; 3]; 3]; 4];
    let mut parts = [0.0f64; 4];
    for q in 0..4 {
        let (oi, oj) = (2 * (q % 2), 2 * (q / 2));
        for j in 0..3 {
            for i in 0..3 {
                subs[q][j][i] = g[oj + j][oi + i];
            }
        }
        parts[q] = simpson_3x3(&subs[q], 2.0 * hx, 2.0 * hy);
    }
    let sum: f64 = parts.iter().sum();
    let delta = sum - whole;
    if depth == 0 || (min_depth == 0 && delta.abs() <= 15.0 * eps) {
        return sum + delta / 15.0;
    }
    let md = min_depth.saturating_sub(1);
    let xm = 0.5 * (x0 + x1);
    let ym = 0.5 * (y0 + y1);
    let rects = [
        (x0, xm, y0, ym),
        (xm, x1, y0, ym),
        (x0, xm, ym, y1),
        (xm, x1, ym, y1),
    ];
    let mut total = 0.0;
    for q in 0..4 {
        let (a, b, c, d) = rects[q];
        total += simpson_2d_rec(f, a, b, c, d, &subs[q], parts[q], 0.25 * eps, depth - 1, md);
    }
    total
}

/// Two-sided p-value of Student's t-test of `mean` (a sample mean with sample `variance` over
/// `n` samples) against the `reference` value.
pub fn t_test(mean: f64, variance: f64, n: u64, reference: f64) -> f64 {
    if n < 2 || !mean.is_finite() || !variance.is_finite() {
        return 0.0;
    }
    if variance <= 0.0 {
        let close = (mean - reference).abs() <= 1e-6 * reference.abs().max(1.0);
        return if close { 1.0 } else { 0.0 };
    }
    let t = (mean - reference) / (variance / n as f64).sqrt();
    match StudentsT::new(0.0, 1.0, (n - 1) as f64) {
        Ok(d) => (2.0 * d.cdf(-t.abs())).min(1.0),
        Err(_) => 0.0,
    }
}

/// Running mean and variance (Welford), for t-tests of Monte Carlo estimates.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeanVar {
    pub n: u64,
    pub mean: f64,
    m2: f64,
}

impl MeanVar {
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Unbiased sample variance.
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            self.m2 / (self.n - 1) as f64
        }
    }

    /// The statistics of the union of two samples (Chan et al.'s parallel update).
    pub fn merge(&self, o: &MeanVar) -> MeanVar {
        let n = self.n + o.n;
        if n == 0 {
            return MeanVar::default();
        }
        let d = o.mean - self.mean;
        let (na, nb) = (self.n as f64, o.n as f64);
        MeanVar {
            n,
            mean: self.mean + d * nb / n as f64,
            m2: self.m2 + o.m2 + d * d * na * nb / n as f64,
        }
    }

    /// Two-sided p-value of the t-test of the mean against `reference`.
    pub fn t_test(&self, reference: f64) -> f64 {
        t_test(self.mean, self.variance(), self.n, reference)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::warp;

    #[test]
    fn merged_statistics_equal_the_whole() {
        let xs: Vec<f64> = (0..101)
            .map(|i| ((i * 37) % 11) as f64 * 0.3 - 1.0)
            .collect();
        let mut whole = MeanVar::default();
        xs.iter().for_each(|&x| whole.push(x));
        let (mut a, mut b) = (MeanVar::default(), MeanVar::default());
        xs[..40].iter().for_each(|&x| a.push(x));
        xs[40..].iter().for_each(|&x| b.push(x));
        let m = a.merge(&b);
        assert_eq!(m.n, whole.n);
        assert!((m.mean - whole.mean).abs() < 1e-12);
        assert!((m.variance() - whole.variance()).abs() < 1e-12);
    }

    #[test]
    fn pcg32_matches_reference_sequence() {
        // Reference output of pcg32_random_r seeded with (42, 54) (pcg-c demo).
        let mut r = Pcg32::new(42, 54);
        let expect = [
            0xa15c02b7u32,
            0x7b47f409,
            0xba1d3330,
            0x83d2f293,
            0xbfa4784b,
            0xcbed606e,
        ];
        for e in expect {
            assert_eq!(r.next_u32(), e);
        }
    }

    #[test]
    fn simpson_is_accurate() {
        let v = integrate_2d(&|x, y| x * x * y.cos(), 0.0, 1.0, 0.0, 1.0, 1e-10, 11);
        assert!((v - 1.0f64.sin() / 3.0).abs() < 1e-9);
        // A narrow peak.
        let s = 0.01;
        let g = |x: f64, _y: f64| (-(x - 0.3) * (x - 0.3) / (2.0 * s * s)).exp();
        let v = integrate_2d(&g, 0.0, 1.0, 0.0, 1.0, 1e-10, 11);
        let exact = s * (2.0 * PI).sqrt();
        assert!((v - exact).abs() < 1e-7 * exact.max(1.0), "{v} {exact}");
    }

    #[test]
    fn chi2_accepts_right_and_rejects_wrong_density() {
        let cfg = Chi2Config {
            sample_count: 200_000,
            ..Default::default()
        };
        let ok = chi2_test(
            |u, _| Some(warp::square_to_cosine_hemisphere(u)),
            warp::cosine_hemisphere_pdf,
            &cfg,
        );
        assert!(ok.passed, "{}", ok.message);
        // Cosine samples against a uniform-hemisphere density: same support, same mass.
        let bad = chi2_test(
            |u, _| Some(warp::square_to_cosine_hemisphere(u)),
            warp::uniform_hemisphere_pdf,
            &cfg,
        );
        assert!(!bad.passed, "{}", bad.message);
        // A subtly wrong sampler: cos^1.05 instead of cos.
        let subtle = chi2_test(
            |u, _| {
                let z = u.x.powf(1.0 / 2.1);
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * std::f32::consts::PI * u.y;
                Some(Vec3::new(r * phi.cos(), r * phi.sin(), z))
            },
            warp::cosine_hemisphere_pdf,
            &Chi2Config {
                sample_count: 1_000_000,
                ..Default::default()
            },
        );
        assert!(!subtle.passed, "{}", subtle.message);
        // A density that does not integrate to the sample fraction.
        let half = chi2_test(
            |u, _| Some(warp::square_to_cosine_hemisphere(u)),
            |w| 0.9 * warp::cosine_hemisphere_pdf(w),
            &cfg,
        );
        assert!(!half.passed, "{}", half.message);
    }

    #[test]
    fn t_test_behaves() {
        // Mean 0.5 of 10⁴ uniforms: p not small; against 0.52: tiny p.
        let mut rng = Pcg32::new(7, 1);
        let mut mv = MeanVar::default();
        for _ in 0..10_000 {
            mv.push(rng.next_f64());
        }
        assert!(mv.t_test(0.5) > 0.001, "{}", mv.t_test(0.5));
        assert!(mv.t_test(0.52) < 1e-6);
        assert!((t_test(0.0, 1.0, 1_000_000, 0.0) - 1.0).abs() < 1e-12);
        // |t| = 1.96 with many dof: p ≈ 0.05 (mean 1.96e-3, variance 1, n = 10⁶).
        let p = t_test(1.96e-3, 1.0, 1_000_000, 0.0);
        assert!((p - 0.05).abs() < 1e-3, "{p}");
        // Few degrees of freedom widen the tails: t = 2.262 with 9 dof is p = 0.05 (Student's
        // table), where the normal would give 0.024.
        let p = t_test(2.262 * (1.0f64 / 10.0).sqrt(), 1.0, 10, 0.0);
        assert!((p - 0.05).abs() < 1e-3, "{p}");
    }
}
