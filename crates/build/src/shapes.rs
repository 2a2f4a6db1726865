//! Shape factories: scene shapes to world-space runtime geometry, with instancing of shared
//! meshes and motion, and the per-shape runtime record ([`ShapeInfo`]).

use std::collections::HashMap;
use std::sync::Arc;

use render::materials::RtMaterial;
use render::math::{Mat3, Mat4, PVec3, Vec2, Vec3};
use render::shapes::{Cylinder, Ellipsoid, Instance, Reads, ShapeGeom, ShapeInfo};

use scene::{Material, SceneDesc, Shape, TriMesh};

use crate::materials::{Declared, float_ref};
use crate::{BuildError, BuildOptions};

/// The world-space geometry of a scene's shapes (one per shape, in order; instances refer to
/// `protos`), and a warning about motion that was dropped. It depends on the shapes' own
/// geometry only (shape, transform, motion, whether they emit), on whether the scene has
/// textures (rotated textured spheres) and on `flatten_instances`: not on materials or
/// lights, so that a build after a material or light edit reuses it (see [`crate::BuildCache`]).
pub(crate) struct Geometry {
    pub geoms: Vec<ShapeGeom>,
    pub protos: Vec<ShapeGeom>,
    pub warning: Option<String>,
}

/// The geometry of every shape of `desc` (see [`Geometry`]).
pub(crate) fn geometry(desc: &SceneDesc, opts: &BuildOptions) -> Result<Geometry, BuildError> {
    // Instancing: a mesh shared (same `Arc`) by two or more shapes that do not emit is a
    // prototype, built once in its object space; each of its shapes is an instance. A mesh
    // used once is copied to world space as before. Emitters are always copied: light
    // sampling works on world-space triangles.
    let mut uses: HashMap<*const TriMesh, u32> = HashMap::new();
    if !opts.flatten_instances {
        for s in &desc.shapes {
            if let Shape::Mesh(m) = &s.shape
                && s.emission.is_none()
            {
                *uses.entry(Arc::as_ptr(m)).or_default() += 1;
            }
        }
    }
    let mut proto_of: HashMap<*const TriMesh, u32> = HashMap::new();
    let mut protos: Vec<ShapeGeom> = Vec::new();
    let mut motion_ignored = false;
    let mut geoms = Vec::with_capacity(desc.shapes.len());
    for s in &desc.shapes {
        // Emitters and infinite planes do not move (light sampling is static; a plane has
        // no bounds to sweep).
        let motion = s
            .motion
            .filter(|m| *m != PVec3::ZERO && m.is_finite())
            .filter(|_| {
                let ok = s.emission.is_none() && !matches!(s.shape, Shape::InfinitePlane { .. });
                motion_ignored |= !ok;
                ok
            })
            .map(Vec3::from);
        let shared = match &s.shape {
            Shape::Mesh(m) if uses.get(&Arc::as_ptr(m)).is_some_and(|&n| n >= 2) => Some(m),
            _ => None,
        };
        let instanced = shared.and_then(|m| {
            let next = protos.len() as u32;
            let proto = *proto_of.entry(Arc::as_ptr(m)).or_insert(next);
            if proto == next {
                protos.push(mesh_geom(m, &Mat4::IDENTITY));
            }
            Instance::new(
                protos[proto as usize].clone(),
                proto,
                s.to_world,
                motion.unwrap_or(Vec3::ZERO),
            )
        });
        let geom = match (&s.shape, instanced) {
            (_, Some(i)) => ShapeGeom::Instance(Box::new(i)),
            (Shape::Mesh(m), None) => mesh_geom(m, &s.to_world),
            (Shape::Rectangle, None) => mesh_geom(&rectangle_mesh(), &s.to_world),
            (Shape::Cube, None) => mesh_geom(&cube_mesh(), &s.to_world),
            (Shape::Sphere { center, radius }, None)
                if scene::is_similarity(&s.to_world)
                    && (desc.textures.is_empty() || no_rotation(&s.to_world)) =>
            {
                // A rotation, uniform scale and translation keep it a sphere (and its uv
                // parameterisation too unless rotated: textured rotated spheres go below).
                let c = s.to_world.transform_point3(*center);
                let r = s
                    .to_world
                    .transform_vector3(PVec3::new(*radius, 0.0, 0.0))
                    .length();
                ShapeGeom::Sphere {
                    center: c.into(),
                    radius: r,
                }
            }
            (Shape::Sphere { center, radius }, None) => {
                // Non-uniform scale or shear: an ellipsoid, the unit sphere of this frame (also a
                // rotated textured sphere, whose uv turns with it).
                let frame = s.to_world
                    * Mat4::from_translation(*center)
                    * Mat4::from_scale(PVec3::splat(*radius));
                match Ellipsoid::new(frame) {
                    Some(e) => ShapeGeom::Ellipsoid(Box::new(e)),
                    None => {
                        return Err(BuildError {
                            loc: s.loc.clone(),
                            message: "sphere with a singular or non-finite transformation".into(),
                        });
                    }
                }
            }
            (Shape::Cylinder, None) => match Cylinder::new(s.to_world) {
                Some(c) => ShapeGeom::Cylinder(Box::new(c)),
                None => {
                    return Err(BuildError {
                        loc: s.loc.clone(),
                        message: "cylinder with a singular or non-finite transformation".into(),
                    });
                }
            },
            (Shape::Disk, None) => {
                let n = (Mat3::from_mat4(s.to_world).inverse().transpose() * Vec3::Z)
                    .normalize_or_zero();
                ShapeGeom::Disk {
                    to_world: s.to_world,
                    normal: n,
                }
            }
            (Shape::InfinitePlane { point, normal }, None) => {
                let nm = Mat3::from_mat4(s.to_world).inverse().transpose();
                ShapeGeom::Plane {
                    point: s.to_world.transform_point3(*point).into(),
                    normal: (nm * *normal).normalize_or_zero().into(),
                }
            }
        };
        // A moving shape that is not already an instance: its own prototype, in world space
        // at time 0, moved by the instance's translation.
        let geom = match (geom, motion) {
            (ShapeGeom::Instance(i), _) => ShapeGeom::Instance(i),
            (g, Some(m)) => {
                let proto = protos.len() as u32;
                protos.push(g.clone());
                match Instance::new(g, proto, Mat4::IDENTITY, m) {
                    Some(i) => ShapeGeom::Instance(Box::new(i)),
                    None => unreachable!("the identity is invertible"),
                }
            }
            (g, None) => g,
        };
        geoms.push(geom);
    }
    let warning = motion_ignored.then(|| {
        format!(
            "{}: warning: motion blur of emitters and infinite planes is not supported; they stay at their time-0 place",
            desc.source.display()
        )
    });
    Ok(Geometry {
        geoms,
        protos,
        warning,
    })
}

/// The runtime record of every shape of `desc`, around its geometry `geoms` (from
/// [`geometry`]): `materials` are the resolved materials, `default_material` the index of
/// Mitsuba's default diffuse among them, `beer` the medium of Beer absorption inside each
/// scene material (`media::beer_media`), which a shape without a declared interior gets as
/// its interior.
pub(crate) fn shape_infos(
    desc: &SceneDesc,
    geoms: Vec<ShapeGeom>,
    materials: &[RtMaterial],
    default_material: u32,
    beer: &[Option<u32>],
    declared: &mut Declared,
) -> Vec<ShapeInfo> {
    let mut shapes = Vec::with_capacity(geoms.len());
    for (s, geom) in desc.shapes.iter().zip(geoms) {
        // Shapes without a material get Mitsuba's default diffuse, emitters none.
        let material = match s.material {
            Some(m) => Some(m.0),
            None if s.emission.is_none() => Some(default_material),
            None => None,
        };
        shapes.push(ShapeInfo {
            geom,
            material,
            emission: s.emission.as_ref().map(|e| declared.color_ref(&e.radiance)),
            flip_normals: s.flip_normals,
            // Emitters stay whole: light sampling picks points on the entire surface.
            opacity: s.material.filter(|_| s.emission.is_none()).and_then(|m| {
                match &desc.materials[m.0 as usize].material {
                    Material::Mask { opacity, .. } => Some(float_ref(opacity)),
                    _ => None,
                }
            }),
            interior: s.media.interior.map(|m| m.0).or_else(|| {
                s.material
                    .and_then(|m| beer.get(m.0 as usize).copied().flatten())
            }),
            exterior: s.media.exterior.map(|m| m.0),
            reads: Reads {
                tangent: !material.is_none_or(|m| materials[m as usize].isotropic()),
                // Only textures read uv (material and emitter parameters, normal maps and
                // opacity masks all go through one).
                uv: !desc.textures.is_empty(),
            },
        });
    }
    shapes
}

pub(crate) fn mesh_geom(mesh: &TriMesh, to_world: &Mat4) -> ShapeGeom {
    let positions: Arc<[Vec3]> = mesh
        .positions
        .iter()
        .map(|p| to_world.transform_point3a((*p).into()))
        .collect();
    let normal_matrix = Mat3::from_mat4(*to_world).inverse().transpose();
    let normals =
        (!mesh.normals.is_empty() && mesh.normals.len() == mesh.positions.len()).then(|| {
            mesh.normals
                .iter()
                .map(|n| (normal_matrix * Vec3::from(*n)).normalize_or_zero())
                .collect::<Arc<[Vec3]>>()
        });
    let uvs = (!mesh.uvs.is_empty() && mesh.uvs.len() == mesh.positions.len())
        .then(|| Arc::<[Vec2]>::from(mesh.uvs.as_slice()));
    // A reflection in to_world flips the winding, hence the geometric normal: keep triangles
    // facing the way their (transformed) normals say by swapping two indices.
    let flip = Mat3::from_mat4(*to_world).determinant() < 0.0;
    let indices: Arc<[[u32; 3]]> = if flip {
        mesh.indices.iter().map(|&[a, b, c]| [a, c, b]).collect()
    } else {
        Arc::from(mesh.indices.as_slice())
    };
    // Vertex normals that only repeat each face's own normal (Mitsuba's rectangles and cubes,
    // OBJ files with per-face `vn`) change nothing but the cost of every hit and light sample:
    // the shading normal is then the geometric one.
    let normals = normals.filter(|n| !is_flat_shading(&positions, n, &indices));
    ShapeGeom::Mesh {
        positions,
        normals,
        uvs,
        indices,
    }
}

/// Whether every vertex normal of every triangle equals that triangle's geometric normal (up
/// to rounding), so that the normals can be dropped without changing any shading frame.
fn is_flat_shading(positions: &[Vec3], normals: &[Vec3], indices: &[[u32; 3]]) -> bool {
    let get = |v: &[Vec3], i: u32| v.get(i as usize).copied();
    indices.iter().all(|&[a, b, c]| {
        let (Some(p0), Some(p1), Some(p2), Some(n0), Some(n1), Some(n2)) = (
            get(positions, a),
            get(positions, b),
            get(positions, c),
            get(normals, a),
            get(normals, b),
            get(normals, c),
        ) else {
            return false;
        };
        let face = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        // A degenerate triangle is never hit nor sampled: its normals do not matter.
        face == Vec3::ZERO || [n0, n1, n2].iter().all(|n| n.dot(face) >= 1.0 - 1e-6)
    })
}

/// Mitsuba's rectangle: [-1,1]² at z = 0, normal +z, uv ((x+1)/2, (y+1)/2).
pub fn rectangle_mesh() -> TriMesh {
    TriMesh {
        positions: vec![
            PVec3::new(-1.0, -1.0, 0.0),
            PVec3::new(1.0, -1.0, 0.0),
            PVec3::new(1.0, 1.0, 0.0),
            PVec3::new(-1.0, 1.0, 0.0),
        ],
        normals: vec![PVec3::Z; 4],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ],
        indices: vec![[0, 1, 2], [2, 3, 0]],
    }
}

/// Mitsuba's cube: [-1,1]³, 24 vertices with per-face normals and uvs, outward winding.
pub fn cube_mesh() -> TriMesh {
    let mut m = TriMesh::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = PVec3::ZERO;
            n[axis] = sign;
            // Two tangent axes forming a right-handed frame with n.
            let mut s = PVec3::ZERO;
            s[(axis + 1) % 3] = 1.0;
            let t = n.cross(s);
            let base = m.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                m.positions.push(n + s * a + t * b);
                m.normals.push(n);
                m.uvs.push(Vec2::new((a + 1.0) * 0.5, (b + 1.0) * 0.5));
            }
            m.indices.push([base, base + 1, base + 2]);
            m.indices.push([base + 2, base + 3, base]);
        }
    }
    m
}

/// The linear part of `m` is a multiple of the identity (no rotation, no reflection).
fn no_rotation(m: &glam::Mat4) -> bool {
    let l = glam::Mat3::from_mat4(*m);
    let d = l.x_axis.x;
    let off = l - glam::Mat3::from_diagonal(glam::Vec3::splat(d));
    off.to_cols_array()
        .iter()
        .all(|x| x.abs() <= 1e-6 * d.abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn has_normals(g: &ShapeGeom) -> bool {
        matches!(
            g,
            ShapeGeom::Mesh {
                normals: Some(_),
                ..
            }
        )
    }

    #[test]
    fn normals_that_repeat_the_faces_are_dropped() {
        // Rectangles and cubes (per-face normals), under a mirroring, non-uniform transform.
        let m = Mat4::from_scale(Vec3::new(-2.0, 0.5, 3.0).into()) * Mat4::from_rotation_y(0.4);
        assert!(!has_normals(&mesh_geom(&rectangle_mesh(), &m)));
        assert!(!has_normals(&mesh_geom(&cube_mesh(), &m)));
        // Smooth normals, or normals against the winding, stay.
        let mut smooth = rectangle_mesh();
        smooth.normals[2] = Vec3::new(0.3, 0.0, 1.0).normalize().into();
        assert!(has_normals(&mesh_geom(&smooth, &m)));
        let mut against = rectangle_mesh();
        against.normals = vec![(-Vec3::Z).into(); 4];
        assert!(has_normals(&mesh_geom(&against, &m)));
    }

    #[test]
    fn cube_faces_point_outwards() {
        let m = cube_mesh();
        assert_eq!(m.indices.len(), 12);
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a).normalize();
            let centre = (a + b + c) / 3.0;
            assert!(n.dot(centre) > 0.0, "face normal {n} at {centre}");
            assert!((n - m.normals[t[0] as usize]).length() < 1e-6);
        }
    }

    #[test]
    fn rectangle_faces_plus_z() {
        let m = rectangle_mesh();
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!((b - a).cross(c - a).z > 0.0);
        }
    }
}
