//! Image-based environment lights: an equirectangular (lat-long) image, bilinearly
//! interpolated, importance-sampled with a piecewise-constant 2D distribution of its pixel
//! luminance weighted by sin θ; or a light probe (Debevec's angular map), sampled uniformly;
//! or pbrt-v4's equal-area octahedral square, looked up nearest-pixel as pbrt-v4 does and
//! sampled in proportion to each pixel's luminance (every pixel subtends 4π/(w·h)).
//! Lat-long local directions map to uv = (atan2(x, −z) / 2π, acos(y) / π), y up, as in
//! Mitsuba; equal-area ones use the light's frame as it is (pbrt-v4's).

use base::EnvMapping;

use super::LightScene;
use super::select::{infinite_emission, infinite_pdf_le, mean, scene_radius};
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::film::Image;
use crate::math::{INV_PI, Mat3, Mat4, PI, Vec2, Vec3, luminance};
use crate::sampling::distrib::Distribution2D;
use crate::sampling::warp;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::ColorMode;

#[derive(Debug)]
pub struct EnvMap {
    pub image: Image,
    pub scale: f32,
    pub to_world: Mat3,
    pub to_local: Mat3,
    pub mapping: EnvMapping,
    pub distribution: Distribution2D,
}

impl EnvMap {
    pub fn new(image: Image, scale: f32, to_world: &Mat4, mapping: EnvMapping) -> EnvMap {
        let (w, h) = (image.width as usize, image.height as usize);
        let rot = Mat3::from_mat4(*to_world);
        let lum = |x: usize, y: usize| {
            let v = luminance(image.get(x as u32, y as u32));
            if v.is_finite() { v.max(0.0) } else { 0.0 }
        };
        if mapping == EnvMapping::EqualArea {
            // Nearest lookups make the radiance piecewise constant over pixels of equal
            // solid angle: sampling by pixel luminance follows it exactly.
            let weights: Vec<f32> = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| lum(x, y))
                .collect();
            return EnvMap {
                distribution: Distribution2D::new(&weights, w, h),
                image,
                scale,
                to_world: rot,
                to_local: rot.inverse(),
                mapping,
            };
        }
        // Mitsuba's lat-long grid: columns are pixel centres (u = (x + ½)/w), rows are grid
        // *vertices* (v = y/(h − 1)), so cell (x, y) of the sampling grid spans the rows y and
        // y + 1 and, through the bilinear lookup, the columns x − 1 … x + 1. Each cell gets the
        // largest luminance of those pixels times sin θ at its centre: the pdf is then never
        // small where the interpolated radiance is large (a one-pixel sun would otherwise
        // bleed into cells the pdf barely samples).
        let rows = h.saturating_sub(1).max(1);
        let mut weights = vec![0f32; w * rows];
        for y in 0..rows {
            let sin_theta = ((y as f32 + 0.5) / rows as f32 * PI).sin();
            for x in 0..w {
                let mut m = 0f32;
                for yy in [y, (y + 1).min(h - 1)] {
                    for dx in [-1i64, 0, 1] {
                        let xx = (x as i64 + dx).rem_euclid(w as i64) as usize;
                        m = m.max(lum(xx, yy));
                    }
                }
                weights[y * w + x] = m * sin_theta;
            }
        }
        EnvMap {
            distribution: Distribution2D::new(&weights, w, rows),
            image,
            scale,
            to_world: rot,
            to_local: rot.inverse(),
            mapping,
        }
    }

    fn dir_to_uv(&self, d_world: Vec3) -> Vec2 {
        let d = (self.to_local * d_world).normalize_or_zero();
        match self.mapping {
            EnvMapping::LatLong => {
                let mut u = d.x.atan2(-d.z) * (0.5 * INV_PI);
                if u < 0.0 {
                    u += 1.0;
                }
                Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() * INV_PI)
            }
            EnvMapping::Probe => {
                // Debevec's angular map: r = acos(-z) / (π √(x² + y²)).
                let xy = (d.x * d.x + d.y * d.y).sqrt();
                let r = if xy > 0.0 {
                    (-d.z).clamp(-1.0, 1.0).acos() * INV_PI / xy
                } else {
                    0.0
                };
                Vec2::new(0.5 + 0.5 * d.x * r, 0.5 - 0.5 * d.y * r)
            }
            EnvMapping::EqualArea => warp::equal_area_sphere_to_square(d),
        }
    }

    /// The world direction at `uv` of a lat-long or equal-area map, and the solid angle per
    /// unit of uv there (0 at a lat-long pole).
    fn uv_to_dir(&self, uv: Vec2) -> (Vec3, f32) {
        if self.mapping == EnvMapping::EqualArea {
            let local = warp::equal_area_square_to_sphere(uv);
            return ((self.to_world * local).normalize(), 4.0 * PI);
        }
        let phi = uv.x * 2.0 * PI;
        let theta = uv.y * PI;
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let local = Vec3::new(st * sp, ct, -st * cp);
        ((self.to_world * local).normalize(), 2.0 * PI * PI * st)
    }

    /// The solid angle per unit of uv at `uv` (see [`Self::uv_to_dir`]).
    fn uv_jacobian(&self, uv: Vec2) -> f32 {
        match self.mapping {
            EnvMapping::EqualArea => 4.0 * PI,
            _ => 2.0 * PI * PI * (uv.y * PI).sin(),
        }
    }

    /// Bilinear lookup on Mitsuba's grid: x = u·w − ½ (pixel centres, wrapping in u),
    /// y = v·(h − 1) (rows at the grid vertices, v = 0 and 1 on the first and last rows).
    /// Probe maps use pixel centres in both axes.
    fn lookup(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        if self.mapping == EnvMapping::EqualArea {
            let px = |t: f32, n: i64| ((t * n as f32) as i64).clamp(0, n - 1) as u32;
            return self.image.get(px(uv.x, w), px(uv.y, h)) * self.scale;
        }
        let x = uv.x * w as f32 - 0.5;
        let y = match self.mapping {
            EnvMapping::LatLong => uv.y * (h - 1) as f32,
            EnvMapping::Probe | EnvMapping::EqualArea => uv.y * h as f32 - 0.5,
        };
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let px = |dx: i64, dy: i64| {
            let xi = (x0 + dx).rem_euclid(w) as u32;
            let yi = (y0 + dy).clamp(0, h - 1) as u32;
            self.image.get(xi, yi)
        };
        ((px(0, 0) * (1.0 - fx) + px(1, 0) * fx) * (1.0 - fy)
            + (px(0, 1) * (1.0 - fx) + px(1, 1) * fx) * fy)
            * self.scale
    }

    pub fn eval(&self, d_world: Vec3) -> Vec3 {
        self.lookup(self.dir_to_uv(d_world))
    }

    /// A direction towards the environment, its radiance and its solid-angle density (what
    /// `sample_li` and `sample_le` draw). Left to the compiler, which keeps it out of line
    /// (`sample_li` calls it, as it did before `sample_le` was a second caller).
    fn sample(&self, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        if self.mapping == EnvMapping::Probe {
            // Probe maps are sampled uniformly over the sphere.
            let d = warp::square_to_uniform_sphere(u);
            return Some((d, self.eval(d), warp::uniform_sphere_pdf()));
        }
        let (uv, pdf_uv) = self.distribution.sample(u);
        let (d, jacobian) = self.uv_to_dir(uv);
        if pdf_uv <= 0.0 || jacobian <= 0.0 {
            return None;
        }
        Some((d, self.lookup(uv), pdf_uv / jacobian))
    }

    fn pdf(&self, d_world: Vec3) -> f32 {
        if self.mapping == EnvMapping::Probe {
            return warp::uniform_sphere_pdf();
        }
        let uv = self.dir_to_uv(d_world);
        let jacobian = self.uv_jacobian(uv);
        if jacobian <= 0.0 {
            return 0.0;
        }
        self.distribution.pdf(uv) / jacobian
    }
}

impl LightModel for EnvMap {
    fn is_delta(&self) -> bool {
        false
    }

    fn is_infinite(&self) -> bool {
        true
    }

    fn environment<M: ColorMode>(&self, d: Vec3, m: &M) -> M::C {
        m.illuminant(self.eval(d))
    }

    fn sample_li<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        _r: &Receiver,
        u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
        let (wi, li, pdf) = self.sample(u)?;
        Some(LightSample {
            wi,
            li: m.illuminant(li),
            pdf,
            delta: false,
            target: ShadowTarget::Infinite,
        })
    }

    fn pdf_li(
        &self,
        _: &impl LightScene,
        _: &Receiver,
        wi: Vec3,
        _: Option<&SurfaceInteraction>,
    ) -> f32 {
        self.pdf(wi)
    }

    /// A direction towards the environment drawn as `sample_li` draws it (the ray travels
    /// the other way), from a point uniform on the disk of the scene's bounding sphere across
    /// that direction: weight L(ω)·π r² / pdf(ω), of mean ∫L dω·π r².
    fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let (wi, li, pdf_dir) = self.sample(u_dir)?;
        infinite_emission(scene, -wi, m.illuminant(li), pdf_dir, u_pos)
    }

    /// (1/π r², the map's sampling density of −d in solid angle, as `pdf_li`); (0, 0) where
    /// that density is 0.
    fn pdf_le(&self, scene: &impl LightScene, _p: Vec3, _n: Vec3, d: Vec3) -> (f32, f32) {
        infinite_pdf_le(scene, self.pdf(-d))
    }

    /// The power through a disk of the scene's bounding radius r: 4π·π r²·L̄, L̄ the
    /// solid-angle mean of the map.
    fn power(&self, scene: &impl LightScene) -> f32 {
        let (w, h) = (self.image.width, self.image.height);
        let (mut sum, mut weight) = (0f64, 0f64);
        for y in 0..h {
            // Lat-long rows are spaced by θ: weight by sin θ for the solid-angle mean.
            let s = match self.mapping {
                EnvMapping::LatLong => ((y as f32 + 0.5) / h as f32 * PI).sin() as f64,
                EnvMapping::Probe | EnvMapping::EqualArea => 1.0,
            };
            for x in 0..w {
                let v = mean(self.image.get(x, y));
                if v.is_finite() {
                    sum += s * v as f64;
                }
                weight += s;
            }
        }
        let avg = if weight > 0.0 { sum / weight } else { 0.0 } as f32 * self.scale.max(0.0);
        let r = scene_radius(scene);
        4.0 * PI * PI * r * r * avg
    }
}
