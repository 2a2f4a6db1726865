//! Warps from the unit square to common domains, each with its pdf (χ²-tested in
//! `tests/chi2_warps.rs`).

use crate::math::{INV_2PI, INV_4PI, INV_PI, PI, Vec2, Vec3};

/// Shirley–Chiu concentric map to the unit disk (area pdf 1/π).
pub fn square_to_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, (PI / 4.0) * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - (PI / 4.0) * (o.x / o.y))
    };
    let (s, c) = theta.sin_cos();
    Vec2::new(r * c, r * s)
}

pub fn uniform_disk_pdf() -> f32 {
    INV_PI
}

/// Cosine-weighted hemisphere around +z (pdf cos θ / π).
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_uniform_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

pub fn cosine_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z > 0.0 { w.z * INV_PI } else { 0.0 }
}

/// Uniform hemisphere around +z (pdf 1/2π).
pub fn square_to_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let (s, c) = phi.sin_cos();
    Vec3::new(r * c, r * s, z)
}

pub fn uniform_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z >= 0.0 { INV_2PI } else { 0.0 }
}

/// Uniform sphere (pdf 1/4π).
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let (s, c) = phi.sin_cos();
    Vec3::new(r * c, r * s, z)
}

pub fn uniform_sphere_pdf() -> f32 {
    INV_4PI
}

/// Uniform cone of directions around +z with cos θ ≥ `cos_max` (pdf 1 / (2π(1 − cos_max))).
pub fn square_to_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = (1.0 - u.x) + u.x * cos_max;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let (s, c) = phi.sin_cos();
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

    #[test]
    fn warps_land_in_their_domains() {
        let n = 64;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
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
    }
}
