//! Materials at run time, resolved once by the builder: no material ids, no chains of
//! `twosided`/`normalmap`/`mask` to walk per hit, no scene-description enum to match.
//!
//! A [`RtMaterial`] is a [`Layer`]: shading-frame perturbations (normal and bump maps, in
//! order) followed either by the scattering model ([`MaterialKind`], or none for `null`) or
//! by a two-sided split into a front and a back layer. On the back side of a two-sided
//! material the shading frame is flipped, as Mitsuba's `twosided` does; the back layer of a
//! `twosided` with one nested material is the front one. Shapes without a material get
//! Mitsuba's default, a one-sided diffuse of reflectance 0.5 — or, on an emitter, none.

use std::sync::Arc;

use base::PhongModel;
use base::dispersion::{Dispersion, DispersionSampling};

use crate::bsdf::{
    Blend, Bsdf, Bumped, Conductor, CourseMaterial, Dielectric, Diffuse, DiffuseTransmission, Ggx,
    IdealLobe, Layered, LayeredBase, LayeredInterface, Microfacet, MicrofacetType, NoriMicrofacet,
    PhongFamily, Plastic, PolarizedPlastic, Principled, PrincipledThin, RoughConductor,
    RoughDielectric, RoughPlastic, RoughPlasticTables, ThinDielectric, rgb_sampling_weight,
};
use crate::math::{Frame, Vec3};
use crate::sampling::sampler::{hash2, u64_to_unit};
use crate::shapes::SurfaceInteraction;
use crate::spectral::DeclaredSpectrum;
use crate::spectral::lanes::{Color, ColorMode, RgbMode};
use crate::textures::{ColorRef, FloatRef, Params, TexCoord, TexRef, Textures};

/// A material as the renderer uses it.
#[derive(Clone, Debug)]
pub struct RtMaterial {
    pub surface: Layer,
    /// Ambient reflectance (the Whitted integrator's ambient term).
    pub ambient: Vec3,
    /// The colour an unlit surface (CENG795 `replace_all`) shows; it scatters nothing.
    pub unlit: Option<ColorRef>,
}

/// Frame perturbations, then a scattering model or a two-sided split.
#[derive(Clone, Debug)]
pub struct Layer {
    pub perturbs: Box<[Perturb]>,
    pub then: Then,
}

#[derive(Clone, Debug)]
pub enum Then {
    /// The scattering model (`None`: the surface does not scatter, as `null`).
    Model(Option<MaterialKind>),
    /// Front (`[0]`) and back (`[1]`) layers of a two-sided material.
    Sides(Box<[Layer; 2]>),
    /// pbrt-v4's `mix`: `layers[1]` with probability `amount`, else `layers[0]`, chosen per
    /// hit by a hash of the point and the outgoing direction (so every query at one vertex
    /// sees the same choice).
    Mix {
        amount: FloatRef,
        layers: Box<[Layer; 2]>,
    },
}

/// A change of the shading frame before scattering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Perturb {
    /// Tangent-space normal map: the texture's RGB in [0,1] encodes the normal 2·c − 1.
    NormalMap { texture: u32 },
    /// Bump map: the normal tilts against the texture's height gradient times `factor`.
    BumpMap { texture: u32, factor: f32 },
    /// Mitsuba 3's `bumpmap`: ∂p/∂u and ∂p/∂v get `scale` times the height's uv gradient
    /// along the normal; their cross product is the new normal (on the geometric normal's
    /// side, mirrored about the old one when `flip` and the viewer sees its back); the BSDF
    /// is then wrapped in [`crate::bsdf::Bumped`] (side test, and the terminator's
    /// shadowing when `shadowing`). Needs the shape's ∂p/∂u, ∂p/∂v (meshes): elsewhere the
    /// frame is left as it is.
    HeightBump {
        texture: u32,
        scale: f32,
        flip: bool,
        shadowing: bool,
    },
}

/// What a [`Perturb::HeightBump`] leaves for the BSDF: the unperturbed and perturbed normals
/// (world space) and the shadowing term's α² (`None`: no shadowing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BumpShading {
    pub n_orig: Vec3,
    pub n_pert: Vec3,
    pub alpha2: Option<f32>,
}

impl BumpShading {
    /// `bsdf` wrapped as Mitsuba's `bumpmap` wraps its nested BSDF, in `frame` (the final
    /// shading frame).
    #[inline]
    pub fn wrap<C: Color>(&self, bsdf: Bsdf<C>, frame: &Frame) -> Bsdf<C> {
        Bsdf::Bumped(Box::new(Bumped {
            inner: bsdf,
            n_orig: frame.to_local(self.n_orig),
            n_pert: frame.to_local(self.n_pert),
            alpha2: self.alpha2,
        }))
    }
}

/// A scattering model with its parameters, evaluated into a [`Bsdf`] at each hit.
#[derive(Clone, Debug)]
pub enum MaterialKind {
    Diffuse {
        reflectance: ColorRef,
    },
    Conductor {
        eta: Vec3,
        k: Vec3,
        specular: ColorRef,
        /// η and k as declared spectra (spectral mode only; `None` in RGB mode).
        spectra: Option<Arc<ConductorSpectra>>,
    },
    Mirror {
        reflectance: ColorRef,
    },
    RoughConductor {
        distribution: MicrofacetType,
        alpha_u: FloatRef,
        alpha_v: FloatRef,
        eta: Vec3,
        k: Vec3,
        specular: ColorRef,
        /// η and k as declared spectra (spectral mode only; `None` in RGB mode).
        spectra: Option<Arc<ConductorSpectra>>,
    },
    /// `int_ior` is the index RGB mode uses (a dispersive one's at the d line); spectral mode
    /// evaluates `dispersion`, when set, at the path's wavelengths (here: the hero's, and the
    /// secondary wavelengths are terminated).
    Dielectric {
        int_ior: f32,
        ext_ior: f32,
        dispersion: Option<Dispersion>,
        reflectance: ColorRef,
        transmittance: ColorRef,
    },
    /// As `Dielectric`; a dispersive sheet keeps every wavelength.
    ThinDielectric {
        int_ior: f32,
        ext_ior: f32,
        dispersion: Option<Dispersion>,
        reflectance: ColorRef,
        transmittance: ColorRef,
    },
    /// As `Dielectric`; `dispersion_sampling` says how a dispersive index treats the path's
    /// wavelengths.
    RoughDielectric {
        distribution: MicrofacetType,
        alpha_u: FloatRef,
        alpha_v: FloatRef,
        int_ior: f32,
        ext_ior: f32,
        dispersion: Option<Dispersion>,
        dispersion_sampling: DispersionSampling,
        reflectance: ColorRef,
        transmittance: ColorRef,
    },
    Plastic {
        diffuse: ColorRef,
        specular: ColorRef,
        int_ior: f32,
        ext_ior: f32,
        nonlinear: bool,
    },
    RoughPlastic {
        microfacet: Microfacet,
        eta: f32,
        /// Tables that depend only on α, the distribution and η: computed once.
        tables: Arc<RoughPlasticTables>,
        diffuse: ColorRef,
        specular: ColorRef,
        nonlinear: bool,
    },
    /// Untextured: the BSDF itself.
    NoriMicrofacet(NoriMicrofacet),
    DiffuseTransmission {
        reflectance: ColorRef,
        transmittance: ColorRef,
    },
    /// pbrt-v4's layered `coateddiffuse` / `coatedconductor` (boxed: rare and large).
    Coated(Box<Coated>),
    /// Mitsuba's `principled` (boxed: rare and large).
    Principled(Box<PrincipledParams>),
    /// Mitsuba's `principledthin` (boxed: rare and large).
    PrincipledThin(Box<PrincipledThinParams>),
    /// Mitsuba's `pplastic` (unpolarised).
    PolarizedPlastic {
        microfacet: Microfacet,
        eta: f32,
        diffuse: ColorRef,
        specular: ColorRef,
    },
    /// Mitsuba's `blendbsdf`: `(1 − weight)·kinds[0] + weight·kinds[1]`, both evaluated.
    Blend {
        weight: FloatRef,
        kinds: Box<[MaterialKind; 2]>,
    },
    /// The CENG795 Phong family, with the ideal lobe of a course mirror, conductor or
    /// dielectric on top when `ideal` is set.
    Phong {
        model: PhongModel,
        normalized: bool,
        kd_fresnel: bool,
        exponent: f32,
        diffuse: ColorRef,
        specular: ColorRef,
        ior: f32,
        absorption: f32,
        ideal: Option<CourseLobe>,
    },
}

/// The parameters of Mitsuba's `principled` (see [`crate::bsdf::Principled`]).
#[derive(Clone, Debug)]
pub struct PrincipledParams {
    pub base_color: ColorRef,
    pub roughness: FloatRef,
    pub anisotropic: FloatRef,
    pub metallic: FloatRef,
    pub spec_trans: FloatRef,
    pub spec_tint: FloatRef,
    pub sheen: FloatRef,
    pub sheen_tint: FloatRef,
    pub flatness: FloatRef,
    pub clearcoat: FloatRef,
    pub clearcoat_gloss: FloatRef,
    /// Interior / exterior index.
    pub eta: f32,
    /// Sampling rates: main specular, clearcoat, diffuse reflection.
    pub rates: [f32; 3],
}

impl PrincipledParams {
    fn bsdf<P: Params, M: ColorMode>(&self, p: &P, at: TexCoord, m: &M) -> Principled<M::C> {
        let rgb = p.color(&self.base_color, at);
        let f = |r: &FloatRef| p.float(r, at);
        let mut b = Principled::with_base(m.albedo_read(p, &self.base_color, rgb), rgb, self.eta);
        b.roughness = f(&self.roughness);
        b.anisotropic = f(&self.anisotropic);
        b.metallic = f(&self.metallic);
        b.spec_trans = f(&self.spec_trans);
        b.spec_tint = f(&self.spec_tint);
        b.sheen = f(&self.sheen);
        b.sheen_tint = f(&self.sheen_tint);
        b.flatness = f(&self.flatness);
        b.clearcoat = f(&self.clearcoat);
        b.clearcoat_gloss = f(&self.clearcoat_gloss);
        b.rates = self.rates;
        b
    }
}

/// The parameters of Mitsuba's `principledthin` (see [`crate::bsdf::PrincipledThin`]).
#[derive(Clone, Debug)]
pub struct PrincipledThinParams {
    pub base_color: ColorRef,
    pub roughness: FloatRef,
    pub anisotropic: FloatRef,
    pub spec_trans: FloatRef,
    pub spec_tint: FloatRef,
    pub sheen: FloatRef,
    pub sheen_tint: FloatRef,
    pub flatness: FloatRef,
    /// Mitsuba's 0..2 `diff_trans`.
    pub diff_trans: FloatRef,
    pub eta: FloatRef,
    /// Sampling rates: specular reflection, specular transmission, diffuse reflection,
    /// diffuse transmission.
    pub rates: [f32; 4],
}

impl PrincipledThinParams {
    fn bsdf<P: Params, M: ColorMode>(&self, p: &P, at: TexCoord, m: &M) -> PrincipledThin<M::C> {
        let rgb = p.color(&self.base_color, at);
        let f = |r: &FloatRef| p.float(r, at);
        let mut b = PrincipledThin::with_base(m.albedo_read(p, &self.base_color, rgb), rgb);
        b.roughness = f(&self.roughness);
        b.anisotropic = f(&self.anisotropic);
        b.spec_trans = f(&self.spec_trans);
        b.spec_tint = f(&self.spec_tint);
        b.sheen = f(&self.sheen);
        b.sheen_tint = f(&self.sheen_tint);
        b.flatness = f(&self.flatness);
        b.diff_trans = f(&self.diff_trans);
        b.eta = f(&self.eta);
        b.rates = self.rates;
        b
    }
}

/// The parameters of a pbrt-v4 coated material (see [`crate::bsdf::Layered`]).
#[derive(Clone, Debug)]
pub struct Coated {
    pub alpha_u: FloatRef,
    pub alpha_v: FloatRef,
    /// The roughness values are pbrt-v4's: α = √r.
    pub remap_roughness: bool,
    pub eta: f32,
    pub thickness: FloatRef,
    pub albedo: ColorRef,
    pub g: FloatRef,
    pub max_depth: u32,
    pub n_samples: u32,
    pub base: CoatedBase,
}

#[derive(Clone, Debug)]
pub enum CoatedBase {
    Diffuse {
        reflectance: ColorRef,
    },
    /// η and k as declared (or derived from `reflectance`), divided by the coating's index
    /// when the BSDF is made.
    Conductor {
        alpha_u: FloatRef,
        alpha_v: FloatRef,
        eta: Vec3,
        k: Vec3,
        spectra: Option<Arc<ConductorSpectra>>,
        reflectance: Option<ColorRef>,
    },
}

/// A conductor's η and k as the scene declared them, for spectral mode: measured spectra of a
/// named conductor, or lists; `None` for one declared as RGB (upsampled, as any RGB value).
#[derive(Clone, Debug, PartialEq)]
pub struct ConductorSpectra {
    pub eta: Option<DeclaredSpectrum>,
    pub k: Option<DeclaredSpectrum>,
}

impl ConductorSpectra {
    /// The declared η and k of `s` (none when `s` is `None`).
    #[inline(always)]
    fn get(
        s: &Option<Arc<ConductorSpectra>>,
    ) -> (Option<&DeclaredSpectrum>, Option<&DeclaredSpectrum>) {
        match s {
            Some(s) => (s.eta.as_ref(), s.k.as_ref()),
            None => (None, None),
        }
    }
}

/// The ideal lobe of a course material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CourseLobe {
    pub lobe: IdealLobe,
    pub reflectance: Vec3,
    pub roughness: f32,
}

impl RtMaterial {
    /// Mitsuba's default material: one-sided diffuse 0.5.
    pub fn default_diffuse() -> RtMaterial {
        RtMaterial {
            surface: Layer {
                perturbs: Box::new([]),
                then: Then::Model(Some(MaterialKind::Diffuse {
                    reflectance: TexRef::Const(Vec3::splat(0.5)),
                })),
            },
            ambient: Vec3::ZERO,
            unlit: None,
        }
    }

    /// The scattering model at `si` and the shading frame it lives in (perturbed by normal
    /// and bump maps, flipped on the back side of a two-sided material); `None` when the
    /// surface does not scatter.
    /// `derivs` gives the shape's ∂p/∂u, ∂p/∂v at `si` (read only by Mitsuba's bump maps);
    /// the last such bump map's [`BumpShading`] is returned with the model.
    #[inline(always)]
    pub fn resolve(
        &self,
        textures: &Textures,
        si: &SurfaceInteraction,
        at: TexCoord,
        derivs: impl Fn() -> Option<(Vec3, Vec3)>,
    ) -> Option<(&MaterialKind, Frame, Option<BumpShading>)> {
        let mut frame = si.shading;
        let mut layer = &self.surface;
        let mut bump = None;
        loop {
            for p in &layer.perturbs {
                frame = match *p {
                    Perturb::HeightBump {
                        texture,
                        scale,
                        flip,
                        shadowing,
                    } => match derivs() {
                        Some(d) => {
                            let h = HeightBumpAt {
                                gradient: textures.get(texture).uv_gradient(at) * scale,
                                derivs: d,
                                ng: si.ng,
                                wo: si.wo,
                            };
                            let (f, b) = h.frame(frame, flip, shadowing);
                            bump = Some(b);
                            f
                        }
                        None => frame,
                    },
                    _ => p.apply(textures, at, frame),
                };
            }
            match &layer.then {
                Then::Model(kind) => return kind.as_ref().map(|k| (k, frame, bump)),
                Then::Mix { amount, layers } => {
                    layer = &layers
                        [usize::from(mix_picks_second(textures.float(amount, at), si.p, si.wo))];
                }
                Then::Sides(sides) => {
                    if si.wo.dot(frame.n) < 0.0 {
                        frame = Frame {
                            s: frame.s,
                            t: -frame.t,
                            n: -frame.n,
                        };
                        layer = &sides[1];
                    } else {
                        layer = &sides[0];
                    }
                }
            }
        }
    }

    /// An index-matched boundary (Mitsuba's `null`): no scattering model anywhere, nothing
    /// shown. Volumetric paths cross it unchanged.
    pub fn is_null(&self) -> bool {
        self.unlit.is_none() && matches!(self.surface.then, Then::Model(None))
    }

    /// Whether shading is unchanged when the tangent frame turns about the normal: no
    /// perturbation and no anisotropic roughness on either side. Interaction may then take
    /// the tangent from a triangle edge instead of the uv parameterisation (see
    /// [`crate::shapes::interaction`]); only the mapping of random numbers to directions
    /// changes, not any distribution.
    pub fn isotropic(&self) -> bool {
        fn layer(l: &Layer) -> bool {
            l.perturbs.is_empty()
                && match &l.then {
                    Then::Model(k) => k.as_ref().is_none_or(MaterialKind::isotropic),
                    Then::Sides(s) | Then::Mix { layers: s, .. } => layer(&s[0]) && layer(&s[1]),
                }
        }
        layer(&self.surface)
    }
}

/// Whether a `mix` of weight `amount` takes its second material at point `p` seen from `wo`
/// (pbrt-v4's rule: the second when a hash of the two in [0, 1) is at most `amount`).
#[inline]
pub fn mix_picks_second(amount: f32, p: Vec3, wo: Vec3) -> bool {
    if amount <= 0.0 {
        return false;
    }
    if amount >= 1.0 {
        return true;
    }
    let bits = |v: Vec3| {
        hash2(
            hash2(u64::from(v.x.to_bits()), u64::from(v.y.to_bits())),
            u64::from(v.z.to_bits()),
        )
    };
    u64_to_unit(hash2(bits(p), bits(wo))) <= amount
}

/// A Mitsuba bump map's inputs at one point.
struct HeightBumpAt {
    /// scale · ∂h/∂(u, v).
    gradient: crate::math::Vec2,
    derivs: (Vec3, Vec3),
    ng: Vec3,
    wo: Vec3,
}

impl HeightBumpAt {
    /// The perturbed frame and what the BSDF wrapper needs (see [`Perturb::HeightBump`]).
    fn frame(&self, frame: Frame, flip: bool, shadowing: bool) -> (Frame, BumpShading) {
        let n = frame.n;
        let (dpdu, dpdv) = self.derivs;
        let du = dpdu + n * (self.gradient.x - n.dot(dpdu));
        let dv = dpdv + n * (self.gradient.y - n.dot(dpdv));
        let mut cr = du.cross(dv);
        if self.ng.dot(cr) < 0.0 {
            cr = -cr;
        }
        let mut nl = frame.to_local(cr);
        if flip {
            let w = frame.to_local(self.wo);
            if w.z * w.dot(nl) <= 0.0 {
                nl = Vec3::new(-nl.x, -nl.y, nl.z);
            }
        }
        let len2 = nl.length_squared();
        let nl = if len2 > 0.0 && len2.is_finite() {
            nl / len2.sqrt()
        } else {
            Vec3::Z
        };
        let s = Vec3::X - nl * nl.x;
        let s2 = s.length_squared();
        let s = if s2 > 0.0 && s2.is_finite() {
            s / s2.sqrt()
        } else {
            Vec3::Y
        };
        let t = nl.cross(s);
        let tan2 = (1.0 - nl.z * nl.z).max(0.0) / (nl.z * nl.z);
        let perturbed = Frame {
            s: frame.to_world(s),
            t: frame.to_world(t),
            n: frame.to_world(nl),
        };
        (
            perturbed,
            BumpShading {
                n_orig: n,
                n_pert: perturbed.n,
                alpha2: shadowing.then(|| (0.125 * tan2).min(1.0)),
            },
        )
    }
}

impl Perturb {
    #[inline]
    fn apply(&self, textures: &Textures, at: TexCoord, frame: Frame) -> Frame {
        match *self {
            Perturb::NormalMap { texture } => {
                let c = textures.get(texture).eval(at);
                let local = (c * 2.0 - Vec3::ONE).normalize_or_zero();
                if local.z > 0.0 {
                    let n = frame.to_world(local).normalize();
                    Frame::from_normal_tangent(n, frame.s)
                } else {
                    frame
                }
            }
            Perturb::BumpMap { texture, factor } => {
                let g = textures.get(texture).height_gradient(at, frame.s, frame.t);
                let n = frame.n;
                let tilted = (n - factor * (g - g.dot(n) * n)).normalize_or(n);
                Frame::from_normal_tangent(tilted, frame.s)
            }
            // Applied by `RtMaterial::resolve`, which has the shape's derivatives.
            Perturb::HeightBump { .. } => frame,
        }
    }
}

impl MaterialKind {
    fn isotropic(&self) -> bool {
        match self {
            MaterialKind::RoughConductor {
                alpha_u, alpha_v, ..
            }
            | MaterialKind::RoughDielectric {
                alpha_u, alpha_v, ..
            } => alpha_u == alpha_v,
            MaterialKind::Principled(b) => b.anisotropic == TexRef::Const(0.0),
            MaterialKind::PrincipledThin(b) => b.anisotropic == TexRef::Const(0.0),
            MaterialKind::Blend { kinds, .. } => kinds.iter().all(MaterialKind::isotropic),
            MaterialKind::PolarizedPlastic { microfacet, .. } => microfacet.is_isotropic(),
            MaterialKind::Coated(c) => {
                c.alpha_u == c.alpha_v
                    && match &c.base {
                        CoatedBase::Conductor {
                            alpha_u, alpha_v, ..
                        } => alpha_u == alpha_v,
                        CoatedBase::Diffuse { .. } => true,
                    }
            }
            _ => true,
        }
    }

    /// The BSDF with its parameters evaluated at `at` (RGB mode).
    #[inline]
    pub fn bsdf<P: Params>(&self, p: &P, at: TexCoord) -> Bsdf {
        self.bsdf_in(p, at, &RgbMode)
    }

    /// The BSDF with its parameters evaluated at `at` and converted to the colour type of
    /// `m`: reflectances and transmittances as albedo spectra (clamped to [0, 1] in spectral
    /// mode, also the unnormalised CENG795 Phong kd/ks), conductor η and k as unbounded
    /// spectra; IORs stay scalar but for dispersive dielectrics (see
    /// [`MaterialKind::Dielectric`], [`ColorMode::smooth_eta`], [`ColorMode::lane_ior`]).
    /// Lobe-selection weights and other fixed 3-channel or channel-mean arithmetic are
    /// computed from the RGB values in every mode.
    #[inline(always)]
    pub fn bsdf_in<P: Params, M: ColorMode>(&self, p: &P, at: TexCoord, m: &M) -> Bsdf<M::C> {
        match self {
            MaterialKind::Diffuse { reflectance } => {
                Bsdf::Diffuse(Diffuse::new(m.albedo_at(p, reflectance, at)))
            }
            MaterialKind::Conductor {
                eta,
                k,
                specular,
                spectra,
            } => {
                let (eta_s, k_s) = ConductorSpectra::get(spectra);
                Bsdf::Conductor(Conductor::new(
                    m.unbounded_declared(*eta, eta_s),
                    m.unbounded_declared(*k, k_s),
                    m.albedo_at(p, specular, at),
                ))
            }
            MaterialKind::Mirror { reflectance } => {
                Bsdf::Conductor(Conductor::mirror(m.albedo_at(p, reflectance, at)))
            }
            MaterialKind::RoughConductor {
                distribution,
                alpha_u,
                alpha_v,
                eta,
                k,
                specular,
                spectra,
            } => {
                let (eta_s, k_s) = ConductorSpectra::get(spectra);
                Bsdf::RoughConductor(RoughConductor::new(
                    *distribution,
                    alpha(p.float(alpha_u, at)),
                    alpha(p.float(alpha_v, at)),
                    m.unbounded_declared(*eta, eta_s),
                    m.unbounded_declared(*k, k_s),
                    m.albedo_at(p, specular, at),
                ))
            }
            MaterialKind::Dielectric {
                int_ior,
                ext_ior,
                dispersion,
                reflectance,
                transmittance,
            } => {
                let ior = with_ior(dispersion, |f| m.smooth_eta(f, *int_ior));
                let mut d = Dielectric::with_lanes(ior, *ext_ior);
                d.specular_reflectance = m.albedo_at(p, reflectance, at);
                d.specular_transmittance = m.albedo_at(p, transmittance, at);
                Bsdf::Dielectric(d)
            }
            MaterialKind::ThinDielectric {
                int_ior,
                ext_ior,
                dispersion,
                reflectance,
                transmittance,
            } => {
                let ior = with_ior(dispersion, |f| m.lane_ior(f, *int_ior));
                let mut d = ThinDielectric::with_lane_ior(ior, *ext_ior);
                d.specular_reflectance = m.albedo_at(p, reflectance, at);
                d.specular_transmittance = m.albedo_at(p, transmittance, at);
                Bsdf::ThinDielectric(d)
            }
            MaterialKind::RoughDielectric {
                distribution,
                alpha_u,
                alpha_v,
                int_ior,
                ext_ior,
                dispersion,
                dispersion_sampling,
                reflectance,
                transmittance,
            } => {
                let ior = with_ior(dispersion, |f| match dispersion_sampling {
                    DispersionSampling::Mis => m.lane_ior(f, *int_ior),
                    DispersionSampling::Terminate => M::C::splat(m.smooth_eta(f, *int_ior)),
                });
                let mut d = RoughDielectric::with_lane_ior(
                    *distribution,
                    alpha(p.float(alpha_u, at)),
                    alpha(p.float(alpha_v, at)),
                    ior,
                    *ext_ior,
                );
                d.specular_reflectance = m.albedo_at(p, reflectance, at);
                d.specular_transmittance = m.albedo_at(p, transmittance, at);
                Bsdf::RoughDielectric(d)
            }
            MaterialKind::Plastic {
                diffuse,
                specular,
                int_ior,
                ext_ior,
                nonlinear,
            } => {
                let (d, s) = (p.color(diffuse, at), p.color(specular, at));
                Bsdf::Plastic(Plastic::with_weight(
                    m.albedo_read(p, diffuse, d),
                    m.albedo_read(p, specular, s),
                    *int_ior,
                    *ext_ior,
                    *nonlinear,
                    rgb_sampling_weight(d, s),
                ))
            }
            MaterialKind::RoughPlastic {
                microfacet,
                eta,
                tables,
                diffuse,
                specular,
                nonlinear,
            } => {
                let (d, s) = (p.color(diffuse, at), p.color(specular, at));
                Bsdf::RoughPlastic(RoughPlastic::with_tables_weighted(
                    *microfacet,
                    *eta,
                    tables.clone(),
                    m.albedo_read(p, diffuse, d),
                    m.albedo_read(p, specular, s),
                    *nonlinear,
                    rgb_sampling_weight(d, s),
                ))
            }
            MaterialKind::NoriMicrofacet(b) => Bsdf::NoriMicrofacet(b.map_lanes(|c| m.albedo(c))),
            MaterialKind::DiffuseTransmission {
                reflectance,
                transmittance,
            } => {
                let (r, t) = (p.color(reflectance, at), p.color(transmittance, at));
                Bsdf::DiffuseTransmission(DiffuseTransmission::new(
                    m.albedo_read(p, reflectance, r),
                    m.albedo_read(p, transmittance, t),
                    (r.max_element(), t.max_element()),
                ))
            }
            MaterialKind::Coated(c) => Bsdf::Layered(Box::new(c.bsdf(p, at, m))),
            MaterialKind::Principled(b) => Bsdf::Principled(Box::new(b.bsdf(p, at, m))),
            MaterialKind::PrincipledThin(b) => Bsdf::PrincipledThin(Box::new(b.bsdf(p, at, m))),
            MaterialKind::PolarizedPlastic {
                microfacet,
                eta,
                diffuse,
                specular,
            } => {
                let (d, s) = (p.color(diffuse, at), p.color(specular, at));
                Bsdf::PolarizedPlastic(PolarizedPlastic {
                    distribution: *microfacet,
                    eta: *eta,
                    diffuse_reflectance: m.albedo_read(p, diffuse, d),
                    specular_reflectance: m.albedo_read(p, specular, s),
                    specular_sampling_weight: rgb_sampling_weight(d, s),
                })
            }
            MaterialKind::Blend { weight, kinds } => Bsdf::Blend(Box::new(Blend::new(
                p.float(weight, at),
                kinds[0].blend_part(p, at, m),
                kinds[1].blend_part(p, at, m),
            ))),
            MaterialKind::Phong {
                model,
                normalized,
                kd_fresnel,
                exponent,
                diffuse,
                specular,
                ior,
                absorption,
                ideal,
            } => {
                let phong = PhongFamily::new(
                    *model,
                    *normalized,
                    *kd_fresnel,
                    *exponent,
                    p.color(diffuse, at),
                    p.color(specular, at),
                    *ior,
                )
                .with_absorption(*ior, *absorption);
                match ideal {
                    None => Bsdf::PhongFamily(phong.map_lanes(|c| m.albedo(c))),
                    Some(i) => Bsdf::Course(Box::new(
                        CourseMaterial::new(phong, i.lobe, i.reflectance, i.roughness)
                            .map_lanes(|c| m.albedo(c)),
                    )),
                }
            }
        }
    }
}

impl MaterialKind {
    /// A part of a blend (out of line: [`MaterialKind::bsdf_in`] is inlined into its callers
    /// and cannot recurse into itself there).
    #[inline(never)]
    fn blend_part<P: Params, M: ColorMode>(&self, p: &P, at: TexCoord, m: &M) -> Bsdf<M::C> {
        self.bsdf_in(p, at, m)
    }
}

impl Coated {
    fn bsdf<P: Params, M: ColorMode>(&self, p: &P, at: TexCoord, m: &M) -> Layered<M::C> {
        let rough = |r: &FloatRef| {
            let v = p.float(r, at).max(0.0);
            if self.remap_roughness { v.sqrt() } else { v }
        };
        let top = LayeredInterface {
            distrib: Ggx::new(rough(&self.alpha_u), rough(&self.alpha_v)),
            eta: if self.eta > 0.0 { self.eta } else { 1.0 },
        };
        let base = match &self.base {
            CoatedBase::Diffuse { reflectance } => {
                LayeredBase::Diffuse(m.albedo_at(p, reflectance, at))
            }
            CoatedBase::Conductor {
                alpha_u,
                alpha_v,
                eta,
                k,
                spectra,
                reflectance,
            } => {
                let (eta, k) = match reflectance {
                    Some(r) => {
                        let r = m.albedo_at(p, r, at);
                        let k = M::C::from_fn(|i| {
                            let x = r.lane(i).clamp(0.0, 0.9999);
                            2.0 * x.sqrt() / (1.0 - x).sqrt()
                        });
                        (M::C::ONE, k)
                    }
                    None => {
                        let (eta_s, k_s) = ConductorSpectra::get(spectra);
                        (
                            m.unbounded_declared(*eta, eta_s),
                            m.unbounded_declared(*k, k_s),
                        )
                    }
                };
                LayeredBase::Conductor {
                    distrib: Ggx::new(rough(alpha_u), rough(alpha_v)),
                    eta: eta / top.eta,
                    k: k / top.eta,
                }
            }
        };
        Layered::new(
            top,
            base,
            p.float(&self.thickness, at),
            m.albedo_at(p, &self.albedo, at),
            p.float(&self.g, at),
            self.max_depth,
            self.n_samples,
        )
    }
}

/// `k` called with a dispersive index as a function of the wavelength in nm (what
/// [`ColorMode`] resolves), or with `None`.
#[inline]
fn with_ior<R>(d: &Option<Dispersion>, k: impl FnOnce(Option<&dyn Fn(f32) -> f32>) -> R) -> R {
    match d {
        None => k(None),
        Some(d) => k(Some(&|lambda: f32| d.ior(f64::from(lambda)) as f32)),
    }
}

/// Mitsuba clamps roughness away from 0 to keep the microfacet models finite.
pub fn alpha(a: f32) -> f32 {
    a.max(1e-4)
}
