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
//! - `-e FILE` an equirectangular environment light (importance sampled), oriented as the
//!   course's `EnvironmentLight`: +Y up (top row), the left edge (u = 0) towards −X, u = ¼
//!   towards +Z (see [`envmap_emitter`]).
//!
//! Point lights differ on purpose: the course's `PointLight::sample_L` returns its colour
//! as incident radiance with no 1/r² falloff; ours is a physical point light of intensity
//! `colour` (W/sr), so irradiance falls off as 1/r². A surface at distance r is r² times
//! darker (brighter below 1) than in the course's renderer; the course scenes light with
//! area lights, which agree.
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

use build::BuildOptions;
use render::adaptive::AdaptiveSettings;
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
    /// Environment map (equirectangular .exr), oriented as CS184's: +Y up, left edge −X.
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
    /// Accumulate bounces (CS184's isAccumBounces): 1 sums every bounce up to -m, 0 keeps
    /// only light that bounced exactly -m times.
    #[arg(short = 'o', default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=1))]
    pub accumulate: u8,
    /// Seed of the sample streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Also write the per-pixel standard error of the image (for `penumbra compare`).
    #[arg(long, value_name = "FILE")]
    pub stderr: Option<PathBuf>,
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
        stderr: args.stderr.clone(),
        build: BuildOptions {
            sensor: 0,
            spp: None,
            resolution: None,
            seed: Some(args.seed),
            integrator: None,
            light_selection: None,
            flatten_instances: false,
            mode: scene::RenderMode::Rgb,
        },
        time: None,
        threads: args.threads,
        quiet: args.quiet,
        adaptive,
        denoise: None,
        display_server: None,
        split: Default::default(),
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
    let mut path = cs184_path(args.max_depth, args.light_samples, args.hemisphere);
    if args.accumulate == 0 {
        // Bounce m: the camera segment plus m more.
        path.only_depth = Some(args.max_depth.saturating_add(1));
    }
    desc.integrator = IntegratorDesc::Path(path);
    if let Some(env) = &args.envmap {
        desc.emitters.push(EmitterDesc {
            name: None,
            medium: None,
            emitter: envmap_emitter(env),
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
        Projection::Orthographic
        | Projection::Window { .. }
        | Projection::RadianceMeter
        | Projection::IrradianceMeter { .. } => {
            return Err(Failure::input(
                "only perspective cameras are supported by cs184",
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

/// The `-e` environment light: our lat-long map turned to CS184's orientation.
///
/// CS184's `EnvironmentLight` maps a world direction d to θ = acos(d.y) (row: v = θ/π, +Y at
/// the top) and φ = atan2(−d.z, d.x) + π (column: u = φ/2π), so the left edge u = 0 looks
/// along −X, u = ¼ along +Z, u = ½ along +X and u = ¾ along −Z. Our (Mitsuba) lat-long map
/// puts u = 0 at −Z and u = ¼ at +X: the two differ by swapping X and Z (a mirror, which
/// keeps solid angles, so sampling and pdfs are unchanged). Rows: CS184 puts the centre of
/// row y at θ = (y + ½)/h · π, we keep Mitsuba's grid (row y at θ = y/(h − 1) · π), at most
/// half a texel apart.
pub(crate) fn envmap_emitter(path: &Path) -> Emitter {
    Emitter::EnvMap {
        path: path.to_path_buf(),
        scale: 1.0,
        to_world: CS184_ENV_TO_WORLD,
        mapping: EnvMapping::LatLong,
    }
}

/// Swap X and Z: our lat-long frame to CS184's world (see [`envmap_emitter`]).
const CS184_ENV_TO_WORLD: Mat4 = Mat4::from_cols_array(&[
    0.0, 0.0, 1.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    1.0, 0.0, 0.0, 0.0, //
    0.0, 0.0, 0.0, 1.0,
]);

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

    /// The direction CS184's `EnvironmentLight` gives the map point (u, v): θ = vπ,
    /// φ = 2πu, d = (−cos φ sin θ, cos θ, sin φ sin θ) (its `theta_phi_to_dir`, restated).
    fn cs184_dir(u: f32, v: f32) -> Vec3 {
        let (theta, phi) = (v * std::f32::consts::PI, u * std::f32::consts::TAU);
        Vec3::new(
            -phi.cos() * theta.sin(),
            theta.cos(),
            phi.sin() * theta.sin(),
        )
    }

    /// `-e`: a map with one bright texel lights the direction CS184 gives that texel and no
    /// other. The X↔Z mirror of the direction (where the unturned Mitsuba map puts the
    /// texel) stays dark, so a lost orientation fails.
    #[test]
    fn envmap_orientation_is_the_courses() {
        use render::film::Image;
        use render::lights::EnvMap;
        let Emitter::EnvMap {
            to_world, mapping, ..
        } = envmap_emitter(Path::new("sky.exr"))
        else {
            panic!("not an environment map")
        };
        let (w, h) = (16u32, 8u32);
        // Texels at the horizon along the axes (u = ¼: +Z, u = ½: +X, u = ¾: −Z) and
        // off-axis ones above and below it.
        // (The mirror of column x lands on column 11 − x (mod 16): none of these is next to
        // its mirror.)
        for (x, y) in [(3, 3), (7, 4), (11, 3), (4, 1), (12, 5), (9, 6)] {
            let mut img = Image::new(w, h);
            img.set(x, y, Vec3::splat(100.0).into());
            let env = EnvMap::new(img, 1.0, &to_world, mapping);
            let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let d = cs184_dir(u, v);
            let lit = env.eval(d.into()).x;
            assert!(lit > 50.0, "texel ({x}, {y}): {lit} along {d}");
            let mirrored = env.eval(Vec3::new(d.z, d.y, d.x).into()).x;
            assert_eq!(
                mirrored, 0.0,
                "texel ({x}, {y}) also lights the mirror of {d}"
            );
            if !(3..=4).contains(&y) {
                let below = env.eval(Vec3::new(d.x, -d.y, d.z).into()).x;
                assert_eq!(below, 0.0, "texel ({x}, {y}) also lights {d} flipped in y");
            }
        }
        // The axes: the map's left edge looks along −X, the top row is +Y.
        let mut img = Image::new(w, h);
        img.set(0, 3, Vec3::splat(1.0).into());
        img.set(0, 4, Vec3::splat(1.0).into());
        img.set(w - 1, 3, Vec3::splat(1.0).into());
        img.set(w - 1, 4, Vec3::splat(1.0).into());
        let env = EnvMap::new(img, 1.0, &to_world, mapping);
        assert!((env.eval(Vec3::NEG_X.into()).x - 1.0).abs() < 1e-5);
        assert_eq!(env.eval(Vec3::X.into()).x, 0.0);
        let mut img = Image::new(w, h);
        for x in 0..w {
            img.set(x, 0, Vec3::splat(1.0).into());
        }
        let env = EnvMap::new(img, 1.0, &to_world, mapping);
        assert!((env.eval(Vec3::Y.into()).x - 1.0).abs() < 1e-5);
        assert_eq!(env.eval(Vec3::NEG_Y.into()).x, 0.0);
    }

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
