//! The `penumbra` command. Thin: parses arguments, reports progress and errors, writes files;
//! all rendering logic lives in `penumbra-render`.

mod comp30019;
mod cs184;
mod debug_paths;
mod denoise;
mod info;
mod memory;
mod progress;
mod split;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use build::spec::{parse_filter, parse_integrator, parse_mode};
use build::{BuildOptions, build};
use clap::{Parser, Subcommand};
use render::adaptive::AdaptiveSettings;
use render::film::{Film, Image};
use render::image_io::{write_image, write_image_tonemapped};
use render::render::{Progress, RenderObserver, RenderOptions, render, render_adaptive};
use scene::{Document, IntegratorDesc, LoadOptions, SceneDesc};

#[derive(Parser)]
#[command(
    name = "penumbra",
    version,
    about = "A physically based offline renderer"
)]
#[command(
    after_help = "Exit codes: 0 finished; 1 a comparison or statistical test failed; \
    2 bad input or usage; 3 an output could not be written (or another failure); \
    130 interrupted by Ctrl-C (the image of the finished passes was written)."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Memory budget for the film and other allocations sized by the input (e.g. 4G, 512M;
    /// default: 75 % of physical memory). Renders that need more exit with code 2.
    #[arg(long, global = true, value_name = "SIZE", value_parser = memory::parse_size)]
    memory_limit: Option<u64>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to EXR and/or PNG.
    Render(Box<RenderArgs>),
    /// Print what was loaded from a scene file: counts, bounds, camera, warnings.
    Info {
        scene: PathBuf,
        /// Override a scene parameter (Mitsuba `<default>`), e.g. `-D spp=64`.
        #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
        define: Vec<(String, String)>,
    },
    /// Run Nori statistical test files (`<test type="ttest|chi2test">`). Exit code 0 only
    /// if every case of every file passes.
    Test {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Seed of the random streams.
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Render a COMP30019 (University of Melbourne) scene with the original program's flags.
    /// Default camera: at the origin looking along +z, y up, 60° horizontal field of view.
    Comp30019(comp30019::Args),
    /// Render a CS184 (UC Berkeley) COLLADA scene with the original program's flags.
    ///
    /// Difference from the course's renderer: its point lights have no 1/r² falloff; ours are
    /// physical (intensity `color` W/sr, irradiance ∝ 1/r²). Area lights agree.
    Cs184(cs184::Args),
    /// Trace a few paths through one pixel and write their segments (PLY edges or JSON).
    DebugPaths(debug_paths::Args),
    /// Denoise an existing image with Intel Open Image Denoise (`pip install pyoidn`), with
    /// optional albedo and normal images (as `render --denoise --keep-noisy` writes them).
    Denoise(denoise::DenoiseCmd),
    /// Join the film states of a render's shards (`render --shard I/K -o PART.state`) into
    /// its images: bit for bit the single-process render. Refuses states of other renders
    /// and says which items are missing or doubled.
    Merge {
        /// The states, in any order.
        #[arg(required = true)]
        states: Vec<PathBuf>,
        /// Output image(s): .exr, .png, .pfm, .hdr, or .state (the merged state).
        #[arg(short, long = "output", value_name = "FILE", required = true)]
        output: Vec<PathBuf>,
        /// Also write the per-pixel standard error of the image.
        #[arg(long, value_name = "FILE")]
        stderr: Option<PathBuf>,
    },
    /// Compare renders with a reference (relMSE, mean ratio, block t-test of
    /// ../shared/references/README.md). Exit code 1 when the t-test fails.
    Compare {
        /// The reference: NAME, NAME.exr (NAME.stderr.exr must exist beside it).
        reference: PathBuf,
        /// K ≥ 16 independent renders of equal spp (see --min-batches), or one render with
        /// --stderr.
        #[arg(required = true)]
        test: Vec<PathBuf>,
        /// Per-pixel standard error of a single test image (e.g. from `render --stderr`).
        #[arg(long)]
        stderr: Option<PathBuf>,
        /// Fewest batches accepted. The t-test is calibrated for 16 (the shared rule): with 8,
        /// unbiased renders of caustic or sun-lit scenes fail now and then (2 of 11 seed sets
        /// of mitsuba-cbox), with 2 always. Lower it only knowing that.
        #[arg(long, default_value_t = MIN_BATCHES, value_name = "K")]
        min_batches: usize,
    },
}

#[derive(clap::Args)]
struct RenderArgs {
    scene: PathBuf,
    /// Output image(s): .exr (linear float), .png (sRGB 8-bit), .pfm. May be repeated.
    /// Default: SCENE.exr and SCENE.png next to the scene file.
    #[arg(short, long = "output", value_name = "FILE")]
    output: Vec<PathBuf>,
    /// Samples per pixel (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Resolution WxH (default: the scene's film; drops its crop window).
    #[arg(long, value_name = "WxH", value_parser = parse_res)]
    res: Option<(u32, u32)>,
    /// Override a scene parameter (Mitsuba `<default>`), e.g. `-D spp=64`.
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
    define: Vec<(String, String)>,
    /// Seed of the sample streams (default: the scene's, else 0).
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Time budget in seconds: stop after the last whole pass that fits.
    #[arg(long, value_name = "SECONDS")]
    time: Option<f64>,
    /// Replace the scene's integrator: path or volpath (Mitsuba's defaults: unidirectional
    /// path tracing, with media), normals, albedo, depth, ao[:samples], or
    /// sppm[:photons[,radius]] (stochastic progressive photon mapping; --spp iterations of
    /// `photons` photons, default one per pixel; the scene's max depth is kept) or
    /// ppm[:photons[,radius[,eye_samples]]] (fixed visible points, 4 per pixel by default),
    /// or photon[:photons[,gather[,k]]] (photon mapping: 10⁶ photons, 16 final gathering
    /// rays, the 64 nearest photons by default), or ptracer (light tracing),
    /// bdpt[:strategies|:weights] (bidirectional path tracing; with an argument it also
    /// writes one EXR per strategy (s, t) beside the first output, OUT_bdpt_dDD_sSS_tTT.exr,
    /// unweighted or MIS-weighted as pbrt-v4's visualizestrategies / visualizeweights; needs
    /// --max-depth) or mlt[:direct_samples[,kelemen]] (primary-sample-space Metropolis
    /// over BDPT; --spp mutations per pixel; paths of one and two edges apart by BDPT at
    /// direct_samples per pixel, 16 by default as Mitsuba 0.6's pssmlt, -1: by the chains
    /// too; multiplexed over BDPT's strategies as pbrt-v3's, or with kelemen a state is a
    /// whole BDPT sample as in Mitsuba 0.6's pssmlt, e.g. mlt:,kelemen). The scene's max
    /// depth is kept.
    #[arg(long, value_parser = parse_integrator)]
    integrator: Option<IntegratorDesc>,
    /// Which sensor of the scene to render (0-based).
    #[arg(long, default_value_t = 0)]
    sensor: usize,
    /// How next-event estimation picks a light: uniform, power or bvh (default: the scene's).
    #[arg(long, value_name = "uniform|power|bvh", value_parser = parse_light_sampler)]
    light_sampler: Option<scene::LightSelection>,
    /// Colour mode: rgb (three channels, the default) or spectral (four wavelengths per
    /// path, converted to RGB at the film). Mitsuba 3 variant names (scalar_rgb,
    /// llvm_ad_spectral, ...) select their colour part, as `mitsuba -m` does.
    #[arg(short = 'm', long, value_name = "rgb|spectral|VARIANT", value_parser = parse_mode)]
    mode: Option<scene::RenderMode>,
    /// Render only the camera with this name (CENG795 camera `id`).
    #[arg(long, value_name = "NAME")]
    camera: Option<String>,
    /// Also write the per-pixel standard error of the image (from per-sample second moments).
    #[arg(long, value_name = "FILE")]
    stderr: Option<PathBuf>,
    /// CS184 adaptive sampling: a pixel stops when the 95 % confidence half-width of its
    /// illuminance is ≤ TOL × its mean, checked every BATCH samples (default 32); --spp is
    /// the cap. Also writes the samples-per-pixel heat map OUTPUT_rate.png.
    #[arg(long, value_name = "TOL[,BATCH]", value_parser = parse_adaptive)]
    adaptive: Option<AdaptiveSettings>,
    /// Render part of the work: shard I of K (0-based; auto/K takes I from
    /// SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX or PENUMBRA_SHARD), written as a film state
    /// with -o PART.state. `penumbra merge` joins the parts into the image the single
    /// process renders, bit for bit (path, volpath, direct, aov and bdpt).
    #[arg(long, value_name = "I/K|auto/K", value_parser = split::parse_shard)]
    shard: Option<split::Shard>,
    /// Save the film state to FILE after passes (at most every --checkpoint-interval
    /// seconds) and when interrupted; continue with --resume FILE.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints (0: after every pass).
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    checkpoint_interval: f64,
    /// Continue the render saved in FILE (by --checkpoint or a shard's -o PART.state) with
    /// the same scene and options (refused otherwise): the result is the uninterrupted
    /// render's, bit for bit.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Target seconds per pass (default 1; 0: one chunk of samples a pass). For tests of
    /// checkpoints, which are written between passes.
    #[arg(long, value_name = "SECONDS", hide = true)]
    pass_seconds: Option<f64>,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
    /// Show the image in a running tev as it converges (pbrt-v4's flag; tev listens on
    /// 127.0.0.1:14158 by default). The render never waits for it; if nothing listens, a
    /// warning, and later passes try again.
    #[arg(long, value_name = "HOST:PORT")]
    display_server: Option<String>,
    #[command(flatten)]
    denoise: denoise::DenoiseArgs,
    #[command(flatten)]
    view: ViewArgs,
    #[command(flatten)]
    transport: TransportArgs,
}

/// Light-transport and sampling overrides any format's scene takes (Mitsuba's names).
#[derive(clap::Args, Debug, Default)]
pub(crate) struct TransportArgs {
    /// Longest path, in segments (Mitsuba `max_depth`; -1: unbounded); Whitted: recursion
    /// depth.
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    max_depth: Option<i32>,
    /// Russian roulette from this many segments on (Mitsuba `rr_depth`).
    #[arg(long, value_name = "N")]
    rr_depth: Option<u32>,
    /// Sample generator: independent, stratified, halton, sobol or multijitter.
    #[arg(long, value_name = "KIND", value_parser = parse_sampler)]
    sampler: Option<scene::SamplerKind>,
    /// Reconstruction filter with Mitsuba's defaults: box, tent, gaussian, mitchell or lanczos.
    #[arg(long, value_name = "KIND", value_parser = parse_filter)]
    filter: Option<scene::FilterDesc>,
    /// Clamp every camera sample to this largest component (removes fireflies; biased).
    #[arg(long, value_name = "X")]
    clamp: Option<f32>,
    /// Next-event estimation: on (default) or off (brute force: emitters only when hit).
    #[arg(long, value_name = "on|off", value_parser = parse_on_off)]
    nee: Option<bool>,
    /// Path guiding (Müller et al. 2017): on or off (default). The path tracer learns the
    /// incident light in training passes of doubling length and samples from it beside the
    /// BSDF.
    #[arg(long, value_name = "on|off", value_parser = parse_on_off)]
    guiding: Option<bool>,
}

fn parse_sampler(s: &str) -> Result<scene::SamplerKind, String> {
    use scene::SamplerKind as K;
    match s {
        "independent" => Ok(K::Independent),
        "stratified" => Ok(K::Stratified),
        "halton" => Ok(K::Halton),
        "sobol" => Ok(K::Sobol),
        "multijitter" => Ok(K::MultiJitter { jitter: true }),
        _ => Err(format!(
            "expected independent, stratified, halton, sobol or multijitter, found '{s}'"
        )),
    }
}

pub(crate) fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("expected on or off, found '{s}'")),
    }
}

impl TransportArgs {
    /// Apply the overrides to every integrator the scene may use (the scene's, each
    /// sensor's, and `--integrator`'s) and to every sensor's sampler and film.
    pub(crate) fn apply(
        &self,
        desc: &mut SceneDesc,
        integrator: &mut Option<IntegratorDesc>,
    ) -> Result<(), Failure> {
        if let Some(c) = self.clamp
            && !(c > 0.0 && c.is_finite())
        {
            return Err(Failure::input(format!(
                "--clamp expects a positive number, found {c}"
            )));
        }
        for s in &mut desc.sensors {
            if let Some(k) = self.sampler {
                s.sampler.kind = k;
            }
            if let Some(f) = self.filter {
                s.film.filter = f;
            }
        }
        let path_only = self.rr_depth.is_some()
            || self.clamp.is_some()
            || self.nee.is_some()
            || self.guiding == Some(true);
        // `--integrator sppm` keeps the scene's path length (a scene's max_depth is part of
        // what its reference shows).
        if let Some(i) = integrator.as_mut() {
            build::spec::keep_scene_max_depth(&desc.integrator, i);
        }
        let targets = std::iter::once(&mut desc.integrator)
            .chain(
                desc.sensors
                    .iter_mut()
                    .filter_map(|s| s.integrator.as_mut()),
            )
            .chain(integrator.as_mut());
        for i in targets {
            match i {
                IntegratorDesc::Path(p) => {
                    if let Some(d) = self.max_depth {
                        p.max_depth = d.max(-1);
                    }
                    if let Some(d) = self.rr_depth {
                        p.rr = scene::RussianRoulette::Throughput { from_depth: d };
                    }
                    if let Some(c) = self.clamp {
                        p.clamp = Some(c);
                    }
                    if let Some(n) = self.nee {
                        p.nee = n;
                    }
                    if let Some(g) = self.guiding {
                        p.guiding = g;
                    }
                }
                IntegratorDesc::VolPath {
                    max_depth,
                    rr_depth,
                    ..
                } if self.clamp.is_none() && self.nee.is_none() && self.guiding != Some(true) => {
                    if let Some(d) = self.max_depth {
                        *max_depth = d.max(-1);
                    }
                    if let Some(d) = self.rr_depth {
                        *rr_depth = d;
                    }
                }
                IntegratorDesc::Whitted { max_depth } if !path_only => {
                    if let Some(d) = self.max_depth {
                        *max_depth = d.max(0) as u32;
                    }
                }
                IntegratorDesc::Sppm(d) if !path_only => {
                    if let Some(m) = self.max_depth {
                        d.max_depth = m.max(-1);
                    }
                }
                IntegratorDesc::Photon(d) if !path_only => {
                    if let Some(m) = self.max_depth {
                        d.max_depth = m.max(-1);
                    }
                }
                IntegratorDesc::Mlt { max_depth, .. } if !path_only => {
                    if let Some(m) = self.max_depth {
                        *max_depth = m.max(-1);
                    }
                }
                IntegratorDesc::Bdpt { max_depth, .. } if !path_only => {
                    if let Some(m) = self.max_depth {
                        *max_depth = m.max(-1);
                    }
                }
                IntegratorDesc::Ptracer { max_depth, .. } if !path_only => {
                    if let Some(m) = self.max_depth {
                        *max_depth = m.max(-1);
                    }
                }
                _ if self.max_depth.is_some() || path_only => {
                    return Err(Failure::input(
                        "--max-depth, --rr-depth, --clamp, --nee and --guiding on apply to the path tracer \
                         (--max-depth and --rr-depth to volpath, --max-depth to Whitted, the \
                         photon mappers and the light-path integrators); this scene or \
                         --integrator uses another",
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// Camera and light overrides (the CS-E5520 application's controls), applied to the scene
/// before rendering.
#[derive(clap::Args, Debug, Default)]
pub(crate) struct ViewArgs {
    /// Camera position.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3)]
    look_from: Option<scene::Vec3>,
    /// Point the camera looks at.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3)]
    look_at: Option<scene::Vec3>,
    /// Camera up vector.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3)]
    up: Option<scene::Vec3>,
    /// Field of view in degrees (along the scene camera's fov axis).
    #[arg(long, value_name = "DEGREES")]
    fov: Option<f32>,
    /// Add a one-sided square area light 'pos;normal;size;emission' (emission: one value or
    /// r,g,b), e.g. '0,0.98,0;0,-1,0;0.5;10'. Replaces an OBJ scene's default light.
    #[arg(long, value_name = "POS;NORMAL;SIZE;EMISSION", value_parser = parse_area_light)]
    area_light: Vec<AreaLightArg>,
}

#[derive(Clone, Debug)]
pub(crate) struct AreaLightArg {
    pos: scene::Vec3,
    normal: scene::Vec3,
    size: f32,
    emission: scene::Vec3,
}

fn parse_floats(s: &str) -> Result<Vec<f32>, String> {
    s.split(',')
        .map(|t| {
            t.trim()
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("'{t}' is not a finite number"))
        })
        .collect()
}

fn parse_vec3(s: &str) -> Result<scene::Vec3, String> {
    match parse_floats(s)?.as_slice() {
        [x, y, z] => Ok(scene::Vec3::new(*x, *y, *z)),
        _ => Err(format!("expected X,Y,Z, found '{s}'")),
    }
}

fn parse_area_light(s: &str) -> Result<AreaLightArg, String> {
    let parts: Vec<&str> = s.split(';').collect();
    let [pos, normal, size, emission] = parts.as_slice() else {
        return Err(format!("expected 'pos;normal;size;emission', found '{s}'"));
    };
    let size = match parse_floats(size)?.as_slice() {
        [v] if *v > 0.0 => *v,
        _ => {
            return Err(format!(
                "the light size must be one positive number, found '{size}'"
            ));
        }
    };
    let emission = match parse_floats(emission)?.as_slice() {
        [v] if *v >= 0.0 => scene::Vec3::splat(*v),
        [r, g, b] if r.min(*g).min(*b) >= 0.0 => scene::Vec3::new(*r, *g, *b),
        _ => {
            return Err(format!(
                "the emission must be E or R,G,B ≥ 0, found '{emission}'"
            ));
        }
    };
    let normal = parse_vec3(normal)?;
    if normal.length_squared() == 0.0 {
        return Err("the light normal must not be zero".into());
    }
    Ok(AreaLightArg {
        pos: parse_vec3(pos)?,
        normal,
        size,
        emission,
    })
}

impl ViewArgs {
    /// Apply the overrides to sensor `sensor` of `desc` and add the lights.
    pub(crate) fn apply(&self, desc: &mut SceneDesc, sensor: usize) -> Result<(), Failure> {
        use scene::formats::objmtl;
        if !self.area_light.is_empty() {
            desc.shapes
                .retain(|s| s.name.as_deref() != Some(objmtl::DEFAULT_LIGHT_NAME));
            for l in &self.area_light {
                let loc = scene::Loc::file(Path::new("--area-light"));
                let shape = objmtl::square_light(l.pos, l.normal, l.size, l.emission, loc)
                    .ok_or_else(|| Failure::input("--area-light: degenerate light"))?;
                desc.shapes.push(shape);
            }
        }
        if self.look_from.is_none()
            && self.look_at.is_none()
            && self.up.is_none()
            && self.fov.is_none()
        {
            return Ok(());
        }
        let Some(s) = desc.sensors.get_mut(sensor) else {
            return Err(Failure::input(format!("the scene has no sensor {sensor}")));
        };
        if self.look_from.is_some() || self.look_at.is_some() || self.up.is_some() {
            let m = s.camera.to_world;
            let origin = m.w_axis.truncate();
            let from = self.look_from.unwrap_or(origin);
            let at = self.look_at.unwrap_or(from + m.z_axis.truncate());
            let up = self.up.unwrap_or(m.y_axis.truncate());
            s.camera.to_world = scene::formats::common::look_at(from, at, up).ok_or_else(|| {
                Failure::input("--look-from/--look-at/--up: degenerate view (zero direction or up parallel to it)")
            })?;
        }
        if let Some(f) = self.fov {
            if !(f > 0.0 && f < 180.0) {
                return Err(Failure::input(format!(
                    "--fov must be in (0, 180) degrees, found {f}"
                )));
            }
            match &mut s.camera.projection {
                scene::Projection::Perspective { fov, .. }
                | scene::Projection::ThinLens { fov, .. } => *fov = f,
                // A window camera (CENG795 NearPlane) becomes a centred one of that fov.
                p @ scene::Projection::Window { .. } => {
                    *p = scene::Projection::Perspective {
                        fov: f,
                        fov_axis: scene::FovAxis::Y,
                    }
                }
                scene::Projection::Orthographic => {
                    return Err(Failure::input(
                        "--fov does not apply to an orthographic camera",
                    ));
                }
                scene::Projection::RadianceMeter | scene::Projection::IrradianceMeter { .. } => {
                    return Err(Failure::input(
                        "--fov does not apply to a radiancemeter or an irradiancemeter",
                    ));
                }
            }
        }
        Ok(())
    }
}

pub(crate) fn parse_define(s: &str) -> Result<(String, String), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, found '{s}'"))?;
    if k.is_empty() {
        return Err(format!("expected NAME=VALUE, found '{s}'"));
    }
    Ok((k.to_string(), v.to_string()))
}

fn parse_light_sampler(s: &str) -> Result<scene::LightSelection, String> {
    match s {
        "uniform" => Ok(scene::LightSelection::Uniform),
        "power" => Ok(scene::LightSelection::Power),
        "bvh" => Ok(scene::LightSelection::Bvh),
        _ => Err(format!("expected uniform, power or bvh, found '{s}'")),
    }
}

fn parse_res(s: &str) -> Result<(u32, u32), String> {
    let err = || format!("expected WIDTHxHEIGHT such as 640x480, found '{s}'");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(err)?;
    let w: u32 = w.trim().parse().map_err(|_| err())?;
    let h: u32 = h.trim().parse().map_err(|_| err())?;
    if w == 0 || h == 0 || w > 1 << 16 || h > 1 << 16 {
        return Err(format!(
            "resolution must be between 1 and 65536 per axis, found '{s}'"
        ));
    }
    Ok((w, h))
}

fn parse_adaptive(s: &str) -> Result<AdaptiveSettings, String> {
    let (tol, batch) = s.split_once(',').unwrap_or((s, "32"));
    let tolerance: f32 = tol
        .trim()
        .parse()
        .ok()
        .filter(|t: &f32| *t > 0.0 && t.is_finite())
        .ok_or_else(|| format!("--adaptive expects a positive tolerance, found '{tol}'"))?;
    let batch: u32 = batch
        .trim()
        .parse()
        .ok()
        .filter(|b| *b >= 2)
        .ok_or_else(|| format!("--adaptive expects a batch size ≥ 2, found '{batch}'"))?;
    Ok(AdaptiveSettings { batch, tolerance })
}

/// The batch count the comparison's t-test is calibrated for (../shared/references/README.md).
const MIN_BATCHES: usize = 16;

/// An error for the user, with its exit code (see `Cli`'s after-help: 1 a test failed, 2 bad
/// input or usage, 3 an output could not be written or another failure, 130 interrupted).
#[derive(Debug)]
pub(crate) struct Failure {
    message: String,
    code: u8,
}

impl Failure {
    pub(crate) fn input(message: impl ToString) -> Self {
        Failure {
            message: message.to_string(),
            code: 2,
        }
    }
    /// A comparison or statistical test rejected its input.
    pub(crate) fn rejected(message: impl ToString) -> Self {
        Failure {
            message: message.to_string(),
            code: 1,
        }
    }
    pub(crate) fn other(message: impl ToString) -> Self {
        Failure {
            message: message.to_string(),
            code: 3,
        }
    }
    /// Ctrl-C: the image of the finished passes was written.
    pub(crate) fn interrupted(message: impl ToString) -> Self {
        Failure {
            message: message.to_string(),
            code: 130,
        }
    }
}

pub(crate) fn load_scene(path: &Path, defines: &[(String, String)]) -> Result<Document, Failure> {
    let xml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    if !defines.is_empty() && (!xml || scene::formats::ceng795::is_ceng795_xml(path)) {
        return Err(Failure::input(format!(
            "{}: -D sets Mitsuba/Nori XML <default> parameters; this scene format has none",
            path.display()
        )));
    }
    let opts = LoadOptions {
        defines: defines.to_vec(),
    };
    let doc = scene::load(path, &opts).map_err(Failure::input)?;
    Ok(doc)
}

pub(crate) fn print_warnings(desc: &SceneDesc) {
    for w in &desc.warnings {
        eprintln!("{w}");
    }
}

fn default_outputs(scene: &Path) -> Vec<PathBuf> {
    vec![scene.with_extension("exr"), scene.with_extension("png")]
}

/// A file name the scene chose (CENG795 `ImageName`), under the scene's folder `dir`: a name
/// that is absolute or climbs out with `..` is refused (a scene must not write anywhere it
/// likes); `-o` writes elsewhere on the user's say.
fn confined_output(dir: &Path, name: &Path) -> Result<PathBuf, Failure> {
    use std::path::Component;
    if name
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return Err(Failure::input(format!(
            "the scene's image name '{}' would be written outside the scene's folder {}; \
             give -o FILE to choose where the image goes",
            name.display(),
            dir.display()
        )));
    }
    Ok(dir.join(name))
}

/// Fail before rendering when an output cannot be written (unknown format, missing folder).
pub(crate) fn check_outputs(outputs: &[PathBuf]) -> Result<(), Failure> {
    for o in outputs {
        if o.is_dir() {
            return Err(Failure::input(format!(
                "{} is a folder: give a file name such as {}",
                o.display(),
                o.join("image.exr").display()
            )));
        }
        let ext = o
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        if !matches!(ext.as_str(), "exr" | "png" | "pfm" | "hdr" | "state") {
            return Err(Failure::input(format!(
                "{}: unsupported output format '.{ext}' (expected .exr, .png, .pfm, .hdr or \
                 .state)",
                o.display()
            )));
        }
        let dir = match o.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if !dir.is_dir() {
            return Err(Failure::input(format!(
                "{}: the output folder {} does not exist",
                o.display(),
                dir.display()
            )));
        }
    }
    Ok(())
}

fn cmd_render(args: RenderArgs) -> Result<(), Failure> {
    let start = std::time::Instant::now();
    let doc = load_scene(&args.scene, &args.define)?;
    if !args.quiet {
        eprintln!(
            "parsed {} in {:.3} s",
            args.scene.display(),
            start.elapsed().as_secs_f64()
        );
    }
    let Document::Scene(mut desc) = doc else {
        return Err(Failure::input(format!(
            "{}: this is a test file; run it with `penumbra test`",
            args.scene.display()
        )));
    };
    print_warnings(&desc);
    args.view.apply(&mut desc, args.sensor)?;
    let denoising = args.denoise.resolve()?.map(Arc::new);
    let mut args = args;
    args.transport.apply(&mut desc, &mut args.integrator)?;
    // CENG795: without -o, every camera (or --camera NAME) renders to its own ImageName,
    // relative to the scene's folder.
    let named: Vec<usize> = match &args.camera {
        Some(name) => {
            let i = desc
                .sensors
                .iter()
                .position(|s| s.name.as_deref() == Some(name.as_str()))
                .ok_or_else(|| {
                    Failure::input(format!(
                        "{}: no camera named '{name}'",
                        args.scene.display()
                    ))
                })?;
            vec![i]
        }
        None => (0..desc.sensors.len())
            .filter(|&i| desc.sensors[i].film.output.is_some())
            .collect(),
    };
    if args.output.is_empty() && desc.sensors.iter().any(|s| s.film.output.is_some()) {
        let dir = args.scene.parent().unwrap_or(Path::new("."));
        for i in named {
            let out = desc.sensors[i].film.output.clone();
            let outputs = match out {
                Some(o) => vec![confined_output(dir, &o)?],
                None => default_outputs(&args.scene),
            };
            let job = render_job(&args, outputs, i, denoising.clone());
            render_scene(&desc, &job)?;
        }
        return Ok(());
    }
    let sensor = match &args.camera {
        Some(_) => named[0],
        None => args.sensor,
    };
    let outputs = if args.output.is_empty() {
        default_outputs(&args.scene)
    } else {
        args.output.clone()
    };
    render_scene(&desc, &render_job(&args, outputs, sensor, denoising))
}

fn render_job(
    args: &RenderArgs,
    outputs: Vec<PathBuf>,
    sensor: usize,
    denoise: Option<Arc<denoise::Denoising>>,
) -> RenderJob {
    RenderJob {
        outputs,
        stderr: args.stderr.clone(),
        build: BuildOptions {
            sensor,
            spp: args.spp,
            resolution: args.res,
            seed: args.seed,
            integrator: args.integrator.clone(),
            light_selection: args.light_sampler,
            flatten_instances: false,
            mode: args.mode.unwrap_or_default(),
        },
        time: args.time,
        threads: args.threads,
        quiet: args.quiet,
        adaptive: args.adaptive,
        denoise,
        display_server: args.display_server.clone(),
        split: Split {
            shard: args.shard,
            checkpoint: args.checkpoint.clone(),
            checkpoint_interval: args.checkpoint_interval,
            resume: args.resume.clone(),
            pass_seconds: args.pass_seconds,
        },
    }
}

/// Shards, checkpoints and resumed renders (see `split.rs`).
#[derive(Default)]
pub(crate) struct Split {
    pub shard: Option<split::Shard>,
    pub checkpoint: Option<PathBuf>,
    pub checkpoint_interval: f64,
    pub resume: Option<PathBuf>,
    pub pass_seconds: Option<f64>,
}

/// Everything `render_scene` needs besides the scene: the shared back end of `render` and
/// of the course-compatible commands.
pub(crate) struct RenderJob {
    pub outputs: Vec<PathBuf>,
    /// Also write the per-pixel standard error here.
    pub stderr: Option<PathBuf>,
    pub build: BuildOptions,
    /// Time budget in seconds.
    pub time: Option<f64>,
    pub threads: Option<usize>,
    pub quiet: bool,
    /// CS184 adaptive sampling (the spp is the cap); writes `<first output>_rate.png`.
    pub adaptive: Option<AdaptiveSettings>,
    /// Denoise the developed image before it is written.
    pub denoise: Option<Arc<denoise::Denoising>>,
    /// Live view: a tev at this address.
    pub display_server: Option<String>,
    pub split: Split,
}

/// What the course-compatible commands add to [`render_scene`].
#[derive(Default)]
pub(crate) struct Extras<'a> {
    /// Applied to the developed image before it is written (display curves, bloom).
    pub develop: Option<&'a (dyn Fn(&mut Image) + Sync)>,
    /// Rewrite the outputs after every pass (progressive preview).
    pub progressive: bool,
}

/// Build, render (progress, Ctrl-C, time budget) and write the outputs of one sensor.
pub(crate) fn render_scene(desc: &SceneDesc, job: &RenderJob) -> Result<(), Failure> {
    render_scene_with(desc, job, &Extras::default())
}

/// Forwards progress and writes the outputs after every pass.
struct Progressive<'a> {
    inner: &'a progress::Reporter,
    outputs: &'a [PathBuf],
    develop: Option<&'a (dyn Fn(&mut Image) + Sync)>,
}

impl RenderObserver for Progressive<'_> {
    fn progress(&self, p: &Progress) {
        self.inner.progress(p);
    }
    fn note(&self, line: &str) {
        self.inner.note(line);
    }
    fn pass_done(&self, film: &Film, spp: u32) {
        self.inner.pass_done(film, spp);
        let mut image = film.develop();
        if let Some(f) = self.develop {
            f(&mut image);
        }
        for o in self.outputs {
            if let Err(e) = write_image(o, &image) {
                eprintln!("warning: progressive write of {} failed: {e}", o.display());
            }
        }
    }
}

/// [`render_scene`] with a developing step and progressive output.
pub(crate) fn render_scene_with(
    desc: &SceneDesc,
    job: &RenderJob,
    extras: &Extras,
) -> Result<(), Failure> {
    check_outputs(&job.outputs)?;
    if let Some(se) = &job.stderr {
        check_outputs(std::slice::from_ref(se))?;
    }
    if let Some(t) = job.time
        && !(t > 0.0 && t.is_finite())
    {
        return Err(Failure::input(format!(
            "--time expects a positive number of seconds, found {t}"
        )));
    }

    let start = std::time::Instant::now();
    let build::Built {
        mut scene,
        integrator,
        spp,
    } = build(desc, &job.build).map_err(Failure::input)?;
    let user_filter = job
        .denoise
        .as_ref()
        .map(|_| denoise::Denoising::prepare(&mut scene));
    if !job.quiet {
        eprintln!(
            "built the scene (BVH, lights) in {:.3} s",
            start.elapsed().as_secs_f64()
        );
    }
    for w in &scene.warnings {
        eprintln!("{w}");
    }
    if let Some(why) = integrator.unsupported(&scene) {
        return Err(Failure::input(why));
    }
    if job.adaptive.is_some() && !integrator.per_sample() {
        return Err(Failure::input(format!(
            "--adaptive needs an integrator with per-sample estimates, not {}",
            integrator.name()
        )));
    }

    let cancel = Arc::new(AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        // A second Ctrl-C while the pass finishes kills the process as usual.
        let _ = ctrlc::set_handler(move || {
            if cancel.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
            eprintln!("\ninterrupted: finishing the current pass, then writing the image");
        });
    }
    let mut ropts = RenderOptions {
        // A time budget without --spp: as many passes as fit.
        spp: if job.time.is_some() && job.build.spp.is_none() {
            u32::MAX / 2
        } else {
            spp
        },
        time_budget: job.time.map(Duration::from_secs_f64),
        cancel,
        // Progressive output: one sample per pixel a pass, the image rewritten after each.
        chunk_spp: if extras.progressive {
            1
        } else {
            render::drive::CHUNK_SPP
        },
        pass_duration: if extras.progressive {
            Duration::ZERO
        } else if let Some(s) = job
            .split
            .pass_seconds
            .filter(|s| *s >= 0.0 && s.is_finite())
        {
            Duration::from_secs_f64(s)
        } else {
            RenderOptions::default().pass_duration
        },
        ..RenderOptions::default()
    };
    memory::check(
        &format!("a {}x{} film", scene.film.width, scene.film.height),
        render::render::memory_needed(&scene, &ropts),
    )?;
    if let Some((what, bytes)) = integrator.memory(&scene) {
        memory::check(what, bytes)?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(job.threads.unwrap_or(0))
        .build()
        .map_err(Failure::other)?;
    let (images, states): (Vec<PathBuf>, Vec<PathBuf>) =
        job.outputs.iter().cloned().partition(|o| !is_state(o));
    let saver = split_render(desc, job, &scene, &integrator, &mut ropts, &images, &states)?;
    let reporter = progress::Reporter::new(job.quiet);
    let display = match &job.display_server {
        Some(server) => {
            let name = job
                .outputs
                .first()
                .and_then(|o| o.file_name())
                .map_or("penumbra".into(), |n| n.to_string_lossy().into_owned());
            Some(render::display::Display::start(server, &name).map_err(Failure::input)?)
        }
        None => None,
    };
    let progressive = Progressive {
        inner: &reporter,
        outputs: &images,
        develop: extras.develop,
    };
    let base: &dyn RenderObserver = if extras.progressive {
        &progressive
    } else {
        &reporter
    };
    let live = display.as_ref().map(|display| denoise::Live {
        inner: base,
        display,
    });
    let observer: &dyn RenderObserver = match &live {
        Some(l) => l,
        None => base,
    };
    let checkpointing = saver.as_ref().map(|saver| split::Checkpointing {
        inner: observer,
        saver,
    });
    let observer: &dyn RenderObserver = match &checkpointing {
        Some(c) => c,
        None => observer,
    };
    let outcome = match &job.adaptive {
        None => pool.install(|| render(&scene, &integrator, &ropts, observer)),
        Some(settings) => {
            if job.time.is_some() {
                return Err(Failure::input(
                    "--time and adaptive sampling do not combine",
                ));
            }
            let a = pool
                .install(|| render_adaptive(&scene, &integrator, &ropts, settings, observer))
                .expect("checked above: a per-sample integrator");
            let (mean_spp, rate_image) = (a.mean_spp(), a.rate_image());
            let outcome = render::render::RenderOutcome {
                spp: a.max_spp,
                passes: 1,
                elapsed: a.elapsed,
                cancelled: a.cancelled,
                extra: Vec::new(),
                items: 0..0,
                film: a.film,
            };
            reporter.finish_adaptive(&outcome, a.total_samples, mean_spp);
            if let Some(first) = job.outputs.first() {
                let stem = first.file_stem().and_then(|s| s.to_str()).unwrap_or("out");
                let rate = first.with_file_name(format!("{stem}_rate.png"));
                write_image(&rate, &rate_image).map_err(Failure::other)?;
                if !job.quiet {
                    eprintln!("wrote {}", rate.display());
                }
            }
            outcome
        }
    };
    if job.adaptive.is_none() {
        reporter.finish(&outcome);
    }
    if let Some(saver) = &saver {
        for e in saver.errors() {
            eprintln!("warning: {e}");
        }
        let cp = job.split.checkpoint.iter();
        for path in states.iter().chain(cp) {
            saver.write(path, &outcome.film, outcome.items.clone())?;
            if !job.quiet {
                eprintln!(
                    "wrote {} (items {}..{} of {})",
                    path.display(),
                    outcome.items.start,
                    outcome.items.end,
                    saver.items_total
                );
            }
        }
    }

    if images.is_empty() && display.is_none() && job.stderr.is_none() {
        // A shard or a render written as a state only: no image to develop.
        return end_of_render(&outcome);
    }
    let mut image = outcome.film.develop();
    let mut layers = Vec::new();
    if let (Some(d), Some(filter)) = (&job.denoise, &user_filter) {
        let denoised = pool.install(|| d.apply(&scene, outcome.spp, image, filter, job.quiet))?;
        image = denoised.image;
        layers = denoised.layers;
    }
    if let Some(f) = extras.develop {
        f(&mut image);
    }
    if let Some(display) = display
        && !display.finish(
            denoise::final_frame(&image, &layers),
            render::display::Display::final_wait(outcome.elapsed),
        )
    {
        eprintln!("warning: live view: tev did not take the final image in time");
    }
    // A depth AOV holds distances: as 8-bit PNG anything beyond 1 was white. PNGs get the
    // depths divided by the largest one (said once); EXR, PFM and HDR keep the distances.
    let depth_png = matches!(
        integrator,
        render::integrators::Integrator::Aov(render::integrators::Aov::Depth)
    )
    .then(|| {
        let far = image
            .pixels
            .iter()
            .map(|p| p.x)
            .filter(|d| d.is_finite())
            .fold(0.0f32, f32::max);
        let mut scaled = image.clone();
        if far > 0.0 {
            scaled.pixels.iter_mut().for_each(|p| *p /= far);
        }
        (scaled, far)
    });
    for o in &images {
        let is_png = o.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if let (true, Some((scaled, far))) = (is_png, &depth_png) {
            write_image(o, scaled).map_err(Failure::other)?;
            if !job.quiet {
                eprintln!(
                    "wrote {} (depth / {far}: black at the camera, white at the farthest hit)",
                    o.display()
                );
            }
            continue;
        }
        write_image_tonemapped(o, &image, scene.film.tonemap.as_ref()).map_err(Failure::other)?;
        if !job.quiet {
            eprintln!("wrote {}", o.display());
        }
    }
    if let Some(first) = images.first() {
        let stem = first.file_stem().and_then(|s| s.to_str()).unwrap_or("out");
        for (name, film) in &outcome.extra {
            let path = first.with_file_name(format!("{stem}_{name}.exr"));
            write_image(&path, &film.develop()).map_err(Failure::other)?;
        }
        if !job.quiet && !outcome.extra.is_empty() {
            eprintln!(
                "wrote {} per-strategy image(s) beside {}",
                outcome.extra.len(),
                first.display()
            );
        }
    }
    if let Some(se) = &job.stderr {
        write_image(se, &outcome.film.develop_stderr()).map_err(Failure::other)?;
        if !job.quiet {
            eprintln!("wrote {}", se.display());
        }
    }
    end_of_render(&outcome)
}

/// What every render says at its end: discarded samples, and exit code 130 if interrupted.
fn end_of_render(outcome: &render::render::RenderOutcome) -> Result<(), Failure> {
    let bad = outcome.film.nonfinite_count();
    if bad > 0 {
        eprintln!("warning: {bad} sample(s) were NaN or infinite and were discarded");
    }
    if outcome.cancelled {
        return Err(Failure::interrupted(format!(
            "interrupted after {} spp (the image of the finished passes was written)",
            outcome.spp
        )));
    }
    Ok(())
}

fn is_state(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("state"))
}

/// Sets a shard's items or a resumed film in `ropts`; returns what writes the render's
/// states (checkpoints, `-o PART.state`), or `None` when the render writes none.
fn split_render(
    desc: &SceneDesc,
    job: &RenderJob,
    scene: &render::world::Scene,
    integrator: &render::integrators::Integrator,
    ropts: &mut RenderOptions,
    images: &[PathBuf],
    states: &[PathBuf],
) -> Result<Option<split::Saver>, Failure> {
    let s = &job.split;
    if s.shard.is_none() && s.checkpoint.is_none() && s.resume.is_none() && states.is_empty() {
        return Ok(None);
    }
    if job.adaptive.is_some() {
        return Err(Failure::input(
            "adaptive sampling cannot be split into shards, checkpointed or written as a state",
        ));
    }
    if let Some(shard) = &s.shard {
        if job.time.is_some() {
            return Err(Failure::input(
                "--shard and --time do not combine: a shard renders its whole part",
            ));
        }
        if states.is_empty() || !images.is_empty() {
            return Err(Failure::input(format!(
                "a shard writes its film state, not images: give -o PART.state (shard \
                 {}/{}), then join the parts with `penumbra merge PART... -o IMAGE.exr`",
                shard.index.map_or("auto".into(), |i| i.to_string()),
                shard.count
            )));
        }
    }
    if !(s.checkpoint_interval >= 0.0 && s.checkpoint_interval.is_finite()) {
        return Err(Failure::input(format!(
            "--checkpoint-interval expects seconds ≥ 0, found {}",
            s.checkpoint_interval
        )));
    }
    let n = integrator
        .work_items(scene, ropts)
        .map_err(Failure::input)?;
    let what = (&job.build, ropts.spp, ropts.tile_size, ropts.chunk_spp);
    let identity = build::spec::identity(desc, &what);
    let range = match &s.shard {
        Some(shard) => {
            let i = shard.resolve()?;
            let r = build::spec::shard_items(i, shard.count, n);
            ropts.items = Some(r.clone());
            r
        }
        None => 0..n,
    };
    if let Some(path) = &s.resume {
        let st = split::read_resume(path, identity)?;
        if st.info.items.start != range.start || st.info.items.end > range.end {
            return Err(Failure::input(format!(
                "--resume {}: it holds items {}..{}, which do not start this render's {}..{} \
                 (another shard?)",
                path.display(),
                st.info.items.start,
                st.info.items.end,
                range.start,
                range.end
            )));
        }
        ropts.resume = Some(Arc::new(render::drive::Resume {
            film: st.film,
            items: st.info.items,
        }));
    }
    let (w, h) = (scene.film.width, scene.film.height);
    let description = format!(
        "{} ({}, {w}x{h}, {} spp, seed {})",
        desc.source.display(),
        integrator.name(),
        ropts.spp,
        scene.sampler.seed
    );
    Ok(Some(split::Saver::new(
        identity,
        description,
        n,
        ropts.spp,
        scene.film.tonemap.clone(),
        s.checkpoint
            .clone()
            .map(|p| (p, Duration::from_secs_f64(s.checkpoint_interval))),
    )))
}

fn cmd_test(files: &[PathBuf], seed: u64) -> Result<(), Failure> {
    let mut failed = 0usize;
    for f in files {
        let Document::Test(test) = load_scene(f, &[])? else {
            return Err(Failure::input(format!(
                "{}: not a test file (<test type=...>)",
                f.display()
            )));
        };
        let report = build::nori_tests::run(&test, seed).map_err(Failure::input)?;
        println!(
            "{}: {} with {} case(s), per-case level {:.3e}",
            f.display(),
            report.kind,
            report.cases.len(),
            report.case_level
        );
        for c in &report.cases {
            println!(
                "  {:<4} {}: statistic {:.4}, p = {:.4e}; {}",
                if c.passed { "ok" } else { "FAIL" },
                c.name,
                c.statistic,
                c.p_value,
                c.detail
            );
        }
        failed += report.cases.iter().filter(|c| !c.passed).count();
    }
    if failed == 0 {
        Ok(())
    } else {
        Err(Failure::rejected(format!("{failed} test case(s) failed")))
    }
}

fn cmd_compare(
    reference: &Path,
    test: &[PathBuf],
    stderr: Option<&Path>,
    min_batches: usize,
) -> Result<(), Failure> {
    use render::compare::{TestImages, compare, load_reference};
    use render::image_io::Decode;
    use render::image_io::read_image_with;
    if stderr.is_none() && test.len() < min_batches.max(2) {
        return Err(Failure::input(format!(
            "{} test image(s): the block t-test needs at least {} independent batches \
             (it is calibrated for {MIN_BATCHES}; with fewer, the batch means of caustic and \
             sun-lit blocks are too skewed and unbiased renders are rejected). Render more \
             batches, give one image with --stderr, or lower --min-batches knowingly",
            test.len(),
            min_batches.max(2)
        )));
    }
    let reference = load_reference(reference).map_err(Failure::input)?;
    let images = match stderr {
        Some(se) => {
            if test.len() != 1 {
                return Err(Failure::input("--stderr goes with exactly one test image"));
            }
            TestImages::MeanStderr {
                mean: read_image_with(&test[0], Decode::Raw).map_err(Failure::input)?,
                stderr: read_image_with(se, Decode::Raw).map_err(Failure::input)?,
            }
        }
        None => TestImages::load_batches(test).map_err(Failure::input)?,
    };
    // Images that cannot be compared (size mismatch, non-finite pixels) are bad input.
    let result = compare(&reference, &images).map_err(Failure::input)?;
    println!("{result}");
    if result.passed {
        Ok(())
    } else {
        Err(Failure::rejected(
            "the block t-test rejects the test image(s)",
        ))
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    memory::set_limit(cli.memory_limit);
    let result = match cli.command {
        Command::Render(args) => cmd_render(*args),
        Command::Merge {
            states,
            output,
            stderr,
        } => split::cmd_merge(&states, &output, stderr.as_deref()),
        Command::Info { scene, define } => {
            load_scene(&scene, &define).and_then(|doc| info::print(&scene, &doc))
        }
        Command::Test { files, seed } => cmd_test(&files, seed),
        Command::Compare {
            reference,
            test,
            stderr,
            min_batches,
        } => cmd_compare(&reference, &test, stderr.as_deref(), min_batches),
        Command::Comp30019(args) => comp30019::run(args),
        Command::Cs184(args) => cs184::run(args),
        Command::DebugPaths(args) => debug_paths::run(args),
        Command::Denoise(args) => denoise::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) if f.code == 130 => {
            eprintln!("{}", f.message);
            ExitCode::from(f.code)
        }
        Err(f) => {
            eprintln!("error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn transport(flags: &[&str]) -> TransportArgs {
        #[derive(clap::Parser)]
        struct Wrap {
            #[command(flatten)]
            t: TransportArgs,
        }
        Wrap::try_parse_from(std::iter::once("x").chain(flags.iter().copied()))
            .unwrap()
            .t
    }

    fn scene_with(integrator: IntegratorDesc) -> SceneDesc {
        let mut d = SceneDesc {
            integrator,
            ..SceneDesc::default()
        };
        d.sensors.push(scene::Sensor {
            medium: None,
            camera: scene::Camera {
                projection: scene::Projection::Orthographic,
                to_world: scene::Mat4::IDENTITY,
                near_clip: 0.0,
                far_clip: 1.0,
            },
            film: scene::Film {
                width: 1,
                height: 1,
                crop: None,
                filter: scene::FilterDesc::Box { radius: 0.5 },
                output: None,
                tonemap: None,
            },
            sampler: scene::SamplerDesc::default(),
            integrator: None,
            name: None,
            loc: Default::default(),
        });
        d
    }

    /// Every flag lands in the scene description the renderer builds from.
    #[test]
    fn transport_flags_reach_the_scene() {
        let t = transport(&[
            "--max-depth",
            "4",
            "--rr-depth",
            "2",
            "--sampler",
            "sobol",
            "--filter",
            "tent",
            "--clamp",
            "10",
            "--nee",
            "off",
        ]);
        let mut d = scene_with(IntegratorDesc::Path(scene::PathDesc::default()));
        let mut cli = None;
        t.apply(&mut d, &mut cli).unwrap();
        let IntegratorDesc::Path(p) = &d.integrator else {
            panic!()
        };
        assert_eq!(p.max_depth, 4);
        assert_eq!(p.rr, scene::RussianRoulette::Throughput { from_depth: 2 });
        assert_eq!(p.clamp, Some(10.0));
        assert!(!p.nee);
        assert_eq!(d.sensors[0].sampler.kind, scene::SamplerKind::Sobol);
        assert_eq!(
            d.sensors[0].film.filter,
            scene::FilterDesc::Tent { radius: 1.0 }
        );
        // Whitted takes --max-depth, and refuses path-tracer-only flags.
        let mut w = scene_with(IntegratorDesc::Whitted { max_depth: 8 });
        transport(&["--max-depth", "3"])
            .apply(&mut w, &mut None)
            .unwrap();
        assert_eq!(w.integrator, IntegratorDesc::Whitted { max_depth: 3 });
        assert!(
            transport(&["--clamp", "1"])
                .apply(&mut w, &mut None)
                .is_err()
        );
    }
}
