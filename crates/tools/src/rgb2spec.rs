//! The RGB → spectrum coefficient table of Jakob & Hanika 2019, computed by our own optimiser
//! (the paper's method, as pbrt-v4's `rgb2spec_opt` also does it; this code is written anew).
//!
//! For every node of the table layout (`render::spectral::rgb`: largest channel m, its value z
//! on the smoothstep² nodes, the two ratios x, y on a uniform grid) it finds the coefficients
//! (A, B, C) of s(t) = S(A·t² + B·t + C), t = (λ − 360)/470 ∈ [0, 1], whose reflectance under
//! the colour space's illuminant (D65 for sRGB) has the node's colour. The residual is the
//! difference in CIELAB (white: the illuminant's own XYZ), so that the fit is perceptually even;
//! it is minimised by Levenberg–Marquardt with the analytic Jacobian (∂XYZ/∂(A, B, C) by the
//! chain rule through S, then through the Lab map). XYZ are sums over the 1 nm CIE tables —
//! the same quadrature the round-trip tests use.
//!
//! Each column (m, x, y) is solved along z from z = nodes[res/5], starting at the flat
//! spectrum ½ (A = B = 0, C = 0), upwards to z = 1 and downwards to the first node above 0,
//! every node starting from its neighbour's solution: the coefficients change smoothly along z,
//! so each solve starts close to its answer. The z = 0 node (black, whose spectrum would need
//! C = −∞) copies the next node's coefficients: colours below that node's z (1.7e-6 at res 64)
//! are then slightly too bright by at most that much. Columns are independent and each is
//! computed in a fixed order, so the table is the same for any thread count.
//!
//! The stored coefficients are those of λ in nm (c₀λ² + c₁λ + c₂), converted in double
//! precision and rounded to f32 once.

use rayon::prelude::*;
use render::spectral::cie::{self, CIE_D65, CIE_SAMPLES, CIE_X, CIE_Y, CIE_Z};
use render::spectral::colorspace::SRGB_TO_XYZ;
use render::spectral::rgb::{RgbToSpectrumTable, z_node};

/// What the optimiser integrates against: the wavelengths in normalised form and the observer
/// under the illuminant, normalised to white Y = 1.
pub struct Observer {
    /// t = (λ − 360)/470 per 1 nm sample.
    t: Vec<f64>,
    /// (x̄, ȳ, z̄)·I / Σ I·ȳ per sample.
    w: Vec<[f64; 3]>,
    /// XYZ of the unit reflectance.
    white: [f64; 3],
    rgb_to_xyz: [[f64; 3]; 3],
}

impl Observer {
    /// Linear sRGB under D65.
    pub fn srgb() -> Observer {
        let norm: f64 = (0..CIE_SAMPLES).map(|i| CIE_D65[i] * CIE_Y[i]).sum();
        let t = (0..CIE_SAMPLES)
            .map(|i| (cie::table_lambda(i) - 360.0) / 470.0)
            .collect();
        let w: Vec<[f64; 3]> = (0..CIE_SAMPLES)
            .map(|i| [CIE_X[i], CIE_Y[i], CIE_Z[i]].map(|c| c * CIE_D65[i] / norm))
            .collect();
        let mut white = [0.0; 3];
        for wi in &w {
            for c in 0..3 {
                white[c] += wi[c];
            }
        }
        Observer {
            t,
            w,
            white,
            rgb_to_xyz: SRGB_TO_XYZ,
        }
    }

    /// XYZ of s(t) = S(A t² + B t + C) and its Jacobian ∂XYZᵢ/∂(A, B, C)ⱼ.
    fn xyz(&self, c: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
        let mut xyz = [0.0; 3];
        let mut jac = [[0.0; 3]; 3];
        for (&t, w) in self.t.iter().zip(&self.w) {
            let p = (c[0] * t + c[1]) * t + c[2];
            let q = 1.0 + p * p;
            let r = 1.0 / q.sqrt();
            let s = 0.5 + 0.5 * p * r;
            let ds = 0.5 * r / q; // S'(p) = ½ (1 + p²)^(−3/2)
            let basis = [t * t, t, 1.0];
            for i in 0..3 {
                xyz[i] += s * w[i];
                let dw = ds * w[i];
                for j in 0..3 {
                    jac[i][j] += dw * basis[j];
                }
            }
        }
        (xyz, jac)
    }

    fn rgb_to_lab(&self, rgb: [f64; 3]) -> [f64; 3] {
        let m = &self.rgb_to_xyz;
        let xyz = [0, 1, 2].map(|r| m[r][0] * rgb[0] + m[r][1] * rgb[1] + m[r][2] * rgb[2]);
        lab(xyz, self.white).0
    }
}

const DELTA: f64 = 6.0 / 29.0;

/// CIELAB's f and f'.
fn lab_f(t: f64) -> (f64, f64) {
    if t > DELTA * DELTA * DELTA {
        let c = t.cbrt();
        (c, 1.0 / (3.0 * c * c))
    } else {
        let k = 1.0 / (3.0 * DELTA * DELTA);
        (t * k + 4.0 / 29.0, k)
    }
}

/// CIELAB of `xyz` against `white`, and ∂Lab/∂XYZ.
fn lab(xyz: [f64; 3], white: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let (fx, dx) = lab_f(xyz[0] / white[0]);
    let (fy, dy) = lab_f(xyz[1] / white[1]);
    let (fz, dz) = lab_f(xyz[2] / white[2]);
    let (dx, dy, dz) = (dx / white[0], dy / white[1], dz / white[2]);
    (
        [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)],
        [
            [0.0, 116.0 * dy, 0.0],
            [500.0 * dx, -500.0 * dy, 0.0],
            [0.0, 200.0 * dy, -200.0 * dz],
        ],
    )
}

/// Solves the 3×3 system `a·x = b` by Gaussian elimination with partial pivoting.
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    for col in 0..3 {
        let p = (col..3)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap();
        if a[p][col].abs() < 1e-300 || !a[p][col].is_finite() {
            return None;
        }
        a.swap(col, p);
        b.swap(col, p);
        for r in col + 1..3 {
            let f = a[r][col] / a[col][col];
            let pivot = a[col];
            for (v, p) in a[r].iter_mut().zip(pivot).skip(col) {
                *v -= f * p;
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for r in (0..3).rev() {
        let s: f64 = (r + 1..3).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Stop when ‖Lab residual‖ is below this.
const TOLERANCE: f64 = 1e-7;
const MAX_ITERATIONS: usize = 300;

/// Outcome of one fit.
#[derive(Clone, Copy, Debug)]
pub struct Fit {
    pub coeffs: [f64; 3],
    /// ‖Lab(fit) − Lab(target)‖.
    pub residual: f64,
    pub iterations: usize,
}

/// Levenberg–Marquardt on the Lab residual from `start`.
pub fn fit(obs: &Observer, rgb: [f64; 3], start: [f64; 3]) -> Fit {
    let target = obs.rgb_to_lab(rgb);
    let residual_at = |c: [f64; 3]| {
        let (xyz, jx) = obs.xyz(c);
        let (l, jl) = lab(xyz, obs.white);
        let r = [0, 1, 2].map(|i| l[i] - target[i]);
        // J = ∂Lab/∂XYZ · ∂XYZ/∂c
        let j: [[f64; 3]; 3] =
            [0, 1, 2].map(|i| [0, 1, 2].map(|k| (0..3).map(|m| jl[i][m] * jx[m][k]).sum()));
        (r, j)
    };
    let norm = |r: [f64; 3]| (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    let mut c = start;
    let (mut r, mut j) = residual_at(c);
    let mut err = norm(r);
    let mut mu = 1e-6;
    let mut it = 0;
    while it < MAX_ITERATIONS && err > TOLERANCE {
        it += 1;
        // Normal equations JᵀJ δ = −Jᵀr, damped on the diagonal (Marquardt).
        let mut a = [[0.0f64; 3]; 3];
        let mut g = [0.0f64; 3];
        for p in 0..3 {
            for q in 0..3 {
                a[p][q] = (0..3).map(|i| j[i][p] * j[i][q]).sum();
            }
            g[p] = -(0..3).map(|i| j[i][p] * r[i]).sum::<f64>();
        }
        let dmax = a[0][0].max(a[1][1]).max(a[2][2]);
        let mut improved = false;
        while mu < 1e12 {
            let mut ad = a;
            for (d, row) in ad.iter_mut().enumerate() {
                row[d] += mu * (row[d] + 1e-12 * dmax);
            }
            if let Some(delta) = solve3(ad, g) {
                let cn = [c[0] + delta[0], c[1] + delta[1], c[2] + delta[2]];
                let (rn, jn) = residual_at(cn);
                let en = norm(rn);
                if en.is_finite() && en < err {
                    (c, r, j, err) = (cn, rn, jn, en);
                    mu = (mu * 0.1).max(1e-12);
                    improved = true;
                    break;
                }
            }
            mu *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Fit {
        coeffs: c,
        residual: err,
        iterations: it,
    }
}

/// (A, B, C) of t = (λ − 360)/470 → (c₀, c₁, c₂) of λ in nm.
pub fn to_nm_domain(c: [f64; 3]) -> [f64; 3] {
    let (o, u) = (360.0, 1.0 / 470.0);
    [
        c[0] * u * u,
        c[1] * u - 2.0 * c[0] * o * u * u,
        c[0] * o * o * u * u - c[1] * o * u + c[2],
    ]
}

/// Figures of a table computation.
#[derive(Clone, Debug, Default)]
pub struct Report {
    pub fits: usize,
    pub iterations: usize,
    pub max_residual: f64,
    /// Nodes whose Lab residual stayed above 1e-3.
    pub unconverged: usize,
    pub worst_rgb: [f64; 3],
}

/// The table of resolution `res` for linear sRGB under D65.
pub fn compute_srgb_table(res: usize) -> (RgbToSpectrumTable, Report) {
    let obs = Observer::srgb();
    let z: Vec<f64> = (0..res).map(|k| z_node(k, res)).collect();
    let columns: Vec<(usize, usize, usize)> = (0..3)
        .flat_map(|m| (0..res).flat_map(move |yi| (0..res).map(move |xi| (m, yi, xi))))
        .collect();
    let solved: Vec<(Vec<[f64; 3]>, Report)> = columns
        .par_iter()
        .map(|&(m, yi, xi)| {
            let x = xi as f64 / (res - 1) as f64;
            let y = yi as f64 / (res - 1) as f64;
            let mut out = vec![[0.0; 3]; res];
            let mut rep = Report::default();
            let solve = |k: usize, start: [f64; 3], rep: &mut Report| {
                let mut rgb = [0.0; 3];
                rgb[m] = z[k];
                rgb[(m + 1) % 3] = x * z[k];
                rgb[(m + 2) % 3] = y * z[k];
                let f = fit(&obs, rgb, start);
                rep.fits += 1;
                rep.iterations += f.iterations;
                if f.residual > rep.max_residual {
                    rep.max_residual = f.residual;
                    rep.worst_rgb = rgb;
                }
                if f.residual > 1e-3 {
                    rep.unconverged += 1;
                }
                f.coeffs
            };
            let start = res / 5;
            let mut c = [0.0; 3];
            for (k, slot) in out.iter_mut().enumerate().skip(start.max(1)) {
                c = solve(k, c, &mut rep);
                *slot = c;
            }
            c = out[start.max(1)];
            for k in (1..start).rev() {
                c = solve(k, c, &mut rep);
                out[k] = c;
            }
            out[0] = out[1];
            (out, rep)
        })
        .collect();

    let mut coeffs = vec![[0.0f32; 3]; 3 * res * res * res];
    let mut report = Report::default();
    for (&(m, yi, xi), (column, rep)) in columns.iter().zip(&solved) {
        for (k, c) in column.iter().enumerate() {
            coeffs[RgbToSpectrumTable::index(res, m, k, yi, xi)] =
                to_nm_domain(*c).map(|v| v as f32);
        }
        report.fits += rep.fits;
        report.iterations += rep.iterations;
        report.unconverged += rep.unconverged;
        if rep.max_residual > report.max_residual {
            report.max_residual = rep.max_residual;
            report.worst_rgb = rep.worst_rgb;
        }
    }
    let z_nodes = z.iter().map(|&v| v as f32).collect();
    let table = RgbToSpectrumTable::new(res, z_nodes, coeffs).expect("a well-formed table");
    (table, report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_reach_their_colour() {
        let obs = Observer::srgb();
        for rgb in [
            [0.2, 0.5, 0.9],
            [0.9, 0.1, 0.05],
            [0.5, 0.5, 0.5],
            [0.05, 0.6, 0.1],
        ] {
            let f = fit(&obs, rgb, [0.0; 3]);
            assert!(f.residual < 1e-6, "{rgb:?}: {f:?}");
        }
    }

    #[test]
    fn nm_domain_is_the_same_polynomial() {
        let c = [3.0, -2.5, 0.7];
        let n = to_nm_domain(c);
        for l in [360.0, 500.0, 830.0] {
            let t = (l - 360.0) / 470.0;
            let a = (c[0] * t + c[1]) * t + c[2];
            let b = (n[0] * l + n[1]) * l + n[2];
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let obs = Observer::srgb();
        let c = [1.5, -0.7, 0.3];
        let (_, j) = obs.xyz(c);
        for k in 0..3 {
            let mut cp = c;
            let mut cm = c;
            cp[k] += 1e-6;
            cm[k] -= 1e-6;
            let (xp, _) = obs.xyz(cp);
            let (xm, _) = obs.xyz(cm);
            for i in 0..3 {
                let fd = (xp[i] - xm[i]) / 2e-6;
                assert!(
                    (fd - j[i][k]).abs() < 1e-6,
                    "({i}, {k}): {fd} vs {}",
                    j[i][k]
                );
            }
        }
    }
}
