//! The `cs184` command: the UC Berkeley CS184 pathtracer's command line
//! (`-t 8 -s 64 -l 16 -m 5 -f out.png scene.dae`), mapped onto our renderer. Issue 6.
//!
//! Meanings (as the course's `pathtracer` binary):
//! - `-s N` camera rays per pixel (default 1); with `-a`, the cap of adaptive sampling.
//! - `-l N` samples per area light at every bounce (all lights are visited; default 1).
//! - `-m N` maximum ray depth in bounces (default 1: direct lighting). `N` bounces are
//!   `N + 1` path segments in our `PathDesc::max_depth`.
//! - `-H` uniform hemisphere sampling, no light sampling (instead of importance sampling).
//! - `-a BATCH TOL` adaptive sampling (off unless given): a pixel stops when
//!   1.96·σ/√n ≤ TOL·μ of its illuminance, checked every BATCH samples; the samples-per-pixel
//!   heat map is written to `OUT_rate.png` beside the image.
//! - `-e FILE` an equirectangular environment light (importance sampled).
//! - `-b R` / `-d D` thin lens: aperture radius and focal distance (scene units).
//! - `-r W H` output resolution. As in CS184's `Camera::configure`, the field of view grows
//!   along whichever axis the new aspect ratio makes too narrow.
//! - `-p X Y DX DY` render only the cell with top-left pixel (X, Y) and size DX × DY (our
//!   film's crop window; rows count from the top of the image).
//! - `-c FILE` a camera settings file as written by CS184's `Camera::dump_settings`
//!   (whitespace-separated: `hFov vFov ar nClip fClip`, `pos[3] target[3]`,
//!   `phi theta r minR maxR`, `c2w` 3×3 row-major (columns: screen right, screen up,
//!   direction to the camera), `screenW screenH screenDist`, optionally
//!   `focalDistance lensRadius`), in the scene's Y-up world.
//! - `-t N` worker threads; `-f FILE` output (.png, .exr...; default `SCENE.png` here).

use std::path::{Path, PathBuf};

use render::adaptive::AdaptiveSettings;
use render::build::BuildOptions;
use scene::formats::collada::cs184_path;
use scene::{
    Camera, CropWindow, Document, Emitter, EmitterDesc, EnvMapping, FovAxis, IntegratorDesc, Loc,
    Mat4, Projection, SceneDesc, Vec3,
};

use crate::{Failure, RenderJob};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The COLLADA scene (.dae).
    pub scene: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(short = 't')]
    pub threads: Option<usize>,
    /// Camera rays per pixel (the cap with -a).
    #[arg(short = 's', default_value_t = 1)]
    pub spp: u32,
    /// Samples per area light.
    #[arg(short = 'l', default_value_t = 1)]
    pub light_samples: u32,
    /// Maximum ray depth (bounces).
    #[arg(short = 'm', default_value_t = 1)]
    pub max_depth: u32,
    /// Environment map (equirectangular .exr).
    #[arg(short = 'e')]
    pub envmap: Option<PathBuf>,
    /// Lens radius (thin lens).
    #[arg(short = 'b')]
    pub lens_radius: Option<f32>,
    /// Focal distance (thin lens).
    #[arg(short = 'd')]
    pub focal_distance: Option<f32>,
    /// Output image.
    #[arg(short = 'f')]
    pub output: Option<PathBuf>,
    /// Resolution: WIDTH HEIGHT.
    #[arg(short = 'r', num_args = 2, value_names = ["W", "H"])]
    pub resolution: Option<Vec<u32>>,
    /// Adaptive sampling: BATCH TOLERANCE.
    #[arg(short = 'a', num_args = 2, value_names = ["BATCH", "TOL"])]
    pub adaptive: Option<Vec<String>>,
    /// Camera settings file (CS184 `dump_settings` format).
    #[arg(short = 'c')]
    pub camera: Option<PathBuf>,
    /// Render one cell: X Y DX DY.
    #[arg(short = 'p', num_args = 4, value_names = ["X", "Y", "DX", "DY"])]
    pub cell: Option<Vec<u32>>,
    /// Uniform hemisphere sampling instead of light sampling.
    #[arg(short = 'H')]
    pub hemisphere: bool,
    /// Seed of the sample streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// No progress output.
    #[arg(short = 'q', long)]
    pub quiet: bool,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let doc = crate::load_scene(&args.scene, &[])?;
    let Document::Scene(mut desc) = doc else {
        return Err(Failure::input(format!(
            "{}: not a scene file",
            args.scene.display()
        )));
    };
    crate::print_warnings(&desc);
    let adaptive = apply(&mut desc, &args)?;
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = args
            .scene
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        PathBuf::from(format!("{stem}.png"))
    });
    let job = RenderJob {
        outputs: vec![output],
        stderr: None,
        build: BuildOptions {
            sensor: 0,
            spp: None,
            resolution: None,
            seed: Some(args.seed),
            integrator: None,
            light_selection: None,
        },
        time: None,
        threads: args.threads,
        quiet: args.quiet,
        adaptive,
    };
    crate::render_scene(&desc, &job)
}

/// Apply the flags to the loaded scene (sensor 0, integrator, emitters).
pub(crate) fn apply(
    desc: &mut SceneDesc,
    args: &Args,
) -> Result<Option<AdaptiveSettings>, Failure> {
    if args.spp == 0 {
        return Err(Failure::input("-s expects at least 1 sample per pixel"));
    }
    if args.threads == Some(0) {
        return Err(Failure::input("-t expects at least 1 thread"));
    }
    desc.integrator = IntegratorDesc::Path(cs184_path(
        args.max_depth,
        args.light_samples,
        args.hemisphere,
    ));
    if let Some(env) = &args.envmap {
        desc.emitters.push(EmitterDesc {
            emitter: Emitter::EnvMap {
                path: env.clone(),
                scale: 1.0,
                to_world: Mat4::IDENTITY,
                mapping: EnvMapping::LatLong,
            },
            loc: Loc::file(env),
        });
    }
    let Some(sensor) = desc.sensors.first_mut() else {
        return Err(Failure::input("the scene has no camera"));
    };
    sensor.integrator = None;
    sensor.sampler.spp = args.spp;
    sensor.sampler.seed = args.seed;

    // Field of view as (tan(hFov/2), tan(vFov/2)).
    let (mut tx, mut ty) = match sensor.camera.projection {
        Projection::Perspective { fov, fov_axis } | Projection::ThinLens { fov, fov_axis, .. } => {
            let t = (fov.to_radians() * 0.5).tan();
            let a = sensor.film.width as f32 / sensor.film.height as f32;
            match fov_axis {
                FovAxis::X => (t, t / a),
                _ => (t * a, t),
            }
        }
        Projection::Orthographic => {
            return Err(Failure::input(
                "orthographic cameras are not supported by cs184",
            ));
        }
    };
    let (mut lens_r, mut focus) = (0.0f32, 1.0f32);
    if let Some(c) = &args.camera {
        let cam = read_camera_file(c)?;
        tx = (cam.hfov.to_radians() * 0.5).tan();
        ty = (cam.vfov.to_radians() * 0.5).tan();
        sensor.camera = Camera {
            to_world: cam.to_world,
            near_clip: cam.near,
            far_clip: cam.far,
            projection: sensor.camera.projection.clone(),
        };
        if let Some((w, h)) = cam.screen {
            sensor.film.width = w;
            sensor.film.height = h;
        }
        if let Some((d, r)) = cam.lens {
            focus = d;
            lens_r = r;
        }
    }
    if let Some(r) = &args.resolution {
        let (w, h) = (r[0], r[1]);
        if w == 0 || h == 0 || w > 1 << 16 || h > 1 << 16 {
            return Err(Failure::input(format!(
                "-r expects a resolution between 1 and 65536 per axis, found {w} {h}"
            )));
        }
        sensor.film.width = w;
        sensor.film.height = h;
    }
    // CS184 Camera::configure: the screen's aspect ratio wins; widen the too-narrow axis.
    let ar = sensor.film.width as f32 / sensor.film.height as f32;
    let (fov, fov_axis) = if tx / ty < ar {
        (2.0 * ty.atan().to_degrees(), FovAxis::Y)
    } else {
        (2.0 * tx.atan().to_degrees(), FovAxis::X)
    };
    if let Some(b) = args.lens_radius {
        lens_r = b;
    }
    if let Some(d) = args.focal_distance {
        focus = d;
    }
    if !(lens_r >= 0.0 && lens_r.is_finite() && focus > 0.0 && focus.is_finite()) {
        return Err(Failure::input(format!(
            "the lens radius must be ≥ 0 and the focal distance > 0, found {lens_r} and {focus}"
        )));
    }
    sensor.camera.projection = if lens_r > 0.0 {
        Projection::ThinLens {
            fov,
            fov_axis,
            aperture_radius: lens_r,
            focus_distance: focus,
        }
    } else {
        Projection::Perspective { fov, fov_axis }
    };
    sensor.film.crop = None;
    if let Some(p) = &args.cell {
        let (x, y, dx, dy) = (p[0], p[1], p[2], p[3]);
        let fits = |o: u32, d: u32, n: u32| d > 0 && o.checked_add(d).is_some_and(|e| e <= n);
        if !fits(x, dx, sensor.film.width) || !fits(y, dy, sensor.film.height) {
            return Err(Failure::input(format!(
                "-p {x} {y} {dx} {dy} is not a non-empty cell inside the {}×{} image",
                sensor.film.width, sensor.film.height
            )));
        }
        sensor.film.crop = Some(CropWindow {
            offset_x: x,
            offset_y: y,
            width: dx,
            height: dy,
        });
    }
    let adaptive = match &args.adaptive {
        None => None,
        Some(a) => {
            let batch: u32 = a[0].parse().ok().filter(|b| *b >= 2).ok_or_else(|| {
                Failure::input(format!(
                    "-a: batch size must be an integer ≥ 2, found '{}'",
                    a[0]
                ))
            })?;
            let tolerance: f32 = a[1]
                .parse()
                .ok()
                .filter(|t: &f32| *t > 0.0 && t.is_finite())
                .ok_or_else(|| {
                    Failure::input(format!(
                        "-a: tolerance must be a positive number, found '{}'",
                        a[1]
                    ))
                })?;
            Some(AdaptiveSettings { batch, tolerance })
        }
    };
    Ok(adaptive)
}

/// A camera read from a CS184 camera settings file.
#[derive(Debug)]
pub(crate) struct CameraFile {
    pub hfov: f32,
    pub vfov: f32,
    pub near: f32,
    pub far: f32,
    /// Ours: looks along +z, +x to the left.
    pub to_world: Mat4,
    pub screen: Option<(u32, u32)>,
    /// (focal distance, lens radius).
    pub lens: Option<(f32, f32)>,
}

pub(crate) fn read_camera_file(path: &Path) -> Result<CameraFile, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::input(format!("{}: cannot read: {e}", path.display())))?;
    parse_camera_file(&text).map_err(|m| Failure::input(format!("{}: {m}", path.display())))
}

pub(crate) fn parse_camera_file(text: &str) -> Result<CameraFile, String> {
    let v: Vec<f64> = text
        .split_ascii_whitespace()
        .map(|t| {
            t.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("'{t}' is not a finite number"))
        })
        .collect::<Result<_, _>>()?;
    // 5 + 6 + 5 + 9 + 3 = 28 numbers, then optionally 2 lens numbers.
    if v.len() != 28 && v.len() != 30 {
        return Err(format!(
            "a CS184 camera file holds 28 or 30 numbers, found {}",
            v.len()
        ));
    }
    let f = |i: usize| v[i] as f32;
    let (hfov, vfov, near, far) = (f(0), f(1), f(3), f(4));
    if !(hfov > 0.0 && hfov < 180.0 && vfov > 0.0 && vfov < 180.0) {
        return Err(format!(
            "fields of view must be in (0, 180) degrees, found {hfov} and {vfov}"
        ));
    }
    let pos = Vec3::new(f(5), f(6), f(7));
    // c2w(i/3, i%3) row-major at 16..25: column j = (c(0,j), c(1,j), c(2,j)).
    let col = |j: usize| Vec3::new(f(16 + j), f(19 + j), f(22 + j));
    let right = col(0).normalize_or_zero();
    let up = col(1).normalize_or_zero();
    let back = col(2).normalize_or_zero();
    if right == Vec3::ZERO || up == Vec3::ZERO || back == Vec3::ZERO {
        return Err("the camera-to-world matrix has a zero column".into());
    }
    let to_world = Mat4::from_cols(
        (-right).extend(0.0),
        up.extend(0.0),
        (-back).extend(0.0),
        pos.extend(1.0),
    );
    let (w, h) = (v[25], v[26]);
    let screen = (w >= 1.0 && h >= 1.0 && w <= 65536.0 && h <= 65536.0)
        .then(|| (w.round() as u32, h.round() as u32));
    let lens = (v.len() == 30).then(|| (f(28), f(29)));
    Ok(CameraFile {
        hfov,
        vfov,
        near: near.max(1e-6),
        far: far.max(near * 2.0),
        to_world,
        screen,
        lens,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_file_round_trip() {
        // A camera at (0, 1, 3) looking along -z: right +x, up +y, back +z.
        let text = "49.1 37.8 1.333 0.1 100\n0 1 3 0 1 0\n0 0 3 0.1 10\n\
                    1 0 0 0 1 0 0 0 1\n640 480 1\n4.5 0.05\n";
        let c = parse_camera_file(text).unwrap();
        assert_eq!(c.screen, Some((640, 480)));
        assert_eq!(c.lens, Some((4.5, 0.05)));
        let m = c.to_world;
        assert_eq!(m.transform_vector3(Vec3::Z), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(m.transform_vector3(Vec3::X), Vec3::new(-1.0, 0.0, 0.0));
        assert_eq!(m.transform_point3(Vec3::ZERO), Vec3::new(0.0, 1.0, 3.0));
        assert!(parse_camera_file("1 2 3").is_err());
        assert!(parse_camera_file(&text.replace("49.1", "nan")).is_err());
    }
}
