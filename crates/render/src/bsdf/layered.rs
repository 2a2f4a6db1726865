//! pbrt-v4's stochastic layered BSDF (`coateddiffuse`, `coatedconductor`): a dielectric
//! interface over an opaque base (Lambertian or conductor), the two separated by a slab of
//! optical thickness `thickness` holding a homogeneous medium (unit extinction; scattering
//! albedo `albedo`, Henyey–Greenstein `g`; none when the albedo is black). Nothing is
//! tabulated: `eval` and `pdf` are Monte Carlo estimates made of random walks between the
//! interfaces (Guo et al. 2018, "Position-Free Monte Carlo Simulation for Arbitrary Layered
//! BSDFs", in pbrt-v4's form), and `sample` follows one walk.
//!
//! The estimates are deterministic functions of their arguments: each seeds its own random
//! sequence with a hash of the directions (and of the sample's random numbers), so the same
//! query always gives the same value. That keeps a light sample's MIS weight and the BSDF
//! sample's weight for the same path consistent, and keeps renders reproducible.
//!
//! Inside the slab a walk reaches the light path (traced from `wi` through the coating) in
//! two ways: by connecting to it, or by sampling a direction that then leaves through the
//! coating towards `wi`. The two are weighted with the power heuristic over the densities of
//! the same inner direction under both strategies. pbrt-v4 weighs the second by the density
//! of `wi` given the inner direction instead; the weights then do not sum to one, and its
//! `f` is neither reciprocal nor what its sampling draws (the tests in
//! `tests/it/layered_bsdf.rs` fail with that weight).
//!
//! Conventions inside this module follow pbrt-v4 (`f` without the cosine, both hemispheres
//! handled by every component, GGX = Trowbridge–Reitz with height-correlated Smith masking);
//! [`Layered`] converts to ours at the boundary (`eval` = f·|cos θi|). Both layered materials
//! are two-sided: a query from below is answered as the mirrored query from above. The bases
//! are opaque, so nothing is transmitted through the whole stack.

use super::fresnel::{fresnel_conductor, fresnel_dielectric};
use super::{BsdfModel, BsdfSample, TransportMode, is_positive};
use crate::math::{INV_4PI, INV_PI, PI, Vec2, Vec3, safe_sqrt};
use crate::media::phase::Phase;
use crate::sampling::sampler::{hash2, mix64, u64_to_unit};
use crate::sampling::warp;
use crate::spectral::lanes::Color;

/// Trowbridge–Reitz (GGX) microfacets as pbrt-v4 defines them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    ax: f32,
    ay: f32,
}

impl Ggx {
    pub fn new(alpha_x: f32, alpha_y: f32) -> Ggx {
        let fix = |a: f32| if a.is_finite() { a.max(0.0) } else { 0.0 };
        Ggx {
            ax: fix(alpha_x),
            ay: fix(alpha_y),
        }
    }

    /// Below this roughness pbrt-v4 treats the surface as perfectly smooth.
    fn smooth(&self) -> bool {
        self.ax.max(self.ay) < 1e-3
    }

    fn d(&self, wm: Vec3) -> f32 {
        let cos2 = wm.z * wm.z;
        let cos4 = cos2 * cos2;
        let e = ((wm.x / self.ax).powi(2) + (wm.y / self.ay).powi(2)) / cos2;
        if cos4 < 1e-16 || !e.is_finite() {
            return 0.0;
        }
        1.0 / (PI * self.ax * self.ay * cos4 * (1.0 + e) * (1.0 + e))
    }

    fn lambda(&self, w: Vec3) -> f32 {
        let a2t2 = ((self.ax * w.x).powi(2) + (self.ay * w.y).powi(2)) / (w.z * w.z);
        if !a2t2.is_finite() {
            return 0.0;
        }
        0.5 * ((1.0 + a2t2).sqrt() - 1.0)
    }

    fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of the visible normal `wm` seen from `w` (either hemisphere).
    fn pdf(&self, w: Vec3, wm: Vec3) -> f32 {
        if w.z == 0.0 {
            return 0.0;
        }
        self.g1(w) / w.z.abs() * self.d(wm) * w.dot(wm).abs()
    }

    /// A visible normal for `w` (Heitz 2018), in the upper hemisphere.
    fn sample_wm(&self, w: Vec3, u: Vec2) -> Vec3 {
        let mut wh = Vec3::new(self.ax * w.x, self.ay * w.y, w.z).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        let t1 = if wh.z < 0.99999 {
            Vec3::Z.cross(wh).normalize()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        let r = u.x.sqrt();
        let (s, c) = warp::sin_cos_2pi(u.y);
        let (px, mut py) = (r * c, r * s);
        let h = safe_sqrt(1.0 - px * px);
        let t = 0.5 * (1.0 + wh.z);
        py = (1.0 - t) * h + t * py;
        let pz = safe_sqrt(1.0 - px * px - py * py);
        let nh = px * t1 + py * t2 + pz * wh;
        Vec3::new(self.ax * nh.x, self.ay * nh.y, nh.z.max(1e-6)).normalize()
    }
}

/// Which lobes a sample or density may use (pbrt-v4's `BxDFReflTransFlags`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Lobes {
    All,
    Reflection,
    Transmission,
}

impl Lobes {
    /// The probabilities of reflection and transmission `(pr, pt)` given their weights.
    fn mask(self, r: f32, t: f32) -> (f32, f32) {
        match self {
            Lobes::All => (r, t),
            Lobes::Reflection => (r, 0.0),
            Lobes::Transmission => (0.0, t),
        }
    }
}

/// A sampled direction in pbrt-v4's terms: `f` without the cosine, `pdf` the density (or the
/// discrete probability of a specular lobe).
#[derive(Clone, Copy, Debug)]
struct Scatter<F> {
    f: F,
    wi: Vec3,
    pdf: f32,
    specular: bool,
}

fn same_side(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

fn flip(mode: TransportMode) -> TransportMode {
    match mode {
        TransportMode::Radiance => TransportMode::Importance,
        TransportMode::Importance => TransportMode::Radiance,
    }
}

fn reflect(w: Vec3, m: Vec3) -> Vec3 {
    2.0 * w.dot(m) * m - w
}

/// `w` refracted through the interface with normal `n` and relative index `eta`
/// (inside/outside, `n` on the outside), and the index ratio crossed; `None` at total
/// internal reflection.
fn refract(w: Vec3, mut n: Vec3, mut eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(w);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    Some((-w / eta + (cos_i / eta - cos_t) * n, eta))
}

/// The power heuristic with one sample per strategy.
fn power(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2.is_infinite() {
        1.0
    } else {
        a2 / (a2 + b2)
    }
}

/// Transmittance of the unit-extinction slab over a height `dz` along `w`.
fn tr(dz: f32, w: Vec3) -> f32 {
    if dz.abs() <= f32::MIN_POSITIVE {
        1.0
    } else {
        (-(dz / w.z).abs()).exp()
    }
}

/// pbrt-v4's `DielectricBxDF` with a GGX distribution: the coating.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interface {
    pub distrib: Ggx,
    /// Relative index of refraction (coating / outside).
    pub eta: f32,
}

impl Interface {
    fn specular(&self) -> bool {
        self.eta == 1.0 || self.distrib.smooth()
    }

    /// The generalised half vector of `wo`, `wi` in the upper hemisphere and the index ratio
    /// of the crossing (1 for reflection); `None` where the BSDF is 0 by geometry.
    fn half(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32)> {
        let (co, ci) = (wo.z, wi.z);
        let etap = if co * ci > 0.0 {
            1.0
        } else if co > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let wm = wi * etap + wo;
        if ci == 0.0 || co == 0.0 || wm.length_squared() == 0.0 {
            return None;
        }
        let mut wm = wm.normalize();
        if wm.z < 0.0 {
            wm = -wm;
        }
        // Microfacets seen from behind contribute nothing.
        if wm.dot(wi) * ci < 0.0 || wm.dot(wo) * co < 0.0 {
            return None;
        }
        Some((wm, etap))
    }

    fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        if self.specular() {
            return 0.0;
        }
        let Some((wm, etap)) = self.half(wo, wi) else {
            return 0.0;
        };
        let fr = fresnel_dielectric(wo.dot(wm), self.eta).0;
        let dg = self.distrib.d(wm) * self.distrib.g(wo, wi);
        if etap == 1.0 {
            return dg * fr / (4.0 * wi.z * wo.z).abs();
        }
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * wi.z * wo.z;
        let ft = dg * (1.0 - fr) * (wi.dot(wm) * wo.dot(wm) / denom).abs();
        if mode == TransportMode::Radiance {
            ft / (etap * etap)
        } else {
            ft
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, lobes: Lobes) -> f32 {
        if self.specular() {
            return 0.0;
        }
        let Some((wm, etap)) = self.half(wo, wi) else {
            return 0.0;
        };
        let r = fresnel_dielectric(wo.dot(wm), self.eta).0;
        let (pr, pt) = lobes.mask(r, 1.0 - r);
        if pr + pt <= 0.0 {
            return 0.0;
        }
        if etap == 1.0 {
            self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt)
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            let dwm_dwi = wi.dot(wm).abs() / denom;
            self.distrib.pdf(wo, wm) * dwm_dwi * pt / (pr + pt)
        }
    }

    fn sample(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        lobes: Lobes,
    ) -> Option<Scatter<f32>> {
        let radiance = |f: f32, etap: f32| {
            if mode == TransportMode::Radiance {
                f / (etap * etap)
            } else {
                f
            }
        };
        if self.specular() {
            let r = fresnel_dielectric(wo.z, self.eta).0;
            let (pr, pt) = lobes.mask(r, 1.0 - r);
            if pr + pt <= 0.0 {
                return None;
            }
            if uc < pr / (pr + pt) {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                return Some(Scatter {
                    f: r / wi.z.abs(),
                    wi,
                    pdf: pr / (pr + pt),
                    specular: true,
                });
            }
            let (wi, etap) = refract(wo, Vec3::Z, self.eta)?;
            if wi.z == 0.0 {
                return None;
            }
            return Some(Scatter {
                f: radiance((1.0 - r) / wi.z.abs(), etap),
                wi,
                pdf: pt / (pr + pt),
                specular: true,
            });
        }
        let wm = self.distrib.sample_wm(wo, u);
        let r = fresnel_dielectric(wo.dot(wm), self.eta).0;
        let (pr, pt) = lobes.mask(r, 1.0 - r);
        if pr + pt <= 0.0 {
            return None;
        }
        let (wi, f, pdf) = if uc < pr / (pr + pt) {
            let wi = reflect(wo, wm);
            if !same_side(wo, wi) {
                return None;
            }
            let pdf = self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt);
            let f = self.distrib.d(wm) * self.distrib.g(wo, wi) * r / (4.0 * wi.z * wo.z).abs();
            (wi, f, pdf)
        } else {
            let (wi, etap) = refract(wo, wm, self.eta)?;
            if same_side(wo, wi) || wi.z == 0.0 {
                return None;
            }
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            let dwm_dwi = wi.dot(wm).abs() / denom;
            let pdf = self.distrib.pdf(wo, wm) * dwm_dwi * pt / (pr + pt);
            let ft = (1.0 - r)
                * self.distrib.d(wm)
                * self.distrib.g(wo, wi)
                * (wi.dot(wm) * wo.dot(wm) / (wi.z * wo.z * denom)).abs();
            (wi, radiance(ft, etap), pdf)
        };
        (pdf > 0.0 && f.is_finite()).then_some(Scatter {
            f,
            wi,
            pdf,
            specular: false,
        })
    }
}

/// The opaque base under the coating.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Base<C: Color> {
    Diffuse(C),
    /// A conductor of complex index `eta + i k` relative to the coating.
    Conductor {
        distrib: Ggx,
        eta: C,
        k: C,
    },
}

impl<C: Color> Base<C> {
    fn specular(&self) -> bool {
        match self {
            Base::Diffuse(_) => false,
            Base::Conductor { distrib, .. } => distrib.smooth(),
        }
    }

    fn f(&self, wo: Vec3, wi: Vec3) -> C {
        if !same_side(wo, wi) {
            return C::ZERO;
        }
        match *self {
            Base::Diffuse(r) => r * INV_PI,
            Base::Conductor { distrib, eta, k } => {
                if distrib.smooth() {
                    return C::ZERO;
                }
                let wm = wi + wo;
                if wm.length_squared() == 0.0 {
                    return C::ZERO;
                }
                let wm = wm.normalize();
                let fr = fresnel_conductor(wo.dot(wm).abs(), eta, k);
                fr * (distrib.d(wm) * distrib.g(wo, wi) / (4.0 * wi.z * wo.z).abs())
            }
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !same_side(wo, wi) {
            return 0.0;
        }
        match *self {
            Base::Diffuse(_) => wi.z.abs() * INV_PI,
            Base::Conductor { distrib, .. } => {
                if distrib.smooth() {
                    return 0.0;
                }
                let wm = wo + wi;
                if wm.length_squared() == 0.0 {
                    return 0.0;
                }
                let mut wm = wm.normalize();
                if wm.z < 0.0 {
                    wm = -wm;
                }
                distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
            }
        }
    }

    fn sample(&self, wo: Vec3, u: Vec2) -> Option<Scatter<C>> {
        if wo.z == 0.0 {
            return None;
        }
        match *self {
            Base::Diffuse(r) => {
                let mut wi = warp::square_to_cosine_hemisphere(u);
                if wo.z < 0.0 {
                    wi.z = -wi.z;
                }
                let pdf = wi.z.abs() * INV_PI;
                (pdf > 0.0).then_some(Scatter {
                    f: r * INV_PI,
                    wi,
                    pdf,
                    specular: false,
                })
            }
            Base::Conductor { distrib, eta, k } => {
                if distrib.smooth() {
                    let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                    let c = wi.z.abs();
                    return Some(Scatter {
                        f: fresnel_conductor(c, eta, k) / c,
                        wi,
                        pdf: 1.0,
                        specular: true,
                    });
                }
                let wm = distrib.sample_wm(wo, u);
                let wi = reflect(wo, wm);
                if !same_side(wo, wi) {
                    return None;
                }
                let pdf = distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs());
                if !is_positive(pdf) || wi.z == 0.0 {
                    return None;
                }
                let fr = fresnel_conductor(wo.dot(wm).abs(), eta, k);
                let f = fr * (distrib.d(wm) * distrib.g(wo, wi) / (4.0 * wi.z * wo.z).abs());
                Some(Scatter {
                    f,
                    wi,
                    pdf,
                    specular: false,
                })
            }
        }
    }
}

/// The random numbers of one estimate: a counter hashed from a seed.
struct Rng(u64);

impl Rng {
    fn new(a: u64, b: u64) -> Rng {
        Rng(hash2(a, b))
    }

    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        u64_to_unit(mix64(self.0))
    }

    fn next2(&mut self) -> Vec2 {
        Vec2::new(self.next(), self.next())
    }
}

fn hash_dir(w: Vec3) -> u64 {
    hash2(
        hash2(u64::from(w.x.to_bits()), u64::from(w.y.to_bits())),
        u64::from(w.z.to_bits()),
    )
}

/// A coating over an opaque base (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Layered<C: Color = Vec3> {
    pub top: Interface,
    pub bottom: Base<C>,
    /// Optical thickness of the slab between the interfaces (> 0).
    pub thickness: f32,
    /// Single-scattering albedo of the slab's medium; black: the slab only absorbs.
    pub albedo: C,
    pub g: f32,
    pub max_depth: u32,
    pub n_samples: u32,
}

impl<C: Color> Layered<C> {
    pub fn new(
        top: Interface,
        bottom: Base<C>,
        thickness: f32,
        albedo: C,
        g: f32,
        max_depth: u32,
        n_samples: u32,
    ) -> Layered<C> {
        Layered {
            top,
            bottom,
            thickness: thickness.max(f32::MIN_POSITIVE),
            albedo,
            g: g.clamp(-0.999, 0.999),
            max_depth,
            n_samples: n_samples.max(1),
        }
    }

    fn phase(&self) -> Phase {
        Phase::HenyeyGreenstein { g: self.g }
    }

    /// f(wo, wi) without the cosine, for `wo` above the surface (pbrt-v4's `f`).
    fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        if !same_side(wo, wi) {
            return C::ZERO;
        }
        let (top, bottom, thick) = (&self.top, &self.bottom, self.thickness);
        let n = self.n_samples;
        let mut f = C::splat(n as f32 * top.f(wo, wi, mode));
        let mut rng = Rng::new(hash_dir(wo), hash_dir(wi));
        let phase = self.phase();
        let scatters = !self.albedo.is_black();
        // The walk leaves through the coating, at the top of the slab.
        let exit_z = thick;
        for _ in 0..n {
            // The path enters through the coating from `wo`; a second one, traced from `wi`
            // the other way, is the light that next-event estimation connects to.
            let Some(wos) = top.sample(wo, rng.next(), rng.next2(), mode, Lobes::Transmission)
            else {
                continue;
            };
            if wos.f == 0.0 || wos.wi.z == 0.0 {
                continue;
            }
            let Some(wis) =
                top.sample(wi, rng.next(), rng.next2(), flip(mode), Lobes::Transmission)
            else {
                continue;
            };
            if wis.f == 0.0 || wis.wi.z == 0.0 {
                continue;
            }
            let mut beta = C::splat(wos.f * wos.wi.z.abs() / wos.pdf);
            let mut z = thick;
            let mut w = wos.wi;
            for depth in 0..self.max_depth {
                if depth > 3 && beta.max_lane() < 0.25 {
                    let q = (1.0 - beta.max_lane()).max(0.0);
                    if rng.next() < q {
                        break;
                    }
                    beta /= 1.0 - q;
                }
                if scatters {
                    let dz = -(1.0 - rng.next()).ln() * w.z.abs();
                    let zp = if w.z > 0.0 { z + dz } else { z - dz };
                    if zp == z {
                        continue;
                    }
                    if 0.0 < zp && zp < thick {
                        // A scattering event inside the slab: connect to the light path
                        // through the coating, then continue by sampling the phase function.
                        let mut wt = 1.0;
                        if !top.specular() {
                            wt = power(wis.pdf, phase.eval(-w, -wis.wi));
                        }
                        f += beta
                            * self.albedo
                            * (phase.eval(-w, -wis.wi) * wt * tr(zp - exit_z, wis.wi) * wis.f
                                / wis.pdf);
                        let (wn, ppdf) = phase.sample(-w, rng.next2());
                        if !is_positive(ppdf) || wn.z == 0.0 {
                            continue;
                        }
                        beta *= self.albedo;
                        w = wn;
                        z = zp;
                        if ((z < exit_z && w.z > 0.0) || (z > exit_z && w.z < 0.0))
                            && !top.specular()
                        {
                            let f_exit = top.f(-w, wi, mode);
                            if f_exit != 0.0 {
                                let wt = power(ppdf, top.pdf(wi, -w, Lobes::Transmission));
                                f += beta * (tr(zp - exit_z, wn) * f_exit * wt);
                            }
                        }
                        continue;
                    }
                    z = zp.clamp(0.0, thick);
                } else {
                    z = if z == thick { 0.0 } else { thick };
                    beta *= tr(thick, w);
                }
                if z == exit_z {
                    // Back at the coating from inside: only its reflection keeps the walk.
                    let Some(bs) = top.sample(-w, rng.next(), rng.next2(), mode, Lobes::Reflection)
                    else {
                        break;
                    };
                    if bs.f == 0.0 || bs.wi.z == 0.0 {
                        break;
                    }
                    beta *= bs.f * bs.wi.z.abs() / bs.pdf;
                    w = bs.wi;
                } else {
                    // At the base: next-event estimation to the light path, then a sample.
                    if !bottom.specular() {
                        let mut wt = 1.0;
                        if !top.specular() {
                            wt = power(wis.pdf, bottom.pdf(-w, -wis.wi));
                        }
                        f += beta
                            * bottom.f(-w, -wis.wi)
                            * (wis.wi.z.abs() * wt * tr(thick, wis.wi) * wis.f / wis.pdf);
                    }
                    let Some(bs) = bottom.sample(-w, rng.next2()) else {
                        break;
                    };
                    if bs.f.is_black() || bs.wi.z == 0.0 {
                        break;
                    }
                    beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
                    w = bs.wi;
                    if !top.specular() {
                        let f_exit = top.f(-w, wi, mode);
                        if f_exit != 0.0 {
                            let mut wt = 1.0;
                            if !bottom.specular() {
                                wt = power(bs.pdf, top.pdf(wi, -w, Lobes::Transmission));
                            }
                            f += beta * (tr(thick, bs.wi) * f_exit * wt);
                        }
                    }
                }
            }
        }
        f / n as f32
    }

    /// The density estimate of `sample`'s directions for `wo` above the surface (pbrt-v4's
    /// `PDF`: the coating's reflection, plus a stochastic estimate of the light that went
    /// through the slab, mixed with a uniform density so that it is never 0).
    fn pdf_above(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        if !same_side(wo, wi) {
            return 0.0;
        }
        let (top, bottom) = (&self.top, &self.bottom);
        let n = self.n_samples;
        let mut rng = Rng::new(hash_dir(wi), hash_dir(wo));
        let mut sum = n as f32 * top.pdf(wo, wi, Lobes::Reflection);
        for _ in 0..n {
            let wos = top.sample(wo, rng.next(), rng.next2(), mode, Lobes::Transmission);
            let wis = top.sample(wi, rng.next(), rng.next2(), flip(mode), Lobes::Transmission);
            let (Some(wos), Some(wis)) = (wos, wis) else {
                continue;
            };
            if !(wos.f > 0.0 && wis.f > 0.0) {
                continue;
            }
            if top.specular() {
                sum += bottom.pdf(-wos.wi, -wis.wi);
                continue;
            }
            let Some(rs) = bottom.sample(-wos.wi, rng.next2()) else {
                continue;
            };
            if rs.f.is_black() {
                continue;
            }
            if bottom.specular() {
                sum += top.pdf(-rs.wi, wi, Lobes::All);
            } else {
                let r_pdf = bottom.pdf(-wos.wi, -wis.wi);
                sum += power(wis.pdf, r_pdf) * r_pdf;
                let t_pdf = top.pdf(-rs.wi, wi, Lobes::All);
                sum += power(rs.pdf, t_pdf) * t_pdf;
            }
        }
        0.1 * INV_4PI + 0.9 * sum / n as f32
    }

    /// Whether every walk is specular: a smooth coating over a smooth conductor, nothing
    /// scattering between them.
    fn all_specular(&self) -> bool {
        self.top.specular() && self.bottom.specular() && self.albedo.is_black()
    }
}

/// `(wo, wi)` mirrored to the upper side when `wo` is below (both materials are two-sided).
fn above(wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) }
}

impl<C: Color> BsdfModel<C> for Layered<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        let (wo, wi) = above(wo, wi);
        if wo.z == 0.0 || self.all_specular() {
            return C::ZERO;
        }
        self.f(wo, wi, mode) * wi.z.abs()
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (wo, wi) = above(wo, wi);
        if wo.z == 0.0 || self.all_specular() {
            return 0.0;
        }
        self.pdf_above(wo, wi, TransportMode::Radiance)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        let below = wo.z < 0.0;
        let wo = if below { -wo } else { wo };
        if wo.z == 0.0 {
            return None;
        }
        let out = |w: Vec3| if below { -w } else { w };
        let (top, thick) = (&self.top, self.thickness);
        let bs = top.sample(wo, u1, u2, mode, Lobes::All)?;
        if bs.f == 0.0 || bs.wi.z == 0.0 {
            return None;
        }
        if same_side(wo, bs.wi) {
            // The coating's own reflection. Its weight is that lobe's f/pdf; MIS needs the
            // density of the whole BSDF.
            let weight = C::splat(bs.f * bs.wi.z.abs() / bs.pdf);
            let pdf = if bs.specular {
                bs.pdf
            } else {
                self.pdf_above(wo, bs.wi, mode)
            };
            return Some(BsdfSample {
                wi: out(bs.wi),
                weight,
                pdf,
                delta: bs.specular,
                transmission: false,
                eta: 1.0,
            });
        }
        let mut rng = Rng::new(
            hash_dir(wo),
            hash2(
                u64::from(u1.to_bits()),
                hash_dir(Vec3::new(u2.x, u2.y, 0.0)),
            ),
        );
        let phase = self.phase();
        let mut w = bs.wi;
        let mut specular_path = bs.specular;
        let mut f = C::splat(bs.f * bs.wi.z.abs());
        let mut pdf = bs.pdf;
        let mut z = thick;
        for depth in 0..self.max_depth {
            let rr = f.max_lane() / pdf;
            if depth > 3 && rr < 0.25 {
                let q = (1.0 - rr).max(0.0);
                if rng.next() < q {
                    return None;
                }
                pdf *= 1.0 - q;
            }
            if w.z == 0.0 {
                return None;
            }
            if !self.albedo.is_black() {
                let dz = -(1.0 - rng.next()).ln() * w.z.abs();
                let zp = if w.z > 0.0 { z + dz } else { z - dz };
                if zp == z {
                    return None;
                }
                if 0.0 < zp && zp < thick {
                    let (wn, ppdf) = phase.sample(-w, rng.next2());
                    if !is_positive(ppdf) || wn.z == 0.0 {
                        return None;
                    }
                    f *= self.albedo * ppdf;
                    pdf *= ppdf;
                    specular_path = false;
                    w = wn;
                    z = zp;
                    continue;
                }
                z = zp.clamp(0.0, thick);
            } else {
                z = if z == thick { 0.0 } else { thick };
                f *= tr(thick, w);
            }
            let s = if z == 0.0 {
                self.bottom.sample(-w, rng.next2())?
            } else {
                let s = top.sample(-w, rng.next(), rng.next2(), mode, Lobes::All)?;
                Scatter {
                    f: C::splat(s.f),
                    wi: s.wi,
                    pdf: s.pdf,
                    specular: s.specular,
                }
            };
            if s.f.is_black() || !is_positive(s.pdf) || s.wi.z == 0.0 {
                return None;
            }
            let crossed = !same_side(-w, s.wi);
            f *= s.f;
            pdf *= s.pdf;
            specular_path &= s.specular;
            w = s.wi;
            if crossed {
                // Out through the coating (the base is opaque, so this is the top).
                let weight = f * (w.z.abs() / pdf);
                if !weight.is_finite() {
                    return None;
                }
                let pdf = if specular_path {
                    pdf
                } else {
                    self.pdf_above(wo, w, mode)
                };
                return Some(BsdfSample {
                    wi: out(w),
                    weight,
                    pdf,
                    delta: specular_path,
                    transmission: false,
                    eta: 1.0,
                });
            }
            f *= w.z.abs();
        }
        None
    }

    fn has_delta(&self) -> bool {
        self.top.specular()
    }

    fn has_smooth(&self) -> bool {
        !self.all_specular()
    }

    /// The base's colour (what a denoiser's albedo should follow).
    fn albedo(&self) -> C {
        match self.bottom {
            Base::Diffuse(r) => r,
            Base::Conductor { eta, k, .. } => fresnel_conductor(1.0, eta, k),
        }
    }
}
