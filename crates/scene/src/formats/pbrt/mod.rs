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
//! Refused with an error: partial spheres, `curve`, `hair`/`measured`/`subsurface`
//! materials, grid media, `goniometric`/`projection` lights, `realistic`/`spherical`
//! cameras, the `directionmix` and `ptex` textures, textured conductor indices,
//! unknown names of any kind.
//! Approximated with a warning: `displacement` (our bump map's slope is per texel), motion
//! other than translation, film sensor/white balance/ISO. Mapped without a warning, as the
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
