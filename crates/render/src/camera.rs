//! Cameras, following Mitsuba 3's conventions exactly.
//!
//! Camera space looks along +z with +y up and +x to the **left** of the image (what Mitsuba's
//! `lookat` produces). Film coordinates are continuous pixel positions: pixel (i, j) covers
//! [i, i+1) × [j, j+1), its centre is (i + 0.5, j + 0.5), rows go down. A film position maps to
//! the normalised screen position s = p / resolution ∈ [0,1]², and
//! `x_cam = -(2 s_x - 1) · tan(fov_x / 2)`, `y_cam = -(2 s_y - 1) · tan(fov_x / 2) / aspect`
//! on the plane z = 1 (Mitsuba's `sample_to_camera`). The ray starts on the near-clip plane and
//! ends on the far-clip plane, as in Mitsuba.
//!
//! - `Perspective`: pinhole.
//! - `ThinLens`: aperture disk of radius `aperture_radius` (concentric mapping), focal plane at
//!   `focus_distance` along +z.
//! - `Orthographic`: the image covers [-1,1] × [-1/aspect, 1/aspect] of the camera plane (scale
//!   it with `to_world`), rays along +z.
//! - `IrradianceMeter`: Mitsuba 3's `irradiancemeter`, attached to a shape
//!   ([`Camera::with_irradiance_meter`]): a ray leaves a point uniform over the shape's area
//!   (from the film sample) in a cosine-distributed direction about its normal (from the lens
//!   sample), and each sample counts π times ([`Camera::sample_weight`]), so that the 1×1
//!   film measures the irradiance averaged over the shape.
//! - `Window`: a pinhole whose image is a given window [l, r] × [b, t] of the z = 1 plane
//!   (right and up in image terms, so x_cam = −(l + s_x (r − l)), y_cam = t − s_y (t − b)).

use base::{FovAxis, Projection};

use crate::geometry::Ray;
use crate::lights::AreaLight;
use crate::math::{Frame, Mat4, PI, Vec2, Vec3};
use crate::sampling::warp::{square_to_cosine_hemisphere, square_to_uniform_disk_concentric};
use crate::shapes::{ShapeGeom, offset_ray_origin};
use crate::textures::TexRef;

#[derive(Clone, Debug)]
pub struct Camera {
    kind: Kind,
    to_world: Mat4,
    /// The inverse of `to_world` (for [`Camera::film_uv`]).
    to_camera: Mat4,
    /// Full film resolution (the crop window does not change the projection).
    resolution: Vec2,
    /// tan(fov_x / 2) and tan(fov_x / 2) / aspect: the half extents of the z = 1 image plane.
    half_extent: Vec2,
    /// The z = 1 plane point of film position (0, 0) (the image's top left corner), as a
    /// negated offset: x_cam = −(2 s_x − 1)·half_extent.x + centre.x, likewise y. Zero for a
    /// centred image; the window of `Window` cameras.
    centre: Vec2,
    near_clip: f32,
    far_clip: f32,
}

#[derive(Clone, Debug)]
enum Kind {
    Perspective,
    ThinLens {
        aperture_radius: f32,
        focus_distance: f32,
    },
    Orthographic,
    /// One ray: the origin along +z (Mitsuba's `radiancemeter`).
    RadianceMeter,
    /// Rays leaving a shape's surface (Mitsuba's `irradiancemeter`).
    IrradianceMeter(Box<MeterShape>),
}

/// The shape an irradiance meter sits on: its world-space geometry and the uniform-by-area
/// point placement of area lights (`AreaLight::sample_position_on`, which is one copy of
/// "a uniform point on a shape" for emitters and this sensor alike).
#[derive(Clone, Debug)]
pub struct MeterShape {
    geom: ShapeGeom,
    flip: f32,
    sampler: AreaLight,
}

impl MeterShape {
    /// The meter on `geom` (world space; a mesh, sphere, disk, cylinder or ellipsoid, not an
    /// instance nor a plane), normals flipped when `flip_normals`. `None` for a shape that
    /// cannot be sampled by area (an infinite plane, an instance, a degenerate mesh).
    pub fn new(geom: ShapeGeom, flip_normals: bool) -> Option<MeterShape> {
        let area = geom.area();
        if !(area > 0.0 && area.is_finite()) {
            return None;
        }
        let triangles = match &geom {
            ShapeGeom::Mesh {
                positions, indices, ..
            } => {
                let areas: Vec<f32> = indices
                    .iter()
                    .map(|t| {
                        let [a, b, c] = t.map(|i| positions[i as usize]);
                        0.5 * (b - a).cross(c - a).length()
                    })
                    .collect();
                Some(crate::shapes::MeshSampling::new(positions, indices, &areas))
            }
            ShapeGeom::Sphere { .. }
            | ShapeGeom::Disk { .. }
            | ShapeGeom::Cylinder(_)
            | ShapeGeom::Ellipsoid(_) => None,
            ShapeGeom::Plane { .. } | ShapeGeom::Instance(_) => return None,
        };
        Some(MeterShape {
            geom,
            flip: if flip_normals { -1.0 } else { 1.0 },
            sampler: AreaLight {
                shape: 0,
                radiance: TexRef::Const(Vec3::ZERO),
                two_sided: false,
                triangles,
                prim: None,
                area,
            },
        })
    }

    /// A point of the surface (uniform by area), its error bound and its unit normal.
    fn sample(&self, u: Vec2) -> Option<(Vec3, Vec3, Vec3)> {
        let (p, err, n, _, _) = self
            .sampler
            .sample_position_on(&self.geom, self.flip, false, u)?;
        Some((p, err, n))
    }
}

/// A camera ray with its extent: valid for 0 < t < `t_max`.
#[derive(Clone, Copy, Debug)]
pub struct CameraRay {
    pub ray: Ray,
    pub t_max: f32,
    /// The lens point the ray leaves (world space; `ray.o` is moved along the ray to the
    /// near clip distance). Bidirectional methods place the camera vertex there.
    pub lens: Vec3,
}

/// A connection from a point in the scene to the camera's lens ([`Camera::sample_wi`]): where
/// it lands on the film and the importance it carries.
#[derive(Clone, Copy, Debug)]
pub struct ImportanceSample {
    /// The lens point (world space): the pinhole, or a point on a thin lens's aperture.
    pub p_lens: Vec3,
    /// Unit direction from the scene point towards `p_lens`.
    pub wi: Vec3,
    /// Distance from the scene point to `p_lens`.
    pub dist: f32,
    /// Film (raster) position the connection reaches.
    pub p_film: Vec2,
    /// We·|cos θ_lens| / (d²·pdf_lens) = 1 / (A·d²·cos³θ): what a light path's throughput
    /// (times the scene point's f·|cos|) becomes as a film splat, A the area of the image on
    /// the camera's z = 1 plane and θ the angle to the optical axis (pbrt-v4's
    /// `PerspectiveCamera::SampleWi`; the film then divides the splats by the number of
    /// light paths per pixel).
    pub weight: f32,
}

/// Horizontal field of view (degrees) from a field of view measured along `axis`, for a film of
/// the given aspect ratio (width / height). Mitsuba's `parse_fov`.
pub fn fov_x_degrees(fov: f32, axis: FovAxis, aspect: f32) -> f32 {
    let axis = match axis {
        FovAxis::Smaller if aspect > 1.0 => FovAxis::Y,
        FovAxis::Smaller => FovAxis::X,
        FovAxis::Larger if aspect > 1.0 => FovAxis::X,
        FovAxis::Larger => FovAxis::Y,
        a => a,
    };
    let half = (0.5 * fov).to_radians().tan();
    let half_x = match axis {
        FovAxis::X => half,
        FovAxis::Y => half * aspect,
        // The diagonal half-extent d satisfies d² = w² + h² with h = w / aspect.
        FovAxis::Diagonal => half / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
        FovAxis::Smaller | FovAxis::Larger => unreachable!("resolved above"),
    };
    2.0 * half_x.atan().to_degrees()
}

impl Camera {
    /// A camera with `projection`, camera-to-world `to_world` (looking along local +z, +y up,
    /// +x to the image's left: Mitsuba's convention) and clip distances, for a film of
    /// `width` × `height` pixels.
    pub fn new(
        projection: &Projection,
        to_world: Mat4,
        near_clip: f32,
        far_clip: f32,
        width: u32,
        height: u32,
    ) -> Camera {
        let aspect = width as f32 / height as f32;
        let (kind, fov_x) = match *projection {
            Projection::Perspective { fov, fov_axis } => (
                Kind::Perspective,
                Some(fov_x_degrees(fov, fov_axis, aspect)),
            ),
            Projection::ThinLens {
                fov,
                fov_axis,
                aperture_radius,
                focus_distance,
            } => (
                Kind::ThinLens {
                    aperture_radius,
                    focus_distance,
                },
                Some(fov_x_degrees(fov, fov_axis, aspect)),
            ),
            Projection::Orthographic => (Kind::Orthographic, None),
            // An irradiance meter's shape comes from `with_irradiance_meter`.
            Projection::RadianceMeter | Projection::IrradianceMeter { .. } => {
                return Camera {
                    kind: Kind::RadianceMeter,
                    to_world,
                    to_camera: to_world.inverse(),
                    resolution: Vec2::new(width as f32, height as f32),
                    half_extent: Vec2::ONE,
                    centre: Vec2::ZERO,
                    near_clip: 0.0,
                    far_clip: f32::INFINITY,
                };
            }
            Projection::Window {
                left,
                right,
                bottom,
                top,
            } => {
                // Camera x points to the image's left: the window's right is −x.
                return Camera {
                    kind: Kind::Perspective,
                    to_world,
                    to_camera: to_world.inverse(),
                    resolution: Vec2::new(width as f32, height as f32),
                    half_extent: Vec2::new(0.5 * (right - left), 0.5 * (top - bottom)),
                    centre: Vec2::new(-0.5 * (left + right), 0.5 * (bottom + top)),
                    near_clip,
                    far_clip,
                };
            }
        };
        let tan_x = match fov_x {
            Some(f) => (0.5 * f).to_radians().tan(),
            None => 1.0,
        };
        Camera {
            kind,
            to_world,
            to_camera: to_world.inverse(),
            resolution: Vec2::new(width as f32, height as f32),
            half_extent: Vec2::new(tan_x, tan_x / aspect),
            centre: Vec2::ZERO,
            near_clip,
            far_clip,
        }
    }

    /// This camera as Mitsuba's `irradiancemeter` on `shape` (the film is 1×1).
    pub fn with_irradiance_meter(mut self, shape: MeterShape) -> Camera {
        self.kind = Kind::IrradianceMeter(Box::new(shape));
        self
    }

    /// The weight every camera sample carries into the film: π for an irradiance meter
    /// (Mitsuba's `irradiancemeter` returns it from `sample_ray`: the cosine-weighted
    /// hemisphere's π), 1 for the others.
    #[inline]
    pub fn sample_weight(&self) -> f32 {
        match self.kind {
            Kind::IrradianceMeter(_) => PI,
            _ => 1.0,
        }
    }

    pub fn position(&self) -> Vec3 {
        self.to_world.w_axis.truncate().into()
    }

    /// The camera-space point on the z = 1 plane for a film position.
    #[inline]
    fn film_to_camera(&self, p_film: Vec2) -> Vec3 {
        let s = p_film / self.resolution;
        Vec3::new(
            -(2.0 * s.x - 1.0) * self.half_extent.x + self.centre.x,
            -(2.0 * s.y - 1.0) * self.half_extent.y + self.centre.y,
            1.0,
        )
    }

    /// The ray through continuous film position `p_film`; `u_lens` is used by the thin lens.
    pub fn generate_ray(&self, p_film: Vec2, u_lens: Vec2) -> CameraRay {
        if let Kind::IrradianceMeter(meter) = &self.kind {
            return meter_ray(meter, p_film / self.resolution, u_lens);
        }
        let p = self.film_to_camera(p_film);
        // `d_cam` need not be unit length: only its direction and its z component relative
        // to its length enter below.
        let (o_cam, d_cam) = match self.kind {
            Kind::Perspective => (Vec3::ZERO, p),
            Kind::ThinLens {
                aperture_radius,
                focus_distance,
            } => {
                let lens = square_to_uniform_disk_concentric(u_lens) * aperture_radius;
                let o = Vec3::new(lens.x, lens.y, 0.0);
                let focus = p * focus_distance;
                (o, focus - o)
            }
            Kind::Orthographic => {
                // The orthographic image plane spans [-1,1] horizontally.
                let q = Vec3::new(p.x / self.half_extent.x, p.y / self.half_extent.x, 0.0);
                (q, Vec3::Z)
            }
            Kind::RadianceMeter => (Vec3::ZERO, Vec3::Z),
            Kind::IrradianceMeter(_) => unreachable!("handled above"),
        };
        let o = self.to_world.transform_point3a(o_cam);
        let d_world = self.to_world.transform_vector3a(d_cam);
        // Mitsuba measures the clip distances along the camera axis (in camera units, so a
        // scaled to_world scales them too) and renormalises the world direction: with `d_cam`
        // of any length, a camera-space depth z is reached at t = z · |d_world| / d_cam.z.
        let len = d_world.length();
        let d = d_world / len;
        let t_per_z = len / d_cam.z;
        let near_t = self.near_clip * t_per_z;
        let far_t = self.far_clip * t_per_z;
        CameraRay {
            ray: Ray::new(o + d * near_t, d),
            t_max: far_t - near_t,
            lens: o,
        }
    }

    /// How far the surface point `p` (normal `n`) moves per pixel step in x and in y: rays
    /// through the neighbouring pixels (from the lens centre, or parallel for an
    /// orthographic camera) meet the tangent plane at `p` there. The world-space analogue
    /// of pbrt-v4's `Approximate_dp_dxy`, which texture filtering reads at every bounce.
    /// Zero where the plane is seen edge-on.
    pub fn approximate_dp_dxy(&self, p: Vec3, n: Vec3) -> (Vec3, Vec3) {
        let pc = self.to_camera.transform_point3a(p);
        // Normals go to camera space by the transpose of camera-to-world's inverse.
        let nc = crate::math::Mat3::from_mat4(self.to_world).transpose() * n;
        let step = 2.0 * self.half_extent / self.resolution;
        let offsets = [Vec3::new(step.x, 0.0, 0.0), Vec3::new(0.0, step.y, 0.0)];
        let on_plane = |o: Vec3, d: Vec3| {
            let t = nc.dot(pc - o) / nc.dot(d);
            let q = o + t * d;
            let dp = self.to_world.transform_vector3a(q - pc);
            if dp.is_finite() { dp } else { Vec3::ZERO }
        };
        if matches!(self.kind, Kind::RadianceMeter | Kind::IrradianceMeter(_)) {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let [dx, dy] = offsets.map(|off| match self.kind {
            Kind::Orthographic => on_plane(
                Vec3::new(pc.x, pc.y, 0.0) + off / self.half_extent.x,
                Vec3::Z,
            ),
            _ => {
                if pc.z <= 0.0 {
                    return Vec3::ZERO;
                }
                on_plane(Vec3::ZERO, pc / pc.z + off)
            }
        });
        (dx, dy)
    }

    /// The film position in [0, 1]² (x right, y down) that the ray leaving the camera in
    /// world direction `d` (from `origin`, which only an orthographic camera reads) comes
    /// through: the inverse of [`Self::generate_ray`] for the lens centre. CENG795's
    /// `replace_background` spreads a texture over the image with it.
    pub fn film_uv(&self, origin: Vec3, d: Vec3) -> Vec2 {
        let inv = &self.to_camera;
        let p = match self.kind {
            Kind::Orthographic => {
                let q = inv.transform_point3a(origin);
                Vec3::new(q.x * self.half_extent.x, q.y * self.half_extent.x, 1.0)
            }
            _ => {
                let c = inv.transform_vector3a(d);
                c / c.z
            }
        };
        Vec2::new(
            0.5 * (1.0 - (p.x - self.centre.x) / self.half_extent.x),
            0.5 * (1.0 - (p.y - self.centre.y) / self.half_extent.y),
        )
    }

    /// Whether light paths can be connected to this camera ([`Self::sample_wi`]): every
    /// projection but the orthographic one (a delta in direction and position alike).
    pub fn supports_importance(&self) -> bool {
        !matches!(
            self.kind,
            Kind::Orthographic | Kind::RadianceMeter | Kind::IrradianceMeter(_)
        )
    }

    /// Connect the world point `p` to the lens (a point on the aperture from `u` for a thin
    /// lens): `None` when `p` is behind the camera, outside the near and far clip distances,
    /// or projects outside the film, and for an orthographic camera. Assumes a rigid
    /// `to_world` (the importance is measured in world units).
    pub fn sample_wi(&self, p: Vec3, u: Vec2) -> Option<ImportanceSample> {
        let o_cam = match self.kind {
            Kind::Perspective => Vec3::ZERO,
            Kind::ThinLens {
                aperture_radius, ..
            } => {
                let lens = square_to_uniform_disk_concentric(u) * aperture_radius;
                Vec3::new(lens.x, lens.y, 0.0)
            }
            Kind::Orthographic | Kind::RadianceMeter | Kind::IrradianceMeter(_) => return None,
        };
        let p_cam = self.to_camera.transform_point3a(p);
        if !(p_cam.z > self.near_clip && p_cam.z < self.far_clip) {
            return None;
        }
        // The film position: where the line from the lens point through p meets the
        // focus plane, seen from the pinhole (generate_ray's inverse).
        let q = match self.kind {
            Kind::ThinLens { focus_distance, .. } => {
                let t = focus_distance / p_cam.z;
                (o_cam + (p_cam - o_cam) * t) / focus_distance
            }
            _ => p_cam / p_cam.z,
        };
        let s = Vec2::new(
            0.5 * (1.0 - (q.x - self.centre.x) / self.half_extent.x),
            0.5 * (1.0 - (q.y - self.centre.y) / self.half_extent.y),
        );
        if !(s.cmpge(Vec2::ZERO).all() && s.cmplt(Vec2::ONE).all()) {
            return None;
        }
        let p_lens = self.to_world.transform_point3a(o_cam);
        let to_lens = p_lens - p;
        let dist = to_lens.length();
        let d_cam = (p_cam - o_cam).normalize();
        let cos = d_cam.z;
        if !(dist > 0.0 && cos > 0.0) {
            return None;
        }
        let area = 4.0 * self.half_extent.x * self.half_extent.y;
        Some(ImportanceSample {
            p_lens,
            wi: to_lens / dist,
            dist,
            p_film: s * self.resolution,
            weight: 1.0 / (area * dist * dist * cos * cos * cos),
        })
    }

    /// The densities with which [`Self::generate_ray`] (film position uniform over the whole
    /// film, lens point uniform over the aperture) produces a ray leaving the lens in world
    /// direction `d`: (per unit lens area, per unit solid angle) = (1 / lens area,
    /// 1 / (A·cos³θ)), A the image's area on the z = 1 plane (pbrt-v4's `PDF_We`); (0, 0)
    /// when `d` does not reach the film, and for an orthographic camera.
    pub fn pdf_we(&self, d: Vec3) -> (f32, f32) {
        let lens_area = match self.kind {
            Kind::Perspective => 1.0,
            Kind::ThinLens {
                aperture_radius, ..
            } => crate::math::PI * aperture_radius * aperture_radius,
            Kind::Orthographic | Kind::RadianceMeter | Kind::IrradianceMeter(_) => {
                return (0.0, 0.0);
            }
        };
        let c = self.to_camera.transform_vector3a(d).normalize();
        if c.z <= 0.0 {
            return (0.0, 0.0);
        }
        // The lens centre's ray in direction d reaches the same film point as every lens
        // point's ray through the focus plane point along d.
        let q = c / c.z;
        let s = Vec2::new(
            0.5 * (1.0 - (q.x - self.centre.x) / self.half_extent.x),
            0.5 * (1.0 - (q.y - self.centre.y) / self.half_extent.y),
        );
        if !(s.cmpge(Vec2::ZERO).all() && s.cmplt(Vec2::ONE).all()) {
            return (0.0, 0.0);
        }
        let area = 4.0 * self.half_extent.x * self.half_extent.y;
        (1.0 / lens_area, 1.0 / (area * c.z * c.z * c.z))
    }

    /// Whether the lens needs a 2D sample.
    pub fn needs_lens_sample(&self) -> bool {
        matches!(self.kind, Kind::ThinLens { .. })
    }
}

/// An irradiance meter's ray: from a point uniform over the shape (`u_pos`) in a cosine
/// distributed direction about its normal (`u_dir`), leaving the surface by its error bound
/// (Mitsuba moves it by a fixed ray epsilon). A degenerate shape gives a ray that finds
/// nothing (t_max = 0).
#[inline(never)]
fn meter_ray(meter: &MeterShape, u_pos: Vec2, u_dir: Vec2) -> CameraRay {
    let Some((p, err, n)) = meter.sample(u_pos) else {
        return CameraRay {
            ray: Ray::new(Vec3::ZERO, Vec3::Z),
            t_max: 0.0,
            lens: Vec3::ZERO,
        };
    };
    let d = Frame::from_normal(n).to_world(square_to_cosine_hemisphere(u_dir));
    CameraRay {
        ray: Ray::new(offset_ray_origin(p, err, n, d), d),
        t_max: f32::INFINITY,
        lens: p,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rays through neighbouring pixel centres land where `approximate_dp_dxy` says, on a
    /// tilted plane seen by a perspective and an orthographic camera.
    #[test]
    fn surface_steps_per_pixel_follow_neighbouring_rays() {
        // At (0.3, 0.5, −4), looking along +z, turned a little.
        let to_world = Mat4::from_translation(glam::Vec3::new(0.3, 0.5, -4.0))
            * Mat4::from_rotation_y(-0.07)
            * Mat4::from_rotation_x(0.12);
        let n = Vec3::new(0.2, 1.0, -0.6).normalize();
        let plane_hit = |r: &Ray| {
            let t = n.dot(-r.o) / n.dot(r.d);
            r.o + t * r.d
        };
        for projection in [
            Projection::Perspective {
                fov: 40.0,
                fov_axis: FovAxis::X,
            },
            Projection::Orthographic,
        ] {
            let cam = Camera::new(&projection, to_world, 0.01, 1e4, 160, 120);
            let film = Vec2::new(70.5, 50.5);
            let at = |f: Vec2| plane_hit(&cam.generate_ray(f, Vec2::ZERO).ray);
            let p = at(film);
            let (dx, dy) = cam.approximate_dp_dxy(p, n);
            for (d, step) in [(dx, Vec2::X), (dy, Vec2::Y)] {
                // Up to the sign convention of the film axes.
                let q = 0.5 * (at(film + step) - at(film - step));
                let err = (q - d).length().min((q + d).length());
                assert!(err < 1e-2 * q.length(), "{projection:?}: {d} vs {q}");
            }
        }
    }

    #[test]
    fn film_uv_inverts_generate_ray() {
        let cam = Camera::new(
            &Projection::Window {
                left: -0.3,
                right: 0.5,
                bottom: -0.2,
                top: 0.4,
            },
            Mat4::from_rotation_y(0.3) * Mat4::from_translation(glam::Vec3::new(1.0, 2.0, 3.0)),
            0.0,
            1e4,
            64,
            48,
        );
        for (x, y) in [(0.5, 0.5), (10.25, 40.0), (63.5, 0.5)] {
            let r = cam.generate_ray(Vec2::new(x, y), Vec2::ZERO);
            let uv = cam.film_uv(r.ray.o, r.ray.d);
            assert!((uv - Vec2::new(x / 64.0, y / 48.0)).length() < 1e-5, "{uv}");
        }
    }

    /// `sample_wi` inverts `generate_ray`: a point on the ray through film position p (and
    /// lens sample u) connects back to p, and its lens point lies on the ray's line.
    #[test]
    fn sample_wi_inverts_generate_ray() {
        let to_world =
            Mat4::from_rotation_y(0.3) * Mat4::from_translation(glam::Vec3::new(1.0, 2.0, 3.0));
        let projections = [
            Projection::Perspective {
                fov: 50.0,
                fov_axis: FovAxis::X,
            },
            Projection::ThinLens {
                fov: 40.0,
                fov_axis: FovAxis::X,
                aperture_radius: 0.3,
                focus_distance: 4.0,
            },
            Projection::Window {
                left: -0.3,
                right: 0.5,
                bottom: -0.2,
                top: 0.4,
            },
        ];
        for proj in &projections {
            let cam = Camera::new(proj, to_world, 0.01, 1e4, 64, 48);
            for (x, y, u, t) in [
                (0.5, 0.5, Vec2::new(0.2, 0.7), 2.0),
                (10.25, 40.0, Vec2::new(0.9, 0.1), 7.0),
                (63.5, 0.5, Vec2::new(0.5, 0.5), 0.5),
            ] {
                let r = cam.generate_ray(Vec2::new(x, y), u).ray;
                let p = r.o + r.d * t;
                let c = cam.sample_wi(p, u).expect("visible");
                assert!(
                    (c.p_film - Vec2::new(x, y)).length() < 2e-3,
                    "{proj:?}: {}",
                    c.p_film
                );
                assert!(c.wi.dot(-r.d) > 1.0 - 1e-5, "{proj:?}");
                assert!(((p - c.p_lens).length() - c.dist).abs() < 1e-4);
            }
        }
        let ortho = Camera::new(&Projection::Orthographic, to_world, 0.01, 1e4, 64, 48);
        assert!(!ortho.supports_importance());
        assert!(
            ortho
                .sample_wi(Vec3::new(1.0, 2.0, 10.0), Vec2::ZERO)
                .is_none()
        );
    }

    /// The importance is normalised: over a plane facing the camera at distance D,
    /// ∫ weight·cos θ dA = ∫ We·cos θ_lens dω = 1 (midpoint rule on a 600² grid over a region
    /// larger than the view; a thin lens averaged over 16 stratified lens samples per point).
    #[test]
    fn importance_integrates_to_one() {
        for proj in [
            Projection::Perspective {
                fov: 50.0,
                fov_axis: FovAxis::X,
            },
            Projection::ThinLens {
                fov: 50.0,
                fov_axis: FovAxis::X,
                aperture_radius: 0.1,
                focus_distance: 2.0,
            },
        ] {
            let cam = Camera::new(&proj, Mat4::IDENTITY, 0.01, 1e4, 40, 30);
            let d = 3.0f32;
            let half = 2.5f32;
            let n = 600;
            let da = (2.0 * half / n as f32).powi(2) as f64;
            let lens = 4;
            let mut sum = 0.0f64;
            for j in 0..n {
                for i in 0..n {
                    let x = -half + (i as f32 + 0.5) * 2.0 * half / n as f32;
                    let y = -half + (j as f32 + 0.5) * 2.0 * half / n as f32;
                    let p = Vec3::new(x, y, d);
                    for k in 0..lens * lens {
                        let u = Vec2::new(
                            ((k % lens) as f32 + 0.5) / lens as f32,
                            ((k / lens) as f32 + 0.5) / lens as f32,
                        );
                        if let Some(c) = cam.sample_wi(p, u) {
                            let cos = c.wi.z.abs();
                            sum += (c.weight * cos) as f64 * da / (lens * lens) as f64;
                        }
                    }
                }
            }
            assert!((sum - 1.0).abs() < 5e-3, "{proj:?}: {sum}");
        }
    }

    /// `pdf_we`'s direction density is a density over the film's directions (∫ = 1 by the
    /// midpoint rule on a (cos θ, φ) grid), 0 outside; and it relates to `sample_wi`'s
    /// weight as pbrt-v4's importance does: We = pdf_pos·pdf_dir / cos θ, so the weight
    /// We·cos θ / (d²·pdf_lens) is pdf_dir / d².
    #[test]
    fn pdf_we_is_the_ray_density() {
        let cam = Camera::new(
            &Projection::Perspective {
                fov: 50.0,
                fov_axis: FovAxis::X,
            },
            Mat4::from_rotation_y(0.3),
            0.01,
            1e4,
            40,
            30,
        );
        let (nt, np) = (1500, 1500);
        let mut sum = 0.0f64;
        for i in 0..nt {
            let cos = (i as f32 + 0.5) / nt as f32;
            let sin = (1.0 - cos * cos).sqrt();
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * 2.0 * crate::math::PI;
                let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
                let d = cam.to_world.transform_vector3a(local);
                sum += cam.pdf_we(d).1 as f64;
            }
        }
        sum *= (1.0 / nt as f64) * (2.0 * std::f64::consts::PI / np as f64);
        assert!((sum - 1.0).abs() < 2e-3, "∫ pdf_dir = {sum}");
        let behind = cam.to_world.transform_vector3a(Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(cam.pdf_we(behind), (0.0, 0.0));
        for p in [Vec3::new(0.3, 0.2, 3.0), Vec3::new(-1.0, 0.5, 4.0)] {
            let pw = cam.to_world.transform_point3a(p);
            let c = cam.sample_wi(pw, Vec2::ZERO).unwrap();
            let (pos, dir) = cam.pdf_we(-c.wi);
            assert_eq!(pos, 1.0);
            let want = dir / (c.dist * c.dist);
            assert!(
                (c.weight / want - 1.0).abs() < 1e-4,
                "{} vs {want}",
                c.weight
            );
        }
    }

    #[test]
    fn fov_axes_agree_for_square_films() {
        for axis in [FovAxis::X, FovAxis::Y, FovAxis::Smaller, FovAxis::Larger] {
            assert!((fov_x_degrees(40.0, axis, 1.0) - 40.0).abs() < 1e-4);
        }
        // Diagonal of a square: half-diagonal tan = √2 · half-width tan.
        let fx = fov_x_degrees(40.0, FovAxis::Diagonal, 1.0);
        let expect = 2.0
            * ((20f32).to_radians().tan() / 2f32.sqrt())
                .atan()
                .to_degrees();
        assert!((fx - expect).abs() < 1e-4);
        // Vertical fov on a 2:1 film doubles the tangent.
        let fx = fov_x_degrees(30.0, FovAxis::Y, 2.0);
        assert!(((0.5 * fx).to_radians().tan() - 2.0 * 15f32.to_radians().tan()).abs() < 1e-5);
        assert_eq!(fov_x_degrees(30.0, FovAxis::Smaller, 2.0), fx);
    }

    #[test]
    fn image_left_is_camera_plus_x_and_top_is_plus_y() {
        let cam = Camera::new(
            &Projection::Perspective {
                fov: 90.0,
                fov_axis: FovAxis::X,
            },
            Mat4::IDENTITY,
            0.0,
            1e4,
            100,
            50,
        );
        let r = cam.generate_ray(Vec2::new(0.0, 25.0), Vec2::ZERO).ray;
        assert!((r.d - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-6);
        let r = cam.generate_ray(Vec2::new(50.0, 0.0), Vec2::ZERO).ray;
        assert!((r.d - Vec3::new(0.0, 0.5, 1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn thin_lens_rays_meet_on_the_focal_plane() {
        let cam = Camera::new(
            &Projection::ThinLens {
                fov: 40.0,
                fov_axis: FovAxis::X,
                aperture_radius: 0.3,
                focus_distance: 5.0,
            },
            Mat4::IDENTITY,
            0.0,
            1e4,
            64,
            64,
        );
        let pin = Camera::new(
            &Projection::Perspective {
                fov: 40.0,
                fov_axis: FovAxis::X,
            },
            Mat4::IDENTITY,
            0.0,
            1e4,
            64,
            64,
        );
        let pf = Vec2::new(10.3, 50.7);
        let target = {
            let r = pin.generate_ray(pf, Vec2::ZERO).ray;
            r.at(5.0 / r.d.z)
        };
        for u in [
            Vec2::new(0.1, 0.9),
            Vec2::new(0.7, 0.2),
            Vec2::new(0.5, 0.5),
        ] {
            let r = cam.generate_ray(pf, u).ray;
            let hit = r.at((5.0 - r.o.z) / r.d.z);
            assert!((hit - target).length() < 1e-4, "{hit} vs {target}");
        }
    }

    #[test]
    fn near_clip_moves_the_origin_along_the_axis() {
        let p = Projection::Perspective {
            fov: 60.0,
            fov_axis: FovAxis::X,
        };
        let cam = Camera::new(&p, Mat4::IDENTITY, 2.0, 10.0, 32, 32);
        let cr = cam.generate_ray(Vec2::new(3.0, 7.0), Vec2::ZERO);
        assert!((cr.ray.o.z - 2.0).abs() < 1e-5);
        assert!((cr.ray.at(cr.t_max).z - 10.0).abs() < 1e-4);
    }

    /// An off-axis window with non-square pixels (the CENG795 NearPlane): the ray through the
    /// film position of a camera-space point passes through that point, and the near clip is
    /// the window's plane along the axis.
    #[test]
    fn window_rays_pass_through_their_points() {
        let (l, r, b, t) = (-0.7f32, 0.3, -0.2, 0.6);
        let p = Projection::Window {
            left: l,
            right: r,
            bottom: b,
            top: t,
        };
        let (w, h) = (40u32, 25u32);
        let cam = Camera::new(&p, Mat4::IDENTITY, 1.5, 1e4, w, h);
        for p in [
            Vec3::new(0.1, 0.2, 3.0),
            Vec3::new(-1.2, -0.3, 5.0),
            Vec3::new(0.6, 1.7, 4.0),
        ] {
            // Image right is camera −x.
            let (u, v) = (-p.x / p.z, p.y / p.z);
            let film = Vec2::new((u - l) / (r - l) * w as f32, (t - v) / (t - b) * h as f32);
            let cr = cam.generate_ray(film, Vec2::ZERO);
            assert!(
                (cr.ray.o.z - 1.5).abs() < 1e-5,
                "near clip at {}",
                cr.ray.o.z
            );
            let q = cr.ray.at((p.z - cr.ray.o.z) / cr.ray.d.z);
            assert!((q - p).length() < 1e-4, "{q} vs {p}");
        }
        // The window's corners are the film's corners.
        let corner = cam.generate_ray(Vec2::ZERO, Vec2::ZERO).ray.d;
        assert!((corner.x / corner.z + l).abs() < 1e-5 && (corner.y / corner.z - t).abs() < 1e-5);
    }
}
