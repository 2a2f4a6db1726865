//! Display tone mapping for 8-bit outputs: Reinhard et al. 2002, "Photographic Tone
//! Reproduction for Digital Images", global operator (their equations 1–4), with the
//! CENG795 options: `key` (a), `burn_percent` (the share of pixels, by scaled luminance, that
//! map to white: L_white is the (100 − burn)-th percentile), `saturation` s and display
//! `gamma`:
//!
//! L̄w = exp(mean(ln(δ + Lw))), L = a·Lw / L̄w, Ld = L (1 + L/L²white) / (1 + L),
//! C_display = clamp(Ld · (C / Lw)^s)^(1/γ).
//!
//! Luminance uses the Rec.709 weights. The result is display-referred in [0, 1].

use super::Image;
use crate::math::Vec3;
use base::Tonemap;

const LUM: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// Apply `tm` to a linear image; the result is display-encoded in [0, 1].
pub fn apply(img: &Image, tm: &Tonemap) -> Image {
    let (key, burn_percent, saturation, gamma) = match *tm {
        Tonemap::Photographic {
            key,
            burn_percent,
            saturation,
            gamma,
        } => (key, burn_percent, saturation, gamma),
        Tonemap::DisplayUnits => {
            let mut out = img.clone();
            for p in &mut out.pixels {
                *p = (*p / 255.0).clamp(Vec3::ZERO, Vec3::ONE);
            }
            return out;
        }
    };
    let lum: Vec<f32> = img
        .pixels
        .iter()
        .map(|p| {
            let l = p.max(Vec3::ZERO).dot(LUM);
            if l.is_finite() { l } else { 0.0 }
        })
        .collect();
    let n = lum.len().max(1) as f64;
    let log_avg = (lum.iter().map(|&l| (1e-6 + l as f64).ln()).sum::<f64>() / n).exp() as f32;
    let scale = if log_avg > 0.0 { key / log_avg } else { 0.0 };
    let mut scaled: Vec<f32> = lum.iter().map(|&l| l * scale).collect();
    let l_white = {
        let burn = burn_percent.clamp(0.0, 100.0) as f64;
        scaled.sort_unstable_by(f32::total_cmp);
        let idx = (((100.0 - burn) / 100.0) * (scaled.len() as f64 - 1.0)).round() as usize;
        scaled.get(idx).copied().unwrap_or(0.0)
    };
    let inv_w2 = if l_white > 0.0 {
        1.0 / (l_white * l_white)
    } else {
        0.0
    };
    let inv_gamma = if gamma > 0.0 { 1.0 / gamma } else { 1.0 };
    let pixels = img
        .pixels
        .iter()
        .zip(&lum)
        .map(|(p, &lw)| {
            if lw <= 0.0 {
                return Vec3::ZERO;
            }
            let l = lw * scale;
            let ld = l * (1.0 + l * inv_w2) / (1.0 + l);
            let c = (p.max(Vec3::ZERO) / lw).powf(saturation) * ld;
            c.clamp(Vec3::ZERO, Vec3::ONE).powf(inv_gamma)
        })
        .collect();
    Image {
        width: img.width,
        height: img.height,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tm(key: f32, burn: f32) -> Tonemap {
        Tonemap::Photographic {
            key,
            burn_percent: burn,
            saturation: 1.0,
            gamma: 1.0,
        }
    }

    #[test]
    fn uniform_image_maps_key_through_the_curve() {
        // Every pixel is the log average, so L = key; no burn-out: L_white = key.
        let img = Image {
            width: 2,
            height: 2,
            pixels: vec![Vec3::splat(5.0); 4],
        };
        let out = apply(&img, &tm(0.18, 0.0));
        let l: f32 = 0.18;
        let expect = l * (1.0 + 1.0 / l) / (1.0 + l);
        assert!((out.pixels[0].x - expect).abs() < 1e-3, "{}", out.pixels[0]);
    }

    #[test]
    fn burn_out_saturates_the_brightest_pixels() {
        let mut pixels: Vec<Vec3> = (0..100)
            .map(|i| Vec3::splat(i as f32 * 0.01 + 0.01))
            .collect();
        pixels[99] = Vec3::splat(1000.0);
        let img = Image {
            width: 10,
            height: 10,
            pixels,
        };
        let out = apply(&img, &tm(0.18, 5.0));
        assert!(out.pixels[99].x >= 0.999);
        assert!(out.pixels[96].x >= 0.999);
        assert!(out.pixels[50].x < 0.99);
        assert!(
            out.pixels
                .iter()
                .all(|p| p.is_finite() && p.max_element() <= 1.0)
        );
    }
}
