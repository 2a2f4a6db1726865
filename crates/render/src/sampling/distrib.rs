//! Discrete and piecewise-constant 1D/2D distributions (light selection by power, environment
//! map importance sampling, filter importance sampling).
//!
//! - [`Distribution1D`]: a piecewise-constant density on `[0, 1)` with `n` equal cells, sampled by
//!   inverting its CDF (binary search). The CDF is built and stored in `f64`, so distributions
//!   with millions of cells and a huge dynamic range (HDR environment maps) keep every non-zero
//!   cell reachable. It doubles as a discrete distribution over the cells.
//! - [`Distribution2D`]: a piecewise-constant density on `[0, 1)²`, sampled as a marginal
//!   distribution over rows (v) times a conditional distribution over columns (u) in the chosen
//!   row (pbrt's `PiecewiseConstant2D`, Mitsuba's `Hierarchical2D` without the hierarchy).
//! - [`AliasTable`]: Walker's alias method built with Vose's numerically stable algorithm, O(1)
//!   sampling of a discrete distribution.
//!
//! Input conventions (shared by all three): negative, NaN and infinite weights are treated as
//! 0. When every weight is 0 the distribution falls back to the uniform one (so a black
//! environment map still yields valid samples with a finite pdf); [`Distribution1D::integral`]
//! still reports 0 so callers can detect it.

use crate::math::Vec2;

/// The largest `f32` below 1.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

#[inline]
fn sanitize_weight(v: f32) -> f32 {
    if v.is_finite() && v > 0.0 { v } else { 0.0 }
}

/// Clamps a sample to `[0, 1)`; NaN becomes 0.
#[inline]
fn sanitize_u(u: f32) -> f32 {
    if u > 0.0 {
        u.min(ONE_MINUS_EPSILON)
    } else {
        0.0
    }
}

/// Piecewise-constant density on `[0, 1)` with `len()` equal cells.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f32>,
    /// `len() + 1` entries, `cdf[0] = 0`, `cdf[len] = 1`, non-decreasing.
    cdf: Vec<f64>,
    /// Σ func.
    sum: f64,
    /// 1 / Σ func (0 when the sum is 0): the pmf is `f · inv_sum`, one multiplication instead
    /// of a double-precision division per sample (the mesh emitters' triangle choice).
    inv_sum: f64,
}

impl Distribution1D {
    /// Builds the distribution proportional to `f` (see the module docs for how negative,
    /// non-finite and all-zero inputs are handled). An empty `f` behaves as one zero cell.
    pub fn new(f: &[f32]) -> Self {
        let func: Vec<f32> = if f.is_empty() {
            vec![0.0]
        } else {
            f.iter().copied().map(sanitize_weight).collect()
        };
        let n = func.len();
        let mut cdf = Vec::with_capacity(n + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &v in &func {
            acc += v as f64;
            cdf.push(acc);
        }
        let sum = acc;
        if sum > 0.0 {
            let inv = 1.0 / sum;
            for c in cdf.iter_mut() {
                *c *= inv;
            }
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f64 / n as f64;
            }
        }
        cdf[n] = 1.0;
        let inv_sum = if sum > 0.0 { 1.0 / sum } else { 0.0 };
        Distribution1D {
            func,
            cdf,
            sum,
            inv_sum,
        }
    }

    /// Number of cells.
    #[inline]
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Always false (an empty input becomes one zero cell); provided for clippy's sake.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// ∫₀¹ f = (Σ fᵢ) / n, with the sanitised weights. 0 for an all-zero input.
    #[inline]
    pub fn integral(&self) -> f32 {
        (self.sum / self.func.len() as f64) as f32
    }

    /// Σ fᵢ (f64), with the sanitised weights.
    #[inline]
    pub fn sum(&self) -> f64 {
        self.sum
    }

    /// The sanitised cell values.
    #[inline]
    pub fn func(&self) -> &[f32] {
        &self.func
    }

    /// The cell whose CDF interval contains `u`. Never a zero-probability cell.
    #[inline]
    fn find_cell(&self, u: f64) -> usize {
        // First index with cdf > u lies in [1, n] because cdf[0] = 0 ≤ u < 1 = cdf[n].
        let i = self.cdf.partition_point(|&c| c <= u);
        i.saturating_sub(1).min(self.func.len() - 1)
    }

    /// Density (w.r.t. x on [0,1)) of cell `i`.
    #[inline]
    fn cell_pdf(&self, i: usize) -> f32 {
        if self.sum > 0.0 {
            (self.func[i] as f64 * self.func.len() as f64 * self.inv_sum) as f32
        } else {
            1.0
        }
    }

    /// Samples `x ∈ [0, 1)` with density ∝ f: returns `(x, pdf(x), cell)`.
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let u = sanitize_u(u) as f64;
        let o = self.find_cell(u);
        let (c0, c1) = (self.cdf[o], self.cdf[o + 1]);
        let du = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.0 };
        let x = ((o as f64 + du) / self.func.len() as f64) as f32;
        (x.min(ONE_MINUS_EPSILON), self.cell_pdf(o), o)
    }

    /// Samples a cell with probability ∝ fᵢ: returns `(cell, pmf, u')` where `u' ∈ [0, 1)` is
    /// `u` remapped within the chosen cell's CDF interval (uniform, independent of the choice).
    pub fn sample_discrete(&self, u: f32) -> (usize, f32, f32) {
        let u = sanitize_u(u) as f64;
        let o = self.find_cell(u);
        let (c0, c1) = (self.cdf[o], self.cdf[o + 1]);
        let du = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.0 };
        (o, self.pmf(o), (du as f32).min(ONE_MINUS_EPSILON))
    }

    /// Probability of choosing cell `i` with [`Self::sample_discrete`] (0 out of range).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        match self.func.get(i) {
            Some(&f) if self.sum > 0.0 => (f as f64 * self.inv_sum) as f32,
            Some(_) => 1.0 / self.func.len() as f32,
            None => 0.0,
        }
    }

    /// Density of [`Self::sample_continuous`] at `x` (0 outside `[0, 1]`; `x = 1` belongs to the
    /// last cell).
    #[inline]
    pub fn pdf(&self, x: f32) -> f32 {
        if !(0.0..=1.0).contains(&x) {
            return 0.0;
        }
        let n = self.func.len();
        let i = ((x * n as f32) as usize).min(n - 1);
        self.cell_pdf(i)
    }
}

/// Piecewise-constant density on `[0, 1)²` over a `width × height` grid of cells, row-major with
/// row `j` covering `v ∈ [j/height, (j+1)/height)`.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    /// One distribution over u per row.
    conditional: Vec<Distribution1D>,
    /// Distribution over rows (v), proportional to the row integrals.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// Builds the distribution proportional to the row-major values `f` (`width * height`
    /// entries; missing entries count as 0, extra ones are ignored; a zero dimension counts
    /// as 1).
    pub fn new(f: &[f32], width: usize, height: usize) -> Self {
        let (w, h) = (width.max(1), height.max(1));
        let mut row = vec![0.0f32; w];
        let mut conditional = Vec::with_capacity(h);
        let mut row_integrals = Vec::with_capacity(h);
        for j in 0..h {
            for (i, r) in row.iter_mut().enumerate() {
                *r = f.get(j * w + i).copied().unwrap_or(0.0);
            }
            let d = Distribution1D::new(&row);
            // Row integral over u ∈ [0,1) in f64, rounded once.
            row_integrals.push((d.sum() / w as f64) as f32);
            conditional.push(d);
        }
        let marginal = Distribution1D::new(&row_integrals);
        Distribution2D {
            conditional,
            marginal,
        }
    }

    #[inline]
    pub fn width(&self) -> usize {
        self.conditional[0].len()
    }

    #[inline]
    pub fn height(&self) -> usize {
        self.conditional.len()
    }

    /// ∫∫ f over the unit square (0 for an all-zero input).
    #[inline]
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// Samples a point with density ∝ f: returns `(p, pdf(p))`, `p ∈ [0, 1)²`.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample_continuous(u.y);
        let (x, pdf_u, _) = self.conditional[row].sample_continuous(u.x);
        (Vec2::new(x, v), pdf_u * pdf_v)
    }

    /// Density of [`Self::sample`] at `p` (0 outside `[0, 1]²`).
    pub fn pdf(&self, p: Vec2) -> f32 {
        if !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
            return 0.0;
        }
        let h = self.conditional.len();
        let row = ((p.y * h as f32) as usize).min(h - 1);
        self.marginal.pdf(p.y) * self.conditional[row].pdf(p.x)
    }
}

#[derive(Clone, Copy, Debug)]
struct AliasBin {
    /// Probability of keeping this bin's own index (vs. its alias), in [0, 1].
    q: f64,
    alias: u32,
    pmf: f32,
}

/// Walker's alias method (Vose's construction): O(1) sampling of a discrete distribution.
///
/// Sampling uses a single `u`: `u · n` picks the bin and its fractional part decides between
/// the bin and its alias, so with `n` entries the decision has about `24 − log₂ n` bits of
/// resolution (as in pbrt-v4); fine for light selection.
#[derive(Clone, Debug, Default)]
pub struct AliasTable {
    bins: Vec<AliasBin>,
}

impl AliasTable {
    /// Builds the table for weights `w` (see the module docs for input conventions). An empty
    /// `w` gives an empty table, whose [`Self::sample`] returns `(0, 0.0)`: check
    /// [`Self::is_empty`] first.
    pub fn new(w: &[f32]) -> Self {
        let n = w.len();
        if n == 0 {
            return AliasTable { bins: Vec::new() };
        }
        let weights: Vec<f64> = w.iter().map(|&v| sanitize_weight(v) as f64).collect();
        let sum: f64 = weights.iter().sum();
        let probs: Vec<f64> = if sum > 0.0 {
            weights.iter().map(|&v| v / sum).collect()
        } else {
            vec![1.0 / n as f64; n]
        };
        let mut bins: Vec<AliasBin> = probs
            .iter()
            .enumerate()
            .map(|(i, &p)| AliasBin {
                q: 1.0,
                alias: i as u32,
                pmf: p as f32,
            })
            .collect();
        // Scaled probabilities: bins with p·n < 1 are under-full and take an alias.
        let mut scaled: Vec<f64> = probs.iter().map(|&p| p * n as f64).collect();
        let mut small: Vec<usize> = Vec::new();
        let mut large: Vec<usize> = Vec::new();
        for (i, &s) in scaled.iter().enumerate() {
            if s < 1.0 {
                small.push(i);
            } else {
                large.push(i);
            }
        }
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            large.pop();
            bins[s].q = scaled[s];
            bins[s].alias = l as u32;
            // Vose: subtract what the small bin borrowed, in the stable order.
            scaled[l] = (scaled[l] + scaled[s]) - 1.0;
            if scaled[l] < 1.0 {
                small.push(l);
            } else {
                large.push(l);
            }
        }
        // Leftovers are (up to rounding) exactly full.
        for i in small.into_iter().chain(large) {
            bins[i].q = 1.0;
            bins[i].alias = i as u32;
        }
        AliasTable { bins }
    }

    #[inline]
    pub fn len(&self) -> usize {
        self.bins.len()
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// Picks an index with probability `pmf(index)`: returns `(index, pmf)`.
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let n = self.bins.len();
        if n == 0 {
            return (0, 0.0);
        }
        let x = sanitize_u(u) as f64 * n as f64;
        let i = (x as usize).min(n - 1);
        let frac = x - i as f64;
        let bin = &self.bins[i];
        let k = if frac < bin.q { i } else { bin.alias as usize };
        (k, self.bins[k].pmf)
    }

    /// Probability of index `i` (0 out of range).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.bins.get(i).map_or(0.0, |b| b.pmf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distribution1d_closed_forms() {
        let d = Distribution1D::new(&[1.0, 3.0, 0.0, 4.0]);
        assert_eq!(d.len(), 4);
        assert!((d.integral() - 2.0).abs() < 1e-6);
        assert!((d.pmf(1) - 3.0 / 8.0).abs() < 1e-7);
        assert_eq!(d.pmf(2), 0.0);
        assert_eq!(d.pmf(9), 0.0);
        assert!((d.pdf(0.3) - 1.5).abs() < 1e-6);
        assert_eq!(d.pdf(-0.1), 0.0);
        // u = 1/8 is the end of cell 0 → start of cell 1.
        let (x, pdf, cell) = d.sample_continuous(0.125 + 3.0 / 16.0);
        assert_eq!(cell, 1);
        assert!((x - 0.375).abs() < 1e-6 && (pdf - 1.5).abs() < 1e-6);
        // The zero cell is never chosen, even at its CDF boundary.
        let (cell, pmf, ur) = d.sample_discrete(0.5);
        assert_eq!(cell, 3);
        assert!((pmf - 0.5).abs() < 1e-7 && ur.abs() < 1e-6);
        let (x, _, _) = d.sample_continuous(1.0);
        assert!(x < 1.0);
        let (x, _, _) = d.sample_continuous(f32::NAN);
        assert_eq!(x, 0.0);
    }

    #[test]
    fn degenerate_inputs_fall_back_to_uniform() {
        for f in [
            &[][..],
            &[0.0, 0.0][..],
            &[f32::NAN, -1.0, f32::INFINITY][..],
        ] {
            let d = Distribution1D::new(f);
            assert_eq!(d.integral(), 0.0);
            let (x, pdf, _) = d.sample_continuous(0.7);
            assert!((x - 0.7).abs() < 1e-6 && pdf == 1.0);
            assert!((d.pmf(0) * d.len() as f32 - 1.0).abs() < 1e-6);
        }
        let d2 = Distribution2D::new(&[], 0, 0);
        let (p, pdf) = d2.sample(Vec2::new(0.25, 0.5));
        assert_eq!((p, pdf), (Vec2::new(0.25, 0.5), 1.0));
        let a = AliasTable::new(&[]);
        assert!(a.is_empty());
        assert_eq!(a.sample(0.3), (0, 0.0));
        let a = AliasTable::new(&[0.0, 0.0]);
        assert_eq!(a.pmf(1), 0.5);
    }

    #[test]
    fn distribution1d_sample_is_inverse_cdf() {
        let f: Vec<f32> = (0..37).map(|i| ((i * 7919) % 13) as f32).collect();
        let d = Distribution1D::new(&f);
        for k in 0..1000 {
            let u = k as f32 / 1000.0;
            let (x, pdf, cell) = d.sample_continuous(u);
            assert!((0.0..1.0).contains(&x));
            assert!(f[cell] > 0.0 && pdf > 0.0);
            assert_eq!(pdf, d.pdf(x));
            assert_eq!(cell, ((x * 37.0) as usize).min(36));
        }
    }

    #[test]
    fn distribution2d_pdf_matches_function() {
        let (w, h) = (5, 3);
        let f: Vec<f32> = (0..w * h).map(|i| (i % 4) as f32).collect();
        let d = Distribution2D::new(&f, w, h);
        let integral: f32 = f.iter().sum::<f32>() / (w * h) as f32;
        assert!((d.integral() - integral).abs() < 1e-6);
        for j in 0..h {
            for i in 0..w {
                let p = Vec2::new((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
                assert!((d.pdf(p) - f[j * w + i] / integral).abs() < 1e-5);
            }
        }
        for k in 0..200 {
            let u = Vec2::new((k as f32 * 0.618).fract(), (k as f32 * 0.382 + 0.1).fract());
            let (p, pdf) = d.sample(u);
            assert!(pdf > 0.0);
            assert!((pdf - d.pdf(p)).abs() < 1e-5 * pdf);
        }
    }

    #[test]
    fn alias_table_pmf_and_zero_weights() {
        let w = [1.0, 0.0, 2.0, 5.0, 0.0];
        let a = AliasTable::new(&w);
        assert!((a.pmf(3) - 0.625).abs() < 1e-7);
        // Sweep u finely: the frequencies approach the pmf and zero bins are never chosen.
        let n = 100_000;
        let mut counts = [0usize; 5];
        for k in 0..n {
            let (i, pmf) = a.sample((k as f32 + 0.5) / n as f32);
            assert_eq!(pmf, a.pmf(i));
            counts[i] += 1;
        }
        assert_eq!(counts[1] + counts[4], 0);
        for (i, &c) in counts.iter().enumerate() {
            assert!((c as f32 / n as f32 - a.pmf(i)).abs() < 1e-3);
        }
    }
}
