//! CS-E5520 (Aalto) OBJ+MTL files as whole scenes: FORMATS.md §3. Issue 7.
//!
//! The OBJ geometry is read by [`obj::read_obj_groups`]; the triangles are split into one mesh
//! per `usemtl` material so that emissive triangles (`Ke`) form their own area-light shapes.
//!
//! # Material mapping
//! MTL describes a Blinn–Phong-style material; we map it onto physically based models:
//! - **transparent** (`illum` 4, 6, 7 or 9): a smooth dielectric of
//!   index `Ni` (1.5 when `Ni` is absent or ≤ 1) with transmittance `Tf` (else 1);
//! - **glossy** (`Ks` non-zero and `Ns` > 0): Mitsuba's rough plastic with a GGX lobe of
//!   roughness α = √(2 / (Ns + 2)) (the Blinn–Phong exponent ↔ Beckmann/GGX α correspondence
//!   of Walter et al. 2007), diffuse `Kd` (or `map_Kd`), specular scale `Ks` (or `map_Ks`) and
//!   η = 1.5. The Fresnel-weighted coat makes highlights weaker than the course's unnormalised
//!   `Ks`; energy is conserved instead;
//! - otherwise **diffuse** `Kd` (or `map_Kd`).
//!
//! `map_Kd` replaces `Kd` (MTL says it multiplies; the course files use `Kd 1` with maps).
//! 8-bit textures are linearised with power 2.2 as the course does; OBJ's `v` axis points up
//! the image, so bitmaps get the uv transform (u, 1 − v). `Ke` becomes two-sided area
//! emission of that radiance on the material's triangles; `map_Ke` an emission texture
//! (replacing `Ke`, as `map_Kd` replaces `Kd`). A missing texture file gives one
//! warning and the constant colour instead. `map_bump`/`bump`/`norm` are tangent-space normal
//! maps (read raw, wrapping the material in `Material::NormalMap`). `map_d` (read raw: its
//! alpha channel when the file has one, else its first channel) or `d` < 1 (`Tr` > 0) on a
//! material that is not transparent is an alpha cut-out (`Material::Mask` outermost). `disp`
//! is a height map (read raw, its first channel, `-bm` its scale, 1 by default) applied as
//! Mitsuba 3's `bumpmap` (`Material::HeightBump`) on a material without a normal map; with
//! one, the normal map alone shades, as in the CS-E5520 renderer, whose path tracer reads
//! normal maps and no height maps (its Chesterfield scene has both, one note says so).
//! `Ka`, `map_Ka` and the other reflection-model keys are reported as ignored.
//!
//! # Scene defaults (the course application's, which the file does not store)
//! A perspective camera looking down −z at the bounding box's centre (just inside the box when
//! its +z face is a wall, as in the course's closed Cornell boxes, else outside it: see
//! [`default_camera`]); 512 × 512 film with a Gaussian filter; Sobol
//! sampling, 64 spp; a path tracer with Russian roulette after 5 segments with termination
//! probability 0.2. A scene without emitters gets the course's square area light (see
//! [`default_square_light`]) with a warning.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::common::look_at;
use super::obj;
use crate::{
    AreaEmission, Camera, ColorParam, Document, FilterDesc, FloatParam, FovAxis, IntegratorDesc,
    LoadOptions, Loc, Mat3, Mat4, Material, MaterialDesc, MaterialId, MicrofacetDistribution,
    PathDesc, Projection, Result, Rgb, RussianRoulette, SamplerDesc, SamplerKind, SceneDesc,
    Sensor, Shape, ShapeDesc, Texture, TextureDesc, TextureFilter, TriMesh, Vec3, Warning,
    WrapMode,
};

/// Name given to the square light added to scenes without emitters (so a command-line light
/// can replace it).
pub const DEFAULT_LIGHT_NAME: &str = "default square light";

/// Gamma the course uses to linearise 8-bit textures.
pub const TEXTURE_GAMMA: f32 = 2.2;

/// One `newmtl` block as written (before mapping to a [`Material`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MtlMaterial {
    pub name: String,
    pub loc: Loc,
    pub kd: Rgb,
    pub ks: Rgb,
    pub ke: Rgb,
    pub tf: Option<Rgb>,
    pub ns: f32,
    pub ni: Option<f32>,
    /// Dissolve (opacity), 1 = opaque; `Tr` is stored as `1 − Tr`.
    pub d: f32,
    pub illum: Option<u32>,
    /// Texture paths resolved against the MTL file's folder.
    pub map_kd: Option<PathBuf>,
    pub map_ks: Option<PathBuf>,
    /// Emission texture (replaces `Ke`, as `map_Kd` replaces `Kd`).
    pub map_ke: Option<PathBuf>,
    pub map_bump: Option<PathBuf>,
    pub map_d: Option<PathBuf>,
    /// `disp`: a height map and its `-bm` scale.
    pub disp: Option<(PathBuf, f32)>,
}

impl MtlMaterial {
    fn new(name: String, loc: Loc) -> Self {
        MtlMaterial {
            name,
            loc,
            kd: Rgb::splat(0.8),
            ks: Rgb::ZERO,
            ke: Rgb::ZERO,
            tf: None,
            ns: 0.0,
            ni: None,
            d: 1.0,
            illum: None,
            map_kd: None,
            map_ks: None,
            map_ke: None,
            map_bump: None,
            map_d: None,
            disp: None,
        }
    }

    /// Transparent per `illum` or dissolve.
    pub fn is_transparent(&self) -> bool {
        matches!(self.illum, Some(4 | 6 | 7 | 9))
    }

    /// The GGX roughness equivalent to the Blinn–Phong exponent `Ns`.
    pub fn alpha(&self) -> f32 {
        ns_to_alpha(self.ns)
    }
}

/// Blinn–Phong exponent → Beckmann/GGX roughness, α = √(2 / (n + 2)).
pub fn ns_to_alpha(ns: f32) -> f32 {
    (2.0 / (ns.max(0.0) + 2.0)).sqrt()
}

/// Parse MTL text. Unknown keys, malformed values and non-finite numbers become warnings; the
/// first definition of a name wins.
pub fn parse_mtl(text: &str, file: &Path, warnings: &mut Vec<Warning>) -> Vec<MtlMaterial> {
    let file_arc = Arc::new(file.to_path_buf());
    let dir = file.parent().unwrap_or(Path::new(""));
    let mut out: Vec<MtlMaterial> = Vec::new();
    let mut current: Option<MtlMaterial> = None;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for (i, raw) in text.lines().enumerate() {
        let loc = Loc::new(&file_arc, u32::try_from(i + 1).unwrap_or(u32::MAX), 0);
        let line = raw.find('#').map_or(raw, |k| &raw[..k]).trim();
        let mut toks = line.split_whitespace();
        let Some(kw) = toks.next() else { continue };
        let rest = line[kw.len()..].trim();
        let warn = |warnings: &mut Vec<Warning>, msg: String| {
            warnings.push(Warning {
                loc: loc.clone(),
                message: msg,
            })
        };
        if kw == "newmtl" {
            if let Some(m) = current.take() {
                push_material(&mut out, m, warnings);
            }
            if rest.is_empty() {
                warn(warnings, "newmtl without a name".into());
            }
            current = Some(MtlMaterial::new(rest.to_string(), loc.clone()));
            continue;
        }
        let Some(m) = current.as_mut() else {
            warn(warnings, format!("'{kw}' before any newmtl ignored"));
            continue;
        };
        let kwl = kw.to_ascii_lowercase();
        match kwl.as_str() {
            "kd" | "ks" | "ke" | "tf" => match colour(rest) {
                Ok(c) => match kwl.as_str() {
                    "kd" => m.kd = c,
                    "ks" => m.ks = c,
                    "ke" => m.ke = c,
                    _ => m.tf = Some(c),
                },
                Err(e) => warn(warnings, format!("{kw}: {e}; ignored")),
            },
            "ns" | "ni" | "d" | "tr" | "illum" => {
                // `d -halo 0.5`: the halo option is ignored.
                let vals = rest.strip_prefix("-halo").unwrap_or(rest).trim();
                match scalar(vals) {
                    Ok(v) => match kwl.as_str() {
                        "ns" => m.ns = v.max(0.0),
                        "ni" => m.ni = Some(v),
                        "d" => m.d = v.clamp(0.0, 1.0),
                        "tr" => m.d = (1.0 - v).clamp(0.0, 1.0),
                        _ if v >= 0.0 && v.fract() == 0.0 && v <= 10.0 => m.illum = Some(v as u32),
                        _ => warn(
                            warnings,
                            format!("illum: '{v}' is not a model 0..10; ignored"),
                        ),
                    },
                    Err(e) => warn(warnings, format!("{kw}: {e}; ignored")),
                }
            }
            "map_kd" | "map_ks" | "map_ke" | "map_bump" | "bump" | "norm" | "map_d" => {
                let Some(name) = map_file(rest) else {
                    warn(warnings, format!("{kw} without a file name ignored"));
                    continue;
                };
                let p = dir.join(name.replace('\\', "/"));
                match kwl.as_str() {
                    "map_kd" => m.map_kd = Some(p),
                    "map_ks" => m.map_ks = Some(p),
                    "map_ke" => m.map_ke = Some(p),
                    "map_d" => m.map_d = Some(p),
                    _ => m.map_bump = Some(p),
                }
            }
            "disp" => match (map_file(rest), bump_multiplier(rest)) {
                (None, _) => warn(warnings, format!("{kw} without a file name ignored")),
                (_, Err(e)) => warn(warnings, format!("{kw}: {e}; ignored")),
                (Some(name), Ok(scale)) => {
                    m.disp = Some((dir.join(name.replace('\\', "/")), scale));
                }
            },
            "ka" | "map_ka" | "sharpness" | "map_ns" | "refl" | "decal" => {
                // Known but meaningless to a path tracer, or not supported: silent for Ka
                // (always present), reported at mapping time for the others.
                if kwl != "ka" {
                    warn(warnings, format!("'{kw}' is not supported; ignored"));
                }
            }
            _ => warn(warnings, format!("unknown MTL key '{kw}' ignored")),
        }
    }
    if let Some(m) = current.take() {
        push_material(&mut out, m, warnings);
    }
    out
}

fn push_material(out: &mut Vec<MtlMaterial>, m: MtlMaterial, warnings: &mut Vec<Warning>) {
    if out.iter().any(|o| o.name == m.name) {
        warnings.push(Warning {
            loc: m.loc.clone(),
            message: format!("material '{}' defined again; the first wins", m.name),
        });
    } else {
        out.push(m);
    }
}

/// The leading numbers of a value list; trailing words (comments) end it.
fn numbers(s: &str) -> std::result::Result<Vec<f32>, String> {
    let mut v = Vec::new();
    for t in s.split_whitespace() {
        match t.parse::<f32>() {
            Ok(x) if x.is_finite() => v.push(x),
            Ok(_) => return Err(format!("'{t}' is not a finite number")),
            Err(_) => break,
        }
        if v.len() == 3 {
            break;
        }
    }
    Ok(v)
}

fn scalar(s: &str) -> std::result::Result<f32, String> {
    numbers(s)?
        .first()
        .copied()
        .ok_or_else(|| format!("expected a number, found '{s}'"))
}

fn colour(s: &str) -> std::result::Result<Rgb, String> {
    let first = s.split_whitespace().next().unwrap_or("");
    if first == "spectral" || first == "xyz" {
        return Err(format!("'{first}' colours are not supported"));
    }
    let v = numbers(s)?;
    let c = match v.as_slice() {
        [g] => Rgb::splat(*g),
        [r, g, b] => Rgb::new(*r, *g, *b),
        _ => return Err(format!("expected 1 or 3 numbers, found '{s}'")),
    };
    Ok(c.max(Rgb::ZERO))
}

/// The `-bm` (bump multiplier) option of a map line: 1 without one.
fn bump_multiplier(rest: &str) -> std::result::Result<f32, String> {
    let toks: Vec<&str> = rest.split_whitespace().collect();
    match toks.iter().position(|t| *t == "-bm") {
        None => Ok(1.0),
        Some(i) => match toks.get(i + 1).map(|t| t.parse::<f32>()) {
            Some(Ok(v)) if v.is_finite() => Ok(v),
            _ => Err("-bm needs a finite number".into()),
        },
    }
}

/// The file name of a `map_*` line after its options (`-bm 1`, `-s 1 1 1`, `-clamp on`...).
fn map_file(rest: &str) -> Option<String> {
    let toks: Vec<&str> = rest.split_whitespace().collect();
    let mut i = 0;
    while i < toks.len() && toks[i].starts_with('-') && toks[i].len() > 1 {
        let opt = toks[i];
        i += 1;
        match opt {
            "-o" | "-s" | "-t" => {
                let mut k = 0;
                while k < 3 && i < toks.len() && toks[i].parse::<f32>().is_ok() {
                    i += 1;
                    k += 1;
                }
            }
            "-mm" => i += 2,
            _ => i += 1,
        }
    }
    let name = toks.get(i..)?.join(" ");
    (!name.is_empty()).then_some(name)
}

/// A one-sided square area light of side `size` centred at `center`, emitting along `normal`.
/// `None` for a degenerate normal or size.
pub fn square_light(
    center: Vec3,
    normal: Vec3,
    size: f32,
    emission: Rgb,
    loc: Loc,
) -> Option<ShapeDesc> {
    let n = normal.normalize_or_zero();
    if n == Vec3::ZERO || !(size > 0.0 && size.is_finite()) || !center.is_finite() {
        return None;
    }
    let rot = glam::Quat::from_rotation_arc(Vec3::Z, n);
    let to_world =
        Mat4::from_scale_rotation_translation(Vec3::new(0.5 * size, 0.5 * size, 1.0), rot, center);
    Some(ShapeDesc {
        media: Default::default(),
        motion: None,
        shape: Shape::Rectangle,
        to_world,
        material: None,
        emission: Some(AreaEmission {
            radiance: ColorParam::Const(emission),
            two_sided: false,
            directional: false,
            loc: loc.clone(),
        }),
        flip_normals: false,
        name: Some("square light".into()),
        loc,
    })
}

/// The course's default light for a bounding box: facing down, centred just under the top,
/// a quarter of the box's width on a side, radiance 10.
pub fn default_square_light(lo: Vec3, hi: Vec3, loc: Loc) -> Option<ShapeDesc> {
    let ext = hi - lo;
    let size = 0.25 * ext.x.max(ext.z);
    let center = Vec3::new(
        0.5 * (lo.x + hi.x),
        hi.y - 1e-3 * ext.length(),
        0.5 * (lo.z + hi.z),
    );
    let mut s = square_light(center, -Vec3::Y, size, Rgb::splat(10.0), loc)?;
    s.name = Some(DEFAULT_LIGHT_NAME.into());
    Some(s)
}

/// The default camera: looking down −z at the box's centre, framing the box's back face
/// with a 45°-or-wider field of view. `closed_front`: the box's +z face is a wall (a room such
/// as the course's Cornell boxes), so the camera goes just inside it; otherwise it stands
/// outside, far enough back for a 45° field of view to frame the front face.
pub fn default_camera(lo: Vec3, hi: Vec3, closed_front: bool) -> Camera {
    let c = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    let r = half.x.max(half.y).max(1e-3);
    let (d, fov) = if closed_front {
        let d = 0.95 * half.z;
        (
            d,
            (2.0 * (r / (d + half.z).max(1e-3)).atan().to_degrees()).max(1.0),
        )
    } else {
        (half.z + r / 22.5f32.to_radians().tan(), 45.0)
    };
    let origin = c + Vec3::new(0.0, 0.0, d);
    let scale = d.max(r);
    Camera {
        projection: Projection::Perspective {
            fov,
            fov_axis: FovAxis::Smaller,
        },
        to_world: look_at(origin, c, Vec3::Y).unwrap_or(Mat4::IDENTITY),
        near_clip: 1e-4 * scale,
        far_clip: 1e4 * scale,
    }
}

/// Some triangle lies in the bounding box's +z face.
fn front_face_closed(mesh: &TriMesh, hi: Vec3, lo: Vec3) -> bool {
    let eps = 1e-4 * (hi - lo).length();
    mesh.indices.iter().any(|t| {
        t.iter()
            .all(|&v| mesh.positions[v as usize].z >= hi.z - eps)
    })
}

pub fn load(path: &Path, opts: &LoadOptions) -> Result<Document> {
    let objm = obj::read_obj_groups(path)?;
    let mut desc = SceneDesc {
        source: path.to_path_buf(),
        ..SceneDesc::default()
    };
    let file_loc = Loc::file(path);
    if !opts.defines.is_empty() {
        desc.warnings.push(Warning {
            loc: file_loc.clone(),
            message: "-D parameters have no meaning for OBJ scenes; ignored".into(),
        });
    }
    // Absolute, so that texture paths do not depend on how the renderer resolves relative ones.
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let dir = abs.parent().unwrap_or(Path::new(""));

    // Material libraries.
    let mut mtls: Vec<MtlMaterial> = Vec::new();
    for lib in &objm.mtllibs {
        let p = dir.join(lib.name.replace('\\', "/"));
        match crate::read_file(&p) {
            Ok(bytes) => {
                let text = String::from_utf8_lossy(&bytes);
                for m in parse_mtl(&text, &p, &mut desc.warnings) {
                    push_material(&mut mtls, m, &mut desc.warnings);
                }
            }
            Err(e) => desc.warnings.push(Warning {
                loc: lib.loc.clone(),
                message: format!("cannot read material library {}: {e}", p.display()),
            }),
        }
    }

    // One scene material (and optional emission) per used OBJ material name.
    let mut tex_cache: HashMap<PathBuf, Option<crate::TextureId>> = HashMap::new();
    let mut slots: Vec<(Option<MaterialId>, Option<ColorParam>)> = Vec::new();
    for used in &objm.materials {
        match mtls.iter().find(|m| m.name == used.name) {
            Some(m) => {
                let (id, emission) = map_material(m, &mut desc, &mut tex_cache);
                slots.push((Some(id), emission));
            }
            None => {
                desc.warnings.push(Warning {
                    loc: used.loc.clone(),
                    message: format!(
                        "material '{}' is not defined in any material library; using diffuse 0.5",
                        used.name
                    ),
                });
                slots.push((None, None));
            }
        }
    }

    // Split the triangles per material.
    let mesh = &objm.mesh;
    if mesh.indices.is_empty() {
        return Err(crate::LoadError::new(file_loc, "the OBJ file has no faces"));
    }
    let mut groups: Vec<Vec<u32>> = vec![Vec::new(); slots.len() + 1];
    for (t, m) in objm.triangle_materials.iter().enumerate() {
        let g = m.map_or(slots.len(), |m| m as usize);
        groups[g.min(slots.len())].push(t as u32);
    }
    for (g, tris) in groups.iter().enumerate() {
        if tris.is_empty() {
            continue;
        }
        let (material, emission) = slots.get(g).cloned().unwrap_or((None, None));
        let (name, loc) = match objm.materials.get(g) {
            Some(n) => (Some(n.name.clone()), n.loc.clone()),
            None => (None, file_loc.clone()),
        };
        desc.shapes.push(ShapeDesc {
            media: Default::default(),
            motion: None,
            shape: Shape::Mesh(Arc::new(submesh(mesh, tris))),
            to_world: Mat4::IDENTITY,
            material,
            emission: emission.map(|radiance| AreaEmission {
                radiance,
                two_sided: true,
                directional: false,
                loc: loc.clone(),
            }),
            flip_normals: false,
            name,
            loc,
        });
    }

    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    if !desc.shapes.iter().any(|s| s.emission.is_some())
        && let Some(light) = default_square_light(lo, hi, file_loc.clone())
    {
        desc.warnings.push(Warning {
            loc: file_loc.clone(),
            message: "the scene has no emitter (Ke); adding the default square light under the top of the bounding box (--area-light to change it)".into(),
        });
        desc.shapes.push(light);
    }

    desc.sensors.push(Sensor {
        medium: None,
        camera: default_camera(lo, hi, front_face_closed(mesh, hi, lo)),
        film: crate::Film {
            width: 512,
            height: 512,
            crop: None,
            filter: FilterDesc::Gaussian {
                stddev: 0.5,
                radius: 2.0,
            },
            output: None,
            tonemap: None,
        },
        sampler: SamplerDesc {
            kind: SamplerKind::Sobol,
            spp: 64,
            seed: 0,
        },
        integrator: None,
        name: None,
        loc: file_loc,
    });
    desc.integrator = IntegratorDesc::Path(PathDesc {
        rr: RussianRoulette::Fixed { after: 5, q: 0.2 },
        ..PathDesc::default()
    });
    Ok(Document::Scene(Box::new(desc)))
}

/// The triangles `tris` of `mesh` as a compact mesh of their own.
fn submesh(mesh: &TriMesh, tris: &[u32]) -> TriMesh {
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    let mut out = TriMesh::default();
    let has_n = !mesh.normals.is_empty();
    let has_uv = !mesh.uvs.is_empty();
    for &t in tris {
        let tri = mesh.indices[t as usize];
        let mut new = [0u32; 3];
        for (k, &v) in tri.iter().enumerate() {
            let v = v as usize;
            if remap[v] == u32::MAX {
                remap[v] = out.positions.len() as u32;
                out.positions.push(mesh.positions[v]);
                if has_n {
                    out.normals.push(mesh.normals[v]);
                }
                if has_uv {
                    out.uvs.push(mesh.uvs[v]);
                }
            }
            new[k] = remap[v];
        }
        out.indices.push(new);
    }
    out
}

/// OBJ's `v` points up the image; our bitmaps have row 0 at the top.
fn obj_to_uv() -> Mat3 {
    Mat3::from_cols(
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 1.0),
    )
}

/// A bitmap texture for `path`, or `None` (with one warning per file) when it cannot be read.
fn texture(
    path: &Path,
    loc: &Loc,
    desc: &mut SceneDesc,
    cache: &mut HashMap<PathBuf, Option<crate::TextureId>>,
    raw: bool,
) -> Option<crate::TextureId> {
    if let Some(t) = cache.get(path) {
        return *t;
    }
    let id = if path.is_file() {
        Some(desc.add_texture(TextureDesc {
            texture: Texture::Bitmap {
                mipmapped: false,
                path: path.to_path_buf(),
                filter: TextureFilter::Bilinear,
                wrap: WrapMode::Repeat,
                raw,
                gamma: (!raw).then_some(TEXTURE_GAMMA),
                to_uv: obj_to_uv(),
                corner_texels: false,
            },
            name: path.file_name().map(|n| n.to_string_lossy().into_owned()),
            loc: loc.clone(),
        }))
    } else {
        desc.warnings.push(Warning {
            loc: loc.clone(),
            message: format!(
                "texture {} not found; using the constant colour instead",
                path.display()
            ),
        });
        None
    };
    cache.insert(path.to_path_buf(), id);
    id
}

/// Map one MTL material to a scene material; returns it and its emitted radiance (`map_Ke`'s
/// texture, else `Ke` when not black).
fn map_material(
    m: &MtlMaterial,
    desc: &mut SceneDesc,
    cache: &mut HashMap<PathBuf, Option<crate::TextureId>>,
) -> (MaterialId, Option<ColorParam>) {
    let mut param = |c: Rgb, map: &Option<PathBuf>, desc: &mut SceneDesc| match map {
        Some(p) => match texture(p, &m.loc, desc, cache, false) {
            Some(t) => ColorParam::Texture(t),
            None => ColorParam::Const(c),
        },
        None => ColorParam::Const(c),
    };
    let material = if m.is_transparent() {
        Material::Dielectric {
            int_ior: m.ni.filter(|n| *n > 1.0).unwrap_or(1.5),
            ext_ior: 1.0,
            dispersion: None,
            specular_reflectance: ColorParam::constant(1.0),
            specular_transmittance: ColorParam::Const(m.tf.unwrap_or(Rgb::ONE).min(Rgb::ONE)),
            absorption: None,
        }
    } else if (m.ks.max_element() > 0.0 || m.map_ks.is_some()) && m.ns > 0.0 {
        Material::RoughPlastic {
            distribution: MicrofacetDistribution::Ggx,
            alpha: m.alpha(),
            diffuse_reflectance: param(m.kd.min(Rgb::ONE), &m.map_kd, desc),
            specular_reflectance: param(m.ks, &m.map_ks, desc),
            int_ior: 1.5,
            ext_ior: 1.0,
            nonlinear: false,
        }
    } else {
        Material::Diffuse {
            reflectance: param(m.kd.min(Rgb::ONE), &m.map_kd, desc),
        }
    };
    // The MTL material is the base; maps wrap it in further materials of the same name.
    let add = |material: Material, desc: &mut SceneDesc| {
        desc.add_material(MaterialDesc {
            material,
            ambient: Rgb::ZERO,
            name: Some(m.name.clone()),
            loc: m.loc.clone(),
        })
    };
    let mut id = add(material, desc);
    // `map_bump`/`bump`/`norm`: a tangent-space normal map (read raw) around the material;
    // else `disp`, a height map, as Mitsuba 3's `bumpmap` with its defaults.
    if let Some(p) = &m.map_bump
        && let Some(texture) = texture(p, &m.loc, desc, cache, true)
    {
        id = add(
            Material::NormalMap {
                nested: id,
                texture,
            },
            desc,
        );
        if let Some((h, _)) = &m.disp {
            desc.warnings.push(Warning {
                loc: m.loc.clone(),
                message: format!(
                    "material '{}': its height map (disp) {} is not applied under its \
                     normal map, which shades alone as in the CS-E5520 renderer",
                    m.name,
                    h.display()
                ),
            });
        }
    } else if let Some((p, scale)) = &m.disp
        && let Some(texture) = texture(p, &m.loc, desc, cache, true)
    {
        id = add(
            Material::HeightBump {
                nested: id,
                texture,
                scale: *scale,
                flip_invalid_normals: true,
                shadowing: true,
            },
            desc,
        );
    }
    // `map_d` / `d`: alpha cut-out (not for the transparent illum modes, which are glass).
    if !m.is_transparent() {
        let map = m
            .map_d
            .as_ref()
            .and_then(|p| texture(p, &m.loc, desc, cache, true));
        let opacity = match map {
            Some(t) => Some(FloatParam::Texture(t)),
            None => (m.d < 1.0).then_some(FloatParam::Const(m.d)),
        };
        if let Some(opacity) = opacity {
            id = add(
                Material::Mask {
                    nested: id,
                    opacity,
                },
                desc,
            );
        }
    }
    let emission = match &m.map_ke {
        Some(p) => match texture(p, &m.loc, desc, cache, false) {
            Some(t) => Some(ColorParam::Texture(t)),
            None => (m.ke.max_element() > 0.0).then_some(ColorParam::Const(m.ke)),
        },
        None => (m.ke.max_element() > 0.0).then_some(ColorParam::Const(m.ke)),
    };
    (id, emission)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec2;

    #[test]
    fn ns_maps_to_alpha() {
        assert!((ns_to_alpha(0.0) - 1.0).abs() < 1e-6);
        assert!((ns_to_alpha(198.0) - 0.1).abs() < 1e-6);
    }

    #[test]
    fn map_options_are_skipped() {
        assert_eq!(
            map_file("-bm 0.5 -s 1 1 1 tex/a b.png").as_deref(),
            Some("tex/a b.png")
        );
        assert_eq!(map_file("-clamp on x.png").as_deref(), Some("x.png"));
        assert_eq!(map_file("-bm 1"), None);
        assert_eq!(bump_multiplier("-bm 0.5 -s 1 1 1 h.png"), Ok(0.5));
        assert_eq!(bump_multiplier("h.png"), Ok(1.0));
        assert!(bump_multiplier("-bm x h.png").is_err());
    }

    #[test]
    fn uv_flip() {
        let p = obj_to_uv().transform_point2(Vec2::new(0.25, 0.1));
        assert!((p - Vec2::new(0.25, 0.9)).length() < 1e-6);
    }
}
