//! Mitsuba 3 XML scenes, also accepting the Mitsuba 0.6 / Nori dialect (and Nori test files).
//!
//! Three stages:
//! 1. [`tree`]: XML → owned element tree. `<include>` is expanded in place (relative to the
//!    including file, then the main file's folder and `<path>` folders; cycles and more than 15
//!    nested levels are errors pointing at the `<include>`), `<default name value>` declares a
//!    parameter unless `-D name=value` (`LoadOptions::defines`) already did, `$name` is
//!    substituted in every attribute value (an undefined name is an error naming it), `<path>`
//!    adds a search folder (a missing folder is a warning).
//! 2. [`plugin`] / [`props`]: each object element is split into typed properties (float,
//!    integer, boolean, string, point/vector, rgb/color, spectrum, transform) and child objects
//!    (inline or `<ref id>`). Spectra: inline `wavelength:value` lists, files, and the
//!    plugins `d65`, `blackbody`, `uniform`, `regular`, `irregular` (the last two sampled
//!    spectra like the lists; Mitsuba 3.9.1's RGB variants cannot evaluate them, Penumbra
//!    converts them as Mitsuba converts the lists). Mitsuba 0.6 / Nori camelCase names
//!    (`toWorld`, `sampleCount`, `intIOR`, `fovAxis`...) are mapped to Mitsuba 3's snake_case. Transforms compose in
//!    document order (each operation is left-multiplied); `lookat` is Mitsuba's
//!    camera-to-world with columns (left, up, dir, origin).
//! 3. [`build`]: plugins → [`SceneDesc`](crate::SceneDesc) with Mitsuba 3's defaults for
//!    Mitsuba tags and Nori's for Nori tags/plugins. Spectra become RGB exactly as Mitsuba 3's
//!    RGB variants do ([`crate::spectra`]); named conductors and dielectrics use Mitsuba's
//!    tables ([`ior`]).
//!
//! Every error is a [`LoadError`](crate::LoadError) displayed as `file:line:col: message`
//! (malformed XML uses roxmltree's position; non-UTF-8 input the first bad byte's). Unused
//! parameters are warned about once per (tag, type, name) and otherwise ignored.
//!
//! Notable defaults (Mitsuba 3 unless stated): sampler independent with 4 spp (Nori: 1);
//! integrator `path` with `max_depth` −1, `rr_depth` 5; film 768×576 with a Gaussian filter
//! (σ = 0.5, radius 4σ); perspective `fov_axis` x, `focal_length` 50mm when no `fov`,
//! near/far clip 0.01/10⁴; Nori `camera`: 1280×720, fov 30°, Gaussian rfilter (radius 2,
//! σ 0.5); dielectrics `int_ior` bk7 = 1.5046, `ext_ior` air = 1.000277; plastics `int_ior`
//! polypropylene = 1.49; rough materials Beckmann with α = 0.1; conductor `material` "none"
//! (η = 0, k = 1: a perfect mirror); diffuse reflectance 0.5 (also Nori's default bsdf).
//! `cylinder`: `p0`, `p1` and `radius` are folded into `to_world` as Mitsuba does
//! (`translate(p0)·to_frame(d)·scale(r, r, |d|)`, the frame of Mitsuba's
//! `coordinate_system`, so that uv's φ = 0 lies where Mitsuba's does); open ends.
//! `directionalarea` (a shape's emitter, no `to_world` of its own, as Mitsuba) emits along
//! the normal only: `AreaEmission::directional`. `projector`'s field of view is kept as
//! given (`fov`, `fov_axis` or `focal_length`) and resolved at build time against its
//! texture's aspect ratio (a bitmap's; 1 for other textures, as Mitsuba).
//! Without a sensor, Mitsuba's default camera (45°, framing the scene's bounds from −z) is
//! added with a warning.

mod build;
pub mod ior;
pub mod ior_data;
mod plugin;
mod props;
mod tree;

use std::path::Path;

use build::{Ctx, Dialect, SceneBuilder, float_list};
use tree::err;

use crate::{Document, LoadOptions, Loc, MaterialId, Result, SceneDesc, TestDesc, TestKind};

pub use crate::formats::common::look_at;

/// Load a Mitsuba 3 / Mitsuba 0.6 / Nori XML file: a scene or a Nori `<test>`.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Document> {
    let src = tree::read(path, opts)?;
    let root = &src.root;
    let dialect = match (root.tag.as_str(), root.value("version")) {
        ("scene", Some(v)) => {
            let major = v.split('.').next().unwrap_or("").trim();
            match major.parse::<u32>() {
                Ok(0) | Ok(1) => Dialect::Legacy,
                Ok(_) => Dialect::Mitsuba3,
                Err(_) => {
                    return Err(err(
                        &root.loc_of("version"),
                        format!("cannot parse version number '{v}'"),
                    ));
                }
            }
        }
        _ => Dialect::Legacy,
    };
    let mut ctx = Ctx::new(&src, path.to_path_buf(), dialect)?;
    match root.tag.as_str() {
        "scene" => {
            let mut b = SceneBuilder::new(&mut ctx);
            b.scene_children(root)?;
            let mut scene = b.finish(&root.loc);
            scene.warnings = std::mem::take(&mut ctx.warnings);
            Ok(Document::Scene(Box::new(scene)))
        }
        "test" => load_test(&mut ctx, root).map(Document::Test),
        other => Err(err(
            &root.loc,
            format!("unknown root element <{other}> (expected <scene> or <test>)"),
        )),
    }
}

/// A Nori `<test type="ttest|chi2test">`: parameters plus nested `<scene>`s or `<bsdf>`s.
fn load_test<'s>(ctx: &mut Ctx<'s>, root: &'s tree::Elem) -> Result<TestDesc> {
    let pl = ctx.plugin(root)?;
    let significance = pl.props.float("significance_level", 0.01)?;
    if !(significance > 0.0 && significance < 1.0) {
        return Err(err(&pl.elem.loc, "significanceLevel must be in (0, 1)"));
    }
    let mut scenes: Vec<SceneDesc> = Vec::new();
    let mut bsdfs: Vec<(SceneDesc, MaterialId)> = Vec::new();
    for c in &pl.children {
        match c.elem.tag.as_str() {
            "scene" => {
                let mut b = SceneBuilder::new(ctx);
                b.scene_children(c.elem)?;
                let mut s = b.finish(&c.loc);
                s.warnings = std::mem::take(&mut ctx.warnings);
                scenes.push(s);
            }
            "bsdf" => {
                let mut b = SceneBuilder::new(ctx);
                let id = b.material(c)?;
                let mut s = b.scene;
                s.warnings = std::mem::take(&mut ctx.warnings);
                bsdfs.push((s, id));
            }
            other => {
                return Err(err(
                    &c.loc,
                    format!("<{other}> cannot appear in a <test> (expected <scene> or <bsdf>)"),
                ));
            }
        }
    }
    let loc: Loc = pl.elem.loc.clone();
    let kind = match pl.ty.as_str() {
        "ttest" => {
            let references = float_list(&pl, "references")?;
            let angles = float_list(&pl, "angles")?;
            let sample_count = pl
                .props
                .int_in("sample_count", 100_000, 1, u32::MAX as i64)?;
            let cases = scenes.len() + bsdfs.len() * angles.len().max(1);
            if references.len() != cases {
                return Err(err(
                    &loc,
                    format!(
                        "ttest: {} references for {cases} cases ({} scenes, {} bsdfs × {} \
                         angles)",
                        references.len(),
                        scenes.len(),
                        bsdfs.len(),
                        angles.len()
                    ),
                ));
            }
            if !bsdfs.is_empty() && angles.is_empty() {
                return Err(err(&loc, "ttest: bsdf cases need an 'angles' list"));
            }
            TestKind::TTest {
                significance,
                references,
                angles,
                sample_count: sample_count as u32,
                scenes,
                bsdfs,
            }
        }
        "chi2test" => {
            if !scenes.is_empty() {
                return Err(err(&loc, "chi2test: only <bsdf> cases are supported"));
            }
            let resolution = pl.props.int_in("resolution", 10, 1, 10_000)? as u32;
            let default_samples = i64::from(resolution) * i64::from(resolution) * 2 * 5000;
            TestKind::Chi2Test {
                significance,
                resolution,
                min_exp_frequency: pl.props.float("min_exp_frequency", 5.0)?,
                sample_count: pl.props.int_in(
                    "sample_count",
                    default_samples.min(u32::MAX as i64),
                    1,
                    u32::MAX as i64,
                )? as u32,
                test_count: pl.props.int_in("test_count", 5, 1, 1_000_000)? as u32,
                bsdfs,
            }
        }
        _ => {
            return Err(err(
                &loc,
                format!("unknown test type '{}' (supported: ttest, chi2test)", pl.ty),
            ));
        }
    };
    ctx.finish(&pl);
    // Test-level warnings go with the first case.
    let rest = std::mem::take(&mut ctx.warnings);
    let mut kind = kind;
    let first = match &mut kind {
        TestKind::TTest { scenes, bsdfs, .. } => scenes
            .first_mut()
            .or_else(|| bsdfs.first_mut().map(|(s, _)| s)),
        TestKind::Chi2Test { bsdfs, .. } => bsdfs.first_mut().map(|(s, _)| s),
    };
    if let Some(s) = first {
        s.warnings.extend(rest);
    }
    Ok(TestDesc { kind, loc })
}
