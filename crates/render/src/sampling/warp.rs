//! Warps from the unit square to common domains, each with its pdf (χ²-tested in
//! `tests/it/chi2_warps.rs`).

use crate::math::{INV_2PI, INV_4PI, INV_PI, PI, Vec2, Vec3, Vec4};

/// Shirley–Chiu concentric map to the unit disk (area pdf 1/π).
pub fn square_to_uniform_disk_concentric(u: Vec2) -> Vec2 {
    concentric(u).0
}

/// The concentric map and its radius `r` (signed: the point is `|r|` from the centre).
#[inline(always)]
fn concentric(u: Vec2) -> (Vec2, f32) {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return (Vec2::ZERO, 0.0);
    }
    // Shirley–Chiu: the radius is the larger coordinate and the angle θ = π/4 · (smaller /
    // larger) lies in [−π/4, π/4]; in the upper/lower wedges the angle is π/2 − θ, which swaps
    // sine and cosine. Written with selects rather than a branch (which way a sample falls
    // cannot be predicted), and with a polynomial sin/cos valid on that interval.
    //
    // The selects are vector selects on a comparison mask: on the SSE2 baseline LLVM lowers a
    // scalar float select (even `select_unpredictable`) to a jump over a move, and which wedge
    // a sample falls in is a coin toss for the branch predictor.
    let swap = Vec4::splat(o.x.abs()).cmple(Vec4::splat(o.y.abs()));
    let ro = Vec4::select(
        swap,
        Vec4::new(o.y, o.x, 0.0, 0.0),
        Vec4::new(o.x, o.y, 0.0, 0.0),
    );
    let (r, other) = (ro.x, ro.y);
    let (s, c) = sin_cos_quarter_pi((PI / 4.0) * (other / r));
    let sc = Vec4::select(swap, Vec4::new(s, c, 0.0, 0.0), Vec4::new(c, s, 0.0, 0.0));
    (Vec2::new(r * sc.x, r * sc.y), r)
}

/// `(sin 2πt, cos 2πt)`: the azimuth of a sample `t ∈ [0, 1)`, reduced exactly to the nearest
/// quarter turn (4t − round(4t) is exact in `f32`) and evaluated by [`sin_cos_quarter_pi`], so
/// it is both cheaper and more accurate than `(2π t).sin_cos()`.
#[inline(always)]
pub fn sin_cos_2pi(t: f32) -> (f32, f32) {
    let q = (4.0 * t).round();
    let (s, c) = sin_cos_quarter_pi((4.0 * t - q) * (PI / 2.0));
    // sin/cos of x + qπ/2: odd quarters swap the pair, quarters 2 and 3 negate the sine,
    // quarters 1 and 2 the cosine.
    let q = q as i32;
    let (s, c) = if q & 1 != 0 { (c, s) } else { (s, c) };
    let s = if q & 2 != 0 { -s } else { s };
    let c = if (q + 1) & 2 != 0 { -c } else { c };
    (s, c)
}

/// `(sin x, cos x)` for `|x| ≤ π/4`, where no range reduction is needed: Cephes' single-precision
/// minimax polynomials (`sinf`/`cosf`, S. Moshier), less than 1 ulp from the exact values there
/// (0.96 ulp at worst over 100 001 points, checked against `f64` in the tests). Inlined and
/// branch-free, where a libm `sincosf` call costs about three times as many instructions.
#[inline(always)]
pub fn sin_cos_quarter_pi(x: f32) -> (f32, f32) {
    let z = x * x;
    let s = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * x + x;
    let c = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (s, c)
}

pub fn uniform_disk_pdf() -> f32 {
    INV_PI
}

/// Cosine-weighted hemisphere around +z (pdf cos θ / π).
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let (d, r) = concentric(u);
    // From the radius rather than from |d|²: the square root then starts alongside the
    // sine/cosine polynomial instead of after it (sin² + cos² = 1 to within an ulp).
    let z = (1.0 - r * r).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

pub fn cosine_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z > 0.0 { w.z * INV_PI } else { 0.0 }
}

/// Uniform hemisphere around +z (pdf 1/2π).
pub fn square_to_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = sin_cos_2pi(u.y);
    Vec3::new(r * c, r * s, z)
}

pub fn uniform_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z >= 0.0 { INV_2PI } else { 0.0 }
}

/// Uniform sphere (pdf 1/4π).
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = sin_cos_2pi(u.y);
    Vec3::new(r * c, r * s, z)
}

pub fn uniform_sphere_pdf() -> f32 {
    INV_4PI
}

/// Clarberg's equal-area octahedral map of the unit square onto the sphere (pbrt-v4's
/// square environment maps): the square's diamond |u'| + |v'| ≤ 1 (u' = 2u − 1, v' = 2v − 1)
/// is the upper hemisphere, its corners the lower one; equal areas map to equal solid
/// angles, so the density is 1/4π per unit of square.
pub fn equal_area_square_to_sphere(p: Vec2) -> Vec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (au, av) = (u.abs(), v.abs());
    let signed = 1.0 - (au + av);
    let r = 1.0 - signed.abs();
    // φ ∈ [0, π/2] within the quadrant, by where the point lies along its diamond edge.
    let phi = if r == 0.0 { 1.0 } else { (av - au) / r + 1.0 } * (PI / 4.0);
    let z = (1.0 - r * r).copysign(signed);
    let (sin_phi, cos_phi) = phi.sin_cos();
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(cos_phi.copysign(u) * s, sin_phi.copysign(v) * s, z)
}

/// The inverse of [`equal_area_square_to_sphere`] for a unit vector.
pub fn equal_area_sphere_to_square(d: Vec3) -> Vec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let t = if a == 0.0 { 0.0 } else { b / a };
    let mut phi = t.atan() * (2.0 / PI);
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        (u, v) = (1.0 - v, 1.0 - u);
    }
    Vec2::new(0.5 * (u.copysign(d.x) + 1.0), 0.5 * (v.copysign(d.y) + 1.0))
}

/// Uniform cone of directions around +z with cos θ ≥ `cos_max` (pdf 1 / (2π(1 − cos_max))).
pub fn square_to_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = (1.0 - u.x) + u.x * cos_max;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (s, c) = sin_cos_2pi(u.y);
    Vec3::new(sin_t * c, sin_t * s, cos_t)
}

pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform barycentrics (b1, b2) over a triangle (Heitz 2019 low-distortion map).
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    let (b0, b1);
    if u.x < u.y {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    Vec2::new(b1, 1.0 - b0 - b1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The points `(i + offset) / n` of an `n × n` grid over the unit square.
    fn grid(n: u32, offset: Vec2) -> impl Iterator<Item = Vec2> {
        (0..n).flat_map(move |i| {
            (0..n).map(move |j| (Vec2::new(i as f32, j as f32) + offset) / n as f32)
        })
    }

    #[test]
    fn polynomial_sin_cos_is_accurate_on_the_quarter_interval() {
        let n = 100_000;
        let mut worst = 0f64;
        for i in 0..=n {
            let x = (-PI / 4.0) + (PI / 2.0) * (i as f32 / n as f32);
            let (s, c) = sin_cos_quarter_pi(x);
            let (se, ce) = (x as f64).sin_cos();
            // Error in units of the last place of the exact value.
            let ulps = |got: f32, exact: f64| {
                let e = (exact as f32).abs();
                (got as f64 - exact).abs() / (f32::from_bits(e.to_bits() + 1) - e) as f64
            };
            let (ds, dc) = (ulps(s, se), ulps(c, ce));
            worst = worst.max(ds).max(dc);
        }
        assert!(worst < 1.0, "worst error {worst} ulp");
    }

    #[test]
    fn sin_cos_2pi_matches_f64() {
        let n = 100_000;
        for i in 0..n {
            let t = i as f32 / n as f32;
            let (s, c) = sin_cos_2pi(t);
            let (se, ce) = (2.0 * std::f64::consts::PI * t as f64).sin_cos();
            assert!(
                (s as f64 - se).abs() < 2e-7 && (c as f64 - ce).abs() < 2e-7,
                "{t}"
            );
        }
    }

    #[test]
    fn concentric_disk_matches_the_trigonometric_mapping() {
        for u in grid(256, Vec2::new(0.37, 0.61)) {
            let o = 2.0 * u - Vec2::ONE;
            let (r, theta) = if o.x.abs() > o.y.abs() {
                (o.x, (PI / 4.0) * (o.y / o.x))
            } else {
                (o.y, PI / 2.0 - (PI / 4.0) * (o.x / o.y))
            };
            let (s, c) = theta.sin_cos();
            let d = square_to_uniform_disk_concentric(u);
            assert!((d - Vec2::new(r * c, r * s)).length() < 1e-6, "{u:?}");
        }
        assert_eq!(
            square_to_uniform_disk_concentric(Vec2::splat(0.5)),
            Vec2::ZERO
        );
    }

    #[test]
    fn warps_land_in_their_domains() {
        for u in grid(64, Vec2::splat(0.5)) {
            assert!(square_to_uniform_disk_concentric(u).length() <= 1.0 + 1e-6);
            let c = square_to_cosine_hemisphere(u);
            assert!((c.length() - 1.0).abs() < 1e-5 && c.z >= 0.0);
            let s = square_to_uniform_sphere(u);
            assert!((s.length() - 1.0).abs() < 1e-5);
            let k = square_to_uniform_cone(u, 0.8);
            assert!(k.z >= 0.8 - 1e-6);
            let b = square_to_uniform_triangle(u);
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
        }
    }

    #[test]
    fn equal_area_map_round_trips_and_keeps_areas() {
        assert!((equal_area_square_to_sphere(Vec2::splat(0.5)) - Vec3::Z).length() < 1e-6);
        for corner in [Vec2::ZERO, Vec2::ONE, Vec2::X, Vec2::Y] {
            assert!((equal_area_square_to_sphere(corner) + Vec3::Z).length() < 1e-6);
        }
        // Direction → square → direction, at cell centres of a fine grid.
        let mut worst = 0f32;
        for p in grid(257, Vec2::splat(0.5)) {
            let d = equal_area_square_to_sphere(p);
            assert!((d.length() - 1.0).abs() < 1e-5, "{p} → {d}");
            let q = equal_area_sphere_to_square(d);
            worst = worst.max((q - p).abs().max_element());
            let d2 = equal_area_square_to_sphere(q);
            assert!((d2 - d).length() < 1e-4, "{p}: {d} → {q} → {d2}");
        }
        assert!(worst < 2e-4, "worst square round trip {worst}");
        // Equal areas: every small cell of the square covers 4π·(its area) of solid angle
        // (the spherical triangle areas of its two halves, by Van Oosterom–Strackee).
        let tri = |a: Vec3, b: Vec3, c: Vec3| {
            let num = a.dot(b.cross(c)).abs() as f64;
            let den = 1.0 + a.dot(b) as f64 + b.dot(c) as f64 + c.dot(a) as f64;
            2.0 * num.atan2(den)
        };
        let (n, sub) = (32, 8);
        let h = 1.0 / (n * sub) as f32;
        let mut total = 0f64;
        for p in grid(n, Vec2::ZERO) {
            let mut omega = 0.0;
            for q in grid(sub, Vec2::ZERO) {
                let o = p + q / n as f32;
                let m = |dx: f32, dy: f32| equal_area_square_to_sphere(o + Vec2::new(dx, dy));
                let (a, b, c, d) = (m(0.0, 0.0), m(h, 0.0), m(h, h), m(0.0, h));
                omega += tri(a, b, c) + tri(a, c, d);
            }
            let expect = 4.0 * std::f64::consts::PI / (n * n) as f64;
            // Flat-sided sub-cells miss a little of the curved cell, never 1 %.
            assert!(
                (omega / expect - 1.0).abs() < 0.01,
                "cell at {p}: {omega} vs {expect}"
            );
            total += omega;
        }
        assert!(
            (total / (4.0 * std::f64::consts::PI) - 1.0).abs() < 2e-3,
            "total {total}"
        );
    }
}
