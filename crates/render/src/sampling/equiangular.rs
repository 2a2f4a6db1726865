//! Equiangular sampling of a distance along a ray towards a point (Kulla & Fajardo 2012): on
//! the segment `o + t·d`, t ∈ [0, end), the density of t is proportional to
//! 1/(h² + (t − Δ)²), where h is the point's distance from the line and Δ the parameter of
//! the foot of the perpendicular. Seen from the point, t is uniform in angle, which cancels
//! the 1/r² of a point light: the volumetric path tracer's strategy for point and spot lights
//! in media.

use crate::math::Vec3;

/// The equiangular distribution of one segment towards one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equiangular {
    delta: f32,
    h: f32,
    /// The angles of the segment's ends seen from the point, a < b.
    a: f32,
    b: f32,
    end: f32,
}

impl Equiangular {
    /// The distribution on `o + t·d` (`d` a unit vector), t ∈ [0, `end`) (`end` may be
    /// infinite), towards `q`; `None` when `q` lies (nearly) on the line or the range is
    /// empty.
    pub fn new(o: Vec3, d: Vec3, end: f32, q: Vec3) -> Option<Equiangular> {
        let delta = (q - o).dot(d);
        let h = (q - o - d * delta).length();
        if h.is_nan() || h <= 1e-6 * (1.0 + delta.abs()) {
            return None;
        }
        let a = (-delta).atan2(h);
        let b = if end.is_finite() {
            (end - delta).atan2(h)
        } else {
            std::f32::consts::FRAC_PI_2
        };
        (b > a).then_some(Equiangular {
            delta,
            h,
            a,
            b,
            end,
        })
    }

    /// The distance for the uniform number `u` ∈ [0, 1) (rounding may put it just outside
    /// [0, end): callers check).
    #[inline]
    pub fn sample(&self, u: f32) -> f32 {
        self.delta + self.h * (self.a + u * (self.b - self.a)).tan()
    }

    /// The density of distance `t` (0 outside [0, end)).
    #[inline]
    pub fn pdf(&self, t: f32) -> f32 {
        if !(0.0..self.end).contains(&t) {
            return 0.0;
        }
        let x = t - self.delta;
        self.h / ((self.b - self.a) * (self.h * self.h + x * x))
    }
}
