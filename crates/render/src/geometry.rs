//! Rays.

use crate::math::Vec3;

/// A ray `o + t d`. `d` need not be normalised for intersection, but every ray the renderer
/// spawns has a unit direction, so `t` is a distance.
///
/// `time` is the instant in the shutter interval [0, 1] the ray belongs to (motion blur):
/// the camera draws it once per sample, but only in scenes with moving shapes (0 otherwise),
/// and every ray spawned from a hit keeps it. Only moving shapes read it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    pub time: f32,
}

impl Ray {
    /// A ray at time 0.
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Ray {
        Ray { o, d, time: 0.0 }
    }
    /// A ray at `time`.
    #[inline]
    pub fn at_time(o: Vec3, d: Vec3, time: f32) -> Ray {
        Ray { o, d, time }
    }
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}
