//! Instances: a prototype mesh seen through a placement, or a moving shape.

use glam::Mat3A;

use super::{Reads, ShapeGeom, SurfaceInteraction, gamma, interaction, mesh};
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::math::{Mat3, Mat4, Vec3, rsqrt};

/// A shape seen through a placement (an instance of a prototype mesh) and moving by a
/// translation over the shutter: at time τ its world geometry is `to_world(x) + τ·motion`.
///
/// Hits are found in the prototype's space (`accel`'s two-level part); the interaction is
/// computed from the hit triangle's vertices mapped to world space with the same arithmetic
/// the flattened copy of the mesh uses, so shading is the same as for a copy (up to the
/// rounding of the barycentrics, which the object-space test finds). The error bound adds the
/// rounding of mapping the spawned ray back into the prototype's space.
#[derive(Clone, Debug)]
pub struct Instance {
    /// A prototype mesh in its object space (its arrays shared by every instance of it), or
    /// for a moving shape that is not instanced, the shape itself at time 0 (`to_world` the
    /// identity).
    pub base: ShapeGeom,
    /// Index of the accelerator's bottom-level tree for `base`.
    pub proto: u32,
    pub to_world: Mat4,
    /// Inverse transpose of `to_world`'s linear part (object normal → world normal).
    pub normal_matrix: Mat3,
    /// `to_world` mirrors: the winding is reversed, as `build`'s flattened meshes do.
    pub mirror: bool,
    /// World translation over the shutter interval [0, 1].
    pub motion: Vec3,
    /// |linear part| of `to_world` and of its inverse, and |translation of the inverse|, for
    /// the error bound.
    abs_m: Mat3A,
    abs_inv: Mat3A,
    abs_inv_t: Vec3,
}

impl Instance {
    /// `None` for a singular or non-finite placement.
    pub fn new(base: ShapeGeom, proto: u32, to_world: Mat4, motion: Vec3) -> Option<Instance> {
        let inv = to_world.inverse();
        let det = Mat3::from_mat4(to_world).determinant();
        if det == 0.0 || !det.is_finite() || !inv.is_finite() || !to_world.is_finite() {
            return None;
        }
        let abs = |m: Mat3A| Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        Some(Instance {
            base,
            proto,
            to_world,
            normal_matrix: Mat3::from_mat4(to_world).inverse().transpose(),
            mirror: det < 0.0,
            motion: if motion.is_finite() {
                motion
            } else {
                Vec3::ZERO
            },
            abs_m: abs(Mat3A::from_mat4(to_world)),
            abs_inv: abs(Mat3A::from_mat4(inv)),
            abs_inv_t: Vec3::from_vec4(inv.w_axis).abs(),
        })
    }

    /// Added to a world point's error bound: the rounding of the shift by `τ·motion` and of
    /// the map into the prototype's space that the next query applies (generously, γ₈).
    #[inline]
    fn extra_error(&self, p: Vec3, shift: Vec3) -> Vec3 {
        let a = p.abs() + shift.abs();
        gamma(8) * (self.abs_m * (self.abs_inv * a + self.abs_inv_t) + a)
    }
}

impl Instance {
    /// [`interaction`] on an instance: out of line, so that ordinary shapes' code is as
    /// before.
    #[inline(never)]
    pub(super) fn interaction(
        &self,
        hit: &Hit,
        ray: &Ray,
        flip: bool,
        reads: Reads,
    ) -> SurfaceInteraction {
        let shift = self.motion * ray.time;
        let mut si = match &self.base {
            ShapeGeom::Mesh {
                positions,
                normals,
                uvs,
                indices,
            } => {
                // The world triangle as the flattened copy stores it (with its winding reversed
                // under a mirroring placement, the barycentrics following).
                let [a, b, c] = indices[hit.prim as usize].map(|i| i as usize);
                let (idx, h) = if self.mirror {
                    (
                        [a, c, b],
                        Hit {
                            u: hit.v,
                            v: hit.u,
                            ..*hit
                        },
                    )
                } else {
                    ([a, b, c], *hit)
                };
                let p = idx.map(|i| self.to_world.transform_point3a(positions[i]) + shift);
                let wo = -ray.d * rsqrt(ray.d.length_squared());
                mesh::interaction(
                    p,
                    idx,
                    normals.as_deref(),
                    |n| (self.normal_matrix * n).normalize_or_zero(),
                    uvs.as_deref(),
                    &h,
                    wo,
                    ray.time,
                    flip,
                    reads,
                )
            }
            // A moving shape that is not a mesh instance (`to_world` is the identity): hit at its
            // time-0 place by the ray shifted back.
            base => {
                let local = Ray::at_time(ray.o - shift, ray.d, ray.time);
                let mut si = interaction(base, hit, &local, flip, reads);
                si.p += shift;
                si
            }
        };
        si.p_error += self.extra_error(si.p, shift);
        si
    }
}
