//! The step from scene description to renderable scene: `SceneDesc` → [`Scene`] (world-space
//! geometry and its BVH, decoded textures, lights, the chosen sensor's camera, film and
//! sampler, the integrator). The runtime scene itself and its queries live in
//! [`crate::world`].

use std::collections::HashMap;
use std::sync::Arc;

use scene::{
    ColorParam, CourseIdeal, CourseIdealKind, FloatParam, IntegratorDesc, LightSelection, Loc,
    Material, MaterialDesc, MaterialId, SceneDesc, Shape, TriMesh,
};

use crate::accel::Accel;
use crate::bsdf::{IdealLobe, Microfacet, MicrofacetType, NoriMicrofacet, RoughPlasticTables};
use crate::camera::Camera;
use crate::image_io::{self, Decode};
use crate::integrators::Integrator;
use crate::lights::select::LightSampler;
use crate::lights::{
    AreaLight, ConstantLight, DirectionalLight, EnvMap, Light, MeshSampling, PointLight, SpotLight,
};
use crate::materials::{CourseLobe, Layer, MaterialKind, Perturb, RtMaterial, Then, alpha};
use crate::math::{Mat3, Mat4, PVec3, Vec2, Vec3};
use crate::shapes::{Ellipsoid, Instance, Reads, ShapeGeom};
use crate::textures::{ColorRef, FloatRef, TexRef, Texture, Textures};
use crate::world::{Scene, ShapeInfo, ShapeLights};

/// A problem found while building (unreadable texture, unsupported feature).
#[derive(Clone, Debug, thiserror::Error)]
#[error("{loc}: {message}")]
pub struct BuildError {
    pub loc: Loc,
    pub message: String,
}

/// Command-line overrides applied on top of the scene's own settings.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Which sensor to render (index into `SceneDesc::sensors`).
    pub sensor: usize,
    pub spp: Option<u32>,
    pub resolution: Option<(u32, u32)>,
    pub seed: Option<u64>,
    pub integrator: Option<IntegratorDesc>,
    /// Overrides `SceneDesc::light_selection`.
    pub light_selection: Option<LightSelection>,
    /// Copy shared meshes into world space instead of instancing them (see [`build`]): the
    /// reference the instanced build is tested against.
    pub flatten_instances: bool,
}

fn mesh_geom(mesh: &TriMesh, to_world: &Mat4) -> ShapeGeom {
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

/// An opacity read from a bitmap whose file has an alpha channel uses that channel (an RGBA
/// `map_d`, or the diffuse map itself as exporters write it); files without one use their
/// first channel, as any scalar texture does. The alpha textures are appended to `textures`.
fn opacity_from_alpha(
    desc: &SceneDesc,
    shapes: &mut [ShapeInfo],
    textures: &mut Vec<Texture>,
) -> Result<(), BuildError> {
    let mut alpha_of: std::collections::HashMap<u32, Option<u32>> = Default::default();
    for shape in shapes.iter_mut() {
        let Some(TexRef::Texture(t)) = &mut shape.opacity else {
            continue;
        };
        let id = match alpha_of.get(t) {
            Some(id) => *id,
            None => {
                let id = alpha_texture(&desc.textures[*t as usize])?.map(|tex| {
                    textures.push(tex);
                    textures.len() as u32 - 1
                });
                alpha_of.insert(*t, id);
                id
            }
        };
        if let Some(id) = id {
            *t = id;
        }
    }
    Ok(())
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

/// The alpha channel of a bitmap texture as a texture, if the file has a non-opaque one.
fn alpha_texture(desc: &scene::TextureDesc) -> Result<Option<Texture>, BuildError> {
    let scene::Texture::Bitmap {
        path,
        filter,
        wrap,
        to_uv,
        corner_texels,
        ..
    } = &desc.texture
    else {
        return Ok(None);
    };
    let (mut image, alpha) =
        image_io::read_image_alpha(path, Decode::Raw).map_err(|e| BuildError {
            loc: desc.loc.clone(),
            message: format!("cannot read texture: {e}"),
        })?;
    if alpha.iter().all(|&a| a >= 1.0) {
        return Ok(None);
    }
    for (p, a) in image.pixels.iter_mut().zip(alpha) {
        *p = Vec3::splat(a);
    }
    Ok(Some(Texture::Bitmap {
        image: Arc::new(image),
        filter: *filter,
        wrap: *wrap,
        to_uv: *to_uv,
        corner_texels: *corner_texels,
    }))
}

fn load_texture(desc: &scene::TextureDesc) -> Result<Texture, BuildError> {
    load_texture_kind(&desc.texture, desc)
}

fn load_texture_kind(
    texture: &scene::Texture,
    desc: &scene::TextureDesc,
) -> Result<Texture, BuildError> {
    Ok(match texture {
        scene::Texture::Constant(c) => Texture::Constant((*c).into()),
        scene::Texture::Checkerboard {
            color0,
            color1,
            to_uv,
        } => Texture::Checkerboard {
            color0: (*color0).into(),
            color1: (*color1).into(),
            to_uv: *to_uv,
        },
        scene::Texture::Bitmap {
            path,
            filter,
            wrap,
            raw,
            gamma,
            to_uv,
            corner_texels,
        } => {
            // Loaders resolve file names (absolute, or relative to the working directory).
            let decode = match (raw, gamma) {
                (true, _) => Decode::Raw,
                (false, Some(g)) => Decode::Gamma(*g),
                (false, None) => Decode::Srgb,
            };
            let image = image_io::read_image_with(path, decode).map_err(|e| BuildError {
                loc: desc.loc.clone(),
                message: format!("cannot read texture: {e}"),
            })?;
            Texture::Bitmap {
                image: Arc::new(image),
                filter: *filter,
                wrap: *wrap,
                to_uv: *to_uv,
                corner_texels: *corner_texels,
            }
        }
        scene::Texture::Perlin { scale, conversion } => Texture::Perlin {
            scale: *scale,
            conversion: *conversion,
        },
        scene::Texture::SolidChecker {
            black,
            white,
            scale,
            offset,
        } => Texture::SolidChecker {
            black: (*black).into(),
            white: (*white).into(),
            scale: *scale,
            offset: *offset,
        },
        scene::Texture::Affine {
            texture,
            scale,
            offset,
        } => Texture::Affine {
            texture: Box::new(load_texture_kind(texture, desc)?),
            scale: *scale,
            offset: (*offset).into(),
        },
    })
}

fn color_ref(p: &ColorParam) -> ColorRef {
    match p {
        ColorParam::Const(c) => TexRef::Const((*c).into()),
        ColorParam::Texture(t) => TexRef::Texture(t.0),
    }
}

fn float_ref(p: &FloatParam) -> FloatRef {
    match p {
        FloatParam::Const(c) => TexRef::Const(*c),
        FloatParam::Texture(t) => TexRef::Texture(t.0),
    }
}

/// How deep `twosided` materials may nest with a normal or bump map between them (each level
/// doubles the resolved material). Nested directly, a `twosided` is resolved statically.
const MAX_SIDE_NESTING: usize = 8;

/// Resolves scene materials into runtime ones: `twosided`, `normalmap`, `bumpmap` and `mask`
/// chains become [`Layer`]s, each scattering model is converted once.
struct MaterialResolver<'a> {
    materials: &'a [MaterialDesc],
    kinds: Vec<Option<Option<MaterialKind>>>,
}

impl MaterialResolver<'_> {
    fn material(&mut self, id: MaterialId) -> Result<RtMaterial, BuildError> {
        let m = &self.materials[id.0 as usize];
        let absorption = match &m.material {
            Material::Dielectric {
                absorption: Some(sigma),
                ..
            }
            | Material::PhongFamily {
                ideal:
                    Some(CourseIdeal {
                        kind:
                            CourseIdealKind::Dielectric {
                                absorption: Some(sigma),
                                ..
                            },
                        ..
                    }),
                ..
            } if *sigma != PVec3::ZERO => Some((*sigma).into()),
            _ => None,
        };
        Ok(RtMaterial {
            surface: self.layer(id, &mut Vec::new(), 0, &m.loc)?,
            ambient: m.ambient.into(),
            absorption,
            unlit: match &m.material {
                Material::Unlit { color } => Some(color_ref(color)),
                _ => None,
            },
        })
    }

    /// The layer from material `id` down. `outer` holds the ids of the enclosing layers (a
    /// cycle ends in a surface that does not scatter); `depth` counts the `twosided` splits
    /// above: inside one, the frame already faces the viewer.
    fn layer(
        &mut self,
        mut id: MaterialId,
        outer: &mut Vec<u32>,
        depth: usize,
        loc: &Loc,
    ) -> Result<Layer, BuildError> {
        let mut perturbs = Vec::new();
        let start = outer.len();
        let done = |perturbs: Vec<Perturb>, outer: &mut Vec<u32>, then| {
            outer.truncate(start);
            Ok(Layer {
                perturbs: perturbs.into(),
                then,
            })
        };
        loop {
            let Some(m) = self.materials.get(id.0 as usize) else {
                return done(perturbs, outer, Then::Model(None));
            };
            if outer.contains(&id.0) {
                return done(perturbs, outer, Then::Model(None));
            }
            outer.push(id.0);
            match &m.material {
                // Directly inside a side the frame faces the viewer: the front is seen.
                Material::TwoSided { front, .. } if depth > 0 && perturbs.is_empty() => id = *front,
                Material::TwoSided { front, back } => {
                    if depth >= MAX_SIDE_NESTING {
                        return Err(BuildError {
                            loc: loc.clone(),
                            message: format!(
                                "twosided materials nested more than {MAX_SIDE_NESTING} deep"
                            ),
                        });
                    }
                    let f = self.layer(*front, outer, depth + 1, loc)?;
                    let b = match back {
                        Some(b) => self.layer(*b, outer, depth + 1, loc)?,
                        None => f.clone(),
                    };
                    return done(perturbs, outer, Then::Sides(Box::new([f, b])));
                }
                Material::NormalMap { nested, texture } => {
                    perturbs.push(Perturb::NormalMap { texture: texture.0 });
                    id = *nested;
                }
                Material::BumpMap {
                    nested,
                    texture,
                    factor,
                } => {
                    perturbs.push(Perturb::BumpMap {
                        texture: texture.0,
                        factor: *factor,
                    });
                    id = *nested;
                }
                // The opacity acts in `Scene::intersect` (a cut-out is never hit).
                Material::Mask { nested, .. } => id = *nested,
                _ => {
                    let kind = self.kind(id);
                    return done(perturbs, outer, Then::Model(kind));
                }
            }
        }
    }

    /// The scattering model of material `id` (a leaf: not a wrapper), converted once.
    fn kind(&mut self, id: MaterialId) -> Option<MaterialKind> {
        let slot = &mut self.kinds[id.0 as usize];
        if slot.is_none() {
            *slot = Some(material_kind(&self.materials[id.0 as usize].material));
        }
        slot.clone().flatten()
    }
}

/// The runtime model of a leaf material (`None`: it does not scatter).
pub fn material_kind(m: &Material) -> Option<MaterialKind> {
    Some(match m {
        Material::Diffuse { reflectance } => MaterialKind::Diffuse {
            reflectance: color_ref(reflectance),
        },
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
        } => MaterialKind::Conductor {
            eta: (*eta).into(),
            k: (*k).into(),
            specular: color_ref(specular_reflectance),
        },
        Material::Mirror { reflectance } => MaterialKind::Mirror {
            reflectance: color_ref(reflectance),
        },
        Material::RoughConductor {
            distribution,
            alpha_u,
            alpha_v,
            eta,
            k,
            specular_reflectance,
        } => MaterialKind::RoughConductor {
            distribution: MicrofacetType::from(*distribution),
            alpha_u: float_ref(alpha_u),
            alpha_v: float_ref(alpha_v),
            eta: (*eta).into(),
            k: (*k).into(),
            specular: color_ref(specular_reflectance),
        },
        Material::Dielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
            ..
        } => MaterialKind::Dielectric {
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            reflectance: color_ref(specular_reflectance),
            transmittance: color_ref(specular_transmittance),
        },
        Material::ThinDielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        } => MaterialKind::ThinDielectric {
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            reflectance: color_ref(specular_reflectance),
            transmittance: color_ref(specular_transmittance),
        },
        Material::RoughDielectric {
            distribution,
            alpha_u,
            alpha_v,
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        } => MaterialKind::RoughDielectric {
            distribution: MicrofacetType::from(*distribution),
            alpha_u: float_ref(alpha_u),
            alpha_v: float_ref(alpha_v),
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            reflectance: color_ref(specular_reflectance),
            transmittance: color_ref(specular_transmittance),
        },
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
            nonlinear,
        } => MaterialKind::Plastic {
            diffuse: color_ref(diffuse_reflectance),
            specular: color_ref(specular_reflectance),
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            nonlinear: *nonlinear,
        },
        Material::RoughPlastic {
            distribution,
            alpha: a,
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
            nonlinear,
        } => {
            let kind = MicrofacetType::from(*distribution);
            let eta = int_ior / ext_ior;
            MaterialKind::RoughPlastic {
                microfacet: Microfacet::isotropic(kind, alpha(*a)),
                eta,
                tables: Arc::new(RoughPlasticTables::new(
                    Microfacet::isotropic(kind, *a),
                    eta,
                )),
                diffuse: color_ref(diffuse_reflectance),
                specular: color_ref(specular_reflectance),
                nonlinear: *nonlinear,
            }
        }
        Material::NoriMicrofacet {
            alpha: a,
            int_ior,
            ext_ior,
            kd,
        } => MaterialKind::NoriMicrofacet(NoriMicrofacet::new(
            alpha(*a),
            *int_ior,
            *ext_ior,
            (*kd).into(),
        )),
        Material::PhongFamily {
            model,
            normalized,
            kd_fresnel,
            exponent,
            diffuse,
            specular,
            ior,
            absorption,
            ideal,
        } => MaterialKind::Phong {
            model: *model,
            normalized: *normalized,
            kd_fresnel: *kd_fresnel,
            exponent: *exponent,
            diffuse: color_ref(diffuse),
            specular: color_ref(specular),
            ior: *ior,
            absorption: *absorption,
            ideal: ideal.map(|i| CourseLobe {
                lobe: match i.kind {
                    CourseIdealKind::Mirror => IdealLobe::Mirror,
                    CourseIdealKind::Conductor { eta, k } => IdealLobe::Conductor { eta, k },
                    CourseIdealKind::Dielectric { ior, .. } => IdealLobe::Dielectric { eta: ior },
                },
                reflectance: i.reflectance.into(),
                roughness: i.roughness,
            }),
        },
        Material::Null
        | Material::Unlit { .. }
        | Material::TwoSided { .. }
        | Material::NormalMap { .. }
        | Material::BumpMap { .. }
        | Material::Mask { .. } => return None,
    })
}

/// Every emitter of the scene: area lights (one per emitting shape, or with `split` one per
/// triangle of an emitting mesh) first, then the others.
fn build_lights(
    desc: &SceneDesc,
    shapes: &[ShapeInfo],
    split: bool,
) -> Result<(Vec<Light>, Vec<ShapeLights>), BuildError> {
    let mut lights = Vec::new();
    let mut shape_light = vec![ShapeLights::None; shapes.len()];
    for (i, (s, d)) in shapes.iter().zip(&desc.shapes).enumerate() {
        let Some(radiance) = &s.emission else {
            continue;
        };
        let two_sided = d.emission.as_ref().is_some_and(|e| e.two_sided);
        let triangles = match &s.geom {
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
                if split {
                    // Degenerate triangles stay (so that triangle t is light first + t):
                    // they have no power and are never chosen.
                    shape_light[i] = ShapeLights::PerTriangle {
                        first: lights.len() as u32,
                        count: areas.len() as u32,
                    };
                    for (t, area) in areas.into_iter().enumerate() {
                        lights.push(Light::Area(AreaLight {
                            shape: i as u32,
                            radiance: *radiance,
                            two_sided,
                            triangles: None,
                            prim: Some(t as u32),
                            area: if area.is_finite() { area } else { 0.0 },
                        }));
                    }
                    continue;
                }
                Some(MeshSampling::new(positions, indices, &areas))
            }
            ShapeGeom::Plane { .. } => {
                return Err(BuildError {
                    loc: d.loc.clone(),
                    message: "an infinite plane cannot be an area light".into(),
                });
            }
            _ => None,
        };
        let area = s.geom.area();
        if !(area > 0.0 && area.is_finite()) {
            continue;
        }
        shape_light[i] = ShapeLights::Whole(lights.len() as u32);
        lights.push(Light::Area(AreaLight {
            shape: i as u32,
            radiance: *radiance,
            two_sided,
            triangles,
            prim: None,
            area,
        }));
    }
    for e in &desc.emitters {
        lights.push(match &e.emitter {
            // Not a light: the Whitted integrator's ambient term (`Scene::ambient`).
            scene::Emitter::Ambient { .. } => continue,
            scene::Emitter::Point {
                position,
                intensity,
            } => Light::Point(PointLight {
                position: (*position).into(),
                intensity: (*intensity).into(),
            }),
            scene::Emitter::Spot {
                to_world,
                intensity,
                cutoff_angle,
                beam_width,
                falloff,
            } => Light::Spot(SpotLight::new(
                to_world,
                (*intensity).into(),
                *cutoff_angle,
                *beam_width,
                *falloff,
            )),
            scene::Emitter::Directional {
                direction,
                irradiance,
            } => Light::Directional(DirectionalLight {
                direction: direction.normalize_or_zero().into(),
                irradiance: (*irradiance).into(),
            }),
            scene::Emitter::Constant { radiance } => Light::Constant(ConstantLight {
                radiance: (*radiance).into(),
            }),
            scene::Emitter::EnvMap {
                path,
                scale,
                to_world,
                mapping,
            } => {
                let image =
                    image_io::read_image_with(path, Decode::Srgb).map_err(|err| BuildError {
                        loc: e.loc.clone(),
                        message: format!("cannot read environment map: {err}"),
                    })?;
                Light::EnvMap(Arc::new(EnvMap::new(image, *scale, to_world, *mapping)))
            }
        });
    }
    Ok((lights, shape_light))
}

/// Turn a loaded scene into a renderable one.
pub fn build(desc: &SceneDesc, opts: &BuildOptions) -> Result<Scene, BuildError> {
    let sensor = desc.sensors.get(opts.sensor).ok_or_else(|| BuildError {
        loc: Loc::file(&desc.source),
        message: format!(
            "the scene has {} sensor(s); sensor {} does not exist",
            desc.sensors.len(),
            opts.sensor
        ),
    })?;

    let mut warnings = Vec::new();
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
    let mut resolver = MaterialResolver {
        materials: &desc.materials,
        kinds: vec![None; desc.materials.len()],
    };
    let mut materials = (0..desc.materials.len() as u32)
        .map(|id| resolver.material(MaterialId(id)))
        .collect::<Result<Vec<_>, _>>()?;
    let default_material = materials.len() as u32;
    materials.push(RtMaterial::default_diffuse());

    let mut proto_of: HashMap<*const TriMesh, u32> = HashMap::new();
    let mut protos: Vec<ShapeGeom> = Vec::new();
    let mut motion_ignored = false;
    let mut shapes = Vec::with_capacity(desc.shapes.len());
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
        // Shapes without a material get Mitsuba's default diffuse, emitters none.
        let material = match s.material {
            Some(m) => Some(m.0),
            None if s.emission.is_none() => Some(default_material),
            None => None,
        };
        shapes.push(ShapeInfo {
            geom,
            material,
            emission: s.emission.as_ref().map(|e| color_ref(&e.radiance)),
            flip_normals: s.flip_normals,
            // Emitters stay whole: light sampling picks points on the entire surface.
            opacity: s.material.filter(|_| s.emission.is_none()).and_then(|m| {
                match &desc.materials[m.0 as usize].material {
                    Material::Mask { opacity, .. } => Some(float_ref(opacity)),
                    _ => None,
                }
            }),
            reads: Reads {
                tangent: !material.is_none_or(|m| materials[m as usize].isotropic()),
                // Only textures read uv (material and emitter parameters, normal maps and
                // opacity masks all go through one).
                uv: !desc.textures.is_empty(),
            },
        });
    }
    if motion_ignored {
        warnings.push(format!(
            "{}: warning: motion blur of emitters and infinite planes is not supported; they stay at their time-0 place",
            desc.source.display()
        ));
    }
    let has_motion = shapes
        .iter()
        .any(|s| matches!(&s.geom, ShapeGeom::Instance(i) if i.motion != Vec3::ZERO));
    let triangle_count = shapes.iter().map(|s| s.geom.triangle_count()).sum();
    let accel = Accel::build_instanced(
        shapes.iter().map(|s| s.geom.accel_shape()).collect(),
        protos.iter().map(ShapeGeom::accel_shape).collect(),
    );
    drop(protos);
    let bounds = accel.bounds();

    let mut textures = desc
        .textures
        .iter()
        .map(load_texture)
        .collect::<Result<Vec<_>, _>>()?;
    opacity_from_alpha(desc, &mut shapes, &mut textures)?;

    let selection = opts.light_selection.unwrap_or(desc.light_selection);
    let split = selection != LightSelection::Uniform;
    let (lights, shape_lights) = build_lights(desc, &shapes, split)?;
    let infinite_lights = (0..lights.len() as u32)
        .filter(|&i| lights[i as usize].is_infinite())
        .collect();

    let has_cutouts = shapes.iter().any(|s| s.opacity.is_some());
    let is_mask = |id: &MaterialId| {
        matches!(
            desc.materials.get(id.0 as usize).map(|m| &m.material),
            Some(Material::Mask { .. })
        )
    };
    if desc
        .shapes
        .iter()
        .any(|s| s.emission.is_some() && s.material.is_some_and(|m| is_mask(&m)))
    {
        warnings.push(format!(
            "{}: warning: an emitting shape's alpha cut-out is ignored (it emits, and is hit, everywhere)",
            desc.source.display()
        ));
    }
    for m in &desc.materials {
        let below = match &m.material {
            Material::TwoSided { front, back } => {
                is_mask(front) || back.as_ref().is_some_and(is_mask)
            }
            Material::NormalMap { nested, .. } | Material::Mask { nested, .. } => is_mask(nested),
            _ => false,
        };
        if below {
            warnings.push(format!(
                "{}: warning: a mask (alpha cut-out) below another material has no effect; put it outermost",
                m.loc
            ));
        }
    }

    let mut film = sensor.film.clone();
    if let Some((w, h)) = opts.resolution {
        film.width = w;
        film.height = h;
        film.crop = None;
    }
    let mut sampler = sensor.sampler.clone();
    if let Some(spp) = opts.spp {
        sampler.spp = spp;
    }
    if let Some(seed) = opts.seed {
        sampler.seed = seed;
    }
    let camera = Camera::new(&sensor.camera, film.width, film.height);
    let integrator = opts
        .integrator
        .clone()
        .or_else(|| sensor.integrator.clone())
        .unwrap_or_else(|| desc.integrator.clone());
    let ambient: Vec3 = desc
        .emitters
        .iter()
        .filter_map(|e| match e.emitter {
            scene::Emitter::Ambient { radiance } => Some(radiance),
            _ => None,
        })
        .map(Vec3::from)
        .sum();
    if ambient != Vec3::ZERO && !matches!(integrator, IntegratorDesc::Whitted { .. }) {
        warnings.push(format!(
            "{}: warning: the ambient light is used only by the Whitted ray tracer; the {} integrator ignores it",
            desc.source.display(),
            Integrator::from_desc(&integrator).map_or("selected", |i| i.name()),
        ));
    }

    let mut scene = Scene {
        accel,
        shapes,
        has_unlit: materials.iter().any(|m| m.unlit.is_some()),
        materials,
        warnings,
        textures: Textures::new(textures),
        camera,
        film,
        sampler,
        integrator,
        background: desc.background.map(Vec3::from),
        background_texture: desc.background_texture.map(|t| t.0),
        ambient,
        lights,
        shape_lights,
        light_sampler: LightSampler::Uniform,
        infinite_lights,
        bounds,
        triangle_count,
        has_cutouts,
        has_motion,
    };
    scene.light_sampler = LightSampler::new(selection, &scene);
    Ok(scene)
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

    fn desc(material: Material) -> MaterialDesc {
        MaterialDesc {
            material,
            ambient: Default::default(),
            name: None,
            loc: Default::default(),
        }
    }

    fn rough(alpha_u: f32, alpha_v: f32) -> Material {
        Material::RoughConductor {
            distribution: scene::MicrofacetDistribution::Ggx,
            alpha_u: FloatParam::Const(alpha_u),
            alpha_v: FloatParam::Const(alpha_v),
            eta: PVec3::splat(1.5),
            k: PVec3::splat(0.0),
            specular_reflectance: ColorParam::constant(1.0),
        }
    }

    fn resolve(mats: &[MaterialDesc], id: u32) -> Result<RtMaterial, BuildError> {
        MaterialResolver {
            materials: mats,
            kinds: vec![None; mats.len()],
        }
        .material(MaterialId(id))
    }

    /// The shape of a resolved layer: perturbation count, then the model's name or the sides.
    fn shape(l: &Layer) -> String {
        let then = match &l.then {
            Then::Model(None) => "none".to_string(),
            Then::Model(Some(MaterialKind::Diffuse { .. })) => "diffuse".to_string(),
            Then::Model(Some(_)) => "other".to_string(),
            Then::Sides(s) => format!("[{} | {}]", shape(&s[0]), shape(&s[1])),
        };
        format!("{}{then}", "p".repeat(l.perturbs.len()))
    }

    #[test]
    fn material_chains_resolve_into_layers() {
        let diffuse = Material::Diffuse {
            reflectance: ColorParam::constant(0.5),
        };
        let two = |front, back: Option<u32>| Material::TwoSided {
            front: MaterialId(front),
            back: back.map(MaterialId),
        };
        let normal = |nested| Material::NormalMap {
            nested: MaterialId(nested),
            texture: scene::TextureId(0),
        };
        let mask = |nested| Material::Mask {
            nested: MaterialId(nested),
            opacity: FloatParam::Const(0.5),
        };
        let mats = [
            desc(diffuse),         // 0
            desc(rough(0.1, 0.1)), // 1
            desc(rough(0.1, 0.3)), // 2
            desc(two(0, Some(2))), // 3
            desc(normal(0)),       // 4
            desc(mask(1)),         // 5
            desc(two(6, None)),    // 6: a cycle
            desc(mask(4)),         // 7
            desc(two(3, None)),    // 8: twosided directly inside twosided: its front
            desc(normal(3)),       // 9: a normal map around a twosided
            desc(two(9, Some(7))), // 10: twosided, normal map, twosided
            desc(Material::Null),  // 11
        ];
        let layer = |id| shape(&resolve(&mats, id).unwrap().surface);
        assert_eq!(layer(0), "diffuse");
        assert_eq!(layer(3), "[diffuse | other]");
        assert_eq!(layer(4), "pdiffuse");
        assert_eq!(layer(5), "other");
        assert_eq!(layer(6), "[none | none]");
        assert_eq!(layer(7), "pdiffuse");
        assert_eq!(layer(8), "[diffuse | diffuse]");
        assert_eq!(layer(9), "p[diffuse | other]");
        assert_eq!(layer(10), "[p[diffuse | other] | pdiffuse]");
        assert_eq!(layer(11), "none");

        let iso = |id| resolve(&mats, id).unwrap().isotropic();
        assert!(iso(0) && iso(1) && iso(5) && iso(6) && iso(8) && iso(11));
        assert!(!iso(2), "alpha_u != alpha_v");
        assert!(!iso(3), "anisotropic back side");
        assert!(!iso(4) && !iso(7) && !iso(9), "normal map");
        assert!(RtMaterial::default_diffuse().isotropic());
    }

    #[test]
    fn twosided_nesting_through_normal_maps_is_bounded() {
        // twosided(normalmap(twosided(normalmap(... diffuse)))) 20 levels deep.
        let mut mats = vec![desc(Material::Diffuse {
            reflectance: ColorParam::constant(0.5),
        })];
        for _ in 0..20 {
            let below = mats.len() as u32 - 1;
            mats.push(desc(Material::NormalMap {
                nested: MaterialId(below),
                texture: scene::TextureId(0),
            }));
            mats.push(desc(Material::TwoSided {
                front: MaterialId(below + 1),
                back: None,
            }));
        }
        let err = resolve(&mats, mats.len() as u32 - 1).unwrap_err();
        assert!(err.message.contains("nested more than"), "{}", err.message);
        assert!(resolve(&mats, 2 * MAX_SIDE_NESTING as u32).is_ok());
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
