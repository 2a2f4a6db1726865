//! The `comp30019` command: the University of Melbourne COMP30019 ray tracer's command line
//! (`-f scene.txt -o out.png -x 3 ...`), mapped onto our renderer. Issue 4.
//!
//! Semantics (ours where the original left room):
//! - default: Whitted ray tracing (every point light and area emitter sampled at the first
//!   non-delta surface, mirror/glass chains followed up to `-d` segments), `-x N` → N×N
//!   stratified samples per pixel;
//! - `-l` (ambient lighting): unidirectional path tracing with next-event estimation and
//!   MIS, N×N×`-q` samples per pixel, without caustic paths (emission reached through
//!   specular bounces after a diffuse one), as the write-up describes; `-c` (caustics) counts
//!   them too. Caustics of point lights cannot be found by a unidirectional tracer either way;
//! - `-g`: the write-up's linear workflow: input colours are linearised with the power 2.2
//!   when the scene is read, and the output is encoded with the inverse power 1/2.2; without
//!   `-g` the image holds the original's raw values (the linear value becomes the 8-bit
//!   display value, as the C# program wrote it);
//! - `-m`: use every core; without it one thread, like the original;
//! - `-s`: also write render layers `OUT_emission.png`, `_direct`, `_indirect`, `_reflection`,
//!   `_refraction` (they sum to the beauty image, see `render::layers`);
//! - `--scale F` multiplies the resolution; `--post` adds a bloom; `--prog` renders passes of
//!   one sample per pixel placed by the 2D Halton sequence and rewrites the output after each; `--dof` uses a `DofCamera`'s lens (without it the scene's
//!   DofCamera is a pinhole); `-r`/`-t` always turn on the thin lens.

use std::path::PathBuf;

use build::{BuildOptions, build};
use clap::ArgAction;
use render::film::Image;
use render::image_io::{srgb_to_linear, write_image};
use render::integrators::Integrator;
use render::layers::{Layer, render_layers};
use render::post::{Bloom, bloom};
use scene::formats::comp30019::{DEFAULT_DEPTH, camera_to_world};
use scene::{IntegratorDesc, Mat4, PathDesc, Projection, SamplerKind, SceneDesc, Vec3};

use crate::{Extras, Failure, RenderJob, print_warnings, render_scene_with};

/// Render a COMP30019 scene. Default camera: at the origin looking along +z, y up, 60°
/// horizontal field of view (a scene's `Camera`/`DofCamera` line replaces it).
#[derive(clap::Args, Debug)]
#[command(disable_help_flag = true)]
pub struct Args {
    /// Scene file (.txt).
    #[arg(short = 'f', long = "file")]
    pub file: PathBuf,
    /// Output image (.png; .exr also works).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Image width in pixels.
    #[arg(short = 'w', long = "width", default_value_t = 400)]
    pub width: u32,
    /// Image height in pixels (`-h` is the height, as in the original; help is `--help`).
    #[arg(short = 'h', long = "height", default_value_t = 400)]
    pub height: u32,
    /// Anti-aliasing: N×N samples per pixel.
    #[arg(short = 'x', long = "aa-mult", default_value_t = 1)]
    pub aa_mult: u32,
    /// Ambient lighting: path tracing with next-event estimation (global illumination).
    #[arg(short = 'l', long = "ambient")]
    pub ambient: bool,
    /// Camera position "x,y,z" (default: the scene's camera, else the origin).
    #[arg(short = 'p', long = "cam-pos", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub cam_pos: Option<Vec3>,
    /// Camera rotation axis "x,y,z" (with --cam-angle).
    #[arg(short = 'a', long = "cam-axis", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub cam_axis: Option<Vec3>,
    /// Camera rotation angle in degrees about --cam-axis.
    #[arg(short = 'n', long = "cam-angle", allow_hyphen_values = true)]
    pub cam_angle: Option<f32>,
    /// Thin-lens aperture radius (depth of field).
    #[arg(short = 'r', long = "aperture-radius")]
    pub aperture_radius: Option<f32>,
    /// Thin-lens focal distance (default 1).
    #[arg(short = 't', long = "focal-length")]
    pub focal_length: Option<f32>,
    /// Quality: samples per pixel are multiplied by this (path tracing noise).
    #[arg(short = 'q', long = "quality", default_value_t = 1)]
    pub quality: u32,
    /// Maximum recursion depth in path segments (default: 8 Whitted, unbounded path tracing).
    #[arg(short = 'd', long = "depth")]
    pub depth: Option<u32>,
    /// Multi-threading: use every core (default: one thread, as the original).
    #[arg(short = 'm', long = "multi-thread")]
    pub multi_thread: bool,
    /// Gamma correction: linear workflow with sRGB-encoded output.
    #[arg(short = 'g', long = "gamma")]
    pub gamma: bool,
    /// Caustics: path tracing (area emitters' caustics through mirrors and glass).
    #[arg(short = 'c', long = "caustics")]
    pub caustics: bool,
    /// Also write render layers (emission, direct, indirect, reflection, refraction).
    #[arg(short = 's', long = "layers")]
    pub layers: bool,
    /// Multiply the resolution by this factor.
    #[arg(long = "scale")]
    pub scale: Option<f32>,
    /// Post-processing: bloom around highlights.
    #[arg(long = "post")]
    pub post: bool,
    /// Progressive: rewrite the output after every pass.
    #[arg(long = "prog")]
    pub prog: bool,
    /// Depth of field with the scene's DofCamera lens.
    #[arg(long = "dof")]
    pub dof: bool,
    /// No progress output.
    #[arg(long = "quiet")]
    pub quiet: bool,
    /// Print help.
    #[arg(long = "help", action = ArgAction::Help)]
    pub help: Option<bool>,
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<&str> = s.split([',', ' ']).filter(|t| !t.is_empty()).collect();
    let err = || format!("expected \"x,y,z\", found '{s}'");
    if v.len() != 3 {
        return Err(err());
    }
    let mut out = [0.0f32; 3];
    for (o, t) in out.iter_mut().zip(v) {
        *o = t.parse().map_err(|_| err())?;
        if !o.is_finite() {
            return Err(err());
        }
    }
    Ok(Vec3::from(out))
}

/// The scene, render settings and extras the flags ask for.
pub(crate) struct Plan {
    pub desc: SceneDesc,
    pub build: BuildOptions,
    pub threads: Option<usize>,
}

/// Apply the flags to a loaded scene.
pub(crate) fn plan(args: &Args) -> Result<Plan, Failure> {
    // `-g`: the scene's colours are gamma-encoded; linearise them (power 2.2).
    let mut desc =
        scene::formats::comp30019::load_with_gamma(&args.file, args.gamma.then_some(GAMMA))
            .map_err(Failure::input)?;
    if args.width == 0 || args.height == 0 {
        return Err(Failure::input("--width and --height must be positive"));
    }
    if args.aa_mult == 0 || args.aa_mult > 64 {
        return Err(Failure::input("--aa-mult must be between 1 and 64"));
    }
    if args.quality == 0 {
        return Err(Failure::input("--quality must be positive"));
    }
    let scale = args.scale.unwrap_or(1.0);
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(Failure::input("--scale must be a positive number"));
    }
    let dim = |v: u32| -> Result<u32, Failure> {
        let d = (v as f64 * scale as f64).round();
        if !(1.0..=65536.0).contains(&d) {
            return Err(Failure::input(
                "the scaled resolution must be between 1 and 65536 pixels per axis",
            ));
        }
        Ok(d as u32)
    };
    let resolution = (dim(args.width)?, dim(args.height)?);

    // Camera.
    let sensor = &mut desc.sensors[0];
    let cam = &mut sensor.camera;
    if args.cam_pos.is_some() || args.cam_axis.is_some() || args.cam_angle.is_some() {
        let pos = args
            .cam_pos
            .unwrap_or_else(|| cam.to_world.w_axis.truncate());
        let rot = if args.cam_axis.is_some() || args.cam_angle.is_some() {
            let axis = args.cam_axis.unwrap_or(Vec3::Y);
            if axis.length_squared() == 0.0 {
                return Err(Failure::input("--cam-axis must not be zero"));
            }
            Mat4::from_axis_angle(axis.normalize(), args.cam_angle.unwrap_or(0.0).to_radians())
        } else {
            // The scene camera's rotation: undo its translation and mirror.
            let mut r = cam.to_world * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
            r.w_axis = Vec3::ZERO.extend(1.0);
            r
        };
        cam.to_world = camera_to_world(pos, rot);
    }
    let (fov, fov_axis, lens) = match cam.projection {
        Projection::Perspective { fov, fov_axis } => (fov, fov_axis, None),
        Projection::ThinLens {
            fov,
            fov_axis,
            aperture_radius,
            focus_distance,
        } => (fov, fov_axis, Some((aperture_radius, focus_distance))),
        Projection::Orthographic
        | Projection::Window { .. }
        | Projection::RadianceMeter
        | Projection::IrradianceMeter { .. } => (60.0, scene::FovAxis::X, None),
    };
    let lens = if args.aperture_radius.is_some() || args.focal_length.is_some() {
        let r = args.aperture_radius.unwrap_or(lens.map_or(0.0, |l| l.0));
        let t = args.focal_length.unwrap_or(lens.map_or(1.0, |l| l.1));
        if !(r >= 0.0 && r.is_finite()) {
            return Err(Failure::input("--aperture-radius must be non-negative"));
        }
        if !(t > 0.0 && t.is_finite()) {
            return Err(Failure::input("--focal-length must be positive"));
        }
        Some((r, t))
    } else if args.dof {
        lens
    } else {
        None
    };
    cam.projection = match lens {
        Some((aperture_radius, focus_distance)) if aperture_radius > 0.0 => Projection::ThinLens {
            fov,
            fov_axis,
            aperture_radius,
            focus_distance,
        },
        _ => Projection::Perspective { fov, fov_axis },
    };
    // --prog: one sample per pixel a pass, placed by the 2D Halton sequence (the write-up).
    sensor.sampler.kind = if args.prog {
        SamplerKind::Halton
    } else {
        SamplerKind::Stratified
    };

    // Integrator and samples.
    let path_traced = args.ambient || args.caustics;
    let integrator = if path_traced {
        IntegratorDesc::Path(PathDesc {
            max_depth: args.depth.map_or(-1, |d| d.min(i32::MAX as u32) as i32),
            // Without -c, diffuse → specular → light paths are not counted (the write-up).
            caustics: args.caustics,
            ..PathDesc::default()
        })
    } else {
        IntegratorDesc::Whitted {
            max_depth: args.depth.unwrap_or(DEFAULT_DEPTH),
        }
    };
    let spp = args
        .aa_mult
        .saturating_mul(args.aa_mult)
        .saturating_mul(if path_traced { args.quality } else { 1 })
        .min(1 << 20);
    if args.quality > 1 && !path_traced {
        eprintln!("warning: --quality only affects path tracing (-l or -c); ignored");
    }
    Ok(Plan {
        desc,
        build: BuildOptions {
            sensor: 0,
            spp: Some(spp),
            resolution: Some(resolution),
            seed: None,
            integrator: Some(integrator),
            ..BuildOptions::default()
        },
        threads: if args.multi_thread { None } else { Some(1) },
    })
}

/// The display gamma of `-g` (input colours are raised to it, output to its inverse).
const GAMMA: f32 = 2.2;

/// The develop step: bloom (on linear radiance), then the display convention.
fn develop(post: bool, gamma: bool) -> impl Fn(&mut Image) + Sync {
    move |img: &mut Image| {
        if post {
            bloom(img, &Bloom::default());
        }
        // The writer encodes with the sRGB curve; pre-decode so that the file holds the raw
        // values (without -g) or the inverse-gamma-encoded ones, v^(1/2.2) (with -g).
        let encode = |v: f32| {
            let v = v.clamp(0.0, 1.0);
            srgb_to_linear(if gamma { v.powf(1.0 / GAMMA) } else { v })
        };
        for p in &mut img.pixels {
            *p = render::math::Vec3::new(encode(p.x), encode(p.y), encode(p.z));
        }
    }
}

/// `OUT.png` → `OUT_layer.png`.
fn layer_path(out: &std::path::Path, layer: &str) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_else(|| "png".into());
    out.with_file_name(format!("{stem}_{layer}.{ext}"))
}

pub fn run(args: Args) -> Result<(), Failure> {
    let plan = plan(&args)?;
    print_warnings(&plan.desc);
    let dev = develop(args.post, args.gamma);
    let job = RenderJob {
        outputs: vec![args.output.clone()],
        stderr: None,
        build: plan.build,
        time: None,
        threads: plan.threads,
        quiet: args.quiet,
        adaptive: None,
        denoise: None,
        display_server: None,
        split: Default::default(),
    };
    if !args.layers {
        return render_scene_with(
            &plan.desc,
            &job,
            &Extras {
                develop: Some(&dev),
                progressive: args.prog,
            },
        );
    }
    render_with_layers(&plan.desc, &job, &dev)
}

/// `-s`: render the beauty image and its layers in one go.
fn render_with_layers(
    desc: &SceneDesc,
    job: &RenderJob,
    dev: &(dyn Fn(&mut Image) + Sync),
) -> Result<(), Failure> {
    crate::check_outputs(&job.outputs)?;
    let build::Built {
        scene,
        integrator,
        spp,
    } = build(desc, &job.build).map_err(Failure::input)?;
    for w in &scene.warnings {
        eprintln!("{w}");
    }
    let Integrator::Path(cfg) = integrator else {
        return Err(Failure::other("render layers need a path-style integrator"));
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(job.threads.unwrap_or(0))
        .build()
        .map_err(Failure::other)?;
    let start = std::time::Instant::now();
    let films = pool.install(|| render_layers(&scene, &cfg, spp, 16));
    if !job.quiet {
        eprintln!(
            "rendered {} spp with layers in {:.2} s",
            spp,
            start.elapsed().as_secs_f64()
        );
    }
    for out in &job.outputs {
        let mut beauty = films.beauty.develop();
        dev(&mut beauty);
        write_image(out, &beauty).map_err(Failure::other)?;
        for (layer, film) in Layer::ALL.iter().zip(&films.layers) {
            let path = layer_path(out, layer.name());
            let mut img = film.develop();
            dev(&mut img);
            write_image(&path, &img).map_err(Failure::other)?;
            if !job.quiet {
                eprintln!("wrote {}", path.display());
            }
        }
        if !job.quiet {
            eprintln!("wrote {}", out.display());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vec3_flags() {
        assert_eq!(parse_vec3("0,2,-0.5").unwrap(), Vec3::new(0.0, 2.0, -0.5));
        assert!(parse_vec3("1,2").is_err());
        assert!(parse_vec3("1,x,2").is_err());
        assert!(parse_vec3("1,inf,2").is_err());
    }

    #[test]
    fn layer_names() {
        assert_eq!(
            layer_path(std::path::Path::new("a/out.png"), "direct"),
            PathBuf::from("a/out_direct.png")
        );
    }
}
