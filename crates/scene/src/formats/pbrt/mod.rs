//! pbrt-v4 scene files (`.pbrt`), also reading pbrt-v3 files as pbrt-v4's `--upgrade` does.
//!
//! Stages, one pass over the text:
//! 1. [`lexer`]: our tokenizer — quoted strings with pbrt's escapes, `[` `]`, `#` comments and
//!    bare words; every token has its line and column; linear time (a 1M-triangle inline mesh
//!    is one long list of numbers).
//! 2. [`parser`]: every directive of the pbrt-v4 format, the graphics state (CTM pairs with
//!    `ActiveTransform`, `AttributeBegin`/`End`, the deprecated `TransformBegin`/`End`,
//!    `ReverseOrientation`, materials, area lights, media, `Attribute` defaults), named
//!    coordinate systems, objects (`ObjectInstance` flattened onto shared meshes with the
//!    instance transform), `Include` and `Import` (cycles and depth checked). Parameters are
//!    typed (`params`); a value of the wrong type is an error at its position.
//! 3. [`build`] and [`shapes`] (with [`subdiv`]): entities → the scene model with pbrt-v4's
//!    defaults. Parameters nobody reads are warned about once per scene.
//!
//! Conventions mapped (details beside the code): matrices are column-major as written; the
//! camera's space has +x to the image's right where ours has it to the left (the camera's
//! `to_world` gets an x flip, so the image is pbrt's); `fov` is on the shorter axis; pbrt's
//! `maxdepth` counts bounces, ours segments (+1); light spectra are normalised to unit
//! luminance as pbrt-v4 does (RGB values are unchanged by it); named metals map to Mitsuba's
//! measured tables (`metal-Cu-eta` → Cu), named glasses to `base::dispersion`; `roughness`
//! is remapped by √r (pbrt-v4's RoughnessToAlpha) unless `remaproughness` is false; image
//! textures are looked up at v' = 1 − v; `MediumInterface "inside" "outside"`.
//!
//! Grid media: `uniformgrid` and `rgbgrid` become heterogeneous media on inline grids
//! (`VolumeFormat::Inline`) over the box `p0`–`p1` of the medium's space, looked up exactly
//! as pbrt-v4's `SampledGrid` (voxel centres at (i + ½)/n, trilinear, 0 beyond the voxels, so
//! values fall off over the outer half voxel). `uniformgrid`: σt = (σa + σs)·`scale`·density
//! with the constant albedo σs/(σa + σs); `Le` times the `Lescale` grid, or without one
//! pbrt-v4's one-voxel scale grid (a tent over the box, 1 at its centre). `rgbgrid`: σt from
//! σa + σs per voxel, the albedo σs(x)/σt(x) with each interpolated on its own
//! (`VolumeParam::SigmaSGrid`), `Le` per voxel times `Lescale`. Our grid media have one
//! extinction for all wavelengths: a chromatic σa + σs is refused, as are `temperature`
//! grids (pbrt-v4 multiplies its peak-normalised black body by the `Lescale` grid) and an
//! `rgbgrid` missing `sigma_a` or `sigma_s`.
//!
//! Shapes: full spheres are ours, mirrored in z so that their uv is pbrt-v4's (u = φ/2π,
//! v = 1 − θ/π; not on sphere lights, which keep v = θ/π and their cone sampling); partial
//! spheres (`zmin`, `zmax`, `phimax`), cylinders and partial disks are triangulated at load
//! (2π/256 steps in φ and θ; area short by < 2·10⁻⁴ relative; pbrt-v4's uv at the vertices)
//! with pbrt-v4's analytic area for `power`. Full disks are ours, whose uv is Mitsuba's
//! (u = r, v = φ/2π where pbrt-v4 has u = φ/2π, v = 1 − r): a texture on a full disk is laid
//! out differently.
//!
//! Lights `goniometric` and `projection` are point lights an image modulates
//! (`Emitter::ImagePoint`), in pbrt-v4's light frame (the CTM after its y–z swap, resp. its
//! y flip): the goniometric image an equal-area square over the sphere, averaged to grey,
//! times `I`·`scale`; the projection image through a pinhole of `fov` on its shorter axis,
//! dark outside it, times `scale`; nearest pixel for both; `power` as pbrt-v4 normalises it.
//! Their transform must be a rotation and uniform scale, and `I` is taken as RGB.
//!
//! The `dots` texture is pbrt-v4's (improved noise picks the cells and jitters the dots).
//!
//! The `subsurface` material is our random-walk one (`Material::Subsurface`: its dielectric
//! boundary around a homogeneous medium; `docs/formats.md`), not pbrt-v4's tabulated BSSRDF.
//!
//! Refused with an error: `curve`, `hair`/`measured` materials, `nanovdb` and
//! `cloud` media, `realistic`/`spherical` cameras, textured conductor indices, unknown names
//! of any kind. Approximated with a warning: the `directionmix` and `ptex` textures (a
//! constant 0.5), `displacement` (our bump map's slope is per texel), motion other than
//! translation, film sensor/white balance/ISO. Mapped without a warning, as the
//! nearest we have: samplers `zsobol`/`paddedsobol`/`pmj02bn` → Sobol; read and without
//! effect, as in pbrt-v4 for what we support: `maxanisotropy` (ours is pbrt-v4's default, 8),
//! film `diagonal` (realistic camera only), `savefp16`. Image textures are MIP-mapped as in
//! pbrt-v4: every filter (`point`, `bilinear`, `trilinear`, `ewa`) reads the level the
//! lookup's footprint picks, the footprint coming from the camera at every hit.
//!
//! pbrt-v4's BSDFs reflect on both sides of a surface: diffuse and conductor materials are
//! wrapped in `twosided` (Mitsuba's, ours, reflect on the normal's side only).

mod build;
mod lexer;
mod params;
mod parser;
mod shapes;
mod subdiv;

use std::path::Path;

use crate::{Document, LoadOptions, Result};

/// Load a pbrt-v4 (or pbrt-v3) scene file.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Document> {
    parser::load(path, opts).map(|s| Document::Scene(Box::new(s)))
}
