//! Point lights whose intensity an image modulates by direction: pbrt-v4's `goniometric`
//! light (an equal-area octahedral square over the sphere of directions, looked up at the
//! nearest pixel, its RGB averaged to one channel) and `projection` light (an image projected
//! through a pinhole, `fov` on the image's shorter axis, nearest pixel, dark outside the
//! image and behind the light). Both are delta lights. Directions are taken in the light's
//! frame as given (pbrt-v4's, after its y–z swap or y flip, which the loader applies).

use super::LightScene;
use super::bvh::LightBounds;
use super::select::{mean, omni};
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::film::Image;
use crate::geometry::Ray;
use crate::math::{Mat3, PI, Vec2, Vec3};
use crate::sampling::warp;
use crate::spectral::lanes::ColorMode;

/// Directions closer to the projection plane than this (the z of a unit direction) are dark,
/// as behind pbrt-v4's near plane.
const HITHER: f32 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Profile {
    Goniometric,
    /// `tan_half`: tan(fov/2); `half`: the screen's half extents (the shorter one 1).
    Projection {
        tan_half: f32,
        half: Vec2,
    },
}

#[derive(Debug)]
pub struct ImagePointLight {
    pub position: Vec3,
    /// World → light directions (a rotation).
    pub to_local: Mat3,
    pub to_world: Mat3,
    /// Linear RGB (a goniometric light's already averaged to grey).
    pub image: Image,
    /// Multiplies the image.
    pub scale: Vec3,
    pub profile: Profile,
    /// cos of the widest direction that can be lit (−1: all of them).
    cos_total: f32,
}

impl ImagePointLight {
    /// `to_world`: the light's frame (rotation columns); `image` in linear RGB.
    pub fn new(
        position: Vec3,
        to_world: Mat3,
        mut image: Image,
        scale: Vec3,
        profile: Profile,
    ) -> ImagePointLight {
        let cos_total = match profile {
            Profile::Goniometric => {
                // pbrt-v4 reads one channel: the average of R, G and B.
                for p in &mut image.pixels {
                    *p = Vec3::splat((p.x + p.y + p.z) / 3.0);
                }
                -1.0
            }
            Profile::Projection { tan_half, half } => {
                Vec3::new(half.x * tan_half, half.y * tan_half, 1.0)
                    .normalize()
                    .z
            }
        };
        ImagePointLight {
            position,
            to_local: to_world.inverse(),
            to_world,
            image,
            scale,
            profile,
            cos_total,
        }
    }

    fn pixel(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.image.width, self.image.height);
        let px = |t: f32, n: u32| ((t * n as f32).max(0.0) as u32).min(n - 1);
        self.image.get(px(uv.x, w), px(uv.y, h))
    }

    /// The intensity (RGB) along the unit light-space direction `w`.
    pub fn intensity(&self, w: Vec3) -> Vec3 {
        match self.profile {
            Profile::Goniometric => self.pixel(warp::equal_area_sphere_to_square(w)) * self.scale,
            Profile::Projection { tan_half, half } => {
                if w.z < HITHER {
                    return Vec3::ZERO;
                }
                let s = Vec2::new(w.x, w.y) / (w.z * tan_half);
                if s.x.abs() > half.x || s.y.abs() > half.y {
                    return Vec3::ZERO;
                }
                // Screen (−half, −half) is the image's first pixel.
                let uv = (s + half) / (2.0 * half);
                self.pixel(uv).max(Vec3::ZERO) * self.scale
            }
        }
    }

    /// The emitted power: ∫ I dω over the sphere, the mean of RGB.
    pub fn power_rgb(&self) -> Vec3 {
        let (w, h) = (self.image.width, self.image.height);
        let n = (w * h) as f32;
        let mut sum = Vec3::ZERO;
        match self.profile {
            // Every pixel of the equal-area square subtends 4π/n.
            Profile::Goniometric => {
                for y in 0..h {
                    for x in 0..w {
                        sum += self.image.get(x, y);
                    }
                }
                sum * self.scale * (4.0 * PI / n)
            }
            // A pixel of screen area a subtends a·cos³θ / tan²(fov/2) (the screen sits at
            // distance 1/tan(fov/2) in screen units), cos θ at its centre as pbrt-v4 takes
            // it (its `power` normalisation uses this sum).
            Profile::Projection { tan_half, half } => {
                for y in 0..h {
                    for x in 0..w {
                        let s = Vec2::new(
                            ((x as f32 + 0.5) / w as f32 * 2.0 - 1.0) * half.x,
                            ((y as f32 + 0.5) / h as f32 * 2.0 - 1.0) * half.y,
                        );
                        let d = Vec3::new(s.x * tan_half, s.y * tan_half, 1.0).normalize();
                        sum += self.image.get(x, y).max(Vec3::ZERO) * d.z.powi(3);
                    }
                }
                let area = 4.0 * half.x * half.y * tan_half * tan_half;
                sum * self.scale * (area / n)
            }
        }
    }
}

impl LightModel for ImagePointLight {
    fn is_delta(&self) -> bool {
        true
    }

    fn position(&self) -> Option<Vec3> {
        Some(self.position)
    }

    fn sample_li<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        r: &Receiver,
        _u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
        let d = self.position - r.p;
        let d2 = d.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let wi = d / d2.sqrt();
        let i = self.intensity((self.to_local * -wi).normalize_or_zero());
        (i != Vec3::ZERO).then(|| LightSample {
            wi,
            li: m.illuminant(i) / d2,
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Point(self.position),
        })
    }

    /// A direction uniform in the cone of every lit direction (the sphere for a goniometric
    /// light): weight I(ω)/pdf.
    fn sample_le<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        _u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let local = warp::square_to_uniform_cone(u_dir, self.cos_total);
        let pdf_dir = warp::uniform_cone_pdf(self.cos_total);
        let i = self.intensity(local);
        if i == Vec3::ZERO {
            return None;
        }
        Some(EmissionSample {
            ray: Ray::new(self.position, (self.to_world * local).normalize()),
            p: self.position,
            weight: m.illuminant(i) / pdf_dir,
            pdf_pos: 1.0,
            pdf_dir,
            n: Vec3::ZERO,
        })
    }

    /// (1, the cone's uniform density) inside the cone, (0, 0) outside.
    fn pdf_le(&self, _scene: &impl LightScene, _p: Vec3, _n: Vec3, d: Vec3) -> (f32, f32) {
        let local = (self.to_local * d).normalize_or_zero();
        if local.z < self.cos_total {
            return (0.0, 0.0);
        }
        (1.0, warp::uniform_cone_pdf(self.cos_total))
    }

    fn power(&self, _scene: &impl LightScene) -> f32 {
        mean(self.power_rgb())
    }

    fn bounds(&self, _scene: &impl LightScene, phi: f32) -> Option<LightBounds> {
        Some(omni(self.position, self.position, phi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32) -> Image {
        let mut img = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                img.set(
                    x,
                    y,
                    Vec3::new((x + 1) as f32, (y + 2) as f32, (x * y) as f32),
                );
            }
        }
        img
    }

    /// The power is ∫ I dω: against a midpoint rule on the equal-area square (every cell
    /// the same solid angle; exact for the goniometric light's nearest lookups, up to the
    /// pixel-centre rule for the projection's); lit directions all lie in the sampling cone.
    #[test]
    fn power_is_the_integral_of_the_intensity() {
        let frame = Mat3::from_rotation_y(0.3);
        for (profile, img) in [
            (Profile::Goniometric, image(4, 4)),
            (
                Profile::Projection {
                    tan_half: 0.7,
                    half: Vec2::new(1.5, 1.0),
                },
                image(6, 4),
            ),
        ] {
            let l = ImagePointLight::new(Vec3::ZERO, frame, img, Vec3::new(1.0, 0.5, 2.0), profile);
            let n = 1024;
            let mut sum = glam::DVec3::ZERO;
            for k in 0..n * n {
                let uv = Vec2::new(
                    ((k % n) as f32 + 0.5) / n as f32,
                    ((k / n) as f32 + 0.5) / n as f32,
                );
                let w = warp::equal_area_square_to_sphere(uv);
                let i = l.intensity(w);
                if i != Vec3::ZERO {
                    assert!(w.z >= l.cos_total - 1e-6, "{w} outside the cone");
                }
                sum += glam::DVec3::new(i.x.into(), i.y.into(), i.z.into());
            }
            let quad =
                Vec3::new(sum.x as f32, sum.y as f32, sum.z as f32) * (4.0 * PI / (n * n) as f32);
            let power = l.power_rgb();
            // pbrt-v4's rule for a projection takes each pixel's cos³θ at its centre.
            let tol = match profile {
                Profile::Goniometric => 2e-3,
                Profile::Projection { .. } => 2e-2,
            };
            assert!(
                (quad - power).abs().max_element() < tol * power.max_element(),
                "{profile:?}: {quad} vs {power}"
            );
        }
    }
}
