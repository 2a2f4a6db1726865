//! The walk: a ray followed through the scene to its next event — a collision in the medium
//! it travels through, a surface, an index-matched (`null`) surface, or its escape — with
//! the medium it is in kept up to date across every surface that bounds media.
//!
//! [`Walker::next`] is the whole step; integrators that do something of their own between
//! finding the surface ahead and sampling the free flight to it (`volpath`'s equiangular
//! sampling towards point lights, the photon mapper's segment estimate in homogeneous
//! media) take it in its three parts: [`Walker::ahead`], [`Walker::fly`], [`Walker::event`].
//! Free flights are sampled in the lane `hero` of the path's colour, and their weights and
//! channel density ratios come back with the event for the caller's throughput (spectral
//! MIS over the hero, see `media::Flight`). A `null` surface is reported
//! ([`Event::Null`]) and crossed by [`Walker::cross`]; what it counts as (nothing for
//! `volpath` and the light-path integrators) is the caller's.

use crate::camera::CameraRay;
use crate::geometry::Ray;
use crate::math::Vec3;
use crate::media::{Flight, Medium};
use crate::sampling::Samples;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, ColorMode};
use crate::world::{Closest, Scene};

/// A ray on its way through the scene, and the medium it travels in.
#[derive(Clone, Copy, Debug)]
pub struct Walker {
    pub ray: Ray,
    /// The ray's parameter range (0, t_max).
    pub t_max: f32,
    pub medium: Option<u32>,
    /// The lane whose density samples free flights.
    pub hero: usize,
}

/// The segment ahead of a walker: the closest surface along its ray (its interaction not yet
/// computed) and its distance (`t_max` when there is none).
pub struct Ahead {
    closest: Closest,
    pub end: f32,
}

/// A segment crossed without a collision: the free flight's throughput weight and channel
/// density ratios (1 outside media), and its length.
#[derive(Clone, Copy, Debug)]
pub struct Pass<C> {
    pub weight: C,
    pub ratio: C,
    pub d: f32,
}

/// What a walker's ray meets next.
pub enum Event<C> {
    /// A real collision in the walker's medium at `p`, distance `d` along the ray: the free
    /// flight's throughput weight (σs over its density), channel density ratios and
    /// emission weight (σa over its density), see `media::Flight`.
    Collision {
        p: Vec3,
        d: f32,
        weight: C,
        ratio: C,
        emit: C,
    },
    /// A surface that scatters or absorbs.
    Surface(SurfaceInteraction, Pass<C>),
    /// An index-matched boundary ([`Walker::cross`] goes on through it).
    Null(SurfaceInteraction, Pass<C>),
    /// The ray left the scene.
    Escape(Pass<C>),
}

impl Walker {
    /// A walker along `ray` (taken as it is) within `(0, t_max)`, in `medium`.
    #[inline]
    pub fn new(ray: Ray, t_max: f32, medium: Option<u32>, hero: usize) -> Walker {
        Walker {
            ray,
            t_max,
            medium,
            hero,
        }
    }

    /// A walker along a camera ray, its direction made a unit vector (free flights measure
    /// distances), in the camera's medium.
    #[inline]
    pub fn camera(scene: &Scene, cray: &CameraRay, hero: usize) -> Walker {
        let len = cray.ray.d.length();
        let ray = Ray::at_time(cray.ray.o, cray.ray.d / len, cray.ray.time);
        Walker::new(ray, cray.t_max * len, scene.camera_medium, hero)
    }

    /// The medium the walker is in.
    #[inline]
    pub fn medium<'s>(&self, scene: &'s Scene) -> Option<&'s Medium> {
        self.medium.map(|m| &scene.media[m as usize])
    }

    /// The segment ahead: the closest surface, its interaction left for [`Walker::reach`].
    #[inline(always)]
    pub fn ahead(&self, scene: &Scene) -> Ahead {
        let closest = scene.closest(&self.ray, self.t_max);
        let end = closest.t(&self.ray, self.t_max);
        Ahead { closest, end }
    }

    /// A free flight through the walker's medium over the segment ahead (no collision, weight
    /// 1, outside media).
    #[inline(always)]
    pub fn fly<M: ColorMode>(
        &self,
        scene: &Scene,
        ahead: &Ahead,
        sampler: &mut impl Samples,
        mode: &M,
    ) -> Flight<M::C> {
        match self.medium(scene) {
            Some(m) => m.sample_in(&self.ray, ahead.end, self.hero, sampler, mode),
            None => Flight::THROUGH,
        }
    }

    /// The surface at the end of the segment ahead (`None`: the ray leaves the scene), its
    /// interaction computed where the caller keeps it.
    #[inline(always)]
    pub fn surface(&self, scene: &Scene, ahead: Ahead) -> Option<SurfaceInteraction> {
        ahead.closest.surface(scene, &self.ray, self.t_max)
    }

    /// The end of the segment ahead, reached with the free flight's `pass`: a surface, a
    /// `null` one, or nothing.
    #[inline(always)]
    pub fn reach<C>(&self, scene: &Scene, ahead: Ahead, pass: Pass<C>) -> Event<C> {
        match ahead.closest.surface(scene, &self.ray, self.t_max) {
            None => Event::Escape(pass),
            Some(si) if scene.is_null(&si) => Event::Null(si, pass),
            Some(si) => Event::Surface(si, pass),
        }
    }

    /// The event a free flight over the segment ahead makes: its collision, or the end of
    /// the segment reached with its pass weight.
    #[inline(always)]
    pub fn event<C>(&self, scene: &Scene, ahead: Ahead, flight: Flight<C>) -> Event<C> {
        match flight {
            Flight::Scatter {
                d,
                weight,
                ratio,
                emit,
            } => Event::Collision {
                p: self.ray.at(d),
                d,
                weight,
                ratio,
                emit,
            },
            Flight::Pass { weight, ratio } => {
                let d = ahead.end;
                self.reach(scene, ahead, Pass { weight, ratio, d })
            }
        }
    }

    /// The next event along the ray ([`Walker::ahead`], [`Walker::fly`], [`Walker::event`]).
    #[inline(always)]
    pub fn next<M: ColorMode>(
        &self,
        scene: &Scene,
        sampler: &mut impl Samples,
        mode: &M,
    ) -> Event<M::C> {
        let ahead = self.ahead(scene);
        let flight = self.fly(scene, &ahead, sampler, mode);
        self.event(scene, ahead, flight)
    }

    /// On through the `null` surface at `si`, into the medium beyond it.
    #[inline]
    pub fn cross(&mut self, scene: &Scene, si: &SurfaceInteraction) {
        self.leave(scene, si, self.ray.d);
    }

    /// Away from the surface at `si` along the world direction `wi`, into the medium on
    /// `wi`'s side of it.
    #[inline]
    pub fn leave(&mut self, scene: &Scene, si: &SurfaceInteraction, wi: Vec3) {
        self.medium = scene.medium_after(si, wi, self.medium);
        self.ray = si.spawn_ray(wi);
        self.t_max = f32::INFINITY;
    }

    /// Away from the collision at `p` along the unit direction `wi`, in the same medium.
    #[inline]
    pub fn scatter(&mut self, p: Vec3, wi: Vec3) {
        self.ray = Ray::at_time(p, wi, self.ray.time);
        self.t_max = f32::INFINITY;
    }
}

impl<C: Color> Pass<C> {
    /// Multiply the pass's weight and ratios into a path's throughput and ratios.
    #[inline(always)]
    pub fn apply(&self, beta: &mut C, ratio: &mut C) {
        *beta *= self.weight;
        *ratio *= self.ratio;
    }
}
