//! Linear sRGB (ITU-R BT.709 primaries, D65 white) ↔ CIE XYZ.
//!
//! The matrices come from `base::cie_data`: BT.709 primaries with the white point of the tabulated
//! D65 under the tabulated CMFs (x, y = 0.312727, 0.329023; the standard's rounded
//! 0.3127, 0.3290 differs in the fifth digit), as pbrt-v4 builds its colour spaces. With them a
//! flat unit reflectance under D65 is RGB (1, 1, 1) to rounding, which the upsampling tables and
//! their round trip rely on. They agree with IEC 61966-2-1's printed matrix to 4e-4.

use crate::math::{Mat3, PVec3, Vec3};
use base::cie_data;

pub use cie_data::{SRGB_TO_XYZ, XYZ_TO_SRGB};

const fn to_mat3(m: [[f64; 3]; 3]) -> Mat3 {
    // glam is column-major; the tables are row-major.
    Mat3::from_cols(
        PVec3::new(m[0][0] as f32, m[1][0] as f32, m[2][0] as f32),
        PVec3::new(m[0][1] as f32, m[1][1] as f32, m[2][1] as f32),
        PVec3::new(m[0][2] as f32, m[1][2] as f32, m[2][2] as f32),
    )
}

/// CIE XYZ → linear sRGB, single precision.
pub const XYZ_TO_SRGB_F32: Mat3 = to_mat3(XYZ_TO_SRGB);
/// Linear sRGB → CIE XYZ, single precision.
pub const SRGB_TO_XYZ_F32: Mat3 = to_mat3(SRGB_TO_XYZ);

/// CIE XYZ → linear sRGB.
#[inline]
pub fn xyz_to_srgb(xyz: Vec3) -> Vec3 {
    XYZ_TO_SRGB_F32.mul_vec3a(xyz)
}

/// Linear sRGB → CIE XYZ.
#[inline]
pub fn srgb_to_xyz(rgb: Vec3) -> Vec3 {
    SRGB_TO_XYZ_F32.mul_vec3a(rgb)
}

/// `m · v` in double precision (tables and tools).
pub fn mul3(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// Linear sRGB of a spectrum, summed over the 1 nm CIE tables in double precision: a
/// reflectance lit by D65 (normalised so that white has Y = 1) when `under_d65`, else an
/// emission (divided by ∫ȳ, as `SampledSpectrum::to_xyz`). The reference of the upsampling
/// round trips (tests and the table generator).
pub fn spectrum_to_srgb(s: &impl super::Spectrum, under_d65: bool) -> [f64; 3] {
    use super::cie::{CIE_D65, CIE_SAMPLES, CIE_X, CIE_Y, CIE_Z, table_lambda};
    let (mut xyz, mut norm) = ([0.0f64; 3], 0.0);
    for i in 0..CIE_SAMPLES {
        let v = f64::from(s.eval(table_lambda(i) as f32));
        let light = if under_d65 { CIE_D65[i] } else { 1.0 };
        xyz[0] += v * light * CIE_X[i];
        xyz[1] += v * light * CIE_Y[i];
        xyz[2] += v * light * CIE_Z[i];
        norm += light * CIE_Y[i];
    }
    mul3(&XYZ_TO_SRGB, xyz.map(|c| c / norm))
}

#[cfg(test)]
mod tests {
    use super::super::cie::{self, CIE_D65};
    use super::*;

    #[test]
    fn matrices_are_inverse_and_map_d65_to_white() {
        for e in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            let back = mul3(&XYZ_TO_SRGB, mul3(&SRGB_TO_XYZ, e));
            for c in 0..3 {
                assert!((back[c] - e[c]).abs() < 1e-12, "{back:?}");
            }
        }
        // White: D65 under the CMFs, normalised to Y = 1.
        let w = cie::integrate_xyz(|l| CIE_D65[(l - 360.0) as usize]);
        let w = w.map(|c| c / w[1]);
        let rgb = mul3(&XYZ_TO_SRGB, w);
        for c in rgb {
            assert!((c - 1.0).abs() < 1e-12, "{rgb:?}");
        }
        // The luminance row is BT.709's (0.2126, 0.7152, 0.0722).
        let y = SRGB_TO_XYZ[1];
        assert!((y[0] - 0.2126).abs() < 1e-4 && (y[1] - 0.7152).abs() < 1e-4);
        assert!((y[2] - 0.0722).abs() < 1e-4);
    }

    #[test]
    fn close_to_the_printed_iec_matrix() {
        // IEC 61966-2-1 (sRGB), XYZ → linear RGB.
        let iec = [
            [3.2406, -1.5372, -0.4986],
            [-0.9689, 1.8758, 0.0415],
            [0.0557, -0.2040, 1.0570],
        ];
        for i in 0..3 {
            for j in 0..3 {
                assert!((iec[i][j] - XYZ_TO_SRGB[i][j]).abs() < 5e-4, "({i}, {j})");
            }
        }
        let v = Vec3::new(0.3, 0.5, 0.2);
        let back = srgb_to_xyz(xyz_to_srgb(v));
        assert!((back - v).abs().max_element() < 1e-6);
        let d = mul3(&XYZ_TO_SRGB, [0.3, 0.5, 0.2]);
        let f = xyz_to_srgb(v);
        for c in 0..3 {
            assert!((d[c] as f32 - f[c]).abs() < 1e-6);
        }
    }
}
