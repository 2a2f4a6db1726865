//! The format-independent scene description (`SceneDesc`).
//!
//! Every loader translates its format into these types; the renderer's `build` step is the only
//! consumer. Plain data: no rendering logic lives here. Conventions:
//! - right-handed world, linear Rec.709 RGB radiance, angles in **degrees** (as the formats
//!   write them; the renderer converts to radians);
//! - shapes keep their object-space geometry plus a `to_world` matrix;
//! - every element keeps the source location it came from (`Loc`) for warnings and errors.

use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::Arc;

pub use glam::{Mat3, Mat4, Vec2, Vec3};

use crate::error::{Loc, Warning};

pub use base::dispersion::{Dispersion, DispersionSampling};
pub use base::*;

/// Linear RGB triple (Rec.709 primaries).
pub type Rgb = Vec3;

/// Index into `SceneDesc::materials`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MaterialId(pub u32);

/// Index into `SceneDesc::media`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MediumId(pub u32);

/// Index into `SceneDesc::textures`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TextureId(pub u32);

/// A colour-valued parameter: a constant, a texture, or a spectrum the scene declared.
#[derive(Clone, Debug, PartialEq)]
pub enum ColorParam {
    Const(Rgb),
    Texture(TextureId),
    /// A constant declared as a spectrum (Mitsuba's `<spectrum>`): RGB mode renders its `rgb`,
    /// exactly as [`ColorParam::Const`] of it; spectral mode samples the declaration.
    Spectrum(Arc<SpectrumDesc>),
}

impl ColorParam {
    pub fn constant(v: f32) -> Self {
        ColorParam::Const(Rgb::splat(v))
    }

    /// The constant RGB value (also of a declared spectrum); `None` for a texture.
    pub fn const_rgb(&self) -> Option<Rgb> {
        match self {
            ColorParam::Const(c) => Some(*c),
            ColorParam::Spectrum(s) => Some(s.rgb),
            ColorParam::Texture(_) => None,
        }
    }
}

impl From<ColorValue> for ColorParam {
    fn from(v: ColorValue) -> Self {
        match v {
            ColorValue::Rgb(c) => ColorParam::Const(c),
            ColorValue::Spectrum(s) => ColorParam::Spectrum(s),
        }
    }
}

/// A constant colour (no texture) that a format may have declared as a spectrum: emitter
/// radiance, intensity and irradiance, conductor η and k.
#[derive(Clone, Debug, PartialEq)]
pub enum ColorValue {
    Rgb(Rgb),
    /// RGB mode renders its `rgb`; spectral mode samples the declaration.
    Spectrum(Arc<SpectrumDesc>),
}

impl ColorValue {
    /// The value RGB mode renders with.
    pub fn rgb(&self) -> Rgb {
        match self {
            ColorValue::Rgb(c) => *c,
            ColorValue::Spectrum(s) => s.rgb,
        }
    }

    /// The declared spectrum, if there is one.
    pub fn spectrum(&self) -> Option<&SpectrumDesc> {
        match self {
            ColorValue::Rgb(_) => None,
            ColorValue::Spectrum(s) => Some(s),
        }
    }

    /// The value divided by `d` (a spectrum's RGB and its `scale` both).
    pub fn divided(&self, d: f32) -> ColorValue {
        match self {
            ColorValue::Rgb(c) => ColorValue::Rgb(*c / d),
            ColorValue::Spectrum(s) => ColorValue::Spectrum(Arc::new(SpectrumDesc {
                rgb: s.rgb / d,
                kind: s.kind.clone(),
                scale: s.scale / d as f64,
            })),
        }
    }
}

impl From<Rgb> for ColorValue {
    fn from(c: Rgb) -> Self {
        ColorValue::Rgb(c)
    }
}

/// A spectrum as a scene declared it, with the linear sRGB value the loader converted it to
/// for RGB mode (for Mitsuba: as Mitsuba 3's RGB variants convert it, `crate::spectra`).
/// Its value at λ is `scale`·`kind`(λ), in the units Mitsuba 3's spectral variants use.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectrumDesc {
    pub rgb: Rgb,
    pub kind: SpectrumKind,
    pub scale: f64,
}

impl SpectrumDesc {
    /// The value at `lambda` nm (`scale`·`kind`(λ)).
    pub fn eval(&self, lambda: f64) -> f64 {
        let v = match &self.kind {
            SpectrumKind::Uniform(v) => *v,
            SpectrumKind::Blackbody { temperature } => crate::spectra::planck(lambda, *temperature),
            kind => {
                let (w, v) = kind.table().expect("tabulated");
                crate::spectra::interpolate(&w, &v, lambda)
            }
        };
        self.scale * v
    }
}

/// The nodes of a tabulated spectrum: wavelengths (nm) and values.
pub type SpectrumTable<'a> = (Cow<'a, [f64]>, Cow<'a, [f64]>);

impl SpectrumKind {
    /// The nodes (wavelengths in nm, values) of a tabulated kind: lists and files, D65's 5 nm
    /// table, a measured conductor's η or k; `None` for uniform and black-body spectra.
    pub fn table(&self) -> Option<SpectrumTable<'_>> {
        match self {
            SpectrumKind::Tabulated {
                wavelengths,
                values,
            } => Some((Cow::Borrowed(wavelengths), Cow::Borrowed(values))),
            SpectrumKind::D65 => {
                let (w, v) = crate::spectra::d65_nodes();
                Some((Cow::Owned(w), Cow::Owned(v)))
            }
            SpectrumKind::Conductor { material, eta } => {
                let m = crate::formats::mitsuba::ior::measured(material)?;
                Some((
                    Cow::Borrowed(m.wavelengths),
                    Cow::Borrowed(if *eta { m.eta } else { m.k }),
                ))
            }
            SpectrumKind::Uniform(_) | SpectrumKind::Blackbody { .. } => None,
        }
    }
}

/// What a declared spectrum is, as written (values before `SpectrumDesc::scale`).
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumKind {
    /// `wavelength:value` pairs (nm, strictly increasing), given inline or in a spectrum file:
    /// linear in between, zero outside the first and last wavelength (Mitsuba's `irregular`).
    Tabulated {
        wavelengths: Vec<f64>,
        values: Vec<f64>,
    },
    /// The same value at every wavelength (Mitsuba's `uniform`).
    Uniform(f64),
    /// Planck's law at `temperature` K in W·m⁻²·sr⁻¹·nm⁻¹, unnormalised (Mitsuba's
    /// `blackbody`; `crate::spectra::planck`).
    Blackbody { temperature: f64 },
    /// CIE D65 normalised to unit luminance (Mitsuba's `d65`: its 5 nm table, linear in
    /// between, times 1/98.997…; `crate::spectra::cie_d65`).
    D65,
    /// The measured η (`eta: true`) or k of a conductor Mitsuba names (`material="Cu"`), from
    /// its `data/ior` files (`formats::mitsuba::ior::measured`).
    Conductor { material: String, eta: bool },
}

/// A scalar parameter: a constant or a texture (whose first channel / luminance is used).
#[derive(Clone, Debug, PartialEq)]
pub enum FloatParam {
    Const(f32),
    Texture(TextureId),
}

/// What a loader produces: either a scene to render or a Nori-style statistical test file.
#[derive(Clone, Debug)]
pub enum Document {
    Scene(Box<SceneDesc>),
    Test(TestDesc),
}

#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    /// The file the scene was loaded from (the main file, not includes).
    pub source: PathBuf,
    pub shapes: Vec<ShapeDesc>,
    pub materials: Vec<MaterialDesc>,
    pub textures: Vec<TextureDesc>,
    /// Emitters that are not attached to a shape (area emitters live on `ShapeDesc`).
    pub emitters: Vec<EmitterDesc>,
    /// Participating media, referenced by shapes (interior/exterior), sensors and emitters.
    pub media: Vec<MediumDesc>,
    /// At least one sensor after loading (loaders add the format's default camera).
    pub sensors: Vec<Sensor>,
    pub integrator: IntegratorDesc,
    /// Background radiance seen by rays that escape (formats with a "background colour").
    pub background: Option<Rgb>,
    /// A texture spread over the image instead (CENG795 `replace_background`): camera rays
    /// that escape see it at the film position (u, v) ∈ [0, 1]², v down.
    pub background_texture: Option<TextureId>,
    /// How integrators pick one emitter for next-event estimation.
    pub light_selection: LightSelection,
    /// Non-fatal findings of the loader (unknown parameters, ignored features...).
    pub warnings: Vec<Warning>,
}

impl SceneDesc {
    /// World-space bounds of the bounded shapes (`None` when there are none).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        bounds_of(&self.shapes)
    }

    pub fn add_material(&mut self, m: MaterialDesc) -> MaterialId {
        self.materials.push(m);
        MaterialId(self.materials.len() as u32 - 1)
    }
    pub fn add_medium(&mut self, m: MediumDesc) -> MediumId {
        self.media.push(m);
        MediumId(self.media.len() as u32 - 1)
    }
    pub fn add_texture(&mut self, t: TextureDesc) -> TextureId {
        self.textures.push(t);
        TextureId(self.textures.len() as u32 - 1)
    }
    pub fn material(&self, id: MaterialId) -> &MaterialDesc {
        &self.materials[id.0 as usize]
    }
    pub fn texture(&self, id: TextureId) -> &TextureDesc {
        &self.textures[id.0 as usize]
    }
}

// ---------------------------------------------------------------------------------------------
// Shapes

#[derive(Clone, Debug)]
pub struct ShapeDesc {
    pub shape: Shape,
    /// Object-to-world transform (identity when the format gives world-space data).
    pub to_world: Mat4,
    /// `None`: the format's default material (diffuse 0.5 grey).
    pub material: Option<MaterialId>,
    /// Set when the shape is an area light.
    pub emission: Option<AreaEmission>,
    /// Flip the shading and geometric normals (Mitsuba `flip_normals`).
    pub flip_normals: bool,
    /// The media on either side of the surface (a medium transition when either is set).
    pub media: MediumInterface,
    /// Motion blur: the shape moves by `τ·motion` (world space, after `to_world`) at time τ
    /// of the shutter interval [0, 1] (CENG795 `MotionBlur`). `None`: static.
    pub motion: Option<Vec3>,
    pub name: Option<String>,
    pub loc: Loc,
}

#[derive(Clone, Debug)]
pub enum Shape {
    /// A triangle mesh in object space.
    Mesh(Arc<TriMesh>),
    /// Sphere in object space.
    Sphere { center: Vec3, radius: f32 },
    /// Mitsuba's rectangle: the square [-1,1]² in the z = 0 plane, normal +z,
    /// uv = ((x+1)/2, (y+1)/2).
    Rectangle,
    /// Mitsuba's disk: the unit disk in the z = 0 plane, normal +z.
    Disk,
    /// Mitsuba's cube: [-1,1]³ with outward normals.
    Cube,
    /// Mitsuba's cylinder: the open unit cylinder x² + y² = 1, 0 ≤ z ≤ 1 (no caps), normals
    /// outward, uv = (φ/2π with φ ∈ [0, 2π) from +x towards +y, z). The Mitsuba loader folds
    /// `p0`, `p1` and `radius` into `to_world`.
    Cylinder,
    /// An infinite plane through `point` with normal `normal` (object space).
    InfinitePlane { point: Vec3, normal: Vec3 },
}

impl ShapeDesc {
    /// World-space bounds (`None` for an infinite plane). Spheres are bounded exactly, also
    /// as ellipsoids: the centre ± radius × the length of each row of the linear part.
    /// Rectangles and disks by the corners of their square, cubes and cylinders by their boxes'.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let m = &self.to_world;
        let corners = |z: [f32; 2]| {
            let mut lo = Vec3::splat(f32::INFINITY);
            let mut hi = Vec3::splat(f32::NEG_INFINITY);
            for x in [-1.0, 1.0] {
                for y in [-1.0, 1.0] {
                    for z in z {
                        let q = m.transform_point3(Vec3::new(x, y, z));
                        lo = lo.min(q);
                        hi = hi.max(q);
                    }
                }
            }
            (lo, hi)
        };
        let b = match &self.shape {
            Shape::Mesh(mesh) => {
                let mut lo = Vec3::splat(f32::INFINITY);
                let mut hi = Vec3::splat(f32::NEG_INFINITY);
                for p in &mesh.positions {
                    let q = m.transform_point3(*p);
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
                (lo, hi)
            }
            Shape::Sphere { center, radius } => {
                let c = m.transform_point3(*center);
                let l = Mat3::from_mat4(*m);
                let ext = Vec3::new(l.row(0).length(), l.row(1).length(), l.row(2).length())
                    * radius.abs();
                (c - ext, c + ext)
            }
            Shape::Rectangle | Shape::Disk => corners([0.0, 0.0]),
            Shape::Cube => corners([-1.0, 1.0]),
            Shape::Cylinder => corners([0.0, 1.0]),
            Shape::InfinitePlane { .. } => return None,
        };
        (b.0.cmple(b.1).all() && b.0.is_finite() && b.1.is_finite()).then_some(b)
    }
}

/// World-space bounds of the bounded ones of `shapes` (`None` when there are none).
pub fn bounds_of<'a>(shapes: impl IntoIterator<Item = &'a ShapeDesc>) -> Option<(Vec3, Vec3)> {
    shapes
        .into_iter()
        .filter_map(ShapeDesc::bounds)
        .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
}

impl Shape {
    pub fn kind_name(&self) -> &'static str {
        match self {
            Shape::Mesh(_) => "mesh",
            Shape::Sphere { .. } => "sphere",
            Shape::Rectangle => "rectangle",
            Shape::Disk => "disk",
            Shape::Cube => "cube",
            Shape::Cylinder => "cylinder",
            Shape::InfinitePlane { .. } => "infinite plane",
        }
    }
}

/// Whether the linear part of `m` is a rotation (or reflection) times a uniform scale, so a
/// sphere stays a sphere under `m` (columns orthogonal and of equal length, to 1e-5).
pub fn is_similarity(m: &Mat4) -> bool {
    let c = [
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    ];
    let l2 = c.map(|v| v.length_squared());
    let s2 = l2[0].max(l2[1]).max(l2[2]);
    if !(s2 > 0.0 && s2.is_finite()) {
        return false;
    }
    let tol = 1e-5 * s2;
    l2.iter().all(|&l| (l - s2).abs() <= 2.0 * tol)
        && c[0].dot(c[1]).abs() <= tol
        && c[0].dot(c[2]).abs() <= tol
        && c[1].dot(c[2]).abs() <= tol
}

/// An indexed triangle mesh. `normals` and `uvs` are either empty or one per position.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<[u32; 3]>,
}

impl TriMesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }
}

#[derive(Clone, Debug)]
pub struct AreaEmission {
    /// Emitted radiance on the front side (the side the normal points to).
    pub radiance: ColorParam,
    /// Emit on both sides (CS184 area lights are one-sided; some formats are two-sided).
    pub two_sided: bool,
    /// Mitsuba 3's `directionalarea`: emit only along the normal (a delta in direction),
    /// `radiance` being the flux per unit area; only light tracing renders its light.
    pub directional: bool,
    pub loc: Loc,
}

/// The media on the two sides of a surface: `interior` on the side opposite the normal,
/// `exterior` on the side it points to (Mitsuba's convention). A ray crossing the surface
/// enters the medium of the side it goes to; `None` is vacuum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumInterface {
    pub interior: Option<MediumId>,
    pub exterior: Option<MediumId>,
}

impl MediumInterface {
    /// Whether crossing the surface can change the medium (either side is set).
    pub fn is_transition(&self) -> bool {
        self.interior.is_some() || self.exterior.is_some()
    }
}

// ---------------------------------------------------------------------------------------------
// Participating media

#[derive(Clone, Debug)]
pub struct MediumDesc {
    pub medium: Medium,
    pub phase: PhaseDesc,
    /// Light the medium emits: the source term of the transfer equation is σa·Le.
    pub emission: Option<MediumEmission>,
    pub name: Option<String>,
    pub loc: Loc,
}

/// A participating medium, with Mitsuba 3's parameters: extinction σt per unit length (world
/// units) times `scale`, and the single-scattering albedo σs/σt.
#[derive(Clone, Debug)]
pub enum Medium {
    /// Constant coefficients: σt = `sigma_t`·`scale`, σs = `albedo`·σt.
    Homogeneous {
        sigma_t: Rgb,
        albedo: Rgb,
        scale: f32,
    },
    /// Coefficients from grids: σt(x) = `scale`·`sigma_t`(x), σs(x) = `albedo`(x)·σt(x).
    Heterogeneous {
        sigma_t: Box<VolumeDesc>,
        albedo: VolumeParam,
        scale: f32,
    },
}

impl Medium {
    pub fn kind_name(&self) -> &'static str {
        match self {
            Medium::Homogeneous { .. } => "homogeneous",
            Medium::Heterogeneous { .. } => "heterogeneous",
        }
    }
}

/// What a medium emits.
#[derive(Clone, Debug)]
pub enum MediumEmission {
    /// The emitted radiance Le (a constant or a grid: Mitsuba's `radiance`).
    Radiance(VolumeParam),
    /// A temperature field in kelvin (our extension): Le is the black-body radiance at that
    /// temperature in Mitsuba's `blackbody` units (W·m⁻²·sr⁻¹·nm⁻¹), projected to RGB, times
    /// `scale`.
    Temperature { grid: Box<VolumeDesc>, scale: f32 },
}

/// A medium parameter: a constant or a grid.
#[derive(Clone, Debug)]
pub enum VolumeParam {
    Const(Rgb),
    Grid(Box<VolumeDesc>),
    /// Only as a heterogeneous medium's albedo: σs from its own grid, in the units of the
    /// `sigma_t` grid (before `scale`) and on its lattice; the albedo is σs(x)/σt(x), each
    /// interpolated on its own (pbrt-v4's `rgbgrid`).
    SigmaSGrid(Box<VolumeDesc>),
}

/// A voxel grid read from a file or given inline, placed in the world: a `.vol` grid and an
/// inline one fill the unit cube [0,1]³ of their own space (Mitsuba's `gridvolume`: the
/// file's bounding box is ignored), mapped to the world by `to_world`; an OpenVDB grid sits
/// in its own local space, where its transform puts it, and `to_world` maps that space to the
/// world. `path` names the file (for an inline grid, the scene file that holds it).
#[derive(Clone, Debug)]
pub struct VolumeDesc {
    pub path: PathBuf,
    pub format: VolumeFormat,
    pub to_world: Mat4,
    /// Trilinear interpolation between voxel centres (Mitsuba's default), or nearest voxel.
    pub trilinear: bool,
    pub loc: Loc,
}

#[derive(Clone, Debug, PartialEq)]
pub enum VolumeFormat {
    /// Mitsuba's binary `.vol` (version 3, float32).
    MitsubaVol,
    /// An OpenVDB file and the name of the grid to read. `own_map`: the grid's own
    /// index-to-local map places its voxels in the space `to_world` starts from (Mitsuba
    /// semantics, voxels land where OpenVDB puts them); otherwise the grid's active box is
    /// the `[0,1]³` that `to_world` places (Nori's user-given bounding box).
    Vdb { grid_name: String, own_map: bool },
    /// Values given in the scene (pbrt-v4's `uniformgrid`/`rgbgrid`): `channels` (1 or 3)
    /// per voxel, `((z·ny + y)·nx + x)·channels + c`, finite and ≥ 0. Looked up as pbrt-v4's
    /// `SampledGrid`: trilinear between voxel centres at (i + ½)/n, voxels beyond the grid
    /// read 0 (so the value falls off over the outer half voxel).
    Inline {
        res: [usize; 3],
        channels: usize,
        data: Arc<[f32]>,
    },
}

/// How a medium scatters: the phase function.
#[derive(Clone, Debug, PartialEq)]
pub enum PhaseDesc {
    Isotropic,
    /// Henyey–Greenstein with mean cosine `g` ∈ (−1, 1) (forward scattering for g > 0).
    HenyeyGreenstein {
        g: f32,
    },
    /// Rayleigh scattering (unpolarised).
    Rayleigh,
    /// Values at scattering cosines spaced evenly over [−1, 1] (1 forward), linear between
    /// them, normalised by the renderer (Mitsuba's `tabphase`): at least two, non-negative,
    /// not all zero.
    Tabulated {
        values: Vec<f32>,
    },
    /// `(1 − weight)·first + weight·second`, weight in [0, 1] (Mitsuba's `blendphase`).
    Blend {
        weight: f32,
        phases: Box<[PhaseDesc; 2]>,
    },
    /// Mitsuba 3's `sggx`: specular SGGX microflakes whose S matrix (S_xx, S_yy, S_zz, S_xy,
    /// S_xz, S_yz) a 6-channel Mitsuba `.vol` grid at `s_grid` gives; the renderer takes it
    /// constant (every voxel equal), `build` refuses one that varies.
    Sggx {
        s_grid: std::path::PathBuf,
    },
}

// ---------------------------------------------------------------------------------------------
// Materials

#[derive(Clone, Debug)]
pub struct MaterialDesc {
    pub material: Material,
    /// Ambient reflectance (CENG795 `AmbientReflectance`), used only with an
    /// [`Emitter::Ambient`] by the course ray tracers; zero elsewhere.
    pub ambient: Rgb,
    pub name: Option<String>,
    pub loc: Loc,
}

/// Every material model any supported format can name. Not all are rendered yet; `build`
/// reports the ones it does not support.
#[derive(Clone, Debug)]
pub enum Material {
    /// Lambertian.
    Diffuse { reflectance: ColorParam },
    /// Smooth conductor with complex index of refraction `eta + i k` (relative to the outside).
    Conductor {
        eta: ColorValue,
        k: ColorValue,
        specular_reflectance: ColorParam,
    },
    /// Microfacet conductor (anisotropic when `alpha_u != alpha_v`).
    RoughConductor {
        distribution: MicrofacetDistribution,
        alpha_u: FloatParam,
        alpha_v: FloatParam,
        eta: ColorValue,
        k: ColorValue,
        specular_reflectance: ColorParam,
    },
    /// Smooth dielectric interface; `absorption` is a Beer–Lambert coefficient per unit length
    /// inside the medium (COMP30019, CENG795). `int_ior` is the index an RGB render uses; when
    /// `dispersion` is set (a named glass, Sellmeier or Cauchy coefficients), `int_ior` is its
    /// value at the d line and a spectral render evaluates `dispersion` per wavelength.
    Dielectric {
        int_ior: f32,
        ext_ior: f32,
        dispersion: Option<Dispersion>,
        specular_reflectance: ColorParam,
        specular_transmittance: ColorParam,
        absorption: Option<Rgb>,
    },
    /// Thin dielectric sheet (no refraction offset). IORs as in `Dielectric`.
    ThinDielectric {
        int_ior: f32,
        ext_ior: f32,
        dispersion: Option<Dispersion>,
        specular_reflectance: ColorParam,
        specular_transmittance: ColorParam,
    },
    /// IORs as in `Dielectric`; `dispersion_sampling` says how a spectral render keeps the
    /// wavelengths through a dispersive index.
    RoughDielectric {
        distribution: MicrofacetDistribution,
        alpha_u: FloatParam,
        alpha_v: FloatParam,
        int_ior: f32,
        ext_ior: f32,
        dispersion: Option<Dispersion>,
        dispersion_sampling: DispersionSampling,
        specular_reflectance: ColorParam,
        specular_transmittance: ColorParam,
    },
    /// Mitsuba's smooth plastic: dielectric coating over a diffuse base.
    Plastic {
        diffuse_reflectance: ColorParam,
        specular_reflectance: ColorParam,
        int_ior: f32,
        ext_ior: f32,
        nonlinear: bool,
    },
    RoughPlastic {
        distribution: MicrofacetDistribution,
        alpha: f32,
        diffuse_reflectance: ColorParam,
        specular_reflectance: ColorParam,
        int_ior: f32,
        ext_ior: f32,
        nonlinear: bool,
    },
    /// Mitsuba `twosided`: `front` on both sides, or `back` on the back side when given.
    TwoSided {
        front: MaterialId,
        back: Option<MaterialId>,
    },
    /// Perfect mirror (Nori `mirror`, Mitsuba `conductor` with material `none`).
    Mirror { reflectance: ColorParam },
    /// Nori's `microfacet`: a Beckmann dielectric-Fresnel specular lobe plus a diffuse term.
    NoriMicrofacet {
        alpha: f32,
        int_ior: f32,
        ext_ior: f32,
        kd: Rgb,
    },
    /// The CENG795 Phong family (and Torrance–Sparrow).
    PhongFamily {
        model: PhongModel,
        /// `_normalized`: energy-normalised lobes.
        normalized: bool,
        /// `_kdfresnel` (Torrance–Sparrow): scale the diffuse term by 1 − F.
        kd_fresnel: bool,
        exponent: f32,
        diffuse: ColorParam,
        specular: ColorParam,
        /// Refraction index used by the Torrance–Sparrow Fresnel term.
        ior: f32,
        /// `AbsorptionIndex` k: when positive, the Torrance–Sparrow Fresnel term is that of a
        /// conductor with complex index `ior + i k` instead of Schlick's dielectric one.
        absorption: f32,
        /// The recursively traced lobe of a course mirror, conductor or dielectric.
        ideal: Option<CourseIdeal>,
    },
    /// Tangent-space normal map around `nested` (Mitsuba `normalmap`): the texture's RGB in
    /// [0,1] encodes the shading normal 2·c − 1 in the frame (dp/du, n × dp/du, n). The texture
    /// must be read raw (no sRGB decoding).
    NormalMap {
        nested: MaterialId,
        texture: TextureId,
    },
    /// Alpha cut-out around `nested` (Mitsuba `mask`, OBJ `map_d`/`d`): the surface is there
    /// with probability `opacity` (a bitmap's alpha channel when its file has one, else its
    /// first channel) and the ray passes through it otherwise. Only meaningful as a shape's own
    /// material: below a `twosided` or `normalmap` the opacity is ignored (with a warning).
    Mask {
        nested: MaterialId,
        opacity: FloatParam,
    },
    /// Bump map around `nested` (CENG795 `bump_normal`): the shading normal tilts against the
    /// gradient of the texture's height (its channel mean), scaled by `factor`.
    BumpMap {
        nested: MaterialId,
        texture: TextureId,
        factor: f32,
    },
    /// Mitsuba 3's `bumpmap` around `nested`: ∂p/∂u and ∂p/∂v get `scale` times the
    /// texture's uv gradient (its first channel) along the shading normal, their cross product
    /// is the shading normal; `flip_invalid_normals` and `use_shadowing_function` (both on by
    /// default) as Mitsuba 3.9.
    HeightBump {
        nested: MaterialId,
        texture: TextureId,
        scale: f32,
        flip_invalid_normals: bool,
        shadowing: bool,
    },
    /// Random-walk subsurface scattering (Cycles' and pbrt-v4's): `boundary`, a `Dielectric` or
    /// `RoughDielectric`, around a homogeneous scattering medium that the build step puts
    /// inside every shape using the material (unless the shape declares an interior), so that
    /// every integrator serving media walks inside it as in any medium.
    Subsurface {
        boundary: Box<Material>,
        medium: SubsurfaceMedium,
    },
    /// No shading at all (CENG795 `replace_all`): the surface shows `color` as radiance to
    /// whoever looks at it, reflects nothing and lights nothing else.
    Unlit { color: ColorParam },
    /// Invisible interface (Mitsuba `null`).
    Null,
    /// pbrt-v4's `diffusetransmission`: Lambertian reflection `reflectance` on the side the
    /// light comes from and Lambertian transmission `transmittance` to the other side.
    DiffuseTransmission {
        reflectance: ColorParam,
        transmittance: ColorParam,
    },
    /// pbrt-v4's `coateddiffuse`: a dielectric interface (index `eta`, GGX `alpha_u/v`, or
    /// pbrt-v4 roughnesses turned into α = √r per lookup when `remap_roughness`; smooth below
    /// α = 10⁻³) over a Lambertian base `reflectance`, the two separated by a
    /// slab of optical `thickness` holding a medium of single-scattering `albedo` (none when
    /// black) with Henyey–Greenstein `g`. Evaluated as pbrt-v4's stochastic layered BSDF:
    /// random walks of at most `max_depth` scattering events, `n_samples` per evaluation.
    CoatedDiffuse {
        reflectance: ColorParam,
        alpha_u: FloatParam,
        alpha_v: FloatParam,
        remap_roughness: bool,
        eta: f32,
        thickness: FloatParam,
        albedo: ColorParam,
        g: FloatParam,
        max_depth: u32,
        n_samples: u32,
    },
    /// pbrt-v4's `coatedconductor`: as `CoatedDiffuse` with a conductor base (GGX
    /// `conductor_alpha_u/v`; index `conductor_eta + i conductor_k` as declared, or, when
    /// `reflectance` is set, the index pbrt-v4 derives from it: η = 1, k = 2√r/√(1−r)). As
    /// pbrt-v4 does, the renderer divides the conductor's index by the coating's.
    CoatedConductor {
        interface_alpha_u: FloatParam,
        interface_alpha_v: FloatParam,
        remap_roughness: bool,
        interface_eta: f32,
        thickness: FloatParam,
        albedo: ColorParam,
        g: FloatParam,
        max_depth: u32,
        n_samples: u32,
        conductor_alpha_u: FloatParam,
        conductor_alpha_v: FloatParam,
        conductor_eta: ColorValue,
        conductor_k: ColorValue,
        reflectance: Option<ColorParam>,
    },
    /// Mitsuba 3's `principled` (Disney's BSDF as Mitsuba defines it).
    Principled(Box<PrincipledDesc>),
    /// Mitsuba 3's `principledthin` (the two-sided thin-sheet variant).
    PrincipledThin(Box<PrincipledThinDesc>),
    /// Mitsuba 3's `pplastic` as its unpolarised variants render it (`alpha_u`/`alpha_v`
    /// constants, Beckmann by default, α = 0.1, polypropylene in air).
    PolarizedPlastic {
        distribution: MicrofacetDistribution,
        alpha_u: f32,
        alpha_v: f32,
        diffuse_reflectance: ColorParam,
        specular_reflectance: ColorParam,
        int_ior: f32,
        ext_ior: f32,
    },
    /// Mitsuba 3's `blendbsdf`: (1 − weight)·materials[0] + weight·materials[1], both
    /// evaluated at every query (unlike `Mix`, which picks one).
    Blend {
        materials: [MaterialId; 2],
        weight: FloatParam,
    },
    /// pbrt-v4's `mix`: at each shading point one of `materials` is chosen, the second with
    /// probability `amount` (a deterministic hash of the point and direction, as pbrt-v4 does).
    Mix {
        materials: [MaterialId; 2],
        amount: FloatParam,
    },
}

/// Mitsuba 3's `principled` parameters, with its defaults (base colour 0.5, roughness 0.5,
/// everything else 0, sampling rates 1). `eta` is the interior/exterior index, given or made
/// from `specular` (η = 2/(1 − √(0.08·specular)) − 1, specular 0.5 by default).
#[derive(Clone, Debug)]
pub struct PrincipledDesc {
    pub base_color: ColorParam,
    pub roughness: FloatParam,
    pub anisotropic: FloatParam,
    pub metallic: FloatParam,
    pub spec_trans: FloatParam,
    pub spec_tint: FloatParam,
    pub sheen: FloatParam,
    pub sheen_tint: FloatParam,
    pub flatness: FloatParam,
    pub clearcoat: FloatParam,
    pub clearcoat_gloss: FloatParam,
    pub eta: f32,
    /// `main_specular_sampling_rate`, `clearcoat_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate`.
    pub rates: [f32; 3],
}

/// Mitsuba 3's `principledthin` parameters, with its defaults (base colour 0.5, roughness
/// 0.5, eta 1.5, everything else 0, sampling rates 1); every parameter but the rates may be
/// a texture. `diff_trans` is Mitsuba's, in 0..2.
#[derive(Clone, Debug)]
pub struct PrincipledThinDesc {
    pub base_color: ColorParam,
    pub roughness: FloatParam,
    pub anisotropic: FloatParam,
    pub spec_trans: FloatParam,
    pub spec_tint: FloatParam,
    pub sheen: FloatParam,
    pub sheen_tint: FloatParam,
    pub flatness: FloatParam,
    pub diff_trans: FloatParam,
    pub eta: FloatParam,
    /// `specular_reflectance_sampling_rate`, `specular_transmittance_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate`, `diffuse_transmittance_sampling_rate`.
    pub rates: [f32; 4],
}

/// The ideal lobe of a CENG795 `mirror`, `conductor` or `dielectric` material, traced on top
/// of its Phong-family lobes (render crate `bsdf::course` gives the exact definitions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CourseIdeal {
    pub kind: CourseIdealKind,
    /// `MirrorReflectance` (mirror, conductor).
    pub reflectance: Rgb,
    /// `Roughness`: side of the square the ideal direction is perturbed in (0: none).
    pub roughness: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CourseIdealKind {
    Mirror,
    /// Complex index `eta + i k` (`RefractionIndex`, `AbsorptionIndex`).
    Conductor {
        eta: f32,
        k: f32,
    },
    /// `RefractionIndex`, and `AbsorptionCoefficient` (Beer–Lambert, per unit length) inside.
    Dielectric {
        ior: f32,
        absorption: Option<Rgb>,
    },
}

impl Material {
    pub fn kind_name(&self) -> &'static str {
        match self {
            Material::Diffuse { .. } => "diffuse",
            Material::Conductor { .. } => "conductor",
            Material::RoughConductor { .. } => "roughconductor",
            Material::Dielectric { .. } => "dielectric",
            Material::ThinDielectric { .. } => "thindielectric",
            Material::RoughDielectric { .. } => "roughdielectric",
            Material::Plastic { .. } => "plastic",
            Material::RoughPlastic { .. } => "roughplastic",
            Material::TwoSided { .. } => "twosided",
            Material::NormalMap { .. } => "normalmap",
            Material::BumpMap { .. } => "bumpmap",
            Material::Unlit { .. } => "unlit",
            Material::Mask { .. } => "mask",
            Material::Mirror { .. } => "mirror",
            Material::NoriMicrofacet { .. } => "microfacet",
            Material::PhongFamily { .. } => "phong-family",
            Material::Null => "null",
            Material::DiffuseTransmission { .. } => "diffusetransmission",
            Material::CoatedDiffuse { .. } => "coateddiffuse",
            Material::CoatedConductor { .. } => "coatedconductor",
            Material::Mix { .. } => "mix",
            Material::Principled(_) => "principled",
            Material::PrincipledThin(_) => "principledthin",
            Material::Blend { .. } => "blendbsdf",
            Material::PolarizedPlastic { .. } => "pplastic",
            Material::HeightBump { .. } => "bumpmap",
            Material::Subsurface { .. } => "subsurface",
        }
    }
}

/// The medium inside a [`Material::Subsurface`]: its coefficients as declared, a scale
/// applied to σa and σs (pbrt-v4's `scale`; units per scene length) and the
/// Henyey–Greenstein asymmetry `g`.
#[derive(Clone, Debug, PartialEq)]
pub struct SubsurfaceMedium {
    pub coefficients: SubsurfaceCoefficients,
    pub scale: f32,
    pub g: f32,
}

#[derive(Clone, Debug, PartialEq)]
pub enum SubsurfaceCoefficients {
    /// Absorption and scattering coefficients per unit length.
    Sigma { sigma_a: Rgb, sigma_s: Rgb },
    /// Mean free path (1/σt) and multiple-scattering albedo, inverted to the single-scattering
    /// albedo by `base::subsurface::single_scattering_albedo`.
    MeanFreePath { mfp: Rgb, albedo: Rgb },
    /// Jensen et al. 2001's measured medium (`base::subsurface::MEASURED`), in mm⁻¹.
    Measured(&'static base::subsurface::Measured),
}

impl SubsurfaceMedium {
    /// σa and σs per unit length, scaled.
    pub fn sigma(&self) -> (Rgb, Rgb) {
        let (a, s) = match &self.coefficients {
            SubsurfaceCoefficients::Sigma { sigma_a, sigma_s } => (*sigma_a, *sigma_s),
            SubsurfaceCoefficients::MeanFreePath { mfp, albedo } => {
                let (a, s) =
                    base::subsurface::coefficients_from_albedo(mfp.to_array(), albedo.to_array());
                (Rgb::from(a), Rgb::from(s))
            }
            SubsurfaceCoefficients::Measured(m) => {
                (Rgb::from(m.sigma_a), Rgb::from(m.sigma_prime_s))
            }
        };
        (a * self.scale, s * self.scale)
    }
}

// ---------------------------------------------------------------------------------------------
// Textures

#[derive(Clone, Debug)]
pub struct TextureDesc {
    pub texture: Texture,
    pub name: Option<String>,
    pub loc: Loc,
}

#[derive(Clone, Debug)]
pub enum Texture {
    Constant(Rgb),
    /// An image file. 8-bit images are sRGB-decoded unless `raw`; float images are linear.
    Bitmap {
        /// Resolved by the loader: absolute, or relative to the working directory.
        path: PathBuf,
        filter: TextureFilter,
        wrap: WrapMode,
        raw: bool,
        /// Gamma used to linearise 8-bit data when not sRGB (CENG795 `_degamma`, CS-E5520 2.2).
        gamma: Option<f32>,
        to_uv: Mat3,
        /// Texel (i, j) sits at uv (i/w, j/h) — the CENG795 course's addressing, where nearest
        /// is texel (round(u·w), round(v·h)) — instead of at its centre ((i+½)/w, (j+½)/h).
        corner_texels: bool,
        /// Every filter reads a MIP level chosen by the lookup's footprint (pbrt-v4's image
        /// textures); otherwise only trilinear and EWA filtering use MIP maps and nearest and
        /// bilinear read the image itself (Mitsuba's and the courses' textures).
        mipmapped: bool,
    },
    Checkerboard {
        color0: Rgb,
        color1: Rgb,
        to_uv: Mat3,
    },
    /// The CENG795 course's Perlin noise at the world-space point p·`scale` (render crate
    /// `textures::perlin` has the definition), converted to [0, 1] as `conversion` says; grey.
    Perlin {
        scale: f32,
        conversion: NoiseConversion,
    },
    /// The CENG795 course's solid checkerboard: cells of side 1/`scale` in world space, shifted
    /// by `offset`; `black` where the parities of ⌊(x + offset)·scale⌋, ⌊(y + …)⌋, ⌊(z + …)⌋
    /// have an odd sum, `white` elsewhere.
    SolidChecker {
        black: Rgb,
        white: Rgb,
        scale: f32,
        offset: f32,
    },
    /// `texture` · `scale` + `offset` (CENG795 `Normalizer` and `blend_kd`).
    Affine {
        texture: Box<Texture>,
        scale: f32,
        offset: Rgb,
    },
    /// `a` · `b` channel by channel (pbrt-v4's `scale`: `tex` × `scale`).
    Product {
        a: Box<Texture>,
        b: Box<Texture>,
    },
    /// (1 − t)·`a` + t·`b`, t the first channel of `amount` (pbrt-v4's `mix`).
    Mix {
        a: Box<Texture>,
        b: Box<Texture>,
        amount: Box<Texture>,
    },
    /// Bilinear interpolation of four values over the unit square of `to_uv`·uv: `v00` at
    /// (0, 0), `v10` at (1, 0), `v01` at (0, 1), `v11` at (1, 1) (pbrt-v4's `bilerp`).
    Bilerp {
        v00: Rgb,
        v01: Rgb,
        v10: Rgb,
        v11: Rgb,
        to_uv: Mat3,
    },
    /// pbrt-v4's 3D `checkerboard`: `a` where ⌊x⌋ + ⌊y⌋ + ⌊z⌋ of the world point mapped by
    /// `to_texture` is even, `b` where it is odd.
    Checker3D {
        a: Box<Texture>,
        b: Box<Texture>,
        to_texture: Mat4,
    },
    /// pbrt-v4's `dots`: in each unit cell of (s, t) = `to_uv`·uv (cells centred on the
    /// integers) that improved noise selects, a dot of radius 0.35 jittered by noise, `inside`
    /// there and `outside` elsewhere.
    Dots {
        inside: Box<Texture>,
        outside: Box<Texture>,
        to_uv: Mat3,
    },
    /// pbrt-v4's noise textures (Perlin's improved noise) at the world point mapped by
    /// `to_texture`; grey but for `Marble`.
    Noise {
        kind: NoiseKind,
        to_texture: Mat4,
    },
}

// ---------------------------------------------------------------------------------------------
// Emitters

#[derive(Clone, Debug)]
pub struct EmitterDesc {
    pub emitter: Emitter,
    /// The medium the emitter sits in (Mitsuba `<ref id="..."/>` in an emitter).
    pub medium: Option<MediumId>,
    /// The emitter's id in the scene file (Mitsuba's `id`), when it has one.
    pub name: Option<String>,
    pub loc: Loc,
}

#[derive(Clone, Debug)]
pub enum Emitter {
    /// Isotropic point light with radiant `intensity` (W/sr).
    Point {
        position: Vec3,
        intensity: ColorValue,
    },
    /// Mitsuba spot light at the origin of `to_world`, shining along its +z.
    Spot {
        to_world: Mat4,
        intensity: ColorValue,
        /// Degrees.
        cutoff_angle: f32,
        /// Degrees.
        beam_width: f32,
        /// How the intensity falls between `beam_width` and `cutoff_angle`.
        falloff: SpotFalloff,
    },
    /// Light arriving from `-direction`... i.e. travelling along `direction` (world).
    Directional {
        direction: Vec3,
        irradiance: ColorValue,
    },
    /// Uniform environment radiance.
    Constant { radiance: ColorValue },
    /// Mitsuba 3's `projector`: a pinhole at `to_world`'s origin projecting the texture
    /// `irradiance` (uv over the image plane at z = 1 of its frame, Mitsuba's perspective
    /// mapping: u from +x to −x, v from +y to −y) times `scale`, normalised as Mitsuba so
    /// that a plane at z = 1 receives irradiance π·scale·E(uv). The field of view is
    /// resolved against the texture's aspect ratio at build time.
    Projector {
        to_world: Mat4,
        irradiance: ColorParam,
        scale: f32,
        fov: f32,
        fov_axis: FovAxis,
    },
    /// The course ray tracers' ambient term: adds `ambient reflectance × radiance` at every
    /// hit of the Whitted integrator (CENG795 `AmbientLight`). Not a physical emitter: the
    /// path tracers ignore it (with a warning at build time).
    Ambient { radiance: Rgb },
    /// A point light whose intensity an image modulates by direction (pbrt-v4's
    /// `goniometric` and `projection` lights): at the origin of `to_world`, directions taken
    /// in its frame (a rotation, up to a uniform scale), the image's linear RGB times
    /// `intensity`; with `power`, rescaled to emit that (pbrt-v4's rule per profile).
    ImagePoint {
        to_world: Mat4,
        /// Resolved by the loader.
        path: PathBuf,
        intensity: Rgb,
        profile: ImageProfile,
        power: Option<f32>,
    },
    /// Mitsuba 3's `sunsky`: the Hošek–Wilkie sky and sun (the renderer's
    /// `lights::sunsky_model`), in the frame of `to_world` (z up).
    SunSky(SunSkyDesc),
    /// Image-based environment light.
    EnvMap {
        /// Resolved by the loader: absolute, or relative to the working directory.
        path: PathBuf,
        scale: f32,
        to_world: Mat4,
        mapping: EnvMapping,
    },
}

/// Mitsuba 3's `sunsky` parameters, with the sun's position already resolved.
#[derive(Clone, Debug)]
pub struct SunSkyDesc {
    /// Atmospheric turbidity in [1, 10].
    pub turbidity: f32,
    /// Ground albedo (each channel in [0, 1]; a grey one is the same at every wavelength).
    pub albedo: Rgb,
    /// Towards the sun's centre, world space (from `sun_direction`, or from the date, time
    /// and place by Blanco-Muriel et al.'s solar vector, as Mitsuba computes it).
    pub sun_direction: Vec3,
    pub sun_scale: f32,
    pub sky_scale: f32,
    /// The sun's full aperture, degrees.
    pub sun_aperture: f32,
    /// The solar radiance function with limb darkening instead of a uniform disk.
    pub complex_sun: bool,
    pub to_world: Mat4,
}

/// How an [`Emitter::ImagePoint`] maps directions to its image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ImageProfile {
    /// pbrt-v4's equal-area octahedral square over the sphere (+z of the square's map is the
    /// frame's +z), nearest pixel, the average of R, G and B.
    Goniometric,
    /// A pinhole projection along the frame's +z, `fov` (degrees) on the image's shorter
    /// axis, the image's first row towards the frame's −y; nearest pixel; dark outside.
    Projection { fov: f32 },
}

impl Emitter {
    pub fn kind_name(&self) -> &'static str {
        match self {
            Emitter::Point { .. } => "point",
            Emitter::Spot { .. } => "spot",
            Emitter::Directional { .. } => "directional",
            Emitter::Constant { .. } => "constant",
            Emitter::Projector { .. } => "projector",
            Emitter::EnvMap { .. } => "envmap",
            Emitter::SunSky(_) => "sunsky",
            Emitter::Ambient { .. } => "ambient",
            Emitter::ImagePoint {
                profile: ImageProfile::Goniometric,
                ..
            } => "goniometric",
            Emitter::ImagePoint { .. } => "projection",
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Sensors: camera + film + sampler

#[derive(Clone, Debug)]
pub struct Sensor {
    pub camera: Camera,
    pub film: Film,
    pub sampler: SamplerDesc,
    /// This camera's own integrator (CENG795 `Renderer` per camera); `None`: the scene's.
    pub integrator: Option<IntegratorDesc>,
    /// The medium the camera sits in (its rays start inside it); `None`: vacuum.
    pub medium: Option<MediumId>,
    pub name: Option<String>,
    pub loc: Loc,
}

#[derive(Clone, Debug)]
pub struct Camera {
    pub projection: Projection,
    /// Camera-to-world. The camera looks along its local +z, with +y up and +x to the
    /// *left* of the image (Mitsuba's convention, as produced by `lookat`).
    pub to_world: Mat4,
    pub near_clip: f32,
    pub far_clip: f32,
}

#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub crop: Option<CropWindow>,
    pub filter: FilterDesc,
    /// Output file requested by the scene itself (CENG795 `ImageName`), if any.
    pub output: Option<PathBuf>,
    /// Tone mapping for 8-bit outputs (CENG795 `Tonemap`); `None`: clamp + sRGB curve.
    /// Linear outputs (EXR, PFM, HDR) are never tone mapped.
    pub tonemap: Option<Tonemap>,
}

// ---------------------------------------------------------------------------------------------
// Integrators

/// How a photon map is searched around a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonLookupDesc {
    /// The k nearest photons (with `radius` as a cap); `None`: every photon within `radius`.
    pub k: Option<u32>,
    /// Search radius (a cap for `k`); `None` with `k`: no cap.
    pub radius: Option<f32>,
    /// `radius` is a fraction of the scene's bounding-sphere radius (Mitsuba 0.6, Nori's
    /// default), resolved by `build`.
    pub relative: bool,
    /// With `k` and no `radius`: the k nearest within a cap chosen from the map (the lower
    /// quartile of its photons' distances to their k-th nearest neighbour; the volume map's
    /// default, see `render::integrators::photon::Lookup::Calibrated`).
    pub calibrated: bool,
}

impl Default for PhotonLookupDesc {
    fn default() -> Self {
        PhotonLookupDesc {
            k: Some(64),
            radius: None,
            relative: false,
            calibrated: false,
        }
    }
}

/// Parameters of photon mapping (Jensen): one photon pass, then a camera pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonDesc {
    /// Longest path in edges (−1: unbounded).
    pub max_depth: i32,
    /// Photon paths emitted.
    pub photons: u64,
    /// Lookups in the global map.
    pub global: PhotonLookupDesc,
    /// Lookups in the caustic map.
    pub caustic: PhotonLookupDesc,
    /// Lookups in the volume map (scenes with media).
    pub volume: PhotonLookupDesc,
    pub kernel: PhotonKernel,
    /// Final gathering rays per camera vertex (0: the map read directly).
    pub final_gather: u32,
    /// Light samples per camera vertex.
    pub direct_samples: u32,
}

impl Default for PhotonDesc {
    fn default() -> Self {
        PhotonDesc {
            max_depth: -1,
            photons: 1_000_000,
            global: PhotonLookupDesc::default(),
            caustic: PhotonLookupDesc::default(),
            volume: PhotonLookupDesc {
                calibrated: true,
                ..PhotonLookupDesc::default()
            },
            kernel: PhotonKernel::Box,
            final_gather: 16,
            direct_samples: 1,
        }
    }
}

/// Parameters of stochastic progressive photon mapping.
#[derive(Clone, Debug, PartialEq)]
pub struct SppmDesc {
    /// Longest path in edges (−1: unbounded).
    pub max_depth: i32,
    /// Russian roulette on camera paths through delta bounces from this depth on.
    pub rr_depth: u32,
    /// Photon paths per iteration (`None`: one per pixel).
    pub photons: Option<u64>,
    /// Initial radius (`None`: guessed from the scene's size and the film's).
    pub initial_radius: Option<f32>,
    /// The fraction of new photons kept per iteration.
    pub alpha: f32,
    /// `Some(n)`: PPM — visible points traced once, `n` per pixel, each keeping its own
    /// radius; `None`: SPPM.
    pub fixed_eye_samples: Option<u32>,
    /// Iterations the scene asks for (Mitsuba 0.6's `maxPasses`), used when the command line
    /// gives no `--spp`; `None`: the sensor's sample count.
    pub passes: Option<u32>,
}

impl Default for SppmDesc {
    fn default() -> Self {
        SppmDesc {
            max_depth: -1,
            rr_depth: 5,
            photons: None,
            initial_radius: None,
            alpha: 2.0 / 3.0,
            fixed_eye_samples: None,
            passes: None,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum IntegratorDesc {
    /// Shading normal as colour (n * 0.5 + 0.5 is *not* applied: raw normal, like Mitsuba's AOV).
    Normals,
    /// Surface albedo (reflectance at the first hit).
    Albedo,
    /// Distance along the camera ray to the first hit (0 when nothing is hit).
    Depth,
    /// Ambient occlusion with cosine-weighted rays of length `length` (infinite when `None`).
    AmbientOcclusion { samples: u32, length: Option<f32> },
    /// Direct illumination (Mitsuba `direct`).
    Direct {
        emitter_samples: u32,
        bsdf_samples: u32,
    },
    /// Unidirectional path tracer (Mitsuba `path` and the course variants).
    Path(PathDesc),
    /// Volumetric path tracer (Mitsuba 3 `volpath`): `max_depth` counts scattering events on
    /// surfaces and in media (−1: unbounded), Russian roulette after `rr_depth` of them.
    VolPath {
        max_depth: i32,
        rr_depth: u32,
        hide_emitters: bool,
        /// Equiangular sampling towards point and spot lights, MIS-combined with free-flight
        /// sampling (our extension, on by default; the mean is Mitsuba's).
        equiangular: bool,
        /// How shadow rays estimate the transmittance of grids (`transmittance`).
        transmittance: TransmittanceEstimator,
        /// Importance-sample emission grids from scattering vertices (`sample_emission`,
        /// our extension, off by default: without MIS it loses to collision estimation in
        /// optically thick emitters, 12× the relMSE at equal time on the plume); off:
        /// collision estimation only.
        sample_emission: bool,
    },
    /// Progressive photon mapping, stochastic (pbrt-v4's and Mitsuba 0.6's `sppm`) or with
    /// fixed visible points (Mitsuba 0.6's `ppm`): the sample count is the number of
    /// iterations.
    Sppm(SppmDesc),
    /// Photon mapping with a global and a caustic map (Nori's and Mitsuba 0.6's
    /// `photonmapper`).
    Photon(PhotonDesc),
    /// Light tracing (Mitsuba's `ptracer`): light paths connected to the camera.
    Ptracer { max_depth: i32, hide_emitters: bool },
    /// Bidirectional path tracing (Mitsuba 0.6's `bdpt`), optionally with one image per
    /// strategy (pbrt-v4's `visualizestrategies`: unweighted; `visualizeweights`:
    /// MIS-weighted, and it wins when both are set).
    Bdpt {
        max_depth: i32,
        visualize_strategies: bool,
        visualize_weights: bool,
    },
    /// Metropolis light transport over BDPT (pbrt-v3's `mlt`; Mitsuba 0.6's `pssmlt`/`mlt`
    /// names): `max_depth` −1 means 6 edges (pbrt's
    /// default `maxdepth` 5, which counts bounces);
    /// `direct_samples` (Mitsuba 0.6's `directSamples`): paths of one or two edges rendered
    /// apart at that many samples per pixel (0: left out), −1: by the chains too;
    /// `multiplexed`: a state is one strategy (pbrt-v3's, Hachisuka 2014), else a whole
    /// BDPT sample (Kelemen 2002, as Mitsuba 0.6's `pssmlt`).
    Mlt {
        max_depth: i32,
        bootstrap: u32,
        chains: u32,
        large_step: f32,
        sigma: f32,
        direct_samples: i32,
        multiplexed: bool,
    },
    /// Whitted-style recursive ray tracer.
    Whitted { max_depth: u32 },
    /// Nori's `simple` (one point light, no shadows from area lights).
    NoriSimple,
    /// Nori's PA-5 integrators and direct variants, with Nori's semantics.
    Nori(NoriIntegrator),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoriIntegrator {
    DirectEms,
    DirectMats,
    DirectMis,
    PathMats,
    PathEms,
    PathMis,
}

impl Default for IntegratorDesc {
    fn default() -> Self {
        IntegratorDesc::Path(PathDesc::default())
    }
}

/// The path tracer's settings. `PathDesc::default()` is Mitsuba's `path`.
#[derive(Clone, Debug, PartialEq)]
pub struct PathDesc {
    /// Maximum number of path segments (Mitsuba `max_depth`); −1 means unbounded.
    pub max_depth: i32,
    pub rr: RussianRoulette,
    /// Emitters seen directly by camera rays are not shown.
    pub hide_emitters: bool,
    /// How emitter sampling and direction sampling are combined.
    pub mis: MisHeuristic,
    /// Next-event estimation at non-delta vertices. Off ("brute force"): emitters contribute
    /// only when a sampled direction hits them.
    pub nee: bool,
    /// How the next direction is drawn at non-delta vertices.
    pub directions: DirectionSampling,
    /// Emitter samples per non-delta vertex, averaged (with `all_lights`: per emitter, as
    /// CS184's `-l`; delta emitters get one).
    pub light_samples: u32,
    /// Next-event estimation visits every emitter instead of choosing one (CS184, Whitted).
    pub all_lights: bool,
    /// Directions traced from the first vertex, each carrying 1/N of the throughput
    /// (CENG795 `SplittingFactor`).
    pub splitting: u32,
    /// Count caustic paths: emission reached through a chain of specular (delta) bounces
    /// after a diffuse (non-delta) one. COMP30019 without `-c` drops them, as its write-up
    /// does; everything else keeps them.
    pub caustics: bool,
    /// Clamp every camera sample's radiance to this maximum component (scaled down as a
    /// whole, pbrt-v4's `maxcomponentvalue`): biased, removes fireflies.
    pub clamp: Option<f32>,
    /// Keep only light that reached the camera along exactly this many segments (CS184's
    /// `-o 0`, `isAccumBounces = false`: only the last bounce).
    pub only_depth: Option<u32>,
    /// Path guiding (our extension: `guiding` on Mitsuba's `path`, `--guiding on`): learn
    /// the incident light online (Müller et al. 2017's SD-tree) and sample from it beside
    /// the BSDF. Applies with BSDF directions, no splitting and no `only_depth`.
    pub guiding: bool,
}

impl Default for PathDesc {
    fn default() -> Self {
        PathDesc {
            max_depth: -1,
            rr: RussianRoulette::Throughput { from_depth: 5 },
            hide_emitters: false,
            mis: MisHeuristic::Power,
            nee: true,
            directions: DirectionSampling::Bsdf,
            light_samples: 1,
            all_lights: false,
            splitting: 1,
            caustics: true,
            clamp: None,
            only_depth: None,
            guiding: false,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Statistical test files (Nori `ttest` / `chi2test`)

#[derive(Clone, Debug)]
pub struct TestDesc {
    pub kind: TestKind,
    pub loc: Loc,
}

#[derive(Clone, Debug)]
pub enum TestKind {
    /// Student's t-test of rendered means (or BSDF albedos at `angles`) against `references`.
    TTest {
        significance: f32,
        references: Vec<f32>,
        /// Incident angles in degrees, for BSDF cases.
        angles: Vec<f32>,
        /// Samples per BSDF case (Nori `sampleCount`, default 100 000).
        sample_count: u32,
        /// Each case: a whole scene.
        scenes: Vec<SceneDesc>,
        /// Each case: a BSDF (with its own scene holding its materials).
        bsdfs: Vec<(SceneDesc, MaterialId)>,
    },
    /// χ² goodness-of-fit of a BSDF's sampling routine against its pdf.
    Chi2Test {
        significance: f32,
        resolution: u32,
        min_exp_frequency: f32,
        sample_count: u32,
        test_count: u32,
        bsdfs: Vec<(SceneDesc, MaterialId)>,
    },
}
