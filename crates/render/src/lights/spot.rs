//! Spot lights: a point light restricted to a cone, with Mitsuba 3's linear falloff in angle
//! between `beam_width` and `cutoff_angle`, the CENG795 course's
//! ((cos α − cos cutoff) / (cos beam − cos cutoff))⁴, or pbrt-v4's smoothstep in cos α; a
//! delta light.

use super::LightScene;
use super::bvh::LightBounds;
use super::select::{mean, omni};
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::geometry::Ray;
use crate::math::{Mat3, Mat4, PI, Vec2, Vec3};
use crate::sampling::warp;
use crate::spectral::DeclaredSpectrum;
use crate::spectral::lanes::ColorMode;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct SpotLight {
    pub position: Vec3,
    pub to_local: Mat3,
    pub intensity: Vec3,
    /// The spectrum it was declared as (spectral mode only; RGB mode renders the RGB value).
    pub spectrum: Option<Arc<DeclaredSpectrum>>,
    pub cos_cutoff: f32,
    pub cos_beam: f32,
    pub cutoff: f32,
    pub inv_transition: f32,
    pub profile: base::SpotFalloff,
}

impl SpotLight {
    pub fn new(
        to_world: &Mat4,
        intensity: Vec3,
        cutoff_deg: f32,
        beam_deg: f32,
        falloff: base::SpotFalloff,
    ) -> SpotLight {
        let cutoff = cutoff_deg.to_radians();
        let beam = beam_deg.to_radians().min(cutoff);
        let rot = Mat3::from_mat4(*to_world);
        SpotLight {
            spectrum: None,
            position: to_world.w_axis.truncate().into(),
            to_local: rot.inverse(),
            intensity,
            cos_cutoff: cutoff.cos(),
            cos_beam: beam.cos(),
            cutoff,
            inv_transition: if cutoff > beam {
                1.0 / (cutoff - beam)
            } else {
                0.0
            },
            profile: falloff,
        }
    }

    /// The falloff for a local direction of cosine `cos_t` about the axis. Always inlined: a
    /// second caller (`sample_le`) must not change the code of `sample_li`.
    #[inline(always)]
    fn falloff(&self, cos_t: f32) -> f32 {
        spot_falloff(
            cos_t,
            self.cos_cutoff,
            self.cos_beam,
            self.cutoff,
            self.inv_transition,
            self.profile,
        )
    }
}

impl LightModel for SpotLight {
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
        let local = (self.to_local * -wi).normalize_or_zero();
        let f = self.falloff(local.z);
        (f > 0.0).then(|| LightSample {
            wi,
            li: m.illuminant_declared(self.intensity, self.spectrum.as_deref()) * f / d2,
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Point(self.position),
        })
    }

    /// A direction uniform in the cone of the cutoff angle (Mitsuba's and pbrt-v4's
    /// `sample_ray`/`SampleLe`): weight I·falloff / pdf. The light's frame is carried to the
    /// world by the inverse of `to_local` (computed here rather than stored: a larger
    /// `SpotLight` would change the layout `sample_li` reads); when that is not a rotation,
    /// the density picks up the Jacobian of the normalised linear map on directions,
    /// dω_local/dω = |det A| / |A ω|³ (A = `to_local`), so that the mean weight is still
    /// ∫ I·falloff(A ω / |A ω|) dω, what `sample_li` emits.
    fn sample_le<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        _u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let local = warp::square_to_uniform_cone(u_dir, self.cos_cutoff);
        let f = self.falloff(local.z);
        if f <= 0.0 {
            return None;
        }
        let w = (self.to_local.inverse() * local).normalize_or_zero();
        let aw = (self.to_local * w).length();
        let pdf_dir = warp::uniform_cone_pdf(self.cos_cutoff) * self.to_local.determinant().abs()
            / (aw * aw * aw);
        if !(pdf_dir > 0.0 && pdf_dir.is_finite()) || w == Vec3::ZERO {
            return None;
        }
        Some(EmissionSample {
            ray: Ray::new(self.position, w),
            p: self.position,
            weight: m.illuminant_declared(self.intensity, self.spectrum.as_deref()) * (f / pdf_dir),
            pdf_pos: 1.0,
            pdf_dir,
            n: Vec3::ZERO,
        })
    }

    /// (1, the cone's uniform density times the Jacobian |det A| / |A d|³) for a direction
    /// whose local direction A d / |A d| has a non-zero falloff, (0, 0) otherwise (`p` is
    /// taken to be the position).
    fn pdf_le(&self, _scene: &impl LightScene, _p: Vec3, _n: Vec3, d: Vec3) -> (f32, f32) {
        let ad = self.to_local * d;
        let local = ad.normalize_or_zero();
        if self.falloff(local.z) <= 0.0 {
            return (0.0, 0.0);
        }
        let aw = ad.length();
        let pdf_dir = warp::uniform_cone_pdf(self.cos_cutoff) * self.to_local.determinant().abs()
            / (aw * aw * aw);
        if !(pdf_dir > 0.0 && pdf_dir.is_finite()) {
            return (0.0, 0.0);
        }
        (1.0, pdf_dir)
    }

    /// 2π·I·((1 − cos θbeam) + (cos θbeam − cos θcutoff)/2).
    fn power(&self, _scene: &impl LightScene) -> f32 {
        2.0 * PI
            * mean(self.intensity)
            * ((1.0 - self.cos_beam) + 0.5 * (self.cos_beam - self.cos_cutoff))
    }

    fn bounds(&self, _scene: &impl LightScene, phi: f32) -> Option<LightBounds> {
        let at = omni(self.position, self.position, phi);
        let w = (self.to_local.inverse() * Vec3::Z).normalize_or_zero();
        if w == Vec3::ZERO {
            return Some(at);
        }
        let theta_e = (self.cos_cutoff.clamp(-1.0, 1.0).acos()
            - self.cos_beam.clamp(-1.0, 1.0).acos())
        .max(0.0);
        Some(LightBounds {
            w,
            cos_o: self.cos_beam,
            cos_e: theta_e.cos(),
            ..at
        })
    }
}

/// Spot falloff of Mitsuba 3 for a local direction (cos θ = z). Always inlined, as
/// [`SpotLight::falloff`].
#[inline(always)]
fn spot_falloff(
    cos_t: f32,
    cos_cutoff: f32,
    cos_beam: f32,
    cutoff: f32,
    inv_trans: f32,
    profile: base::SpotFalloff,
) -> f32 {
    if cos_t <= cos_cutoff {
        return 0.0;
    }
    if cos_t >= cos_beam {
        return 1.0;
    }
    let s = ((cos_t - cos_cutoff) / (cos_beam - cos_cutoff)).clamp(0.0, 1.0);
    match profile {
        base::SpotFalloff::Cosine4 => (s * s) * (s * s),
        base::SpotFalloff::SmoothStep => s * s * (3.0 - 2.0 * s),
        base::SpotFalloff::Mitsuba => {
            ((cutoff - cos_t.clamp(-1.0, 1.0).acos()) * inv_trans).clamp(0.0, 1.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CENG795 spot profile: full intensity inside the falloff cone, nothing outside the
    /// coverage cone, ((cos α − cos c) / (cos f − cos c))⁴ between; Mitsuba's is linear in α,
    /// pbrt-v4's the smoothstep of t = (cos α − cos c) / (cos f − cos c).
    #[test]
    fn course_spot_profile() {
        let light = |falloff| SpotLight::new(&Mat4::IDENTITY, Vec3::ONE, 30.0, 10.0, falloff);
        let at = |l: &SpotLight, deg: f32| l.falloff(deg.to_radians().cos());
        let course = light(base::SpotFalloff::Cosine4);
        let mitsuba = light(base::SpotFalloff::Mitsuba);
        for deg in [0.0f32, 5.0, 9.9] {
            assert_eq!(at(&course, deg), 1.0);
        }
        for deg in [30.1f32, 45.0, 120.0] {
            assert_eq!(at(&course, deg), 0.0);
        }
        for deg in [12.0f32, 20.0, 28.0] {
            let (c, cc, cb) = (
                deg.to_radians().cos(),
                30f32.to_radians().cos(),
                10f32.to_radians().cos(),
            );
            let expected = ((c - cc) / (cb - cc)).powi(4);
            assert!((at(&course, deg) - expected).abs() < 1e-5, "{deg}°");
            let linear = (30.0 - deg) / 20.0;
            assert!((at(&mitsuba, deg) - linear).abs() < 1e-4, "{deg}°");
            let t = (c - cc) / (cb - cc);
            let pbrt = light(base::SpotFalloff::SmoothStep);
            assert!(
                (at(&pbrt, deg) - t * t * (3.0 - 2.0 * t)).abs() < 1e-5,
                "{deg}°"
            );
            assert!(
                (at(&course, deg) - at(&mitsuba, deg)).abs() > 0.02,
                "{deg}°"
            );
        }
    }
}
