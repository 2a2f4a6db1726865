//! Integration tests of `render::accel`: primitives against analytic answers, watertightness,
//! BVH against brute force on random mixed scenes, occlusion against closest hit.

use std::sync::Arc;

use render::accel::prim::{
    intersect_cylinder, intersect_disk, intersect_ellipsoid, intersect_plane, intersect_sphere,
    intersect_triangle,
};
use render::accel::{Accel, AccelShape, Hit};
use render::geometry::Ray;
use render::math::{Mat4, Vec3};

/// PCG32 (O'Neill 2014): a fixed-seed stream for reproducible tests.
struct Rng(u64);
impl Rng {
    fn new(seed: u64) -> Rng {
        Rng(seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407))
    }
    fn u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }
    fn f(&mut self) -> f32 {
        (self.u32() >> 8) as f32 / (1u32 << 24) as f32
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
    fn vec(&mut self, a: f32, b: f32) -> Vec3 {
        Vec3::new(self.range(a, b), self.range(a, b), self.range(a, b))
    }
    fn dir(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()).max(1.0)
}

// ---------------------------------------------------------------- triangles

#[test]
fn triangle_analytic() {
    let (p0, p1, p2) = (
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    );
    // Straight down onto (0.25, 0.5): barycentrics u = 0.25 (weight of p1), v = 0.5 (p2).
    let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
    let (t, u, v) = intersect_triangle(&ray, p0, p1, p2, f32::INFINITY).unwrap();
    assert_eq!(t, 2.0);
    assert!(close(u, 0.25, 1e-6) && close(v, 0.5, 1e-6), "{u} {v}");
    // Back face too.
    let ray_up = Ray::new(Vec3::new(0.25, 0.5, -3.0), Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(
        intersect_triangle(&ray_up, p0, p1, p2, f32::INFINITY)
            .unwrap()
            .0,
        3.0
    );
    // Non-normalised direction: t in parameter units.
    let ray2 = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -4.0));
    assert_eq!(
        intersect_triangle(&ray2, p0, p1, p2, f32::INFINITY)
            .unwrap()
            .0,
        0.5
    );
    // t_max is exclusive, as is t = 0.
    assert!(intersect_triangle(&ray, p0, p1, p2, 2.0).is_none());
    assert!(intersect_triangle(&ray, p0, p1, p2, 2.0001).is_some());
    let on = Ray::new(Vec3::new(0.25, 0.5, 0.0), Vec3::new(0.0, 0.0, -1.0));
    assert!(intersect_triangle(&on, p0, p1, p2, f32::INFINITY).is_none());
    // Behind the origin.
    let away = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, 1.0));
    assert!(intersect_triangle(&away, p0, p1, p2, f32::INFINITY).is_none());
    // Misses outside the edges.
    for o in [
        Vec3::new(0.6, 0.6, 1.0),
        Vec3::new(-0.01, 0.5, 1.0),
        Vec3::new(0.5, -0.01, 1.0),
    ] {
        assert!(intersect_triangle(&Ray::new(o, -Vec3::Z), p0, p1, p2, 10.0).is_none());
    }
    // Oblique ray: hit point reconstructs from barycentrics.
    let mut rng = Rng::new(1);
    for _ in 0..1000 {
        let (q0, q1, q2) = (rng.vec(-1.0, 1.0), rng.vec(-1.0, 1.0), rng.vec(-1.0, 1.0));
        let (a, b) = (rng.f(), rng.f());
        let (a, b) = if a + b > 1.0 {
            (1.0 - a, 1.0 - b)
        } else {
            (a, b)
        };
        let target = q0 + a * (q1 - q0) + b * (q2 - q0);
        let o = rng.vec(-3.0, 3.0);
        let ray = Ray::new(o, target - o);
        if let Some((t, u, v)) = intersect_triangle(&ray, q0, q1, q2, 10.0) {
            let p = (1.0 - u - v) * q0 + u * q1 + v * q2;
            assert!((ray.at(t) - p).length() < 1e-4, "{:?} vs {p:?}", ray.at(t));
            assert!((p - target).length() < 1e-3);
            assert!(close(t, 1.0, 1e-3));
        } else {
            // Only allowed when the target is within rounding of an edge.
            assert!(a.min(b).min(1.0 - a - b) < 1e-4, "{a} {b}");
        }
    }
}

#[test]
fn degenerate_triangles_never_hit_or_nan() {
    let mut rng = Rng::new(2);
    let p = Vec3::new(0.5, 0.25, 0.125);
    let q = Vec3::new(1.0, 2.0, 3.0);
    let degenerate = [
        [p, p, p],
        [p, q, q],
        [Vec3::ZERO, q, 2.0 * q], // exactly collinear
        [
            Vec3::ZERO,
            Vec3::new(1e-30, 0.0, 0.0),
            Vec3::new(0.0, 1e-30, 0.0),
        ], // edge functions underflow
    ];
    for (k, tri) in degenerate.into_iter().enumerate() {
        for _ in 0..2000 {
            // Rays aimed at the degenerate triangle, some in its line/plane.
            let o = rng.vec(-2.0, 2.0);
            let target = tri[0] + rng.f() * (tri[1] - tri[0]) + rng.f() * (tri[2] - tri[0]);
            let ray = Ray::new(o, target - o);
            if let Some((t, u, v)) = intersect_triangle(&ray, tri[0], tri[1], tri[2], f32::INFINITY)
            {
                // Coincident vertices transform identically, so their edge functions are exactly
                // zero: no hit. Collinear or underflowing triangles may become slivers after the
                // ray's shear and be hit, but never with NaN (the accel skips them at build).
                assert!(
                    k >= 2 && t.is_finite() && u.is_finite() && v.is_finite(),
                    "degenerate hit t={t} u={u} v={v}"
                );
            }
        }
    }
    // Through an accel: zero-area triangles (zero cross product, no normal) are never hit.
    let positions: Arc<[Vec3]> = vec![Vec3::ZERO, q, 2.0 * q, Vec3::X, Vec3::Y].into();
    let indices: Arc<[[u32; 3]]> = vec![[0, 1, 2], [0, 0, 0], [0, 3, 4], [1, 1, 2]].into();
    let accel = Accel::build(vec![AccelShape::Triangles { positions, indices }]);
    for i in 0..4000u32 {
        let o = rng.vec(-2.0, 2.0);
        let ray = if i.is_multiple_of(2) {
            Ray::new(o, rng.dir())
        } else {
            Ray::new(o, q * rng.f() - o) // aimed at the collinear triangle
        };
        if let Some(h) = accel.intersect(&ray, f32::INFINITY) {
            assert_eq!(h.prim, 2);
            assert!(h.t.is_finite() && h.u.is_finite() && h.v.is_finite());
        }
    }
}

/// A closed mesh: an icosphere of `level` subdivisions (shared vertices).
fn icosphere(level: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut nf = Vec::new();
        let mut midpoint = |a: u32, b: u32, v: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                v.len() as u32 - 1
            })
        };
        for [a, b, c] in f {
            let ab = midpoint(a, b, &mut v);
            let bc = midpoint(b, c, &mut v);
            let ca = midpoint(c, a, &mut v);
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    (v, f)
}

fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let v: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32) * 2.0 - 1.0
        })
        .collect();
    let f = vec![
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ];
    (v, f)
}

/// Shoots rays from interior points at vertices, at points on edges and near them: a closed mesh
/// must be hit by every one of them, both by the primitive test and through the BVH.
fn check_watertight(v: Vec<Vec3>, f: Vec<[u32; 3]>, origins: &[Vec3], seed: u64) {
    let mut rng = Rng::new(seed);
    let mut targets: Vec<Vec3> = v.clone();
    for tri in &f {
        for e in 0..3 {
            let (a, b) = (v[tri[e] as usize], v[tri[(e + 1) % 3] as usize]);
            targets.push((a + b) * 0.5);
            for _ in 0..3 {
                targets.push(a + rng.f() * (b - a));
            }
        }
    }
    let accel = Accel::build(vec![AccelShape::Triangles {
        positions: v.clone().into(),
        indices: f.clone().into(),
    }]);
    let mut shot = 0;
    for &o in origins {
        for &target in &targets {
            // Aim at the point and (for scale-invariance) with a scaled direction.
            for d in [target - o, (target - o) * 3.7] {
                let ray = Ray::new(o, d);
                let brute = f.iter().any(|t| {
                    intersect_triangle(
                        &ray,
                        v[t[0] as usize],
                        v[t[1] as usize],
                        v[t[2] as usize],
                        f32::INFINITY,
                    )
                    .is_some()
                });
                assert!(
                    brute,
                    "ray {ray:?} escaped the closed mesh (primitive test)"
                );
                assert!(
                    accel.intersect(&ray, f32::INFINITY).is_some(),
                    "ray {ray:?} escaped (BVH)"
                );
                assert!(
                    accel.occluded(&ray, f32::INFINITY),
                    "ray {ray:?} not occluded (BVH)"
                );
                shot += 1;
            }
        }
    }
    assert!(shot > 1000);
}

#[test]
fn watertight_icosphere() {
    let (v, f) = icosphere(2);
    let mut rng = Rng::new(3);
    let mut origins = vec![Vec3::ZERO, Vec3::new(0.1, 0.0, 0.0)];
    origins.extend((0..4).map(|_| rng.vec(-0.5, 0.5)));
    check_watertight(v, f, &origins, 4);
}

#[test]
fn watertight_cube() {
    let (v, f) = cube();
    let mut rng = Rng::new(5);
    // The centre makes rays through edges/vertices exactly axis-aligned or diagonal.
    let mut origins = vec![
        Vec3::ZERO,
        Vec3::new(0.5, 0.5, 0.0),
        Vec3::new(0.0, 0.0, 0.999),
    ];
    origins.extend((0..20).map(|_| rng.vec(-0.9, 0.9)));
    check_watertight(v, f, &origins, 6);
}

// ---------------------------------------------------------------- spheres, disks, planes

#[test]
fn sphere_analytic() {
    let c = Vec3::new(1.0, 2.0, 3.0);
    let r = 0.5;
    let ray = Ray::new(c - Vec3::new(0.0, 0.0, 10.0), Vec3::Z);
    assert!(close(
        intersect_sphere(&ray, c, r, f32::INFINITY).unwrap(),
        9.5,
        1e-6
    ));
    // Non-normalised direction.
    let ray2 = Ray::new(ray.o, Vec3::Z * 2.0);
    assert!(close(
        intersect_sphere(&ray2, c, r, f32::INFINITY).unwrap(),
        4.75,
        1e-6
    ));
    // t_max exclusive; the far root is found when the near one is cut.
    assert!(intersect_sphere(&ray, c, r, 9.5).is_none());
    // From inside: the exit point.
    let inside = Ray::new(c + Vec3::new(0.0, 0.0, 0.1), Vec3::Z);
    assert!(close(
        intersect_sphere(&inside, c, r, f32::INFINITY).unwrap(),
        0.4,
        1e-5
    ));
    let inside2 = Ray::new(c, -Vec3::X);
    assert!(close(
        intersect_sphere(&inside2, c, r, f32::INFINITY).unwrap(),
        0.5,
        1e-6
    ));
    // Behind and misses.
    assert!(intersect_sphere(&Ray::new(ray.o, -Vec3::Z), c, r, f32::INFINITY).is_none());
    assert!(
        intersect_sphere(
            &Ray::new(ray.o + Vec3::X * 0.51, Vec3::Z),
            c,
            r,
            f32::INFINITY
        )
        .is_none()
    );
    // Grazing: just inside the silhouette hits near the tangent point, just outside misses.
    let g = Ray::new(c + Vec3::new(0.4999, 0.0, -10.0), Vec3::Z);
    let tg = intersect_sphere(&g, c, r, f32::INFINITY).unwrap();
    assert!((tg - 10.0).abs() < 0.02, "{tg}");
    let gm = Ray::new(c + Vec3::new(0.5001, 0.0, -10.0), Vec3::Z);
    assert!(intersect_sphere(&gm, c, r, f32::INFINITY).is_none());
}

#[test]
fn sphere_from_far_away() {
    // A unit sphere seen from 10^3..10^6 radii away, off-axis: the naive b²-4ac loses every digit
    // of the discriminant here; the robust form keeps the hit and its distance.
    let mut rng = Rng::new(7);
    let c = Vec3::new(0.3, -0.2, 0.1);
    for dist in [1e3f32, 1e4, 1e5, 1e6] {
        for _ in 0..200 {
            let dir = rng.dir();
            let o = c - dir * dist;
            // Aim at a point of the sphere's cross-section within 0.9 radius of the centre.
            let (a, b) = (rng.range(-0.6, 0.6), rng.range(-0.6, 0.6));
            let f = render::math::Frame::from_normal(dir);
            let target = c + f.s * a + f.t * b;
            let d = target - o;
            let ray = Ray::new(o, d);
            let t = intersect_sphere(&ray, c, 1.0, f32::INFINITY)
                .unwrap_or_else(|| panic!("missed from {dist}"));
            // Expected distance along the normalised direction, computed in f64.
            let (od, dd, cd) = (o.as_dvec3(), d.as_dvec3().normalize(), c.as_dvec3());
            let fo = od - cd;
            let bb = fo.dot(dd);
            let cc = fo.dot(fo) - 1.0;
            let exact = -bb - (bb * bb - cc).sqrt();
            let got = f64::from(t) * d.as_dvec3().length();
            // The origin itself carries an f32 rounding of ~dist·2⁻²⁴.
            assert!(
                (got - exact).abs() <= 4.0 * f64::from(dist) * 6e-8 + 1e-4,
                "{got} vs {exact}"
            );
        }
    }
}

#[test]
fn disk_analytic() {
    // Non-uniform scale 2 × 0.5, rotated to face +x, moved to (5, 0, 0).
    let to_world = Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0).into())
        * Mat4::from_rotation_y(std::f32::consts::FRAC_PI_2)
        * Mat4::from_scale(Vec3::new(2.0, 0.5, 1.0).into());
    let to_object = to_world.inverse();
    // Object x axis maps to world -z (scaled by 2), object y to world y (scaled by 0.5).
    let ray = Ray::new(Vec3::new(0.0, 0.25, -1.0), Vec3::X * 2.0);
    let (t, x, y) = intersect_disk(&ray, &to_object, f32::INFINITY).unwrap();
    assert!(close(t, 2.5, 1e-6));
    assert!(close(x, 0.5, 1e-5) && close(y, 0.5, 1e-5), "{x} {y}");
    // Outside the ellipse along y (0.5 · 1.01).
    assert!(
        intersect_disk(
            &Ray::new(Vec3::new(0.0, 0.505, 0.0), Vec3::X),
            &to_object,
            100.0
        )
        .is_none()
    );
    // Inside along x up to 2.
    assert!(
        intersect_disk(
            &Ray::new(Vec3::new(0.0, 0.0, 1.99), Vec3::X),
            &to_object,
            100.0
        )
        .is_some()
    );
    assert!(
        intersect_disk(
            &Ray::new(Vec3::new(0.0, 0.0, 2.01), Vec3::X),
            &to_object,
            100.0
        )
        .is_none()
    );
    // Parallel, behind, t_max.
    assert!(
        intersect_disk(
            &Ray::new(Vec3::new(5.0, 0.0, 0.0), Vec3::Y),
            &to_object,
            100.0
        )
        .is_none()
    );
    assert!(
        intersect_disk(
            &Ray::new(Vec3::new(6.0, 0.0, 0.0), Vec3::X),
            &to_object,
            100.0
        )
        .is_none()
    );
    assert!(intersect_disk(&Ray::new(Vec3::ZERO, Vec3::X), &to_object, 5.0).is_none());
    // Through Accel: shape index and u, v.
    let accel = Accel::build(vec![
        AccelShape::Sphere {
            center: Vec3::new(0.0, 10.0, 0.0),
            radius: 1.0,
        },
        AccelShape::Disk { to_world },
    ]);
    let h = accel.intersect(&ray, f32::INFINITY).unwrap();
    assert_eq!((h.shape, h.prim), (1, 0));
    assert!(close(h.t, 2.5, 1e-6) && close(h.u, 0.5, 1e-5) && close(h.v, 0.5, 1e-5));
    let (lo, hi) = accel.bounds();
    assert!(lo.x <= 5.0 && hi.x >= 5.0 && lo.z <= -2.0 && hi.z >= 2.0 && hi.y >= 11.0);
}

/// Mitsuba's open cylinder (radius 2, z from 1 to 4 here): the near wall from outside, the
/// far wall from inside and through an open end, nothing along the axis or past the ends.
#[test]
fn cylinder_analytic() {
    let to_world = Mat4::from_translation(glam::Vec3::new(0.0, 0.0, 1.0))
        * Mat4::from_scale(glam::Vec3::new(2.0, 2.0, 3.0));
    let to_object = to_world.inverse();
    let hit = |o: Vec3, d: Vec3, t_max| intersect_cylinder(&Ray::new(o, d), &to_object, t_max);
    // From outside across the middle: the near wall at x = -2.
    let t = hit(Vec3::new(-5.0, 0.0, 2.0), Vec3::X, f32::INFINITY).unwrap();
    assert!(close(t, 3.0, 1e-6), "{t}");
    assert!(hit(Vec3::new(-5.0, 0.0, 2.0), Vec3::X, 2.9).is_none());
    // From inside: the wall ahead.
    let t = hit(Vec3::new(0.5, 0.0, 2.0), Vec3::X, f32::INFINITY).unwrap();
    assert!(close(t, 1.5, 1e-6), "{t}");
    // Down through the open top end onto the far wall: enters at z = 4 inside.
    let d = Vec3::new(1.0, 0.0, -1.0);
    let t = hit(Vec3::new(-1.0, 0.0, 5.0), d, f32::INFINITY).unwrap();
    assert!(close(t, 3.0, 1e-5), "{t}");
    // Along the axis, and past the ends: no caps.
    assert!(hit(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, f32::INFINITY).is_none());
    assert!(hit(Vec3::new(-5.0, 0.0, 4.5), Vec3::X, f32::INFINITY).is_none());
    assert!(hit(Vec3::new(-5.0, 0.0, 0.5), Vec3::X, f32::INFINITY).is_none());
    // The BVH finds it and bounds it.
    let accel = Accel::build(vec![AccelShape::Cylinder { to_world }]);
    let h = accel
        .intersect(&Ray::new(Vec3::new(-5.0, 0.0, 2.0), Vec3::X), f32::INFINITY)
        .unwrap();
    assert!(close(h.t, 3.0, 1e-6));
    let (lo, hi) = accel.bounds();
    assert!(lo.cmple(Vec3::new(-2.0, -2.0, 1.0)).all() && hi.cmpge(Vec3::new(2.0, 2.0, 4.0)).all());
    assert!((hi - lo - Vec3::new(4.0, 4.0, 3.0)).abs().max_element() < 1e-4);
}

#[test]
fn plane_analytic() {
    let (p, n) = (Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 2.0, 0.0));
    let ray = Ray::new(Vec3::new(3.0, 4.0, 5.0), Vec3::new(0.0, -2.0, 0.0));
    assert!(close(
        intersect_plane(&ray, p, n, f32::INFINITY).unwrap(),
        2.5,
        1e-6
    ));
    assert!(intersect_plane(&ray, p, n, 2.5).is_none());
    assert!(intersect_plane(&Ray::new(ray.o, Vec3::X), p, n, f32::INFINITY).is_none());
    assert!(intersect_plane(&Ray::new(ray.o, Vec3::Y), p, n, f32::INFINITY).is_none());
    // Planes are not in the bounds but are hit, and occlude.
    let accel = Accel::build(vec![
        AccelShape::Sphere {
            center: Vec3::new(3.0, 0.0, 5.0),
            radius: 0.5,
        },
        AccelShape::Plane {
            point: p,
            normal: n,
        },
    ]);
    let h = accel.intersect(&ray, f32::INFINITY).unwrap();
    assert_eq!(h.shape, 0);
    assert!(close(h.t, 1.75, 1e-6));
    let miss_sphere = Ray::new(Vec3::new(10.0, 4.0, 5.0), Vec3::new(0.0, -1.0, 0.0));
    let h = accel.intersect(&miss_sphere, f32::INFINITY).unwrap();
    assert_eq!(h.shape, 1);
    assert!(close(h.t, 5.0, 1e-6));
    assert!(accel.occluded(&miss_sphere, 5.5) && !accel.occluded(&miss_sphere, 5.0));
    assert_eq!(
        accel.bounds(),
        (Vec3::new(2.5, -0.5, 4.5), Vec3::new(3.5, 0.5, 5.5))
    );
}

#[test]
fn empty_and_invalid() {
    let accel = Accel::build(Vec::new());
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(accel.intersect(&ray, f32::INFINITY).is_none());
    assert!(!accel.occluded(&ray, f32::INFINITY));
    assert_eq!(accel.bounds(), (Vec3::ZERO, Vec3::ZERO));
    // Invalid shapes are skipped without panicking.
    let accel = Accel::build(vec![
        AccelShape::Triangles {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)].into(),
            indices: vec![[0, 1, 7], [0, 1, 2]].into(),
        },
        AccelShape::Sphere {
            center: Vec3::ZERO,
            radius: -1.0,
        },
        AccelShape::Disk {
            to_world: Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0).into()),
        },
        AccelShape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::ZERO,
        },
    ]);
    let mut rng = Rng::new(8);
    for _ in 0..100 {
        let ray = Ray::new(rng.vec(-2.0, 2.0), rng.dir());
        assert!(accel.intersect(&ray, f32::INFINITY).is_none());
    }
    // Degenerate rays.
    let accel = Accel::build(vec![AccelShape::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    }]);
    assert!(
        accel
            .intersect(&Ray::new(Vec3::X * 3.0, Vec3::ZERO), f32::INFINITY)
            .is_none()
    );
    assert!(
        accel
            .intersect(&Ray::new(Vec3::NAN, Vec3::X), f32::INFINITY)
            .is_none()
    );
    assert!(
        accel
            .intersect(&Ray::new(Vec3::X * 3.0, -Vec3::X), f32::NAN)
            .is_none()
    );
    assert!(
        accel
            .intersect(&Ray::new(Vec3::X * 3.0, -Vec3::X), f32::INFINITY)
            .is_some()
    );
}

// ---------------------------------------------------------------- BVH vs brute force

fn brute(shapes: &[AccelShape], ray: &Ray, mut t_max: f32) -> Option<Hit> {
    let mut best = None;
    for (s, shape) in shapes.iter().enumerate() {
        let s = s as u32;
        match shape {
            AccelShape::Triangles { positions, indices } => {
                for (i, t) in indices.iter().enumerate() {
                    let p = |k: usize| positions[t[k] as usize];
                    if let Some((th, u, v)) = intersect_triangle(ray, p(0), p(1), p(2), t_max) {
                        t_max = th;
                        best = Some(Hit {
                            t: th,
                            shape: s,
                            prim: i as u32,
                            u,
                            v,
                        });
                    }
                }
            }
            &AccelShape::Sphere { center, radius } => {
                if let Some(t) = intersect_sphere(ray, center, radius, t_max) {
                    t_max = t;
                    best = Some(Hit {
                        t,
                        shape: s,
                        prim: 0,
                        u: 0.0,
                        v: 0.0,
                    });
                }
            }
            AccelShape::Disk { to_world } => {
                if let Some((t, u, v)) = intersect_disk(ray, &to_world.inverse(), t_max) {
                    t_max = t;
                    best = Some(Hit {
                        t,
                        shape: s,
                        prim: 0,
                        u,
                        v,
                    });
                }
            }
            AccelShape::Ellipsoid { to_world } => {
                if let Some(t) = intersect_ellipsoid(ray, &to_world.inverse(), t_max) {
                    t_max = t;
                    best = Some(Hit {
                        t,
                        shape: s,
                        prim: 0,
                        u: 0.0,
                        v: 0.0,
                    });
                }
            }
            AccelShape::Cylinder { to_world } => {
                if let Some(t) = intersect_cylinder(ray, &to_world.inverse(), t_max) {
                    t_max = t;
                    best = Some(Hit {
                        t,
                        shape: s,
                        prim: 0,
                        u: 0.0,
                        v: 0.0,
                    });
                }
            }
            AccelShape::Instance { .. } => unreachable!("brute force takes flattened shapes"),
            &AccelShape::Plane { point, normal } => {
                if let Some(t) = intersect_plane(ray, point, normal, t_max) {
                    t_max = t;
                    best = Some(Hit {
                        t,
                        shape: s,
                        prim: 0,
                        u: 0.0,
                        v: 0.0,
                    });
                }
            }
        }
    }
    best
}

fn random_scene(rng: &mut Rng, n_shapes: usize, tris_per_mesh: usize) -> Vec<AccelShape> {
    (0..n_shapes)
        .map(|_| match rng.u32() % 8 {
            0..=3 => {
                let c = rng.vec(-5.0, 5.0);
                let n = 1 + (rng.u32() as usize % tris_per_mesh);
                let positions: Vec<Vec3> = (0..3 * n).map(|_| c + rng.vec(-1.5, 1.5)).collect();
                // Some shared vertices, some soup.
                let indices: Vec<[u32; 3]> = (0..n)
                    .map(|i| {
                        let k = (3 * i) as u32;
                        if i > 0 && rng.u32().is_multiple_of(2) {
                            [k - 1, k, k + 1]
                        } else {
                            [k, k + 1, k + 2]
                        }
                    })
                    .collect();
                AccelShape::Triangles {
                    positions: positions.into(),
                    indices: indices.into(),
                }
            }
            4 => AccelShape::Sphere {
                center: rng.vec(-5.0, 5.0),
                radius: rng.range(0.05, 1.5),
            },
            5 => AccelShape::Ellipsoid {
                to_world: Mat4::from_translation(rng.vec(-5.0, 5.0).into())
                    * Mat4::from_axis_angle(rng.dir().into(), rng.range(0.0, 6.0))
                    * Mat4::from_scale(
                        Vec3::new(
                            rng.range(0.05, 1.5),
                            rng.range(0.05, 1.5),
                            rng.range(0.05, 1.5),
                        )
                        .into(),
                    ),
            },
            6 => AccelShape::Disk {
                to_world: Mat4::from_translation(rng.vec(-5.0, 5.0).into())
                    * Mat4::from_axis_angle(rng.dir().into(), rng.range(0.0, 6.0))
                    * Mat4::from_scale(
                        Vec3::new(rng.range(0.2, 2.0), rng.range(0.2, 2.0), 1.0).into(),
                    ),
            },
            _ => {
                let k = rng.u32() % 4;
                if k == 0 {
                    AccelShape::Plane {
                        point: rng.vec(-8.0, 8.0),
                        normal: rng.dir(),
                    }
                } else if k == 1 {
                    // Mitsuba's open cylinder, sometimes elliptic.
                    AccelShape::Cylinder {
                        to_world: Mat4::from_translation(rng.vec(-5.0, 5.0).into())
                            * Mat4::from_axis_angle(rng.dir().into(), rng.range(0.0, 6.0))
                            * Mat4::from_scale(
                                Vec3::new(
                                    rng.range(0.1, 1.5),
                                    rng.range(0.1, 1.5),
                                    rng.range(0.2, 3.0),
                                )
                                .into(),
                            ),
                    }
                } else {
                    AccelShape::Sphere {
                        center: rng.vec(-5.0, 5.0),
                        radius: rng.range(0.05, 0.5),
                    }
                }
            }
        })
        .collect()
}

fn compare_with_brute(shapes: Vec<AccelShape>, rng: &mut Rng, rays: usize) {
    let accel = Accel::build(shapes.clone());
    for i in 0..rays {
        let o = rng.vec(-8.0, 8.0);
        let d = rng.dir() * rng.range(0.5, 2.0);
        let ray = Ray::new(o, d);
        let t_max = if i.is_multiple_of(3) {
            rng.range(0.5, 10.0)
        } else {
            f32::INFINITY
        };
        let a = accel.intersect(&ray, t_max);
        let b = brute(&shapes, &ray, t_max);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert_eq!(a.t, b.t, "ray {ray:?}: {a:?} vs {b:?}");
                // Equal t may come from different primitives (shared edges); otherwise identical.
                if (a.shape, a.prim) == (b.shape, b.prim) {
                    assert!(
                        close(a.u, b.u, 1e-5) && close(a.v, b.v, 1e-5),
                        "{a:?} vs {b:?}"
                    );
                }
                assert!(a.t > 0.0 && a.t < t_max);
            }
            _ => panic!("ray {ray:?} t_max {t_max}: accel {a:?} vs brute {b:?}"),
        }
        assert_eq!(
            accel.occluded(&ray, t_max),
            b.is_some(),
            "occluded disagrees for {ray:?}"
        );
        if let Some(b) = b {
            // Occlusion just short of the hit must ignore it (unless another hit ties).
            let o2 = accel.occluded(&ray, b.t);
            assert_eq!(o2, accel.intersect(&ray, b.t).is_some());
        }
    }
}

/// `proto` placed by `m` (an affine map) in world space, for the brute-force reference.
fn placed(proto: &AccelShape, m: Mat4) -> AccelShape {
    match proto {
        AccelShape::Triangles { positions, indices } => AccelShape::Triangles {
            positions: positions.iter().map(|p| m.transform_point3a(*p)).collect(),
            indices: indices.clone(),
        },
        &AccelShape::Sphere { center, radius } => AccelShape::Ellipsoid {
            to_world: m
                * Mat4::from_translation(center.into())
                * Mat4::from_scale(glam::Vec3::splat(radius)),
        },
        &AccelShape::Ellipsoid { to_world } => AccelShape::Ellipsoid {
            to_world: m * to_world,
        },
        &AccelShape::Disk { to_world } => AccelShape::Disk {
            to_world: m * to_world,
        },
        &AccelShape::Cylinder { to_world } => AccelShape::Cylinder {
            to_world: m * to_world,
        },
        other => other.clone(),
    }
}

/// Instances (rotated, non-uniformly and mirror scaled, some moving) of a few prototypes among
/// ordinary shapes agree with the same scene flattened at each ray's time. The instanced
/// query works in object space, so `t` agrees to rounding and a ray grazing an edge may hit on
/// one side only: a few such disagreements are allowed.
#[test]
fn instances_match_flattened_brute_force() {
    let mut rng = Rng::new(21);
    let protos: Vec<AccelShape> = random_scene(&mut rng, 12, 30)
        .into_iter()
        .filter(|s| !matches!(s, AccelShape::Plane { .. }))
        .collect();
    let mut shapes = random_scene(&mut rng, 10, 6);
    let mut placements = Vec::new();
    for k in 0..40 {
        let proto = rng.u32() % protos.len() as u32;
        let mirror = if k % 5 == 0 { -1.0 } else { 1.0 };
        let to_world = Mat4::from_translation(rng.vec(-6.0, 6.0).into())
            * Mat4::from_axis_angle(rng.dir().into(), rng.range(0.0, 6.0))
            * Mat4::from_scale(glam::Vec3::new(
                mirror * rng.range(0.3, 1.5),
                rng.range(0.3, 1.5),
                rng.range(0.3, 1.5),
            ));
        let motion = if k % 2 == 0 {
            rng.vec(-3.0, 3.0)
        } else {
            Vec3::ZERO
        };
        placements.push((shapes.len(), proto, to_world, motion));
        shapes.push(AccelShape::Instance {
            proto,
            to_world,
            motion,
        });
    }
    let accel = Accel::build_instanced(shapes.clone(), protos.clone());
    assert_eq!(accel.instancing_stats().0, protos.len());
    let (rays, mut disagree) = (3000, 0);
    let mut hits = 0;
    for i in 0..rays {
        let time = if i % 4 == 0 { 0.0 } else { rng.f() };
        let ray = Ray::at_time(rng.vec(-9.0, 9.0), rng.dir() * rng.range(0.5, 2.0), time);
        let mut flat = shapes.clone();
        for &(s, proto, to_world, motion) in &placements {
            let m = Mat4::from_translation((motion * time).into()) * to_world;
            flat[s] = placed(&protos[proto as usize], m);
        }
        let a = accel.intersect(&ray, f32::INFINITY);
        let b = brute(&flat, &ray, f32::INFINITY);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) if a.shape == b.shape && close(a.t, b.t, 1e-4) => {
                hits += 1;
                assert!(accel.occluded(&ray, a.t * 1.001));
            }
            _ => disagree += 1,
        }
        assert_eq!(
            accel.occluded(&ray, f32::INFINITY),
            a.is_some(),
            "occluded and intersect disagree for {ray:?}"
        );
    }
    println!("{hits} agreeing hits, {disagree} disagreements of {rays} rays");
    assert!(hits > rays / 6, "only {hits} hits");
    assert!(disagree <= rays / 500, "{disagree} of {rays} rays disagree");
}

#[test]
fn bvh_matches_brute_force_small_scenes() {
    let mut rng = Rng::new(9);
    for n in [1, 2, 3, 5, 10, 10, 20] {
        let shapes = random_scene(&mut rng, n, 6);
        compare_with_brute(shapes, &mut rng, 400);
    }
}

#[test]
fn bvh_matches_brute_force_large_scene() {
    let mut rng = Rng::new(10);
    let shapes = random_scene(&mut rng, 60, 400);
    compare_with_brute(shapes, &mut rng, 1500);
}

#[test]
fn coincident_primitives_build_and_hit() {
    // Thousands of identical triangles and spheres: a degenerate build must not fail and must
    // still report the (tied) closest hit.
    let tri = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let positions: Arc<[Vec3]> = tri.to_vec().into();
    let indices: Arc<[[u32; 3]]> = vec![[0, 1, 2]; 5000].into();
    let mut shapes = vec![AccelShape::Triangles { positions, indices }];
    shapes.extend((0..300).map(|_| AccelShape::Sphere {
        center: Vec3::new(0.0, 0.0, 5.0),
        radius: 1.0,
    }));
    let accel = Accel::build(shapes);
    let ray = Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::Z);
    let h = accel.intersect(&ray, f32::INFINITY).unwrap();
    assert_eq!((h.shape, h.t), (0, 3.0));
    let ray = Ray::new(Vec3::new(0.0, 0.0, 10.0), -Vec3::Z);
    let h = accel.intersect(&ray, f32::INFINITY).unwrap();
    assert!(h.shape >= 1 && close(h.t, 4.0, 1e-6));
    assert!(accel.occluded(&ray, f32::INFINITY));
}

#[test]
fn concurrent_queries() {
    let mut rng = Rng::new(11);
    let shapes = random_scene(&mut rng, 30, 100);
    let accel = Accel::build(shapes);
    let rays: Vec<Ray> = (0..2000)
        .map(|_| Ray::new(rng.vec(-8.0, 8.0), rng.dir()))
        .collect();
    let serial: Vec<Option<(u32, u32, f32)>> = rays
        .iter()
        .map(|r| {
            accel
                .intersect(r, f32::INFINITY)
                .map(|h| (h.shape, h.prim, h.t))
        })
        .collect();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..2)
            .map(|_| {
                s.spawn(|| {
                    rays.iter()
                        .map(|r| {
                            accel
                                .intersect(r, f32::INFINITY)
                                .map(|h| (h.shape, h.prim, h.t))
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            assert_eq!(h.join().unwrap(), serial);
        }
    });
}

#[test]
fn exponentially_spaced_spheres_deep_tree() {
    // Sizes and gaps growing geometrically give bottom-up builders a deep, caterpillar-like
    // tree: traversal must stay within its stack and still find the closest hit.
    let shapes: Vec<AccelShape> = (0..200)
        .map(|i| {
            let s = 1.5f32.powi(i);
            AccelShape::Sphere {
                center: Vec3::new(s, 0.0, 0.0),
                radius: 0.2 * s,
            }
        })
        .collect();
    let accel = Accel::build(shapes.clone());
    let mut rng = Rng::new(12);
    for _ in 0..300 {
        let i = (rng.u32() % 200) as i32;
        let s = 1.5f32.powi(i);
        let o = Vec3::new(
            s * rng.range(0.5, 3.0),
            s * rng.range(-0.1, 0.1),
            s * rng.range(-0.1, 0.1),
        );
        let ray = Ray::new(
            o,
            Vec3::new(-1.0, rng.range(-0.05, 0.05), rng.range(-0.05, 0.05)),
        );
        let a = accel.intersect(&ray, f32::INFINITY).map(|h| (h.shape, h.t));
        let b = brute(&shapes, &ray, f32::INFINITY).map(|h| (h.shape, h.t));
        assert_eq!(a, b, "ray {ray:?}");
        assert_eq!(accel.occluded(&ray, f32::INFINITY), b.is_some());
    }
}
