//! BSDF models in the local shading frame (normal = +z), following Mitsuba 3's definitions
//! (parameters, defaults, Fresnel conventions) so renders converge to Mitsuba's references.
//!
//! Conventions shared by every model:
//! - `wo` points away from the surface towards the camera / previous path vertex; `wi` is the
//!   other direction (the one `sample` generates). Both are unit vectors in the local frame.
//! - `eval(wo, wi)` returns f(wo, wi)·|cos θi| (Mitsuba's convention) and 0 for delta lobes.
//! - `pdf(wo, wi)` is the solid-angle density with which `sample` produces `wi` through its
//!   non-delta lobes (delta lobes are excluded).
//! - `sample` returns `weight = f·|cos θi| / pdf`; for a delta lobe `pdf` is the discrete
//!   probability of picking that lobe (as in Mitsuba), and `delta` is set.
//! - One-sided models (everything but the dielectrics) return 0 / `None` for `wo.z ≤ 0`; the
//!   caller makes a material two-sided by flipping the frame. Dielectrics are naturally
//!   two-sided: `wo.z < 0` means the query comes from inside the medium.
//! - Every variant is a small struct with already-evaluated parameters: textures are
//!   looked up by the caller before building the `Bsdf`. Rough plastic's precomputed tables
//!   are shared (`Arc`) rather than copied, so `Bsdf` is `Clone` but not `Copy`.

mod blend;
mod bumped;
mod conductor;
mod course;
mod dielectric;
mod diffuse;
mod diffuse_transmission;
pub mod fresnel;
mod layered;
pub mod microfacet;
mod nori_microfacet;
mod phong;
mod plastic;
mod pplastic;
mod principled;
mod principled_thin;
mod rough_conductor;
mod rough_dielectric;
mod rough_plastic;
mod thin_dielectric;

pub use blend::Blend;
pub use bumped::Bumped;
pub use conductor::Conductor;
pub use course::{CourseMaterial, IdealLobe};
pub use dielectric::Dielectric;
pub use diffuse::Diffuse;
pub use diffuse_transmission::DiffuseTransmission;
pub use layered::{Base as LayeredBase, Ggx, Interface as LayeredInterface, Layered};
pub use microfacet::{Microfacet, MicrofacetType};
pub use nori_microfacet::NoriMicrofacet;
pub use phong::PhongFamily;
pub use plastic::{Plastic, rgb_sampling_weight};
pub use pplastic::PolarizedPlastic;
pub use principled::{Principled, disney_alphas, luminance};
pub use principled_thin::PrincipledThin;
pub use rough_conductor::RoughConductor;
pub use rough_dielectric::RoughDielectric;
pub use rough_plastic::{RoughPlastic, RoughPlasticTables};
pub use thin_dielectric::ThinDielectric;

use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

/// Which quantity a path carries: radiance (camera paths) or importance (light paths). Only
/// matters for refraction, where radiance is scaled by 1/η² and importance is not.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TransportMode {
    #[default]
    Radiance,
    Importance,
}

/// The result of [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample<C: Color = Vec3> {
    /// Sampled direction (local frame, unit length).
    pub wi: Vec3,
    /// eval·|cos θi| / pdf (for delta lobes: the lobe's weight divided by its probability).
    pub weight: C,
    /// Solid-angle density of `wi`, or the discrete lobe probability when `delta` is set.
    pub pdf: f32,
    /// The direction comes from a delta (perfectly specular) lobe.
    pub delta: bool,
    /// The direction crosses the surface (`wi.z` and `wo.z` have opposite signs).
    pub transmission: bool,
    /// Relative index of refraction crossed (η_inside/η_outside when entering, its inverse
    /// when leaving), 1 for reflection. Radiance scales by 1/eta² across the interface.
    pub eta: f32,
}

impl<C: Color> BsdfSample<C> {
    /// A sample of a non-delta reflection lobe (no interface crossed).
    #[inline]
    pub fn glossy_reflection(wi: Vec3, weight: C, pdf: f32) -> BsdfSample<C> {
        BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
            transmission: false,
            eta: 1.0,
        }
    }
}

/// The operations every BSDF model implements (dispatched by the [`Bsdf`] enum), in the
/// colour type `C` (RGB `Vec3` or `SampledSpectrum`).
pub(crate) trait BsdfModel<C: Color = Vec3> {
    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C;
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32;
    /// `(eval, pdf)` at once (Mitsuba's `eval_pdf`): models whose two share work override it.
    fn eval_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (C, f32) {
        (self.eval(wo, wi, mode), self.pdf(wo, wi))
    }
    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>>;
    fn has_delta(&self) -> bool;
    fn has_smooth(&self) -> bool;
    fn albedo(&self) -> C;
}

/// Closed set of BSDF models.
///
/// Lives on the stack, built per hit; kept small (no variant carries a table inline) because
/// it is moved several times per path vertex.
///
/// PROTOTYPE: generic over the colour type `C` (RGB `Vec3` or `SampledSpectrum`), as every
/// model is; the runtime material converts the RGB parameters through a `ColorMode`.
#[derive(Clone, Debug)]
pub enum Bsdf<C: Color = Vec3> {
    Diffuse(Diffuse<C>),
    Conductor(Conductor<C>),
    RoughConductor(RoughConductor<C>),
    Dielectric(Dielectric<C>),
    ThinDielectric(ThinDielectric<C>),
    RoughDielectric(RoughDielectric<C>),
    Plastic(Plastic<C>),
    RoughPlastic(RoughPlastic<C>),
    NoriMicrofacet(NoriMicrofacet<C>),
    PhongFamily(PhongFamily<C>),
    /// Boxed: the largest model by far, and only CENG795 scenes build it; inline it would grow
    /// every `Bsdf` moved through the path loop from 80 to 112 bytes.
    Course(Box<CourseMaterial<C>>),
    DiffuseTransmission(DiffuseTransmission<C>),
    /// Boxed for the same reason as `Course` (pbrt-v4 scenes only).
    Layered(Box<Layered<C>>),
    /// Boxed: a dozen parameters (Mitsuba scenes only).
    Principled(Box<Principled<C>>),
    /// Boxed for the same reason as `Principled`.
    PrincipledThin(Box<PrincipledThin<C>>),
    PolarizedPlastic(PolarizedPlastic<C>),
    /// Mitsuba's `blendbsdf` of two models (boxed: it holds two `Bsdf`s).
    Blend(Box<Blend<C>>),
    /// A model under Mitsuba's `bumpmap` (boxed: it holds a `Bsdf`).
    Bumped(Box<Bumped<C>>),
}

/// `$e` on the model inside `$self`.
macro_rules! dispatch {
    ($self:expr, $b:ident => $e:expr) => {
        match $self {
            Bsdf::Diffuse($b) => $e,
            Bsdf::Conductor($b) => $e,
            Bsdf::Dielectric($b) => $e,
            Bsdf::RoughConductor($b) => $e,
            Bsdf::ThinDielectric($b) => $e,
            Bsdf::RoughDielectric($b) => $e,
            Bsdf::Plastic($b) => $e,
            Bsdf::RoughPlastic($b) => $e,
            Bsdf::NoriMicrofacet($b) => $e,
            Bsdf::PhongFamily($b) => $e,
            Bsdf::Course($b) => {
                let $b = &**$b;
                $e
            }
            Bsdf::DiffuseTransmission($b) => $e,
            Bsdf::Layered($b) => {
                let $b = &**$b;
                $e
            }
            Bsdf::Principled($b) => {
                let $b = &**$b;
                $e
            }
            Bsdf::PrincipledThin($b) => {
                let $b = &**$b;
                $e
            }
            Bsdf::PolarizedPlastic($b) => $e,
            Bsdf::Blend($b) => {
                let $b = &**$b;
                $e
            }
            Bsdf::Bumped($b) => {
                let $b = &**$b;
                $e
            }
        }
    };
}

impl<C: Color> Bsdf<C> {
    /// f(wo, wi)·|cos θi|; 0 for delta lobes.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        dispatch!(self, b => b.eval(wo, wi, mode))
    }

    /// Solid-angle density of `sample`'s non-delta part.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        dispatch!(self, b => b.pdf(wo, wi))
    }

    /// [`Self::eval`] and [`Self::pdf`] with one dispatch (next-event estimation with MIS
    /// needs both).
    #[inline]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (C, f32) {
        dispatch!(self, b => b.eval_pdf(wo, wi, mode))
    }

    /// Sample a direction `wi` given `wo`, with `u1` choosing the lobe and `u2` the direction.
    #[inline]
    pub fn sample(
        &self,
        wo: Vec3,
        u1: f32,
        u2: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample<C>> {
        dispatch!(self, b => b.sample(wo, u1, u2, mode))
    }

    /// Has at least one delta (perfectly specular) lobe.
    #[inline]
    pub fn has_delta(&self) -> bool {
        dispatch!(self, b => b.has_delta())
    }

    /// Whether path guiding samples this BSDF's directions from the learnt distribution too
    /// (`integrators/path/guided.rs`): no delta lobe, and no lobe so glossy (microfacet
    /// α < 0.25, principled roughness < 0.5) that the half of its samples spent on the learnt
    /// distribution, which does not know the lobe, would cost more than they save. With a
    /// fixed mixing fraction that is the case Müller et al. 2017 leave to the BSDF.
    pub fn guidable(&self) -> bool {
        const MIN_ALPHA: f32 = 0.25;
        let rough = |m: &Microfacet| m.alpha_u.min(m.alpha_v) >= MIN_ALPHA;
        match self {
            Bsdf::Diffuse(_) | Bsdf::DiffuseTransmission(_) => true,
            Bsdf::RoughConductor(b) => rough(&b.distribution),
            Bsdf::RoughDielectric(b) => rough(&b.distribution),
            Bsdf::RoughPlastic(b) => rough(&b.distribution),
            Bsdf::NoriMicrofacet(b) => rough(&b.distribution),
            Bsdf::Principled(p) => p.roughness >= 0.5 && !self.has_delta(),
            Bsdf::Bumped(b) => b.inner.guidable(),
            _ => false,
        }
    }

    /// Has at least one non-delta lobe (worth light sampling / MIS).
    #[inline]
    pub fn has_smooth(&self) -> bool {
        dispatch!(self, b => b.has_smooth())
    }

    /// Has a non-delta transmission lobe.
    #[inline]
    pub fn has_transmission(&self) -> bool {
        match self {
            Bsdf::RoughDielectric(_) | Bsdf::DiffuseTransmission(_) => true,
            Bsdf::Principled(p) => p.spec_trans > 0.0 && p.metallic < 1.0,
            Bsdf::PrincipledThin(p) => p.transmits(),
            Bsdf::Blend(b) => b.bsdfs.iter().any(Bsdf::has_transmission),
            Bsdf::Bumped(b) => b.inner.has_transmission(),
            _ => false,
        }
    }

    /// A colour for the albedo AOV.
    #[inline]
    pub fn albedo(&self) -> C {
        dispatch!(self, b => b.albedo())
    }
}

macro_rules! impl_from {
    ($($t:ident),*) => {$(
        impl<C: Color> From<$t<C>> for Bsdf<C> {
            fn from(b: $t<C>) -> Bsdf<C> {
                Bsdf::$t(b)
            }
        }
    )*};
}
impl_from!(
    Diffuse,
    Conductor,
    Dielectric,
    ThinDielectric,
    RoughConductor,
    RoughDielectric,
    Plastic,
    RoughPlastic,
    NoriMicrofacet,
    PhongFamily,
    DiffuseTransmission,
    PolarizedPlastic
);

impl<C: Color> From<CourseMaterial<C>> for Bsdf<C> {
    fn from(b: CourseMaterial<C>) -> Bsdf<C> {
        Bsdf::Course(Box::new(b))
    }
}

impl<C: Color> From<Principled<C>> for Bsdf<C> {
    fn from(b: Principled<C>) -> Bsdf<C> {
        Bsdf::Principled(Box::new(b))
    }
}

impl<C: Color> From<PrincipledThin<C>> for Bsdf<C> {
    fn from(b: PrincipledThin<C>) -> Bsdf<C> {
        Bsdf::PrincipledThin(Box::new(b))
    }
}

impl<C: Color> From<Blend<C>> for Bsdf<C> {
    fn from(b: Blend<C>) -> Bsdf<C> {
        Bsdf::Blend(Box::new(b))
    }
}

impl<C: Color> From<Layered<C>> for Bsdf<C> {
    fn from(b: Layered<C>) -> Bsdf<C> {
        Bsdf::Layered(Box::new(b))
    }
}

/// Mirror `w` about the normal (+z): the specular reflection direction in the local frame.
#[inline]
pub(crate) fn reflect_z(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// The sample of a mixture of reflection lobes once the direction `wi` is chosen: the
/// weight is the full `eval / pdf` (both over all lobes), as a one-sample MIS estimate.
pub(crate) fn mixture_reflection_sample<C: Color, B: BsdfModel<C>>(
    b: &B,
    wo: Vec3,
    wi: Vec3,
    mode: TransportMode,
) -> Option<BsdfSample<C>> {
    if wi.z <= 0.0 {
        return None;
    }
    let pdf = b.pdf(wo, wi);
    if !is_positive(pdf) {
        return None;
    }
    Some(BsdfSample::glossy_reflection(
        wi,
        b.eval(wo, wi, mode) / pdf,
        pdf,
    ))
}

/// `x > 0` (false for NaN): guards densities before dividing by them.
#[inline]
pub(crate) fn is_positive(x: f32) -> bool {
    x > 0.0
}

/// Average of the three channels.
#[inline]
pub(crate) fn mean(c: Vec3) -> f32 {
    (c.x + c.y + c.z) * (1.0 / 3.0)
}

/// Reflect `w` about the unit vector `m` (both pointing away from the surface).
#[inline]
pub(crate) fn reflect_z_about(w: Vec3, m: Vec3) -> Vec3 {
    2.0 * w.dot(m) * m - w
}
