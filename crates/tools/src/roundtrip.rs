//! The upsampling round trip (issue 21, acceptance 2), measured on a computed table before it is
//! written: every colour of an n³ grid of [0, 1]³ → spectrum → XYZ by the 1 nm CIE tables →
//! linear sRGB, for the three spectrum kinds. `crates/render/tests/it/spectral.rs` asserts the
//! same on the checked-in table.

use render::spectral::colorspace::spectrum_to_srgb;
use render::spectral::rgb::{
    RgbAlbedoSpectrum, RgbIlluminantSpectrum, RgbToSpectrumTable, RgbUnboundedSpectrum,
};

/// Largest |RGB out − RGB in| over the grid and the three channels, and where.
#[derive(Clone, Copy, Debug, Default)]
pub struct Worst {
    pub error: f64,
    pub rgb: [f64; 3],
}

impl Worst {
    fn add(&mut self, rgb_in: [f64; 3], rgb_out: [f64; 3]) {
        for c in 0..3 {
            let e = (rgb_out[c] - rgb_in[c]).abs();
            if e > self.error || e.is_nan() {
                self.error = e;
                self.rgb = rgb_in;
            }
        }
    }
}

/// Worst round trips of albedo (grid), unbounded (grid × `scale`, under D65) and illuminant
/// (grid × `scale`, emitted) spectra over an `n`³ grid.
pub fn round_trip(table: &RgbToSpectrumTable, n: usize, scale: f64) -> [Worst; 3] {
    let mut worst = [Worst::default(); 3];
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let g = [i, j, k].map(|v| v as f64 / (n - 1) as f64);
                let rgb = render::math::Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32);
                worst[0].add(
                    g,
                    spectrum_to_srgb(&RgbAlbedoSpectrum::new(table, rgb), true),
                );
                let gs = g.map(|v| v * scale);
                let rgbs = rgb * scale as f32;
                worst[1].add(
                    gs,
                    spectrum_to_srgb(&RgbUnboundedSpectrum::new(table, rgbs), true),
                );
                worst[2].add(
                    gs,
                    spectrum_to_srgb(&RgbIlluminantSpectrum::new(table, rgbs), false),
                );
            }
        }
    }
    worst
}
