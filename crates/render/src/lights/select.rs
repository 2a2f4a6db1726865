//! Choosing one light for next-event estimation: uniformly (Mitsuba), in proportion to
//! emitted power (an alias table, pbrt-v4's `PowerLightSampler`) or with the light BVH
//! ([`super::bvh`]), and the power and bounds of each light these need.
//!
//! Power follows pbrt-v4's `Phi` with the channel mean of RGB: π·A·L̄ for area lights (twice
//! for two-sided ones), 4π·I for point lights, 2π·I·((1 − cos θbeam) + (cos θbeam −
//! cos θcutoff)/2) for spots, and for infinite lights the power through a disk of the scene's
//! bounding radius r: π r²·E (directional), 4π·π r²·L̄ (constant and environment maps, L̄ the
//! solid-angle mean). Textured emitters use the mean of an 8×8 grid of texture lookups.
//! That disk is also where infinite lights' photons start ([`disk_before_scene`]).

use base::LightSelection;

use super::{EmissionSample, LightScene};
use crate::geometry::Ray;
use crate::math::{Frame, PI, Vec2, Vec3};
use crate::sampling::distrib::AliasTable;
use crate::sampling::warp;
use crate::textures::{ColorRef, TexCoord, TexRef};

use super::bvh::{LightBounds, LightBvh};
use super::{Light, Receiver};

/// The light selection strategy of a scene, built once.
#[derive(Clone, Debug)]
pub enum LightSampler {
    Uniform,
    Power(AliasTable),
    Bvh(LightBvh),
}

#[inline]
pub(super) fn mean(c: Vec3) -> f32 {
    ((c.x + c.y + c.z) / 3.0).max(0.0)
}

/// Mean radiance of an emitter's colour over its texture space.
pub(super) fn mean_radiance(scene: &impl LightScene, c: &ColorRef) -> f32 {
    match c {
        TexRef::Const(c) => mean(*c),
        TexRef::Texture(_) => {
            const N: usize = 8;
            let mut sum = 0.0;
            for i in 0..N * N {
                let uv = Vec2::new(
                    ((i % N) as f32 + 0.5) / N as f32,
                    ((i / N) as f32 + 0.5) / N as f32,
                );
                sum += mean(scene.color(c, TexCoord::uv(uv)));
            }
            sum / (N * N) as f32
        }
    }
}

/// Radius of the bounding sphere of the scene's bounded geometry (1 if it has none).
pub(super) fn scene_radius(scene: &impl LightScene) -> f32 {
    let (lo, hi) = scene.bounds();
    let r = 0.5 * (hi - lo).length();
    if r.is_finite() && r > 0.0 { r } else { 1.0 }
}

/// Where a ray of an infinite light travelling along the unit direction `d` starts (photon
/// emission, pbrt-v4's `SampleLe`): a point uniform on the disk of the scene's bounding
/// sphere ([`scene_radius`] r, about the bounds' centre) perpendicular to `d`, placed r before
/// the centre, so that every ray along `d` through the scene starts on it. The origin and its
/// density per unit area, 1/(π r²).
pub(super) fn disk_before_scene(scene: &impl LightScene, d: Vec3, u: Vec2) -> (Vec3, f32) {
    let r = scene_radius(scene);
    let (lo, hi) = scene.bounds();
    let c = 0.5 * (lo + hi);
    let c = if c.is_finite() { c } else { Vec3::ZERO };
    let p = warp::square_to_uniform_disk_concentric(u);
    let f = Frame::from_normal(d);
    (
        c + r * (f.to_world(Vec3::new(p.x, p.y, -1.0))),
        disk_pdf(scene),
    )
}

/// The emitted ray of an infinite light travelling along the unit direction `d`, carrying
/// `radiance` (from the direction −d) drawn with solid-angle density `pdf_dir` (1 for a
/// directional light's delta): its origin from [`disk_before_scene`] and its weight
/// L/(pdf_pos·pdf_dir). `None` where `pdf_dir` is not a positive finite density.
pub(super) fn infinite_emission<C: Copy + std::ops::Div<f32, Output = C>>(
    scene: &impl LightScene,
    d: Vec3,
    radiance: C,
    pdf_dir: f32,
    u_pos: Vec2,
) -> Option<EmissionSample<C>> {
    if !(pdf_dir > 0.0 && pdf_dir.is_finite()) {
        return None;
    }
    let (o, pdf_pos) = disk_before_scene(scene, d, u_pos);
    Some(EmissionSample {
        ray: Ray::new(o, d),
        p: o,
        weight: radiance / (pdf_pos * pdf_dir),
        pdf_pos,
        pdf_dir,
        n: Vec3::ZERO,
    })
}

/// An infinite light's `pdf_le` for a direction it samples with density `pdf_dir`:
/// (1/(π r²), `pdf_dir`), or (0, 0) where `pdf_dir` is not a positive finite density.
pub(super) fn infinite_pdf_le(scene: &impl LightScene, pdf_dir: f32) -> (f32, f32) {
    if !(pdf_dir > 0.0 && pdf_dir.is_finite()) {
        return (0.0, 0.0);
    }
    (disk_pdf(scene), pdf_dir)
}

/// The density per unit area of the origins [`disk_before_scene`] draws, 1/(π r²): an
/// infinite light's `pdf_pos`, of whatever direction.
pub(super) fn disk_pdf(scene: &impl LightScene) -> f32 {
    let r = scene_radius(scene);
    1.0 / (PI * r * r)
}

/// A light bounds box with no preferred direction (emission to every side) of power `phi`.
pub(super) fn omni(lo: Vec3, hi: Vec3, phi: f32) -> LightBounds {
    LightBounds {
        lo,
        hi,
        w: Vec3::Z,
        phi,
        cos_o: -1.0,
        cos_e: 0.0,
        two_sided: false,
    }
}

/// One of `n > 0` lights, uniformly. In u32: conversions between f32 and 64-bit unsigned
/// integers take several instructions on x86-64, 32-bit ones one or two.
#[inline(always)]
fn uniform_choice(u: f32, n: usize) -> Option<(u32, f32)> {
    let n = n as u32;
    let i = ((u * n as f32) as u32).min(n - 1);
    Some((i, 1.0 / n as f32))
}

impl LightSampler {
    /// Builds the strategy `kind` over `lights` (`infinite`: the indices of the infinite ones)
    /// of `scene`.
    pub fn new(
        kind: LightSelection,
        lights: &[Light],
        infinite: &[u32],
        scene: &impl LightScene,
    ) -> LightSampler {
        match kind {
            LightSelection::Uniform => LightSampler::Uniform,
            LightSelection::Power => {
                let w: Vec<f32> = lights.iter().map(|l| l.power(scene)).collect();
                LightSampler::Power(AliasTable::new(&w))
            }
            LightSelection::Bvh => {
                let bounds: Vec<Option<LightBounds>> = lights
                    .iter()
                    .map(|l| {
                        if l.is_infinite() {
                            None
                        } else {
                            l.bounds(scene)
                        }
                    })
                    .collect();
                LightSampler::Bvh(LightBvh::new(&bounds, infinite))
            }
        }
    }

    /// A light index for `r` among `n` lights and its probability.
    #[inline]
    pub fn sample(&self, u: f32, r: &Receiver, n: usize) -> Option<(u32, f32)> {
        if n == 0 {
            return None;
        }
        match self {
            LightSampler::Uniform => uniform_choice(u, n),
            _ => self.sample_other(u, r, n),
        }
    }

    /// [`Self::sample`] by power or with the light BVH: out of line (one call site keeps the
    /// uniform choice inlined into the path loop at a few instructions).
    #[inline(never)]
    fn sample_other(&self, u: f32, r: &Receiver, n: usize) -> Option<(u32, f32)> {
        match self {
            LightSampler::Uniform => uniform_choice(u, n),
            LightSampler::Power(table) => {
                let (i, pmf) = table.sample(u);
                (pmf > 0.0).then_some((i as u32, pmf))
            }
            LightSampler::Bvh(bvh) => bvh.sample(u, r),
        }
    }

    /// Probability that [`Self::sample`] returns `light`.
    #[inline]
    pub fn pmf(&self, r: &Receiver, light: u32, n: usize) -> f32 {
        match self {
            LightSampler::Uniform => 1.0 / n.max(1) as u32 as f32,
            LightSampler::Power(table) => table.pmf(light as usize),
            LightSampler::Bvh(bvh) => bvh.pmf(r, light),
        }
    }
}
