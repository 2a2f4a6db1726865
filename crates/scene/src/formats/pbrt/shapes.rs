//! pbrt-v4 shapes → the scene model: triangle meshes (inline or PLY), spheres and disks as
//! themselves, and the shapes our renderer lacks (cylinders, partial spheres and disks,
//! bilinear patches, Loop subdivision surfaces) as triangles made at load time. Alpha, area
//! lights, media and `ReverseOrientation` apply to every kind.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3};

use super::params::{Params, Ty};
use super::parser::{Loader, TexVal, motion_of};
use crate::model::*;
use crate::{LoadError, Loc, Result};

/// Segments around a tessellated cylinder or partial disk (the rendered outline differs from
/// the true circle by less than 1 - cos(π/N) of the radius: 1.2e-4 at 256).
const SEGMENTS: u32 = 256;
/// Most triangles a load-time tessellation (subdivision, patches) may make.
const MAX_GENERATED: usize = 1 << 24;

fn err(loc: &Loc, m: impl Into<String>) -> LoadError {
    LoadError::new(loc.clone(), m)
}

impl Loader {
    pub(super) fn make_shape(&mut self, ty: &str, p: &Params, loc: &Loc) -> Result<()> {
        let [m0, m1] = self.gs.ctm;
        let mut to_world = m0;
        let mut object_area: Option<f32> = None;
        let shape = match ty {
            "trianglemesh" => Shape::Mesh(Arc::new(triangle_mesh(p, loc)?)),
            "plymesh" => {
                let Some((file, fp)) = p.string_opt("filename")? else {
                    return Err(err(loc, "plymesh needs a \"string filename\""));
                };
                let path = self.resolve(file);
                if !path.is_file() {
                    return Err(fp.err(format!("PLY file '{}' not found", path.display())));
                }
                if p.get("displacement", &[Ty::Texture])?.is_some() {
                    let _ = p.float("edgelength", 1.0);
                    self.warn(loc, "plymesh: 'displacement' is not supported (ignored)");
                }
                match self.meshes.get(&path) {
                    Some(m) => Shape::Mesh(m.clone()),
                    None => {
                        let mesh = Arc::new(read_ply(&path)?);
                        self.meshes.insert(path, mesh.clone());
                        Shape::Mesh(mesh)
                    }
                }
            }
            "sphere" => {
                let r = p.float("radius", 1.0)?;
                let z0 = p.float("zmin", -r)?;
                let z1 = p.float("zmax", r)?;
                let phimax = p.float("phimax", 360.0)?;
                if !(r > 0.0 && r.is_finite() && z0.is_finite() && z1.is_finite()) {
                    return Err(err(loc, format!("sphere: radius {r} must be positive")));
                }
                // pbrt-v4 orders and clamps the z range and clamps φmax to [0°, 360°].
                let (zmin, zmax) = (z0.min(z1).clamp(-r, r), z0.max(z1).clamp(-r, r));
                let phimax = phimax.clamp(0.0, 360.0).to_radians();
                object_area = Some(phimax * r * (zmax - zmin));
                if zmin > -r || zmax < r || phimax < 2.0 * PI {
                    Shape::Mesh(Arc::new(partial_sphere(r, zmin, zmax, phimax)))
                } else {
                    // Ours runs v = θ/π from +z, pbrt-v4's v = 1 − θ/π: mirrored in z the
                    // sphere and its u = φ/2π are unchanged and v becomes pbrt's. Not on
                    // sphere lights: a mirrored sphere in a textured scene is built as an
                    // ellipsoid, whose emission is sampled by area rather than by the cone
                    // the sphere subtends.
                    if self.gs.area_light.is_none() {
                        to_world = m0 * Mat4::from_scale(Vec3::new(1.0, 1.0, -1.0));
                    }
                    Shape::Sphere {
                        center: Vec3::ZERO,
                        radius: r,
                    }
                }
            }
            "disk" => {
                let h = p.float("height", 0.0)?;
                let r = p.float("radius", 1.0)?;
                let ri = p.float("innerradius", 0.0)?;
                let phimax = p.float("phimax", 360.0)?.clamp(0.0, 360.0);
                if !(r > 0.0 && r.is_finite() && ri >= 0.0 && ri < r && h.is_finite()) {
                    return Err(err(loc, "disk: needs 0 ≤ innerradius < radius"));
                }
                object_area = Some(phimax.to_radians() * 0.5 * (r * r - ri * ri));
                if ri == 0.0 && phimax >= 360.0 {
                    to_world = m0
                        * Mat4::from_translation(Vec3::new(0.0, 0.0, h))
                        * Mat4::from_scale(Vec3::new(r, r, 1.0));
                    Shape::Disk
                } else {
                    Shape::Mesh(Arc::new(annulus(h, ri, r, phimax.to_radians())))
                }
            }
            "cylinder" => {
                let r = p.float("radius", 1.0)?;
                let z0 = p.float("zmin", -1.0)?;
                let z1 = p.float("zmax", 1.0)?;
                let phimax = p.float("phimax", 360.0)?.clamp(0.0, 360.0);
                if !(r > 0.0 && r.is_finite() && z0.is_finite() && z1.is_finite()) {
                    return Err(err(loc, "cylinder: needs a positive radius"));
                }
                let (z0, z1) = (z0.min(z1), z0.max(z1));
                object_area = Some((z1 - z0) * r * phimax.to_radians());
                Shape::Mesh(Arc::new(cylinder(r, z0, z1, phimax.to_radians())))
            }
            "bilinearmesh" => Shape::Mesh(Arc::new(bilinear_mesh(p, loc)?)),
            "loopsubdiv" => {
                let levels = p.int_in("levels", 3, 0, 8)? as u32;
                let mesh = super::subdiv::loop_subdivide(p, levels, loc)?;
                Shape::Mesh(Arc::new(mesh))
            }
            "curve" => {
                return Err(err(
                    loc,
                    "shape \"curve\" (hair and curves) is not supported yet",
                ));
            }
            _ => {
                return Err(err(
                    loc,
                    format!(
                        "unknown shape \"{ty}\" (pbrt-v4 has trianglemesh, plymesh, sphere, disk, \
                         cylinder, bilinearmesh, loopsubdiv, curve)"
                    ),
                ));
            }
        };

        // pbrt-v4 starts with a "diffuse" material (reflectance 0.5) in the graphics state,
        // so that an area light without a Material directive reflects too; the scene model's
        // `None` would make an emitter black (Mitsuba's rule).
        let mut material = match self.gs.material {
            Some(m) => m,
            None => self.default_material(loc),
        };
        // Alpha: a constant or a float texture, as a mask around the material.
        if let Some(t) = self.tex_param(p, "alpha", false, super::build::Usage::Unbounded)? {
            let opacity = match t {
                TexVal::Const(c) if c.x >= 1.0 => None,
                TexVal::Const(c) => Some(FloatParam::Const(c.x.max(0.0))),
                TexVal::Spectrum(s) => Some(FloatParam::Const(s.rgb.x)),
                TexVal::Tex(t) => Some(FloatParam::Texture(t)),
            };
            if let Some(opacity) = opacity {
                material = self.scene.add_material(MaterialDesc {
                    material: Material::Mask {
                        nested: material,
                        opacity,
                    },
                    ambient: Rgb::ZERO,
                    name: None,
                    loc: loc.clone(),
                });
            }
        }
        let _ = p.get("emission", &[Ty::Rgb, Ty::Spectrum, Ty::Blackbody]);
        self.finish_params("Shape", ty, p);

        let mut desc = ShapeDesc {
            shape,
            to_world,
            material: Some(material),
            emission: None,
            flip_normals: self.gs.reverse,
            media: MediumInterface {
                interior: self.medium_id(&self.gs.inside.clone(), loc)?,
                exterior: self.medium_id(&self.gs.outside.clone(), loc)?,
            },
            motion: motion_of(&m0, &m1),
            name: None,
            loc: loc.clone(),
        };
        if m0 != m1 && desc.motion.is_none() {
            self.warn_once(
                "shape motion",
                loc,
                "only translating motion is supported: shapes use their shutter-open transform",
            );
        }
        if let Some(area) = self.gs.area_light.clone() {
            if self.object.is_some() {
                self.warn_once(
                    "instanced area light",
                    loc,
                    "area lights inside ObjectBegin are ignored (as pbrt-v4 does)",
                );
            } else {
                let a = world_area(&desc, object_area);
                desc.emission = Some(self.area_emission(&area.1, a, loc)?);
            }
        }
        match &mut self.object {
            Some((_, shapes)) => shapes.push(desc),
            None => self.scene.shapes.push(desc),
        }
        Ok(())
    }

    /// pbrt's default material (diffuse, reflectance 0.5), made once when a mask needs it.
    fn default_material(&mut self, loc: &Loc) -> MaterialId {
        if let Some(&id) = self.named_materials.get("\u{0}default") {
            return id;
        }
        let id = self.scene.add_material(MaterialDesc {
            material: Material::Diffuse {
                reflectance: ColorParam::constant(0.5),
            },
            ambient: Rgb::ZERO,
            name: None,
            loc: loc.clone(),
        });
        self.named_materials.insert("\u{0}default".into(), id);
        id
    }
}

/// The world-space area of a shape, for an area light's `power`: meshes exactly, spheres and
/// disks as pbrt-v4 measures them (in object space).
fn world_area(s: &ShapeDesc, object_area: Option<f32>) -> Option<f32> {
    match &s.shape {
        Shape::Mesh(m) => Some(
            m.indices
                .iter()
                .map(|&[a, b, c]| {
                    let p = |i: u32| s.to_world.transform_point3(m.positions[i as usize]);
                    0.5 * (p(b) - p(a)).cross(p(c) - p(a)).length()
                })
                .sum(),
        ),
        _ => object_area,
    }
}

fn read_ply(path: &std::path::Path) -> Result<TriMesh> {
    let name = path.to_string_lossy();
    if name.ends_with(".gz") {
        let data = base::read_file(path)
            .map_err(|e| err(&Loc::file(path), format!("cannot read PLY file: {e}")))?;
        let mut out = Vec::new();
        use std::io::Read;
        flate2::read::GzDecoder::new(&data[..])
            .take(1 << 32)
            .read_to_end(&mut out)
            .map_err(|e| err(&Loc::file(path), format!("cannot decompress: {e}")))?;
        return crate::formats::ply::parse_ply(&out, path);
    }
    crate::formats::ply::read_ply(path)
}

/// Indices (3 per triangle, or 4 per patch) checked against the vertex count.
fn indices(p: &Params, name: &str, per: usize, n: usize, loc: &Loc) -> Result<Option<Vec<u32>>> {
    let Some(q) = p.nums(name, Ty::Integer)? else {
        return Ok(None);
    };
    let v = q.nums();
    if v.len() % per != 0 {
        return Err(q.err(format!("{} indices are not a multiple of {per}", v.len())));
    }
    let mut out = Vec::with_capacity(v.len());
    for &i in v {
        if i < 0.0 || i >= n as f64 {
            return Err(q.err(format!("index {i} is outside the {n} vertices")));
        }
        out.push(i as u32);
    }
    let _ = loc;
    Ok(Some(out))
}

fn points3(p: &Params, name: &str, ty: Ty) -> Result<Option<Vec<Vec3>>> {
    Ok(p.nums(name, ty)?.map(|q| {
        q.nums()
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect()
    }))
}

/// uv coordinates: `point2 uv` (pbrt-v4), or pbrt-v3's `float uv` / `st` lists.
fn uvs(p: &Params, n: usize) -> Result<Vec<Vec2>> {
    let q = match p.get("uv", &[Ty::Point2, Ty::Float])? {
        Some(q) => Some(q),
        None => p.get("st", &[Ty::Point2, Ty::Float])?,
    };
    let Some(q) = q else { return Ok(Vec::new()) };
    let v: Vec<Vec2> = q
        .nums()
        .chunks_exact(2)
        .map(|c| Vec2::new(c[0] as f32, c[1] as f32))
        .collect();
    if v.len() != n {
        return Err(q.err(format!("{} uvs for {n} vertices", v.len())));
    }
    Ok(v)
}

fn triangle_mesh(p: &Params, loc: &Loc) -> Result<TriMesh> {
    let Some(positions) = points3(p, "P", Ty::Point3)? else {
        return Err(err(loc, "trianglemesh needs \"point3 P\""));
    };
    let n = positions.len();
    let idx = match indices(p, "indices", 3, n, loc)? {
        Some(i) => i,
        None if n == 3 => vec![0, 1, 2],
        None => {
            return Err(err(
                loc,
                "trianglemesh without \"integer indices\" must have exactly 3 points",
            ));
        }
    };
    let normals = match points3(p, "N", Ty::Normal)? {
        Some(v) if v.len() != n => {
            return Err(err(
                loc,
                format!("trianglemesh: {} normals for {n} points", v.len()),
            ));
        }
        Some(v) => v,
        None => Vec::new(),
    };
    let uvs = uvs(p, n)?;
    let _ = p.get("S", &[Ty::Vector3])?;
    let _ = p.get("faceIndices", &[Ty::Integer])?;
    Ok(TriMesh {
        positions,
        normals,
        uvs,
        indices: idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    })
}

/// Bilinear patches (vertices p00 p10 p01 p11): planar ones as two triangles, others as a
/// grid of 8 × 8 quads.
fn bilinear_mesh(p: &Params, loc: &Loc) -> Result<TriMesh> {
    let Some(pos) = points3(p, "P", Ty::Point3)? else {
        return Err(err(loc, "bilinearmesh needs \"point3 P\""));
    };
    let n = pos.len();
    let idx = match indices(p, "indices", 4, n, loc)? {
        Some(i) => i,
        None if n == 4 => vec![0, 1, 2, 3],
        None => return Err(err(loc, "bilinearmesh without indices must have 4 points")),
    };
    let normals = points3(p, "N", Ty::Normal)?.unwrap_or_default();
    if !normals.is_empty() && normals.len() != n {
        return Err(err(loc, "bilinearmesh: one normal per point is needed"));
    }
    let uv = uvs(p, n)?;
    let _ = p.get("faceIndices", &[Ty::Integer])?;
    let mut m = TriMesh::default();
    for q in idx.chunks_exact(4) {
        let c = [q[0], q[1], q[2], q[3]].map(|i| i as usize);
        let [p00, p10, p01, p11] = c.map(|i| pos[i]);
        let planar = (p10 - p00).cross(p01 - p00).dot(p11 - p00).abs()
            <= 1e-6 * (p11 - p00).length().powi(3).max(f32::MIN_POSITIVE);
        let k = if planar { 1 } else { 8 };
        if m.indices.len() + 2 * k * k > MAX_GENERATED {
            return Err(err(loc, "bilinearmesh: too many patches"));
        }
        let base = m.positions.len() as u32;
        for j in 0..=k {
            for i in 0..=k {
                let (u, v) = (i as f32 / k as f32, j as f32 / k as f32);
                let lerp4 = |a: Vec3, b: Vec3, cc: Vec3, d: Vec3| {
                    (1.0 - u) * (1.0 - v) * a + u * (1.0 - v) * b + (1.0 - u) * v * cc + u * v * d
                };
                m.positions.push(lerp4(p00, p10, p01, p11));
                if !normals.is_empty() {
                    let [a, b, cc, d] = c.map(|i| normals[i]);
                    m.normals.push(lerp4(a, b, cc, d).normalize_or_zero());
                }
                let uvp = if uv.is_empty() {
                    Vec2::new(u, v)
                } else {
                    let [a, b, cc, d] = c.map(|i| uv[i]);
                    (1.0 - u) * (1.0 - v) * a + u * (1.0 - v) * b + (1.0 - u) * v * cc + u * v * d
                };
                m.uvs.push(uvp);
            }
        }
        let at = |i: usize, j: usize| base + (j * (k + 1) + i) as u32;
        for j in 0..k {
            for i in 0..k {
                // pbrt's patch normal is ∂p/∂u × ∂p/∂v: (p10 − p00) × (p01 − p00).
                m.indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                m.indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    Ok(m)
}

/// A partial disk or annulus in the plane z = h (normal +z), uv as pbrt's:
/// u = φ/φmax, v = (r − r_inner)... pbrt's v runs from the outer edge (0) inwards.
fn annulus(h: f32, ri: f32, r: f32, phimax: f32) -> TriMesh {
    let n = ((SEGMENTS as f32 * phimax / (2.0 * PI)).ceil() as u32).max(1);
    let mut m = TriMesh::default();
    for i in 0..=n {
        let phi = phimax * i as f32 / n as f32;
        let (s, c) = phi.sin_cos();
        for (rad, v) in [(r, 0.0), (ri, 1.0)] {
            m.positions.push(Vec3::new(rad * c, rad * s, h));
            m.normals.push(Vec3::Z);
            m.uvs.push(Vec2::new(i as f32 / n as f32, v));
        }
    }
    for i in 0..n {
        let (o0, i0, o1, i1) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        m.indices.push([o0, o1, i1]);
        if ri > 0.0 {
            m.indices.push([o0, i1, i0]);
        }
    }
    m
}

/// Rings of a tessellated partial sphere per π of θ (its segments in φ are [`SEGMENTS`] per
/// 2π: both steps 2π/256).
const RINGS: u32 = SEGMENTS / 2;

/// The part of the sphere of radius `r` between the heights `zmin` and `zmax` and the angles
/// φ ∈ [0, φmax], open, with outward normals and pbrt-v4's uv: u = φ/φmax,
/// v = (θ − θmin)/(θmax − θmin), θ from +z, θmin at `zmin`.
fn partial_sphere(r: f32, zmin: f32, zmax: f32, phimax: f32) -> TriMesh {
    let (t0, t1) = (
        (zmin / r).clamp(-1.0, 1.0).acos(),
        (zmax / r).clamp(-1.0, 1.0).acos(),
    );
    let n = ((SEGMENTS as f32 * phimax / (2.0 * PI)).ceil() as u32).max(1);
    let k = ((RINGS as f32 * (t0 - t1) / PI).ceil() as u32).max(1);
    let mut m = TriMesh::default();
    for j in 0..=k {
        let theta = t0 + (t1 - t0) * j as f32 / k as f32;
        let (mut st, mut ct) = theta.sin_cos();
        // A ring at a pole is exactly a point, so that its triangles collapse exactly.
        if j == 0 && zmin <= -r || j == k && zmax >= r {
            (st, ct) = (0.0, ct.signum());
        }
        for i in 0..=n {
            let (sp, cp) = (phimax * i as f32 / n as f32).sin_cos();
            let d = Vec3::new(st * cp, st * sp, ct);
            m.positions.push(d * r);
            m.normals.push(d);
            m.uvs
                .push(Vec2::new(i as f32 / n as f32, j as f32 / k as f32));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..k {
        for i in 0..n {
            // Ring j is below ring j + 1; a ring at a pole is a point, and its triangles
            // collapse: those are left out.
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            for t in [[a, b, c], [a, c, d]] {
                let [p, q, w] = t.map(|v| m.positions[v as usize]);
                if (q - p).cross(w - p).length_squared() > 0.0 {
                    m.indices.push(t);
                }
            }
        }
    }
    m
}

/// A cylinder around z from z0 to z1 with outward normals, uv = (φ/φmax, (z − z0)/(z1 − z0)).
fn cylinder(r: f32, z0: f32, z1: f32, phimax: f32) -> TriMesh {
    let n = ((SEGMENTS as f32 * phimax / (2.0 * PI)).ceil() as u32).max(1);
    let mut m = TriMesh::default();
    for i in 0..=n {
        let phi = phimax * i as f32 / n as f32;
        let (s, c) = phi.sin_cos();
        for (z, v) in [(z0, 0.0), (z1, 1.0)] {
            m.positions.push(Vec3::new(r * c, r * s, z));
            m.normals.push(Vec3::new(c, s, 0.0));
            m.uvs.push(Vec2::new(i as f32 / n as f32, v));
        }
    }
    for i in 0..n {
        let (b0, t0, b1, t1) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        m.indices.push([b0, b1, t1]);
        m.indices.push([b0, t1, t0]);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(m: &TriMesh) -> f64 {
        m.indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// The tessellation (2π/256 steps in φ and θ) is inscribed in the sphere: its area falls
    /// short of pbrt-v4's φmax·r·(zmax − zmin) by less than 2e-4 relative, its uv are pbrt's.
    #[test]
    fn partial_spheres_have_pbrts_area_and_uv() {
        for (r, z0, z1, phimax) in [
            (1.0f32, -1.0f32, 1.0f32, 2.0 * PI),
            (2.0, -0.5, 1.5, PI / 3.0),
            (0.5, 0.0, 0.5, 1.9 * PI),
            (1.0, -0.999, -0.99, 0.01),
        ] {
            let m = partial_sphere(r, z0, z1, phimax);
            let want = f64::from(phimax * r * (z1 - z0));
            let rel = (area(&m) - want) / want;
            assert!(
                (-2e-4..=0.0).contains(&rel),
                "{r} {z0} {z1} {phimax}: {rel:e}"
            );
            for (p, uv) in m.positions.iter().zip(&m.uvs) {
                let phi = p.y.atan2(p.x).rem_euclid(2.0 * PI);
                let phi = if uv.x > 0.5 && phi < 1e-3 {
                    2.0 * PI
                } else {
                    phi
                };
                let theta = (p.z / r).clamp(-1.0, 1.0).acos();
                let (t0, t1) = ((z0 / r).acos(), (z1 / r).acos());
                let v = (theta - t0) / (t1 - t0);
                if p.x.hypot(p.y) > 1e-4 * r {
                    assert!((phi / phimax - uv.x).abs() < 1e-3, "u at {p}: {uv}");
                }
                assert!((v - uv.y).abs() < 1e-3, "v at {p}: {uv}");
                assert!((p.length() - r).abs() < 1e-5 * r);
            }
        }
    }

    #[test]
    fn tessellated_normals_face_out() {
        let c = cylinder(1.0, -1.0, 1.0, 2.0 * PI);
        for t in &c.indices {
            let [a, b, d] = t.map(|i| c.positions[i as usize]);
            let n = (b - a).cross(d - a);
            let mid = (a + b + d) / 3.0;
            assert!(n.dot(Vec3::new(mid.x, mid.y, 0.0)) > 0.0);
        }
        let s = partial_sphere(2.0, -2.0, 1.0, 1.5 * PI);
        for t in &s.indices {
            let [a, b, d] = t.map(|i| s.positions[i as usize]);
            assert!((b - a).cross(d - a).dot(a + b + d) > 0.0);
        }
        let d = annulus(0.5, 0.25, 1.0, PI);
        for t in &d.indices {
            let [a, b, e] = t.map(|i| d.positions[i as usize]);
            assert!((b - a).cross(e - a).z > 0.0);
        }
    }
}
