//! Emitters and their sampling, following Mitsuba 3's definitions: a file per kind behind
//! one enum, dispatched like `bsdf/` — [`AreaLight`] (an emitting shape), [`PointLight`],
//! [`SpotLight`], [`DirectionalLight`], [`ConstantLight`], [`EnvMap`] and [`SunSkyLight`]
//! (Mitsuba's `sunsky`, its model in [`sunsky_model`]) and [`DirectionalAreaLight`]
//! (Mitsuba's `directionalarea`, a shape emitting only along its normal) and [`ProjectorLight`]
//! (Mitsuba's `projector`). Light selection
//! ([`select`]) and the light BVH ([`bvh`]) read each kind's power and bounds.
//!
//! Adding an emitter kind: a file here with its struct and its [`LightModel`] impl, a
//! variant of [`Light`] (and the dispatch line), and its factory in `build`.

mod area;
pub mod bvh;
mod constant;
mod directional;
mod directional_area;
mod envmap;
mod image_point;
mod point;
mod projector;
pub mod select;
mod spot;
mod sunsky;
pub mod sunsky_model;

use std::sync::Arc;

pub use area::AreaLight;
pub use bvh::LightBounds;
pub use constant::ConstantLight;
pub use directional::DirectionalLight;
pub use directional_area::DirectionalAreaLight;
pub use envmap::EnvMap;
pub use image_point::{ImagePointLight, Profile as ImageProfile};
pub use point::PointLight;
pub use projector::ProjectorLight;
pub use spot::SpotLight;
pub use sunsky::SunSkyLight;

use crate::geometry::Ray;
use crate::math::{Vec2, Vec3};
use crate::shapes::{ShapeInfo, SurfaceInteraction};
use crate::spectral::lanes::{Color, ColorMode};
use crate::textures::Params;

/// What lights read of the scene they light: the emitting shapes, parameter values
/// ([`Params`]) and the bounds of the geometry. The runtime scene (`world::Scene`) holds the
/// lights and implements this; lights depend on it, not on the scene.
pub trait LightScene: Params {
    fn shape(&self, i: u32) -> &ShapeInfo;
    fn bounds(&self) -> (Vec3, Vec3);
}

/// A point on an emitter with what it sends towards the receiver, in the colour type `C` of
/// the mode the light was sampled in.
#[derive(Clone, Copy, Debug)]
pub struct LightSample<C = Vec3> {
    /// Unit direction from the receiver towards the light.
    pub wi: Vec3,
    /// Emitted radiance arriving along `-wi` (for delta lights: intensity / d² or irradiance).
    pub li: C,
    /// Solid-angle density of choosing `wi` (1 for delta lights), not including light selection.
    pub pdf: f32,
    pub delta: bool,
    /// Where the shadow ray must stop.
    pub target: ShadowTarget,
}

#[derive(Clone, Copy, Debug)]
pub enum ShadowTarget {
    /// A point on a surface (offset by its error bound along `n`).
    Surface { p: Vec3, p_error: Vec3, n: Vec3 },
    /// A point in space (point and spot lights).
    Point(Vec3),
    /// Infinitely far along `wi`.
    Infinite,
}

impl ShadowTarget {
    /// The shadow ray from `si` towards this light sample (direction `wi`) and its range
    /// `(0, t_max)`.
    #[inline]
    pub fn ray_from(&self, si: &SurfaceInteraction, wi: Vec3) -> (Ray, f32) {
        match *self {
            ShadowTarget::Infinite => (si.spawn_ray(wi), f32::INFINITY),
            ShadowTarget::Point(p) => si.spawn_ray_to(p),
            ShadowTarget::Surface { p, p_error, n } => si.spawn_ray_to_surface(p, p_error, n),
        }
    }
}

/// A ray leaving an emitter: how photon tracing (and light tracing) starts a path.
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample<C = Vec3> {
    /// Leaves the emitter (off its surface, for an area light).
    pub ray: Ray,
    /// The point emitting the ray: on the surface for an area light (`ray.o` is offset off
    /// it by the error bound), `ray.o` for the other lights. [`Light::pdf_le`] takes it.
    pub p: Vec3,
    /// Le(p, ω)·|cos θ| / (pdf_pos·pdf_dir): the power the path carries, given that this
    /// light was chosen (divide by the light's selection probability). Its mean over the
    /// samples is the light's emitted power Φ.
    pub weight: C,
    /// Density of the origin per unit area: of the emitting surface, of the disk an
    /// infinite light's rays start from (its normal is the direction); 1 for point and spot
    /// lights.
    pub pdf_pos: f32,
    /// Density of the direction per unit solid angle; 1 for a directional light.
    pub pdf_dir: f32,
    /// Surface normal at the origin (area lights; zero for the others).
    pub n: Vec3,
}

/// The density per unit area on the disk infinite lights start their emitted rays from
/// (1 / (π R²), R the scene's bounding radius).
pub fn infinite_disk_pdf(scene: &impl LightScene) -> f32 {
    select::disk_pdf(scene)
}

/// The receiving point of a light query.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    pub p: Vec3,
    /// Shading normal at `p` (either orientation), or zero for a point without one; used
    /// only to guide light selection (the light BVH).
    pub n: Vec3,
}

impl Receiver {
    /// A receiver without a normal.
    pub fn at(p: Vec3) -> Receiver {
        Receiver { p, n: Vec3::ZERO }
    }
}

impl From<&SurfaceInteraction> for Receiver {
    fn from(si: &SurfaceInteraction) -> Self {
        Receiver {
            p: si.p,
            n: si.shading.n,
        }
    }
}

/// What every emitter kind implements (dispatched by [`Light`]).
pub(crate) trait LightModel {
    /// A delta light (point, spot, directional): `sample_li` is its only access.
    fn is_delta(&self) -> bool;

    /// Infinitely far (directional and environment lights).
    fn is_infinite(&self) -> bool {
        false
    }

    /// The point a light emits from, for lights that are a point (point, spot).
    fn position(&self) -> Option<Vec3> {
        None
    }

    /// Radiance of an environment light seen along `d` (escaping ray direction).
    fn environment<M: ColorMode>(&self, _d: Vec3, _m: &M) -> M::C {
        M::C::ZERO
    }

    /// Sample a direction from `r` towards this light; the radiance in the colour of `m`.
    fn sample_li<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        r: &Receiver,
        u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>>;

    /// Solid-angle density with which `sample_li` from `r` produces the direction towards
    /// `si`, a point on this (area) light — or, for environment lights, the direction `wi`.
    /// 0 for delta lights.
    fn pdf_li(
        &self,
        _scene: &impl LightScene,
        _r: &Receiver,
        _wi: Vec3,
        _si: Option<&SurfaceInteraction>,
    ) -> f32 {
        0.0
    }

    /// Radiance leaving an area light at `si` towards `si.wo`.
    fn le<M: ColorMode>(&self, _scene: &impl LightScene, _si: &SurfaceInteraction, _m: &M) -> M::C {
        M::C::ZERO
    }

    /// Emitted power, up to a common factor ([`select`] has the definitions).
    fn power(&self, scene: &impl LightScene) -> f32;

    /// A ray leaving the light (photon emission): `u_pos` places its origin, `u_dir` its
    /// direction; colours as `sample_li` of the same light gives them. `None` for a
    /// degenerate sample. Every kind implements it (no default: a light that could not emit
    /// photons would silently darken photon-mapped images).
    fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>>;

    /// The densities `(pdf_pos, pdf_dir)` of [`EmissionSample`] with which `sample_le` draws
    /// the ray from `p` (normal `n` for area lights) along the unit direction `d`; (0, 0) for
    /// a ray it cannot draw. No default, as for `sample_le`: bidirectional methods weigh light
    /// paths with it.
    fn pdf_le(&self, scene: &impl LightScene, p: Vec3, n: Vec3, d: Vec3) -> (f32, f32);

    /// Bounds for the light BVH of a bounded light of power `phi` (`None`: infinite).
    fn bounds(&self, _scene: &impl LightScene, _phi: f32) -> Option<LightBounds> {
        None
    }
}

#[derive(Clone, Debug)]
pub enum Light {
    Area(AreaLight),
    Point(PointLight),
    Spot(SpotLight),
    Directional(DirectionalLight),
    Constant(ConstantLight),
    EnvMap(Arc<EnvMap>),
    ImagePoint(Arc<ImagePointLight>),
    SunSky(Arc<SunSkyLight>),
    DirectionalArea(Box<DirectionalAreaLight>),
    Projector(Box<ProjectorLight>),
}

macro_rules! dispatch {
    ($self:expr, $l:ident => $e:expr) => {
        match $self {
            Light::Area($l) => $e,
            Light::Point($l) => $e,
            Light::Spot($l) => $e,
            Light::Directional($l) => $e,
            Light::Constant($l) => $e,
            Light::EnvMap($l) => $e,
            Light::ImagePoint($l) => $e,
            Light::SunSky($l) => $e,
            Light::DirectionalArea($l) => $e,
            Light::Projector($l) => $e,
        }
    };
}

impl Light {
    #[inline]
    pub fn is_delta(&self) -> bool {
        dispatch!(self, l => l.is_delta())
    }

    #[inline]
    pub fn is_infinite(&self) -> bool {
        dispatch!(self, l => l.is_infinite())
    }

    /// Radiance of an environment light seen along `d` (escaping ray direction).
    #[inline]
    pub fn environment<M: ColorMode>(&self, d: Vec3, m: &M) -> M::C {
        dispatch!(self, l => l.environment(d, m))
    }

    /// The point a point or spot light emits from (`None` for other lights).
    #[inline]
    pub fn position(&self) -> Option<Vec3> {
        dispatch!(self, l => l.position())
    }

    /// Sample a direction from `r` towards this light; the radiance in the colour of `m`.
    /// Out of line, as the compiler chose for the RGB-only loop (inlined into the path loop,
    /// as a second colour mode made the compiler do, it cost RGB 7 % on bench-cbox).
    #[inline(never)]
    pub fn sample_li<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        r: &Receiver,
        u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
        dispatch!(self, l => l.sample_li(scene, r, u, m))
    }

    /// Solid-angle density with which `sample_li` from `r` produces the direction towards
    /// `si`, a point on this (area) light — or, for environment lights, the direction `wi`.
    #[inline]
    pub fn pdf_li(
        &self,
        scene: &impl LightScene,
        r: &Receiver,
        wi: Vec3,
        si: Option<&SurfaceInteraction>,
    ) -> f32 {
        dispatch!(self, l => l.pdf_li(scene, r, wi, si))
    }

    /// Radiance leaving an area light at `si` towards `si.wo`.
    #[inline]
    pub fn le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        si: &SurfaceInteraction,
        m: &M,
    ) -> M::C {
        dispatch!(self, l => l.le(scene, si, m))
    }

    /// A ray leaving the light, for photon tracing ([`EmissionSample`]).
    pub fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        dispatch!(self, l => l.sample_le(scene, u_pos, u_dir, m))
    }

    /// The densities `sample_le` would have drawn an emitted ray with: origin `p` (with
    /// surface normal `n` for area lights, zero otherwise) and unit direction `d`:
    /// (pdf_pos, pdf_dir), exactly the [`EmissionSample`] fields for that ray (pbrt-v4's
    /// `Light::PDF_Le`). (0, 0) when `sample_le` cannot produce it.
    ///
    /// - `p`: [`EmissionSample::p`], the unoffset point. It is not checked to lie on the
    ///   light: point and spot lights ignore it (their origin is their position), infinite
    ///   lights too (pbrt's convention: pdf_pos is the density 1/(π R²) on the disk of the
    ///   scene's bounding radius R across `d`, wherever the ray starts); area lights read it
    ///   only where the area density varies (ellipsoids).
    /// - `n`: the normal of the emitting side ([`EmissionSample::n`]; for a one-sided light,
    ///   the side `le` emits to; either side for a two-sided one).
    pub fn pdf_le(&self, scene: &impl LightScene, p: Vec3, n: Vec3, d: Vec3) -> (f32, f32) {
        dispatch!(self, l => l.pdf_le(scene, p, n, d))
    }

    /// Emitted power (see [`select`]); 0 for a light that emits nothing.
    pub fn power(&self, scene: &impl LightScene) -> f32 {
        let p = dispatch!(self, l => l.power(scene));
        if p.is_finite() { p.max(0.0) } else { 0.0 }
    }

    /// Bounds for the light BVH (`None` for infinite lights and lights without power).
    pub fn bounds(&self, scene: &impl LightScene) -> Option<LightBounds> {
        let phi = self.power(scene);
        if phi <= 0.0 {
            return None;
        }
        dispatch!(self, l => l.bounds(scene, phi))
    }
}
