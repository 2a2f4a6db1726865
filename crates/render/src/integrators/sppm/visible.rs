//! Visible points: where a camera path stops being a chain of delta bounces — a surface with
//! a non-delta lobe, or a collision in a medium — and what photons arriving near one add to
//! its measurement.

use super::SppmConfig;
use super::grid::Grid;
use crate::bsdf::{Bsdf, TransportMode};
use crate::integrators::photons::{self, CameraWalk, PhotonHit, Segment, Vertex, Visit};
use crate::integrators::transport::Scatterer;
use crate::math::{Frame, UVec2, Vec3};
use crate::media::Phase;
use crate::sampling::Sampler;
use crate::session::camera_sample;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// What scatters at a visible point, owned.
pub(super) enum Scattering<C: Color> {
    /// A BSDF in its shading frame, `wo` towards the camera in that frame.
    Surface {
        bsdf: Bsdf<C>,
        frame: Frame,
        wo: Vec3,
    },
    /// A phase function of medium `medium`, `wo` towards the camera.
    Medium { phase: Phase, wo: Vec3, medium: u32 },
}

/// A camera path's first vertex with a non-delta lobe, or its first collision in a medium.
pub(super) struct VisiblePoint<C: Color> {
    /// The measurement it adds to: the pixel (row-major within the crop window) in SPPM,
    /// the pixel's eye sample in PPM.
    pub(super) slot: u32,
    /// Edges from the camera to this point.
    pub(super) depth: u32,
    pub(super) p: Vec3,
    pub(super) at: Scattering<C>,
    /// The camera path's weight: times the photons' density around the point it is the
    /// radiance the point stands for (at a collision the throughput divided by σs, which the
    /// photons' density holds).
    pub(super) beta: C,
    /// Whether the camera path's secondary wavelengths were terminated (spectral mode).
    pub(super) terminated: bool,
}

impl<C: Color> VisiblePoint<C> {
    /// Whether it lies in a medium (its photons are the collisions there, its kernel a
    /// sphere).
    pub(super) fn in_medium(&self) -> bool {
        matches!(self.at, Scattering::Medium { .. })
    }
}

/// One camera sample of SPPM's camera pass (or PPM's): its identity, and whether it makes
/// next-event estimates.
pub(super) struct CameraSample {
    pub(super) pixel: UVec2,
    pub(super) sample: u32,
    pub(super) slot: u32,
    pub(super) nee: bool,
}

/// What the camera pass needs besides a sample: the scene, the configuration, and where the
/// point and spot lights are (segment estimates in media, `photons::segment_point`).
pub(super) struct CameraPass<'a> {
    pub(super) scene: &'a Scene,
    pub(super) cfg: &'a SppmConfig,
    pub(super) points: &'a [Vec3],
}

impl CameraPass<'_> {
    /// One camera sample: the estimate `ld` (emission seen along delta bounces and the
    /// next-event estimates at the visible points, linear sRGB) and its visible points.
    pub(super) fn camera_path<M: PathMode>(
        &self,
        sampler: &mut Sampler,
        c: &CameraSample,
        m: &M,
        vps: &mut Vec<VisiblePoint<M::C>>,
    ) -> Vec3 {
        let scene = self.scene;
        let (_, cray) = camera_sample(scene, sampler, c.pixel, c.sample);
        let w = CameraWalk::camera_walker(scene, &cray, m, sampler);
        let walk = CameraWalk {
            depth: 0,
            see_emitters: true,
            see_media: true,
            max_depth: self.cfg.max_depth,
            rr_depth: self.cfg.rr_depth,
        };
        let mut visit = Visits {
            pass: self,
            c,
            m,
            vps,
        };
        let ld = walk.run(scene, w, M::C::ONE, m, sampler, &mut visit);
        m.to_rgb(ld)
    }
}

/// A camera path's visits: visible points where it stops being a delta chain and at segment
/// estimates in media, and the next-event estimates there.
struct Visits<'p, 'a, M: PathMode> {
    pass: &'p CameraPass<'a>,
    c: &'p CameraSample,
    m: &'p M,
    vps: &'p mut Vec<VisiblePoint<M::C>>,
}

impl<M: PathMode> Visits<'_, '_, M> {
    /// The shortest photon path that can reach a visible point: 2 edges when next-event
    /// estimation has the direct light, else 1.
    fn first(&self) -> u32 {
        if self.c.nee { 2 } else { 1 }
    }

    /// A visible point at `v` (its camera throughput `beta` such that times the photons'
    /// density it is radiance) and the next-event estimate there, not yet times `v.beta`.
    fn visit(&mut self, v: &Vertex<M::C>, beta: M::C, sampler: &mut Sampler) -> M::C {
        let (scene, cfg) = (self.pass.scene, self.pass.cfg);
        if cfg.allows(v.depth + self.first())
            && let Some(vp) = visible_point(v, beta, self.c.slot, self.m)
        {
            self.vps.push(vp);
        }
        if self.c.nee && cfg.allows(v.depth + 1) {
            photons::next_event(scene, v, sampler, self.m)
        } else {
            M::C::ZERO
        }
    }
}

impl<M: PathMode> Visit<M> for Visits<'_, '_, M> {
    fn vertex(&mut self, v: &Vertex<M::C>, sampler: &mut Sampler) -> M::C {
        // In a medium the photons' density holds σs (their power after a collision is σs/σt
        // of it), which the collision's throughput holds too: divided out once.
        let beta = match (v.at, v.medium) {
            (Scatterer::Medium { .. }, Some(i)) => {
                let sigma_s = self.pass.scene.media[i as usize].sigma_s_in(v.p, self.m);
                v.beta
                    * M::C::from_fn(|k| {
                        let s = sigma_s.lane(k);
                        if s > 0.0 { 1.0 / s } else { 0.0 }
                    })
            }
            _ => v.beta,
        };
        self.visit(v, beta, sampler)
    }

    fn segment(&mut self, seg: &Segment<M::C>, sampler: &mut Sampler) -> Option<(M::C, M::C)> {
        let room = self.pass.cfg.allows(seg.depth + 1);
        let sp = photons::segment_point(self.pass.points, seg, room, sampler, self.m)?;
        let l = match &sp.x {
            Some(x) => x.beta * sp.sigma_s * self.visit(x, x.beta, sampler),
            None => M::C::ZERO,
        };
        Some((sp.tr, l))
    }
}

/// The visible point a camera walk's vertex `v` makes for measurement `slot`, its camera
/// throughput `beta`.
fn visible_point<M: PathMode>(
    v: &Vertex<M::C>,
    beta: M::C,
    slot: u32,
    m: &M,
) -> Option<VisiblePoint<M::C>> {
    let at = match v.at {
        Scatterer::Surface { bsdf, frame, wo } => Scattering::Surface {
            bsdf: bsdf.clone(),
            frame: *frame,
            wo,
        },
        Scatterer::Medium { phase, wo } => Scattering::Medium {
            phase: phase.clone(),
            wo,
            medium: v.medium?,
        },
    };
    Some(VisiblePoint {
        slot,
        depth: v.depth,
        p: v.p,
        at,
        beta,
        terminated: m.terminated(),
    })
}

/// The visible points of one photon pass, their grid and radii, and how photons count.
pub(super) struct Gatherers<'a, C: Color> {
    pub(super) cfg: &'a SppmConfig,
    pub(super) grid: &'a Grid,
    pub(super) vps: &'a [VisiblePoint<C>],
    /// The surface and volume radius of every slot.
    pub(super) radii: &'a [[f32; 2]],
    /// The edge of a photon path from which it deposits (photons from emitting media
    /// deposit from their first: next-event estimation does not reach their direct light).
    pub(super) first: u32,
}

impl<C: Color> Gatherers<'_, C> {
    /// Add photon `hit` (carried in mode `photon`) to every visible point of its kind (a
    /// surface hit to surface points, a collision to points in the same medium) within its
    /// slot's radius whose camera path leaves room for it: (visible point, β_vp·f·β_photon
    /// as linear sRGB, f the BSDF without its cosine or the phase function). Both paths
    /// carry the iteration's wavelengths; `modes` converts with all of them or, when either
    /// path has terminated its secondary wavelengths, the hero's alone.
    pub(super) fn gather<M: PathMode<C = C>>(
        &self,
        hit: &PhotonHit<C>,
        photon: &M,
        modes: &(M, M),
        out: &mut Vec<(u32, Vec3)>,
    ) {
        if hit.v.depth < self.first && !hit.from_volume {
            return;
        }
        let p = hit.v.p;
        for &v in self.grid.near(p) {
            let vp = &self.vps[v as usize];
            let kind = vp.in_medium() as usize;
            let r = self.radii[vp.slot as usize][kind];
            if (vp.p - p).length_squared() > r * r || !self.cfg.allows(vp.depth + hit.v.depth) {
                continue;
            }
            let f = match (&vp.at, hit.v.si) {
                (Scattering::Surface { bsdf, frame, wo }, Some(_)) => {
                    let wl = frame.to_local(hit.wi);
                    if wl.z == 0.0 {
                        continue;
                    }
                    // eval is f·|cos θi|; the photon's flux already holds the cosine.
                    bsdf.eval(*wo, wl, TransportMode::Radiance) / wl.z.abs()
                }
                (Scattering::Medium { phase, wo, medium }, None)
                    if hit.v.medium == Some(*medium) =>
                {
                    C::splat(phase.eval(*wo, hit.wi))
                }
                _ => continue,
            };
            if f.is_black() {
                continue;
            }
            let mode = if vp.terminated || photon.terminated() {
                &modes.1
            } else {
                &modes.0
            };
            out.push((v, mode.to_rgb(vp.beta * f * hit.v.beta)));
        }
    }
}
