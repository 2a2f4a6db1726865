//! The Hošek–Wilkie sky (2012) and sun (2013) as Mitsuba 3.9.1's `sunsky` emitter evaluates
//! them, from the datasets Mitsuba ships (`crates/render/data/sunsky/`, with their licences
//! and origin): the coefficients are interpolated once per emitter — linearly in turbidity
//! (levels 1…10) and ground albedo (0 and 1, per channel), by the quintic Bézier of the
//! model in the sun's elevation — and the radiance of a direction is then the model's
//! nine-parameter formula per channel, plus the sun's disk.
//!
//! Two colour forms, as Mitsuba's variants have them: RGB (the `_rgb` datasets, times
//! Mitsuba's CIE Y normalisation, the sun with its RGB conversion constant), and spectral (11
//! channels at 320…720 nm every 40 nm, linearly interpolated in wavelength; zero outside, as
//! in Mitsuba). The sun is a uniform disk of the sun's mean radiance (its irradiance over the
//! solid angle of the real sun, rescaled so that a wider `sun_aperture` keeps the
//! irradiance), or with `complex_sun` the elevation-dependent solar radiance polynomial with
//! limb darkening.

use std::collections::HashMap;
use std::sync::OnceLock;

use crate::math::Vec3;

const DATASETS: &[u8] = include_bytes!("../../data/sunsky/sunsky_datasets.bin");
const SAMPLING_DATA: &[u8] = include_bytes!("../../data/sunsky/sampling_data.bin");

/// Spectral channels of the model: 320, 360, …, 720 nm.
pub const WAVELENGTH_COUNT: usize = 11;
const WAVELENGTH_FIRST: f32 = 320.0;
const WAVELENGTH_STEP: f32 = 40.0;
const TURBIDITY_LEVELS: usize = 10;
const SKY_PARAMS: usize = 9;
const SKY_CTRL: usize = 6;
const SUN_SEGMENTS: usize = 45;
const SUN_CTRL: usize = 4;
const SUN_LD: usize = 6;
const IRRADIANCE_ELEVATIONS: usize = 30;

/// The real sun's half aperture (0.5358° across), radians.
pub const SUN_HALF_APERTURE: f64 = std::f64::consts::PI * (0.5 * 0.5358) / 180.0;
/// Mitsuba's factor from the solar radiance datasets to RGB.
const SPEC_TO_RGB_SUN: f64 = 467.069280386;
/// Mitsuba's `MI_CIE_Y_NORMALIZATION` (1 / ∫ȳ over its 360…830 nm table).
const CIE_Y_NORMALIZATION: f64 = 1.0 / 106.750_287_287_22;

/// One array of a `TensorFile`, widened to f64, row-major.
struct Field {
    shape: Vec<usize>,
    data: Vec<f64>,
}

/// The model's `i`-th wavelength (nm).
pub fn wavelength(i: usize) -> f32 {
    WAVELENGTH_FIRST + WAVELENGTH_STEP * i as f32
}

/// Mitsuba's `TensorFile` container: "tensor_file\0", version (u16), field count (u32), then
/// per field its name (u16 length, bytes), rank (u16), type (u8: 10 f32, 11 f64), offset
/// (u64) and shape (u64 per axis); little-endian.
fn parse_tensor_file(bytes: &[u8]) -> HashMap<String, Field> {
    struct Reader<'a>(&'a [u8], usize);
    impl Reader<'_> {
        fn take(&mut self, n: usize) -> &[u8] {
            let s = &self.0[self.1..self.1 + n];
            self.1 += n;
            s
        }
        fn u16(&mut self) -> u16 {
            u16::from_le_bytes(self.take(2).try_into().unwrap())
        }
        fn u32(&mut self) -> u32 {
            u32::from_le_bytes(self.take(4).try_into().unwrap())
        }
        fn u64(&mut self) -> u64 {
            u64::from_le_bytes(self.take(8).try_into().unwrap())
        }
    }
    assert_eq!(
        &bytes[..12],
        b"tensor_file\0",
        "sunsky dataset: not a TensorFile"
    );
    let mut r = Reader(bytes, 12);
    let _version = r.u16();
    let n = r.u32();
    let mut fields = HashMap::new();
    for _ in 0..n {
        let len = r.u16() as usize;
        let name = String::from_utf8_lossy(r.take(len)).into_owned();
        let rank = r.u16() as usize;
        let ty = r.take(1)[0];
        let offset = r.u64() as usize;
        let shape: Vec<usize> = (0..rank).map(|_| r.u64() as usize).collect();
        let count: usize = shape.iter().product();
        let data = match ty {
            10 => bytes[offset..offset + 4 * count]
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes(c.try_into().unwrap()) as f64)
                .collect(),
            11 => bytes[offset..offset + 8 * count]
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                .collect(),
            _ => panic!("sunsky dataset: field {name} of unknown type {ty}"),
        };
        fields.insert(name, Field { shape, data });
    }
    fields
}

fn fields() -> &'static HashMap<String, Field> {
    static FIELDS: OnceLock<HashMap<String, Field>> = OnceLock::new();
    FIELDS.get_or_init(|| {
        let mut f = parse_tensor_file(DATASETS);
        f.extend(parse_tensor_file(SAMPLING_DATA));
        f
    })
}

fn field(name: &str) -> &'static Field {
    fields()
        .get(name)
        .unwrap_or_else(|| panic!("sunsky dataset: no field {name}"))
}

/// Linear interpolation along the first axis at the fractional index `t` (clamped to the
/// axis): the sub-array of the remaining axes.
fn take_interp(data: &[f64], n: usize, t: f64) -> Vec<f64> {
    let block = data.len() / n;
    let t = t.clamp(0.0, (n - 1) as f64);
    let i0 = (t.floor() as usize).min(n - 1);
    let i1 = (i0 + 1).min(n - 1);
    let f = t - i0 as f64;
    (0..block)
        .map(|k| (1.0 - f) * data[i0 * block + k] + f * data[i1 * block + k])
        .collect()
}

/// The sky datasets (`[turbidity][albedo][control point][channel][params]`) interpolated in
/// turbidity, per-channel albedo and, by the model's quintic Bézier, the sun's elevation
/// `eta` (radians): `[channel][params]`.
fn sky_coefficients(f: &Field, turbidity: f64, albedo: &[f64], eta: f64) -> Vec<f64> {
    let channels = f.shape[3];
    let per_channel = f.data.len() / (TURBIDITY_LEVELS * 2 * SKY_CTRL * channels);
    let t = take_interp(&f.data, TURBIDITY_LEVELS, turbidity - 1.0);
    let half = t.len() / 2;
    let a: Vec<f64> = (0..half)
        .map(|k| {
            let w = albedo[(k / per_channel) % channels];
            (1.0 - w) * t[k] + w * t[half + k]
        })
        .collect();
    let x = (2.0 / std::f64::consts::PI * eta)
        .cbrt()
        .min(1.0 - f32::EPSILON as f64 / 2.0);
    const BINOMIAL: [f64; SKY_CTRL] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    let block = a.len() / SKY_CTRL;
    (0..block)
        .map(|k| {
            (0..SKY_CTRL)
                .map(|c| {
                    BINOMIAL[c]
                        * x.powi(c as i32)
                        * (1.0 - x).powi((SKY_CTRL - 1 - c) as i32)
                        * a[c * block + k]
                })
                .sum()
        })
        .collect()
}

/// What an emitter declares of the sun and sky.
#[derive(Clone, Copy, Debug)]
pub struct SunSkyParams {
    /// In [1, 10].
    pub turbidity: f32,
    /// Ground albedo in RGB (for the RGB datasets).
    pub albedo_rgb: [f32; 3],
    /// Ground albedo at the model's 11 wavelengths (for the spectral datasets).
    pub albedo_spectral: [f32; WAVELENGTH_COUNT],
    /// Towards the sun, in the emitter's local frame (z up).
    pub sun_dir: Vec3,
    pub sun_scale: f32,
    pub sky_scale: f32,
    /// Radians.
    pub sun_half_aperture: f32,
    pub complex_sun: bool,
}

/// The model in one colour form: per channel the sky's nine parameters and mean radiance,
/// the sun's disk radiance (uniform sun) and its polynomial (complex sun).
#[derive(Clone, Debug)]
struct Channels {
    sky_params: Vec<[f32; SKY_PARAMS]>,
    sky_rad: Vec<f32>,
    /// Uniform sun: its radiance per channel, before the aperture's ratio and scale.
    sun_uniform: Vec<f32>,
    /// Complex sun, RGB: `[segment][channel][ctrl][ld]`; spectral: `[segment][channel][ctrl]`.
    sun_poly: Vec<f32>,
}

/// The sun and sky of one `sunsky` emitter, in its local frame (z up).
#[derive(Clone, Debug)]
pub struct SunSkyModel {
    pub sun_dir: Vec3,
    pub sun_scale: f32,
    pub sky_scale: f32,
    pub cos_aperture: f32,
    sin_aperture: f32,
    area_ratio: f32,
    complex_sun: bool,
    rgb: Channels,
    spectral: Channels,
    /// Spectral limb darkening, `[channel][ld]`.
    sun_ld: Vec<f32>,
}

impl SunSkyModel {
    pub fn new(p: &SunSkyParams) -> SunSkyModel {
        let sun_dir = p.sun_dir.normalize();
        let turbidity = p.turbidity.clamp(1.0, 10.0) as f64;
        let eta = std::f64::consts::FRAC_PI_2 - (sun_dir.z.clamp(-1.0, 1.0) as f64).acos();
        let albedo_rgb: Vec<f64> = p.albedo_rgb.iter().map(|&a| a as f64).collect();
        let albedo_spec: Vec<f64> = p.albedo_spectral.iter().map(|&a| a as f64).collect();

        // The sun's spectral irradiance at this turbidity and elevation (2°…89° every 3°).
        let irr = field("sun_irradiance");
        let irr_t = take_interp(&irr.data, TURBIDITY_LEVELS, turbidity - 1.0);
        let angle = ((eta.to_degrees() - 2.0) / 3.0).clamp(0.0, (IRRADIANCE_ELEVATIONS - 1) as f64);
        let sun_irr = take_interp(&irr_t, IRRADIANCE_ELEVATIONS, angle);
        // The real sun's solid angle and the aperture's ratio, with the cosines in single
        // precision as Mitsuba computes them (1 − cos of a quarter degree keeps only a few
        // digits in f32: 0.2 % on the sun's radiance).
        let one_minus_cos = |a: f64| (1.0 - (a as f32).cos()) as f64;
        let sun_solid = 2.0 * std::f64::consts::PI * one_minus_cos(SUN_HALF_APERTURE);
        // RGB: the spectrum's sRGB (CIE 1931 at the 11 wavelengths, their mean).
        let mut xyz = [0f64; 3];
        for (i, e) in sun_irr.iter().enumerate() {
            let bar = crate::spectral::cie::xyz_bar(WAVELENGTH_FIRST + WAVELENGTH_STEP * i as f32);
            for (c, b) in xyz.iter_mut().zip([bar.x, bar.y, bar.z]) {
                *c += b as f64 * e / WAVELENGTH_COUNT as f64;
            }
        }
        let m = base::cie_data::XYZ_TO_SRGB;
        let sun_rgb: Vec<f32> = (0..3)
            .map(|r| {
                let v: f64 = (0..3).map(|c| m[r][c] * xyz[c]).sum();
                (v / sun_solid) as f32
            })
            .collect();
        let sun_spec: Vec<f32> = sun_irr.iter().map(|e| (e / sun_solid) as f32).collect();

        let params = |name: &str, albedo: &[f64]| -> Vec<[f32; SKY_PARAMS]> {
            sky_coefficients(field(name), turbidity, albedo, eta)
                .chunks_exact(SKY_PARAMS)
                .map(|c| std::array::from_fn(|i| c[i] as f32))
                .collect()
        };
        let rad = |name: &str, albedo: &[f64]| -> Vec<f32> {
            sky_coefficients(field(name), turbidity, albedo, eta)
                .iter()
                .map(|&v| v as f32)
                .collect()
        };
        let poly = |name: &str| -> Vec<f32> {
            take_interp(&field(name).data, TURBIDITY_LEVELS, turbidity - 1.0)
                .iter()
                .map(|&v| v as f32)
                .collect()
        };
        let half = p.sun_half_aperture as f64;
        SunSkyModel {
            sun_dir,
            sun_scale: p.sun_scale,
            sky_scale: p.sky_scale,
            cos_aperture: half.cos() as f32,
            sin_aperture: half.sin() as f32,
            area_ratio: (one_minus_cos(SUN_HALF_APERTURE) / one_minus_cos(half)) as f32,
            complex_sun: p.complex_sun,
            rgb: Channels {
                sky_params: params("sky_params_rgb", &albedo_rgb),
                sky_rad: rad("sky_rad_rgb", &albedo_rgb),
                sun_uniform: sun_rgb,
                sun_poly: if p.complex_sun {
                    poly("sun_rad_rgb")
                } else {
                    Vec::new()
                },
            },
            spectral: Channels {
                sky_params: params("sky_params_spec", &albedo_spec),
                sky_rad: rad("sky_rad_spec", &albedo_spec),
                sun_uniform: sun_spec,
                sun_poly: if p.complex_sun {
                    poly("sun_rad_spec")
                } else {
                    Vec::new()
                },
            },
            sun_ld: field("sun_ld_spec")
                .data
                .iter()
                .map(|&v| v as f32)
                .collect(),
        }
    }

    /// The sun is above the horizon (below it, Mitsuba's sky is black too).
    pub fn sun_up(&self) -> bool {
        self.sun_dir.z >= 0.0
    }

    /// The direction `d` (local, unit) falls in the sun's disk.
    #[inline]
    pub fn in_sun(&self, d: Vec3) -> bool {
        self.sun_dir.dot(d) >= self.cos_aperture
    }

    /// The model's sky formula for one channel.
    #[inline]
    fn sky(p: &[f32; SKY_PARAMS], rad: f32, cos_theta: f32, gamma: f32) -> f32 {
        let cos_gamma = gamma.cos();
        let cg2 = cos_gamma * cos_gamma;
        let c1 = 1.0 + p[0] * (p[1] / (cos_theta + 0.01)).exp();
        let chi = (1.0 + cg2) / (1.0 + p[8] * p[8] - 2.0 * p[8] * cos_gamma).powf(1.5);
        let c2 = p[2]
            + p[3] * (p[4] * gamma).exp()
            + p[5] * cg2
            + p[6] * chi
            + p[7] * cos_theta.max(0.0).sqrt();
        c1 * c2 * rad
    }

    /// The sun's elevation segment and the offset in it, and cos ψ (the limb's angle), of the
    /// complex sun seen along a direction of cos θ `cos_theta` at `gamma` from its centre.
    fn sun_geometry(&self, cos_theta: f32, gamma: f32) -> (usize, f32, f32) {
        let elevation = std::f32::consts::FRAC_PI_2 - cos_theta.clamp(-1.0, 1.0).acos();
        let seg = ((2.0 * elevation * std::f32::consts::FRAC_1_PI).cbrt() * SUN_SEGMENTS as f32)
            .floor()
            .max(0.0) as usize;
        let seg = seg.min(SUN_SEGMENTS - 1);
        let break_x = std::f32::consts::FRAC_PI_2 * (seg as f32 / SUN_SEGMENTS as f32).powi(3);
        let sg = gamma.sin() / self.sin_aperture;
        let cos_psi = (1.0 - sg * sg).max(0.0).sqrt();
        (seg, elevation - break_x, cos_psi)
    }

    /// Radiance in RGB along the local unit direction `d` (Mitsuba's `llvm_ad_rgb`).
    pub fn eval_rgb(&self, d: Vec3) -> Vec3 {
        let cos_theta = d.z;
        if cos_theta < 0.0 || !self.sun_up() {
            return Vec3::ZERO;
        }
        let gamma = unit_angle(self.sun_dir, d);
        let ch = &self.rgb;
        let mut res = [0f32; 3];
        if self.sky_scale > 0.0 {
            for (c, r) in res.iter_mut().enumerate() {
                *r = self.sky_scale * Self::sky(&ch.sky_params[c], ch.sky_rad[c], cos_theta, gamma);
            }
        }
        if self.sun_scale > 0.0 && self.in_sun(d) {
            let scale = self.sun_scale * self.area_ratio * SPEC_TO_RGB_SUN as f32;
            if self.complex_sun {
                let (seg, x, cos_psi) = self.sun_geometry(cos_theta, gamma);
                let base = seg * 3 * SUN_CTRL * SUN_LD;
                for (c, r) in res.iter_mut().enumerate() {
                    let mut v = 0f32;
                    for k in 0..SUN_CTRL {
                        for j in 0..SUN_LD {
                            v += x.powi(k as i32)
                                * cos_psi.powi(j as i32)
                                * ch.sun_poly[base + (c * SUN_CTRL + k) * SUN_LD + j];
                        }
                    }
                    *r += scale * v;
                }
            } else {
                for (c, r) in res.iter_mut().enumerate() {
                    *r += scale * ch.sun_uniform[c];
                }
            }
        }
        Vec3::from(res) * CIE_Y_NORMALIZATION as f32
    }

    /// Spectral radiance at `lambda` (nm) along the local unit direction `d` (Mitsuba's
    /// spectral variants): the channels linearly interpolated, zero outside 320…720 nm.
    pub fn eval_spectral(&self, d: Vec3, lambda: f32) -> f32 {
        let cos_theta = d.z;
        if cos_theta < 0.0 || !self.sun_up() {
            return 0.0;
        }
        let n = (lambda - WAVELENGTH_FIRST) / WAVELENGTH_STEP;
        if !(0.0..=(WAVELENGTH_COUNT - 1) as f32).contains(&n) {
            return 0.0;
        }
        let lo = (n.floor() as usize).min(WAVELENGTH_COUNT - 1);
        let hi = (lo + 1).min(WAVELENGTH_COUNT - 1);
        let f = n - lo as f32;
        let lerp = |a: f32, b: f32| a + (b - a) * f;
        let gamma = unit_angle(self.sun_dir, d);
        let ch = &self.spectral;
        let mut res = 0.0;
        if self.sky_scale > 0.0 {
            let s = |c: usize| Self::sky(&ch.sky_params[c], ch.sky_rad[c], cos_theta, gamma);
            res = self.sky_scale * lerp(s(lo), s(hi));
        }
        if self.sun_scale > 0.0 && self.in_sun(d) {
            let (rad, ld) = if self.complex_sun {
                let (seg, x, cos_psi) = self.sun_geometry(cos_theta, gamma);
                let sun = |c: usize| {
                    let base = (seg * WAVELENGTH_COUNT + c) * SUN_CTRL;
                    (0..SUN_CTRL)
                        .map(|k| x.powi(k as i32) * ch.sun_poly[base + k])
                        .sum::<f32>()
                };
                let ld: f32 = (0..SUN_LD)
                    .map(|j| {
                        cos_psi.powi(j as i32)
                            * lerp(self.sun_ld[lo * SUN_LD + j], self.sun_ld[hi * SUN_LD + j])
                    })
                    .sum();
                (lerp(sun(lo), sun(hi)), ld)
            } else {
                (lerp(ch.sun_uniform[lo], ch.sun_uniform[hi]), 1.0)
            };
            res += self.sun_scale * rad * ld * self.area_ratio;
        }
        res
    }
}

/// The angle between two unit vectors, accurate near 0 and π (Mitsuba's `unit_angle`).
#[inline]
pub fn unit_angle(a: Vec3, b: Vec3) -> f32 {
    let dot = a.dot(b);
    let angle = 2.0 * (0.5 * (b - a * dot.signum()).length()).min(1.0).asin();
    if dot >= 0.0 {
        angle
    } else {
        std::f32::consts::PI - angle
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(sun: Vec3) -> SunSkyParams {
        SunSkyParams {
            turbidity: 4.3,
            albedo_rgb: [0.2; 3],
            albedo_spectral: [0.2; WAVELENGTH_COUNT],
            sun_dir: sun.normalize(),
            sun_scale: 1.0,
            sky_scale: 1.0,
            sun_half_aperture: SUN_HALF_APERTURE as f32,
            complex_sun: false,
        }
    }

    #[test]
    fn datasets_parse() {
        assert_eq!(field("sky_params_rgb").shape, vec![10, 2, 6, 3, 9]);
        assert_eq!(field("sun_irradiance").shape, vec![10, 30, 11]);
    }

    /// Relative agreement within `tol` (or absolute below 1e-6).
    fn close(a: f32, b: f64, tol: f64) -> bool {
        ((a as f64) - b).abs() <= tol * b.abs().max(1e-6)
    }

    /// Values printed by Mitsuba 3.9.1 (`scalar_rgb` and `scalar_spectral`, `emitter.eval`
    /// with `si.wi = −d`) for a sun at (0.3, 0.4, 0.5)/‖·‖, turbidity 4.3, albedo 0.2:
    /// zenith, a direction near the horizon, a sky direction, the sun's centre and a point
    /// of its disk off centre (limb darkening with `complex_sun`).
    #[test]
    fn matches_mitsuba_rgb_and_spectral() {
        let sun = Vec3::new(0.3, 0.4, 0.5).normalize();
        let near = (sun + Vec3::new(0.001, 0.0, 0.0)).normalize();
        let dirs = [
            Vec3::Z,
            Vec3::new(1.0, 0.0, 0.05).normalize(),
            Vec3::new(0.6, -0.2, 0.3).normalize(),
            sun,
            near,
        ];
        let rgb_uniform: [[f64; 3]; 5] = [
            [
                0.03221668303012848,
                0.04840143024921417,
                0.08648781478404999,
            ],
            [
                0.17010274529457092,
                0.20274043083190918,
                0.22955653071403503,
            ],
            [0.06000618636608124, 0.09156095236539841, 0.1506534218788147],
            [20380.8203125, 16657.6171875, 12299.4189453125],
            [20380.8203125, 16657.6171875, 12299.4189453125],
        ];
        let rgb_complex_sun: [[f64; 3]; 2] = [
            [24576.58984375, 20843.18359375, 16285.92578125],
            [24363.974609375, 20629.16796875, 16075.2353515625],
        ];
        let mut p = params(sun);
        let m = SunSkyModel::new(&p);
        for (d, want) in dirs.iter().zip(rgb_uniform) {
            let got = m.eval_rgb(*d);
            for c in 0..3 {
                assert!(close(got[c], want[c], 2e-4), "{d:?}: {got:?} vs {want:?}");
            }
        }
        p.complex_sun = true;
        let m = SunSkyModel::new(&p);
        for (d, want) in dirs[3..].iter().zip(rgb_complex_sun) {
            let got = m.eval_rgb(*d);
            for c in 0..3 {
                assert!(close(got[c], want[c], 2e-4), "{d:?}: {got:?} vs {want:?}");
            }
        }

        // Spectral, at 400, 515, 630 and 700 nm: sky, sky, sun centre, sun off centre.
        let lambdas = [400.0, 515.0, 630.0, 700.0];
        let spec_uniform: [[f64; 4]; 4] = [
            [
                0.09301401674747467,
                0.06154759228229523,
                0.030794255435466766,
                0.02074239030480385,
            ],
            [
                0.14667482674121857,
                0.11469432711601257,
                0.05727710574865341,
                0.03801757097244263,
            ],
            [
                7385.55908203125,
                15948.740234375,
                16148.7392578125,
                15056.9755859375,
            ],
            [
                7385.55908203125,
                15948.740234375,
                16148.7392578125,
                15056.9755859375,
            ],
        ];
        let spec_complex_sun: [[f64; 4]; 2] = [
            [
                10122.447265625,
                20204.98828125,
                19568.14453125,
                17887.537109375,
            ],
            [9973.453125, 19986.8046875, 19392.263671875, 17745.556640625],
        ];
        let spec_dirs = [dirs[0], dirs[2], dirs[3], dirs[4]];
        p.complex_sun = false;
        let m = SunSkyModel::new(&p);
        for (d, want) in spec_dirs.iter().zip(spec_uniform) {
            for (l, w) in lambdas.iter().zip(want) {
                let got = m.eval_spectral(*d, *l);
                assert!(close(got, w, 2e-4), "{d:?} at {l} nm: {got} vs {w}");
            }
        }
        p.complex_sun = true;
        let m = SunSkyModel::new(&p);
        for (d, want) in spec_dirs[2..].iter().zip(spec_complex_sun) {
            for (l, w) in lambdas.iter().zip(want) {
                let got = m.eval_spectral(*d, *l);
                assert!(close(got, w, 2e-4), "{d:?} at {l} nm: {got} vs {w}");
            }
        }
    }

    /// A coloured albedo and a 2° sun (Mitsuba keeps the irradiance: the disk's radiance
    /// falls by the ratio of solid angles).
    #[test]
    fn matches_mitsuba_albedo_and_aperture() {
        let sun = Vec3::new(0.3, 0.4, 0.5).normalize();
        let mut p = params(sun);
        p.albedo_rgb = [0.1, 0.5, 0.9];
        p.sun_half_aperture = 1f32.to_radians();
        let m = SunSkyModel::new(&p);
        let cases: [(Vec3, [f64; 3]); 3] = [
            (
                Vec3::Z,
                [
                    0.030892983078956604,
                    0.055259641259908676,
                    0.11715081334114075,
                ],
            ),
            (
                Vec3::new(0.6, -0.2, 0.3).normalize(),
                [
                    0.05600842460989952,
                    0.10960690677165985,
                    0.21366342902183533,
                ],
            ),
            (
                sun,
                [1460.0831298828125, 1193.45556640625, 881.297119140625],
            ),
        ];
        for (d, want) in cases {
            let got = m.eval_rgb(d);
            for c in 0..3 {
                assert!(close(got[c], want[c], 2e-4), "{d:?}: {got:?} vs {want:?}");
            }
        }
    }
}
