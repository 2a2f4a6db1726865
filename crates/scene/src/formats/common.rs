//! Helpers every loader shares.

use crate::model::{Mat4, Vec3};

/// Camera-to-world in Mitsuba's convention (columns left, up, dir, origin: the camera looks
/// along +z with +x to the image's left), as Mitsuba's `look_at`: a zero `up` means any vector
/// orthogonal to the direction; `None` when the direction is zero, `up` is parallel to it, or
/// anything is not finite.
pub fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - origin).normalize_or_zero();
    if dir == Vec3::ZERO || !origin.is_finite() {
        return None;
    }
    let up = if up.length_squared() == 0.0 {
        dir.any_orthonormal_vector()
    } else {
        up
    };
    let left = up.cross(dir).normalize_or_zero();
    if left == Vec3::ZERO || !left.is_finite() {
        return None;
    }
    Some(Mat4::from_cols(
        left.extend(0.0),
        dir.cross(left).extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}

/// The whitespace-separated numbers of `text`, every one finite; the error names the first
/// word that is not (the caller adds where it was).
pub fn finite_floats(text: &str) -> std::result::Result<Vec<f32>, String> {
    text.split_whitespace()
        .map(|t| {
            t.parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("'{t}' is not a finite number"))
        })
        .collect()
}
