//! Photon emission (`Light::sample_le`) of every emitter kind, tested statistically on tiny
//! Mitsuba scenes: point, spot (Mitsuba's falloff, under a non-rigid frame, and the CENG795
//! profile), directional, constant, environment map, and area lights on a one-sided mesh (a
//! cube, triangles chosen by area), a two-sided mesh (a rectangle, the one-step
//! parallelogram), a mesh split into per-triangle lights (light selection by power), a
//! textured rectangle, a disk, a sphere and an ellipsoid.
//!
//! - The mean `weight` over 2¹⁸ independent uniform (u_pos, u_dir) is the light's emitted
//!   power Φ (z-test per lane, RGB mode with distinct channels, and spectral mode at four
//!   fixed wavelengths with uniform declared spectra, grey maps and textures; a weight that
//!   never varies — point, directional, constant, most area lights — must equal Φ to 10⁻⁵
//!   instead), with Φ derived here: 4π·I; I·2π∫falloff
//!   (numerically); E·πR² and L·4π·πR² (R the bounding sphere's radius of the box the scene
//!   holds); πR²·∫L dω of the map (bilinear on Mitsuba's grid: exact per row, Simpson in θ);
//!   π·A·L (twice when two-sided) with A from the shape's parameters (the prolate spheroid's
//!   area in closed form). A constant weight cannot tell where the power leaves, so for area
//!   lights the mean of weight × [origin in a part of the surface] is also z-tested against
//!   π·L·(that part's area): a strip of a rectangle, a segment of the disk, a zone of the
//!   sphere, a face of the cube, a zone of the spheroid (its area by Simpson's rule).
//! - The directions follow `pdf_dir` (χ², 16 × 32 cells in (cos θ, φ)) with densities written
//!   here: uniform (point, constant, the sphere's marginal), the cone (spots, with the
//!   Jacobian of a non-rigid frame), the cosine lobes of the cube's faces, a two-sided
//!   rectangle and a disk, the environment map's own `pdf_li`; the ellipsoid's object-sphere
//!   points (uniform) and cosine directions about its analytic normal; the disk an infinite
//!   light's rays start from (uniform, χ² on 16 × 16 cells).
//! - Rays start where they should: area-light origins lie on the surface (to the error
//!   bound), leave on the emitting side and never hit their own emitter; `n`, `pdf_pos` and
//!   `pdf_dir` are the analytic ones; point-like lights emit from their position; infinite
//!   lights' rays start on the disk R before the scene's centre, and hit the scene's box in
//!   the proportion its projected area πR² predicts (z-test of hit − A⊥(ω)/πR²).
//!
//! - `pdf_le` (not statistical) gives back each sample's `pdf_pos` and `pdf_dir` (10⁻³), its
//!   direction density integrates to 1 over the sphere (10⁻², midpoint rule), and it is 0
//!   for rays `sample_le` never draws.
//!
//! Significance: α = 0.01 over every statistical test of this file together, Šidák-corrected
//! ([`TESTS`] = 14 × (3 + 4) lane z-tests + 7 part z-tests + 3 hit-fraction z-tests + 13 χ²
//! tests = 121, each at level 1 − 0.99^(1/121) ≈ 8.3·10⁻⁵: |z| < 3.935, χ² p-values above
//! it). Fixed seeds.

use std::f64::consts::PI;

use base::LightSelection;
use build::{BuildOptions, build};
use glam::{DMat3, DMat4, DVec3, Mat4};
use render::lights::{EmissionSample, Light, Receiver};
use render::math::{Frame, Vec2, Vec3};
use render::spectral::lanes::{Color, ColorMode, RgbMode, SpectralMode};
use render::spectral::{RgbToSpectrumTable, SampledWavelengths};
use render::stats::{Chi2Config, Chi2Result, Pcg32, chi2_test, chi2_test_2d, sidak};
use render::world::Scene;
use scene::{Emitter, Shape, SpotFalloff};
use statrs::distribution::{ContinuousCDF, Normal};

/// Cases of [`cases`] (each a z-test per lane in both modes).
const CASES: usize = 14;
/// Infinite lights (a hit-fraction z-test each).
const INFINITE: usize = 3;
/// Area-light cases (a z-test each of the power leaving a part of the surface, RGB red).
const AREA: usize = 7;
/// χ² tests of [`directions_and_positions_follow_their_densities`].
const CHI2: usize = 13;
/// Every statistical test of the file: z-tests of 3 RGB and 4 spectral lanes per case, the
/// hit fractions, the χ² tests.
const TESTS: usize = CASES * (3 + 4) + AREA + INFINITE + CHI2;
// The module documentation states the count.
const _: () = assert!(TESTS == 121);
const ALPHA: f64 = 0.01;
/// Samples per z-test.
const N: usize = 1 << 18;

fn level() -> f64 {
    sidak(ALPHA, TESTS)
}

/// Two-sided critical |z| at the per-test level.
fn z_crit() -> f64 {
    Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - level() / 2.0)
}

fn dv(v: Vec3) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

fn dmat(m: Mat4) -> DMat4 {
    m.as_dmat4()
}

/// Spectral mode at 430, 500, 570 and 640 nm.
fn spectral() -> SpectralMode<'static> {
    SpectralMode::new(
        SampledWavelengths::sample_uniform(0.0, 430.0, 710.0),
        RgbToSpectrumTable::srgb(),
    )
}

#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Rgb,
    Spectral,
}

impl Mode {
    fn lanes(self) -> usize {
        match self {
            Mode::Rgb => 3,
            Mode::Spectral => 4,
        }
    }

    /// A light's colour parameter `name`: RGB `rgb` or, in spectral mode, the uniform spectrum
    /// `s` (which spectral mode samples as `s` at every wavelength); and its lanes.
    fn colour(self, name: &str, rgb: [f64; 3], s: f64) -> (String, Vec<f64>) {
        match self {
            Mode::Rgb => (
                format!(
                    r#"<rgb name="{name}" value="{}, {}, {}"/>"#,
                    rgb[0], rgb[1], rgb[2]
                ),
                rgb.to_vec(),
            ),
            Mode::Spectral => (
                format!(r#"<spectrum name="{name}" value="{s}"/>"#),
                vec![s; 4],
            ),
        }
    }

    /// Lanes of an RGB emission value that is grey (g, g, g) in spectral mode: an illuminant
    /// spectrum, linear in g (the upsampling of a grey is the same curve at any level).
    fn grey_lanes(self, rgb: [f64; 3]) -> Vec<f64> {
        match self {
            Mode::Rgb => rgb.to_vec(),
            Mode::Spectral => {
                let one = spectral().illuminant(Vec3::ONE);
                (0..4).map(|i| rgb[0] * one.lane(i) as f64).collect()
            }
        }
    }
}

/// A part of an area light's surface, in its object space (`Place::Surface`).
#[derive(Clone, Copy, Debug)]
enum Part {
    /// x > t (rectangles, disks).
    XAbove(f64),
    /// z > t (spheres, ellipsoids).
    ZAbove(f64),
    /// The cube's +x face.
    PlusXFace,
}

impl Part {
    fn holds(self, q: DVec3) -> bool {
        match self {
            Part::XAbove(t) => q.x > t,
            Part::ZAbove(t) => q.z > t,
            Part::PlusXFace => q.abs().max_position() == 0 && q.x > 0.0,
        }
    }
}

/// Where an emitter is, for the geometric checks.
#[derive(Clone, Debug)]
enum Place {
    Point(DVec3),
    /// `to_world`: the linear part of the light's frame (its axis is +z).
    Spot {
        position: DVec3,
        to_world: DMat3,
        cos_cutoff: f64,
    },
    /// An infinite light in a scene holding the box [lo, hi].
    Infinite {
        lo: DVec3,
        hi: DVec3,
        /// The directional light's direction of travel.
        direction: Option<DVec3>,
    },
    /// An emitting shape: the unit shape of `kind` under `to_world`; `area` of the light
    /// (of one triangle for a split mesh).
    Surface {
        kind: Surf,
        to_world: DMat4,
        two_sided: bool,
        area: f64,
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Surf {
    Rectangle,
    Disk,
    Sphere,
    Ellipsoid,
    Cube,
}

struct Case {
    name: &'static str,
    scene: Scene,
    /// The lights whose photons are counted: one, or the triangles of a split mesh (one is
    /// chosen uniformly per sample and its weight multiplied by their number).
    lights: Vec<usize>,
    /// Analytic power per lane.
    phi: Vec<f64>,
    place: Place,
    /// Area lights: a part of the surface and the fraction of Φ that leaves it.
    part: Option<(Part, f64)>,
}

const SENSOR: &str = r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>"#;

/// The box the infinite lights' scenes hold: [−1, 3] × [1, 3] × [2.5, 3.5].
const BOX: &str = r#"<shape type="cube"><transform name="to_world"><scale x="2" y="1" z="0.5"/><translate x="1" y="2" z="3"/></transform></shape>"#;
const BOX_LO: DVec3 = DVec3::new(-1.0, 1.0, 2.5);
const BOX_HI: DVec3 = DVec3::new(3.0, 3.0, 3.5);

fn box_radius() -> f64 {
    0.5 * (BOX_HI - BOX_LO).length()
}

fn load(name: &str, body: &str) -> scene::SceneDesc {
    let xml = format!(r#"<scene version="3.0.0">{SENSOR}{body}</scene>"#);
    *scene::load_xml_text(&format!("emission-{name}"), &xml).unwrap()
}

fn built(desc: &scene::SceneDesc, mode: Mode, selection: Option<LightSelection>) -> Scene {
    let opts = BuildOptions {
        mode: match mode {
            Mode::Rgb => base::RenderMode::Rgb,
            Mode::Spectral => base::RenderMode::Spectral,
        },
        light_selection: selection,
        ..Default::default()
    };
    build(desc, &opts).unwrap().scene
}

/// A 64 × 32 lat-long sky: a gradient and a 2 × 1-pixel sun, coloured (grey in spectral mode).
fn sky(mode: Mode) -> std::path::PathBuf {
    let (w, h) = (64u32, 32u32);
    let mut img = render::film::Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let v = 0.2 + 0.8 * (y as f32 / h as f32) + 0.1 * (x as f32 / w as f32);
            let c = match mode {
                Mode::Rgb => Vec3::new(v, 0.5 * v + 0.3 * (x as f32 / w as f32), 1.2 - v),
                Mode::Spectral => Vec3::splat(v),
            };
            img.set(x, y, c);
        }
    }
    let sun = match mode {
        Mode::Rgb => [
            Vec3::new(400.0, 300.0, 150.0),
            Vec3::new(250.0, 200.0, 100.0),
        ],
        Mode::Spectral => [Vec3::splat(400.0), Vec3::splat(250.0)],
    };
    img.set(20, 9, sun[0]);
    img.set(21, 9, sun[1]);
    // A file per call: the tests of this binary build their cases in parallel threads.
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("penumbra-emission-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("sky-{call}.exr"));
    render::image_io::write_image(&path, &img).unwrap();
    path
}

/// ∫ L dω of an environment map (per RGB channel), from its pixels: on Mitsuba's lat-long
/// grid the bilinear lookup integrates over u (columns at pixel centres, wrapping) to the
/// row's mean, and is linear in v between rows at v = y/(h − 1); dω = 2π² sin(πv) du dv.
fn env_integral(light: &Light) -> [f64; 3] {
    let Light::EnvMap(e) = light else {
        panic!("not an environment map")
    };
    let (w, h) = (e.image.width, e.image.height);
    let rows: Vec<DVec3> = (0..h)
        .map(|y| (0..w).map(|x| dv(e.image.get(x, y))).sum::<DVec3>() / w as f64)
        .collect();
    let mut total = DVec3::ZERO;
    let k = 256;
    for y in 0..h as usize - 1 {
        let (a, b) = (y as f64 / (h - 1) as f64, (y + 1) as f64 / (h - 1) as f64);
        let f = |v: f64| {
            let t = (v - a) / (b - a);
            (rows[y] * (1.0 - t) + rows[y + 1] * t) * (PI * v).sin()
        };
        // Composite Simpson.
        let hstep = (b - a) / k as f64;
        let mut s = f(a) + f(b);
        for i in 1..k {
            s += f(a + i as f64 * hstep) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        total += s * hstep / 3.0;
    }
    (total * 2.0 * PI * PI * e.scale as f64).to_array()
}

/// ∫ falloff dω / 2π of Mitsuba's spot (1 inside the beam, linear in angle to the cutoff),
/// by Simpson's rule in θ.
fn mitsuba_cone(cutoff_deg: f64, beam_deg: f64) -> f64 {
    let (c, b) = (cutoff_deg.to_radians(), beam_deg.to_radians());
    let f = |t: f64| {
        let fall = if t <= b {
            1.0
        } else {
            ((c - t) / (c - b)).clamp(0.0, 1.0)
        };
        fall * t.sin()
    };
    let k = 100_000;
    let hstep = c / k as f64;
    let mut s = f(0.0) + f(c);
    for i in 1..k {
        s += f(i as f64 * hstep) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * hstep / 3.0
}

/// ∫ falloff(M⁻¹ω/|M⁻¹ω|) dω of Mitsuba's spot whose frame's linear part is `m`: over the
/// local cone, with dω = |det M| / |M ω_l|³ dω_l (midpoint rule, 2000 × 2000).
fn mitsuba_cone_under(m: DMat3, cutoff_deg: f64, beam_deg: f64) -> f64 {
    let (c, b) = (cutoff_deg.to_radians(), beam_deg.to_radians());
    let det = m.determinant().abs();
    let (nt, np) = (2000, 2000);
    let mut s = 0.0;
    for i in 0..nt {
        let t = c * (i as f64 + 0.5) / nt as f64;
        let fall = if t <= b { 1.0 } else { (c - t) / (c - b) };
        let mut ring = 0.0;
        for j in 0..np {
            let p = 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let wl = DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
            ring += det / (m * wl).length().powi(3);
        }
        s += fall * t.sin() * ring;
    }
    s * (c / nt as f64) * (2.0 * PI / np as f64)
}

/// The prolate spheroid's area (semi-axes a, a, c > a).
fn spheroid_area(a: f64, c: f64) -> f64 {
    let e = (1.0 - a * a / (c * c)).sqrt();
    2.0 * PI * a * a * (1.0 + c / (a * e) * e.asin())
}

/// Area of the zone z ∈ [z0·c, z1·c] of that spheroid (a surface of revolution of radius
/// ρ(z) = a√(1 − z²/c²): dA = 2π ρ √(1 + ρ'²) dz = 2π a √(1 − z²/c² + a²z²/c⁴) dz), by
/// Simpson's rule.
fn spheroid_zone(a: f64, c: f64, z0: f64, z1: f64) -> f64 {
    let f = |z: f64| 2.0 * PI * a * (1.0 - z * z / (c * c) + a * a * z * z / c.powi(4)).sqrt();
    let k = 20_000;
    let (lo, hi) = (z0 * c, z1 * c);
    let h = (hi - lo) / k as f64;
    let mut s = f(lo) + f(hi);
    for i in 1..k {
        s += f(lo + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// An area light's case: name, shape, its XML (an open `<shape>`), two-sided, split into a
/// light per triangle, area, a part of it and the fraction of the area that part has.
type AreaSpec = (&'static str, Surf, String, bool, bool, f64, Part, f64);

/// Whether a two-sided z-test rejects at `crit` (a NaN statistic rejects).
fn rejects(z: f64, crit: f64) -> bool {
    z.is_nan() || z.abs() >= crit
}

/// Every case, built in `mode`.
fn cases(mode: Mode) -> Vec<Case> {
    let mut out = Vec::new();
    let lane_mul = |k: f64, lanes: &[f64]| lanes.iter().map(|l| k * l).collect::<Vec<_>>();

    // Point light.
    {
        let (c, lanes) = mode.colour("intensity", [1.0, 2.0, 3.0], 2.5);
        let desc = load(
            "point",
            &format!(
                r#"<emitter type="point"><point name="position" x="0.3" y="-0.2" z="1"/>{c}</emitter>"#
            ),
        );
        out.push(Case {
            name: "point",
            scene: built(&desc, mode, None),
            lights: vec![0],
            phi: lane_mul(4.0 * PI, &lanes),
            place: Place::Point(DVec3::new(0.3, -0.2, 1.0)),
            part: None,
        });
    }

    // Spot lights: Mitsuba's falloff under a rigid and a non-rigid frame, and CENG795's.
    for (name, scale, course) in [
        ("spot", "", false),
        (
            "spot, scaled frame",
            r#"<scale x="1" y="2.5" z="0.6"/>"#,
            false,
        ),
        ("spot, CENG795 falloff", "", true),
    ] {
        let (c, lanes) = mode.colour("intensity", [2.0, 1.0, 0.5], 1.5);
        let mut desc = load(
            "spot",
            &format!(
                r#"<emitter type="spot"><transform name="to_world">{scale}<lookat origin="1, 2, 0" target="0, 0.5, 1" up="0, 1, 0"/></transform>
                <float name="cutoff_angle" value="40"/><float name="beam_width" value="15"/>{c}</emitter>"#
            ),
        );
        let Emitter::Spot {
            to_world, falloff, ..
        } = &mut desc.emitters[0].emitter
        else {
            panic!()
        };
        if course {
            *falloff = SpotFalloff::Cosine4;
        }
        let m = DMat3::from_mat4(dmat(*to_world));
        let (cc, cb) = (40f64.to_radians().cos(), 15f64.to_radians().cos());
        let k = if course {
            // ∫ ((cos θ − cos c) / (cos b − cos c))⁴ d cos θ = (cos b − cos c) / 5.
            2.0 * PI * ((1.0 - cb) + (cb - cc) / 5.0)
        } else if scale.is_empty() {
            2.0 * PI * mitsuba_cone(40.0, 15.0)
        } else {
            mitsuba_cone_under(m, 40.0, 15.0)
        };
        out.push(Case {
            name,
            place: Place::Spot {
                position: dmat(*to_world).w_axis.truncate(),
                to_world: m,
                cos_cutoff: cc,
            },
            scene: built(&desc, mode, None),
            lights: vec![0],
            phi: lane_mul(k, &lanes),
            part: None,
        });
    }

    let r = box_radius();
    let disk = PI * r * r;
    // Directional light.
    {
        let (c, lanes) = mode.colour("irradiance", [0.5, 1.0, 2.0], 0.8);
        let desc = load(
            "directional",
            &format!(
                r#"{BOX}<emitter type="directional"><vector name="direction" x="1" y="-2" z="0.5"/>{c}</emitter>"#
            ),
        );
        out.push(Case {
            name: "directional",
            scene: built(&desc, mode, None),
            lights: vec![0],
            phi: lane_mul(disk, &lanes),
            place: Place::Infinite {
                lo: BOX_LO,
                hi: BOX_HI,
                direction: Some(DVec3::new(1.0, -2.0, 0.5).normalize()),
            },
            part: None,
        });
    }
    // Constant environment.
    {
        let (c, lanes) = mode.colour("radiance", [0.2, 0.4, 0.8], 0.3);
        let desc = load(
            "constant",
            &format!(r#"{BOX}<emitter type="constant">{c}</emitter>"#),
        );
        out.push(Case {
            name: "constant",
            scene: built(&desc, mode, None),
            lights: vec![0],
            phi: lane_mul(4.0 * PI * disk, &lanes),
            place: Place::Infinite {
                lo: BOX_LO,
                hi: BOX_HI,
                direction: None,
            },
            part: None,
        });
    }
    // Environment map.
    {
        let desc = load(
            "envmap",
            &format!(
                r#"{BOX}<emitter type="envmap"><string name="filename" value="{}"/><float name="scale" value="1.5"/>
                <transform name="to_world"><rotate y="1" angle="40"/></transform></emitter>"#,
                sky(mode).display()
            ),
        );
        let scene = built(&desc, mode, None);
        let light = scene.lights.len() - 1;
        let integral = env_integral(&scene.lights[light]);
        out.push(Case {
            name: "envmap",
            phi: lane_mul(disk, &mode.grey_lanes(integral)),
            scene,
            lights: vec![light],
            place: Place::Infinite {
                lo: BOX_LO,
                hi: BOX_HI,
                direction: None,
            },
            part: None,
        });
    }

    // Area lights: (name, shape, its XML, two-sided, split into triangles, area, a part of
    // it with the fraction of the area it has).
    let (a, b, c) = (0.5, 1.0, 1.5);
    let spheroid = (0.7, 1.6);
    // Of the unit disk, the segment x > 0.3: (acos t − t√(1 − t²)) / π.
    let segment = (0.3f64.acos() - 0.3 * (1.0 - 0.09f64).sqrt()) / PI;
    let shapes: [AreaSpec; AREA] = [
        (
            "cube (mesh, one-sided)",
            Surf::Cube,
            format!(
                r#"<shape type="cube"><transform name="to_world"><scale x="{a}" y="{b}" z="{c}"/><rotate x="1" y="1" angle="30"/><translate x="0" y="1" z="2"/></transform>"#
            ),
            false,
            false,
            8.0 * (a * b + b * c + c * a),
            Part::PlusXFace,
            4.0 * b * c / (8.0 * (a * b + b * c + c * a)),
        ),
        (
            "rectangle (mesh, two-sided)",
            Surf::Rectangle,
            r#"<shape type="rectangle"><transform name="to_world"><scale x="1.5" y="0.7" z="1"/><rotate x="1" angle="70"/><translate x="0.2" y="0.3" z="1"/></transform>"#.into(),
            true,
            false,
            4.0 * 1.5 * 0.7,
            Part::XAbove(0.3),
            0.35,
        ),
        (
            "rectangle (a light per triangle)",
            Surf::Rectangle,
            r#"<shape type="rectangle"><transform name="to_world"><scale x="0.9" y="1.3" z="1"/><rotate y="1" angle="-50"/><translate x="0.2" y="0.3" z="1"/></transform>"#.into(),
            false,
            true,
            4.0 * 0.9 * 1.3,
            Part::XAbove(0.3),
            0.35,
        ),
        (
            "rectangle (textured)",
            Surf::Rectangle,
            r#"<shape type="rectangle"><transform name="to_world"><scale x="0.8" y="1.1" z="1"/><rotate z="1" angle="20"/><rotate x="1" angle="-30"/></transform>"#.into(),
            false,
            false,
            4.0 * 0.8 * 1.1,
            // u > 0.65: both checker colours over the whole v range, half each.
            Part::XAbove(0.3),
            0.35,
        ),
        (
            "disk",
            Surf::Disk,
            r#"<shape type="disk"><transform name="to_world"><scale x="1.2" y="0.6" z="1"/><rotate y="1" angle="150"/><translate x="0.3" y="0" z="2.5"/></transform>"#.into(),
            false,
            false,
            PI * 1.2 * 0.6,
            Part::XAbove(0.3),
            segment,
        ),
        (
            "sphere",
            Surf::Sphere,
            r#"<shape type="sphere"><point name="center" x="0.5" y="-1" z="2"/><float name="radius" value="0.8"/>"#.into(),
            false,
            false,
            4.0 * PI * 0.8 * 0.8,
            // Archimedes: a zone's area is proportional to its height.
            Part::ZAbove(0.5),
            0.25,
        ),
        (
            "ellipsoid",
            Surf::Ellipsoid,
            format!(
                r#"<shape type="sphere"><transform name="to_world"><scale x="{0}" y="{0}" z="{1}"/><rotate x="1" angle="30"/><translate x="0.5" y="-0.2" z="1"/></transform>"#,
                spheroid.0, spheroid.1
            ),
            false,
            false,
            spheroid_area(spheroid.0, spheroid.1),
            Part::ZAbove(0.5),
            spheroid_zone(spheroid.0, spheroid.1, 0.5, 1.0) / spheroid_area(spheroid.0, spheroid.1),
        ),
    ];
    // The zone integral against the closed form.
    let whole = spheroid_zone(spheroid.0, spheroid.1, -1.0, 1.0);
    assert!((whole / spheroid_area(spheroid.0, spheroid.1) - 1.0).abs() < 1e-9);
    for (name, kind, shape, two_sided, split, area, part, fraction) in shapes {
        let textured = name.contains("textured");
        let (emission, lanes) = if textured {
            // A 2 × 2 checkerboard over the rectangle's uv square: half of each colour.
            let (c0, c1) = match mode {
                Mode::Rgb => ([4.0, 2.0, 1.0], [1.0, 1.0, 3.0]),
                Mode::Spectral => ([2.0; 3], [0.5; 3]),
            };
            let mean = [0, 1, 2].map(|i| 0.5 * (c0[i] + c1[i]));
            (
                format!(
                    r#"<texture type="checkerboard" name="radiance"><rgb name="color0" value="{}, {}, {}"/><rgb name="color1" value="{}, {}, {}"/></texture>"#,
                    c0[0], c0[1], c0[2], c1[0], c1[1], c1[2]
                ),
                mode.grey_lanes(mean),
            )
        } else {
            mode.colour("radiance", [1.0, 0.5, 0.25], 1.2)
        };
        let mut desc = load(
            "area",
            &format!(r#"{shape}<emitter type="area">{emission}</emitter></shape>"#),
        );
        desc.shapes[0].emission.as_mut().unwrap().two_sided = two_sided;
        let mut to_world = dmat(desc.shapes[0].to_world);
        if let Shape::Sphere { center, radius } = &desc.shapes[0].shape {
            to_world = to_world
                * DMat4::from_translation(center.as_dvec3())
                * DMat4::from_scale(DVec3::splat(*radius as f64));
        }
        let scene = built(&desc, mode, split.then_some(LightSelection::Power));
        let lights: Vec<usize> = (0..scene.lights.len()).collect();
        assert_eq!(lights.len(), if split { 2 } else { 1 }, "{name}");
        let sides = if two_sided { 2.0 } else { 1.0 };
        out.push(Case {
            name,
            scene,
            phi: lane_mul(PI * sides * area, &lanes),
            place: Place::Surface {
                kind,
                to_world,
                two_sided,
                area: area / lights.len() as f64,
            },
            lights,
            part: Some((part, fraction)),
        });
    }
    assert_eq!(out.len(), CASES);
    out
}

/// One photon of `case`: a light chosen uniformly among its lights, then `sample_le`; the
/// weight multiplied by the number of lights (divided by the choice's probability).
fn emit<M: ColorMode>(case: &Case, rng: &mut Pcg32, m: &M) -> Option<EmissionSample<M::C>> {
    let k = case.lights.len();
    let i = if k > 1 {
        ((rng.next_f32() * k as f32) as usize).min(k - 1)
    } else {
        0
    };
    let (u_pos, u_dir) = (rng.next_vec2(), rng.next_vec2());
    let light = &case.scene.lights[case.lights[i]];
    light.sample_le(&case.scene, u_pos, u_dir, m).map(|mut s| {
        s.weight *= k as f32;
        s
    })
}

/// z statistic of a sample mean against `want`; a sample that never varies has none: it must
/// equal `want` to 10⁻⁵ (z reported as 0, else ∞).
fn z_of(sum: f64, sum2: f64, n: usize, want: f64) -> f64 {
    let n = n as f64;
    let mean = sum / n;
    let var = ((sum2 - sum * mean) / (n - 1.0)).max(0.0);
    if var <= 1e-10 * mean * mean {
        if (mean - want).abs() <= 1e-5 * want.abs() {
            0.0
        } else {
            f64::INFINITY
        }
    } else {
        (mean - want) / (var / n).sqrt()
    }
}

/// z statistics of the mean weight per lane against `case.phi` (a failed sample counts as
/// zero), and, for an area light, of the mean of lane 0 of weight × [origin in its part]
/// against the part's share of Φ.
fn power_z<M: ColorMode>(case: &Case, m: &M, seed: u64) -> (Vec<f64>, Option<f64>) {
    let mut rng = Pcg32::new(seed, 0xe1);
    let lanes = case.phi.len();
    let (mut sum, mut sum2) = (vec![0f64; lanes], vec![0f64; lanes]);
    let (mut part_sum, mut part_sum2) = (0f64, 0f64);
    let to_object = match &case.place {
        Place::Surface { to_world, .. } => Some(to_world.inverse()),
        _ => None,
    };
    for _ in 0..N {
        if let Some(s) = emit(case, &mut rng, m) {
            for i in 0..lanes {
                let w = s.weight.lane(i) as f64;
                assert!(w.is_finite() && w >= 0.0, "{}: weight {w}", case.name);
                sum[i] += w;
                sum2[i] += w * w;
            }
            if let (Some((part, _)), Some(inv)) = (case.part, to_object)
                && part.holds(inv.transform_point3(dv(s.ray.o)))
            {
                let w = s.weight.lane(0) as f64;
                part_sum += w;
                part_sum2 += w * w;
            }
        }
    }
    let z = (0..lanes)
        .map(|i| z_of(sum[i], sum2[i], N, case.phi[i]))
        .collect();
    let part = case
        .part
        .map(|(_, fraction)| z_of(part_sum, part_sum2, N, fraction * case.phi[0]));
    (z, part)
}

fn check_power<M: ColorMode>(mode: Mode, m: &M, seed0: u64) {
    let crit = z_crit();
    let mut failures = Vec::new();
    let mut parts = 0;
    for (k, case) in cases(mode).iter().enumerate() {
        let (z, part) = power_z(case, m, seed0 + k as u64);
        assert_eq!(z.len(), mode.lanes());
        let phi: Vec<String> = case.phi.iter().map(|p| format!("{p:.5}")).collect();
        print!(
            "{}: Φ = [{}], z = [{}]",
            case.name,
            phi.join(", "),
            z.iter()
                .map(|z| format!("{z:+.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        if z.iter().any(|&z| rejects(z, crit)) {
            failures.push(format!("{}: z = {z:?}", case.name));
        }
        // The parts are tested once, in RGB mode.
        if let (Mode::Rgb, Some(zp), Some((part, fraction))) = (mode, part, case.part) {
            parts += 1;
            print!("; {part:?}: {:.5} of Φ, z = {zp:+.2}", fraction);
            if rejects(zp, crit) {
                failures.push(format!("{}: {part:?}: z = {zp}", case.name));
            }
        }
        println!();
    }
    if mode == Mode::Rgb {
        assert_eq!(parts, AREA);
    }
    println!("|z| < {crit:.3} (α = {ALPHA} over {TESTS} tests, Šidák)");
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn mean_weight_is_the_emitted_power_rgb() {
    check_power(Mode::Rgb, &RgbMode, 100);
}

#[test]
fn mean_weight_is_the_emitted_power_spectral() {
    let m = spectral();
    // The units of a declared uniform spectrum: the point light's intensity arrives at 1 m
    // unchanged at every wavelength.
    let point = &cases(Mode::Spectral)[0];
    let li = point.scene.lights[0]
        .sample_li(
            &point.scene,
            &Receiver::at(Vec3::new(0.3, -0.2, 2.0)),
            Vec2::ZERO,
            &m,
        )
        .unwrap()
        .li;
    for i in 0..4 {
        assert!((li.lane(i) - 2.5).abs() < 1e-5, "{li:?}");
    }
    check_power(Mode::Spectral, &m, 200);
}

/// Checks of one emitted ray against where its light is. Returns the origin's distance from
/// the surface relative to the origin's magnitude (area lights).
fn check_ray(case: &Case, s: &EmissionSample) -> Result<f64, String> {
    let (o, d, n) = (dv(s.ray.o), dv(s.ray.d), dv(s.n));
    if (d.length() - 1.0).abs() > 1e-5 {
        return Err(format!("direction {d} is not a unit vector"));
    }
    let close = |a: f64, b: f64, rel: f64| (a - b).abs() <= rel * b.abs() + 1e-9;
    match &case.place {
        Place::Point(p) => {
            if (o - *p).abs().max_element() > 1e-6 || n != DVec3::ZERO || s.pdf_pos != 1.0 {
                return Err(format!("origin {o}, n {n}, pdf_pos {}", s.pdf_pos));
            }
            if !close(s.pdf_dir as f64, 0.25 / PI, 1e-6) {
                return Err(format!("pdf_dir {}", s.pdf_dir));
            }
            Ok(0.0)
        }
        Place::Spot {
            position,
            to_world,
            cos_cutoff,
        } => {
            if (o - *position).abs().max_element() > 1e-6 || n != DVec3::ZERO || s.pdf_pos != 1.0 {
                return Err(format!("origin {o}, n {n}, pdf_pos {}", s.pdf_pos));
            }
            let a = to_world.inverse();
            let local = (a * d).normalize();
            if local.z < cos_cutoff - 1e-5 {
                return Err(format!("direction {d} outside the cone (cos {})", local.z));
            }
            let pdf =
                a.determinant().abs() / (a * d).length().powi(3) / (2.0 * PI * (1.0 - cos_cutoff));
            if !close(s.pdf_dir as f64, pdf, 1e-4) {
                return Err(format!("pdf_dir {} but the cone's is {pdf}", s.pdf_dir));
            }
            Ok(0.0)
        }
        Place::Infinite { lo, hi, direction } => {
            let c = 0.5 * (*lo + *hi);
            let r = 0.5 * (*hi - *lo).length();
            let tol = 1e-5 * (c.length() + r);
            let along = (o - c).dot(d);
            let across = ((o - c) - along * d).length();
            if (along + r).abs() > tol || across > r + tol {
                return Err(format!(
                    "origin {o}: {along} along the direction, {across} across (r = {r})"
                ));
            }
            if n != DVec3::ZERO || !close(s.pdf_pos as f64, 1.0 / (PI * r * r), 1e-5) {
                return Err(format!("n {n}, pdf_pos {}", s.pdf_pos));
            }
            if let Some(dir) = direction
                && ((d - *dir).length() > 1e-6 || s.pdf_dir != 1.0)
            {
                return Err(format!("direction {d}, pdf_dir {}", s.pdf_dir));
            }
            Ok(0.0)
        }
        Place::Surface {
            kind,
            to_world,
            two_sided,
            area,
        } => {
            let q = to_world.inverse().transform_point3(o);
            let inv_t = DMat3::from_mat4(to_world.inverse()).transpose();
            let eps = 1e-5;
            // The implicit surface in object space (zero on it, positive on the emitting
            // side) and its object-space gradient; whether q is within the shape.
            let (f, grad, within) = match kind {
                Surf::Rectangle => (
                    q.z,
                    DVec3::Z,
                    q.x.abs() <= 1.0 + eps && q.y.abs() <= 1.0 + eps,
                ),
                Surf::Disk => (q.z, DVec3::Z, q.x * q.x + q.y * q.y <= 1.0 + eps),
                Surf::Sphere | Surf::Ellipsoid => (q.length() - 1.0, q.normalize(), true),
                Surf::Cube => {
                    let i = q.abs().max_position();
                    let mut g = DVec3::ZERO;
                    g[i] = q[i].signum();
                    let others = (0..3).all(|j| j == i || q[j].abs() <= 1.0 + eps);
                    (q[i].abs() - 1.0, g, others)
                }
            };
            let g = inv_t * grad;
            let dist = f / g.length();
            let n_w = g.normalize();
            let side = if *two_sided { n.dot(n_w).signum() } else { 1.0 };
            let scale = 1.0 + o.abs().max_element();
            if !within {
                return Err(format!("origin {o} (object {q}) is off the shape"));
            }
            if n.dot(n_w) * side < 1.0 - 1e-4 {
                return Err(format!("n {n} but the emitting normal is {}", n_w * side));
            }
            // On the surface, up to the error bound (a few ulps of the coordinates).
            if dist.abs() > 1e-5 * scale {
                return Err(format!("origin {o} is {dist} off the surface"));
            }
            // On the emitting side of it, where the renderer's surface is exactly this one
            // (a sphere from its centre and radius, a disk from its matrix; meshes have
            // vertices rounded to f32 in world space, the spheroid a composed matrix: for
            // them, the ray must not hit its emitter again, below).
            if matches!(kind, Surf::Sphere | Surf::Disk) && dist * side < 0.0 {
                return Err(format!("origin {o} is {dist} behind the emitting side"));
            }
            let cos = d.dot(n);
            if cos <= 0.0 {
                return Err(format!("direction {d} leaves the back (n {n})"));
            }
            let pdf_pos = match kind {
                Surf::Ellipsoid => {
                    let qn = q.normalize();
                    1.0 / (4.0 * PI * to_world.determinant().abs() * (inv_t * qn).length())
                }
                _ => 1.0 / area,
            };
            if !close(s.pdf_pos as f64, pdf_pos, 1e-3) {
                return Err(format!("pdf_pos {} but the area's is {pdf_pos}", s.pdf_pos));
            }
            let pdf_dir = cos / (PI * if *two_sided { 2.0 } else { 1.0 });
            if !close(s.pdf_dir as f64, pdf_dir, 1e-3) {
                return Err(format!("pdf_dir {} but cos/π is {pdf_dir}", s.pdf_dir));
            }
            if let Some(hit) = case.scene.intersect(&s.ray, f32::INFINITY) {
                return Err(format!(
                    "the ray from {o} along {d} hits its emitter again at {}",
                    hit.p
                ));
            }
            Ok(dist * side / scale)
        }
    }
}

/// Projected area of the box [lo, hi] seen along `d`.
fn projected_area(lo: DVec3, hi: DVec3, d: DVec3) -> f64 {
    let e = hi - lo;
    d.x.abs() * e.y * e.z + d.y.abs() * e.x * e.z + d.z.abs() * e.x * e.y
}

#[test]
fn rays_start_on_the_emitter_and_cross_the_scene() {
    let crit = z_crit();
    let mut failures = Vec::new();
    let mut infinite = 0;
    for (k, case) in cases(Mode::Rgb).iter().enumerate() {
        let mut rng = Pcg32::new(300 + k as u64, 0xe2);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut none = 0usize;
        // Infinite lights: hit − A⊥/πR² per ray (mean 0 when the rays cover the disk).
        let (mut sum, mut sum2) = (0f64, 0f64);
        let n = 1usize << 16;
        for _ in 0..n {
            let Some(s) = emit(case, &mut rng, &RgbMode) else {
                none += 1;
                continue;
            };
            match check_ray(case, &s) {
                Ok(off) => {
                    lo = lo.min(off);
                    hi = hi.max(off);
                }
                Err(e) => {
                    failures.push(format!("{}: {e}", case.name));
                    break;
                }
            }
            if let Place::Infinite { lo, hi, .. } = &case.place {
                let r = 0.5 * (*hi - *lo).length();
                let hit = case.scene.intersect(&s.ray, f32::INFINITY).is_some() as u8 as f64;
                let x = hit - projected_area(*lo, *hi, dv(s.ray.d)) / (PI * r * r);
                sum += x;
                sum2 += x * x;
            }
        }
        print!("{}: {none} of {n} samples failed", case.name);
        if let Place::Surface { .. } = case.place {
            print!("; origins off the surface by [{lo:.2e}, {hi:.2e}] × (1 + |o|∞)");
        }
        if none * 1000 > n {
            failures.push(format!("{}: {none} of {n} samples failed", case.name));
        }
        if let Place::Infinite { lo, hi, .. } = &case.place {
            infinite += 1;
            let (b_lo, b_hi) = case.scene.bounds;
            if (dv(b_lo) - *lo).abs().max_element() > 1e-5
                || (dv(b_hi) - *hi).abs().max_element() > 1e-5
            {
                failures.push(format!(
                    "{}: scene bounds {b_lo} – {b_hi}, not the box",
                    case.name
                ));
            }
            let m = sum / n as f64;
            let var = (sum2 - sum * m) / (n - 1) as f64;
            let z = m / (var / n as f64).sqrt();
            print!("; hit fraction − A⊥/πR²: {m:+.5}, z = {z:+.2}");
            if rejects(z, crit) {
                failures.push(format!("{}: hit fraction z = {z}", case.name));
            }
        }
        println!();
    }
    assert_eq!(infinite, INFINITE);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The direction (or, with `pos`, the quantity `map` reads) of `case`'s photons under χ²
/// against `pdf`; `u_dir` (or `u_pos` with `pos`) is the χ² test's own variate, the other
/// drawn from a generator of its own.
fn chi2_emission(
    case: &Case,
    seed: u64,
    pos: bool,
    map: impl Fn(&EmissionSample) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
) -> Chi2Result {
    let cfg = Chi2Config {
        res: 16,
        sample_count: 1 << 18,
        min_exp_frequency: 5.0,
        significance: level(),
        seed,
    };
    let mut rng = Pcg32::new(seed, 0xe3);
    let light = &case.scene.lights[case.lights[0]];
    chi2_test(
        |u2, _| {
            let other = rng.next_vec2();
            let (u_pos, u_dir) = if pos { (u2, other) } else { (other, u2) };
            light
                .sample_le(&case.scene, u_pos, u_dir, &RgbMode)
                .and_then(|s| map(&s))
        },
        pdf,
        &cfg,
    )
}

/// Where an infinite light's ray starts, in units of R across its direction: χ² against the
/// uniform density 1/π on the unit disk.
fn chi2_disk(case: &Case, seed: u64) -> Chi2Result {
    let Place::Infinite { lo, hi, .. } = case.place else {
        panic!()
    };
    let (c, r) = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
    let cfg = Chi2Config {
        res: 16,
        sample_count: 1 << 18,
        min_exp_frequency: 5.0,
        significance: level(),
        seed,
    };
    let mut rng = Pcg32::new(seed, 0xe4);
    let light = &case.scene.lights[case.lights[0]];
    chi2_test_2d(
        |u2, _| {
            let s = light.sample_le(&case.scene, u2, rng.next_vec2(), &RgbMode)?;
            let f = Frame::from_normal(s.ray.d);
            let p = (dv(s.ray.o) - c) / r;
            let (x, y) = (p.dot(dv(f.s)), p.dot(dv(f.t)));
            Some(Vec2::new(x as f32, y as f32))
        },
        |p| {
            if p.length_squared() <= 1.0 {
                std::f32::consts::FRAC_1_PI
            } else {
                0.0
            }
        },
        Vec2::splat(-1.0),
        Vec2::splat(1.0),
        &cfg,
    )
}

#[test]
fn directions_and_positions_follow_their_densities() {
    let cases = cases(Mode::Rgb);
    let case = |name: &str| cases.iter().find(|c| c.name == name).unwrap();
    let dir = |s: &EmissionSample| Some(s.ray.d);
    let uniform = |_: Vec3| 0.25 * std::f32::consts::FRAC_1_PI;
    let frame_of = |c: &Case| match &c.place {
        Place::Surface { to_world, .. } => *to_world,
        _ => panic!(),
    };
    // The emitting normal of a plane-like shape (+z in object space).
    let normal_of = |c: &Case| {
        let m = frame_of(c);
        (DMat3::from_mat4(m.inverse()).transpose() * DVec3::Z).normalize()
    };
    let cone = |c: &Case, v: Vec3| -> f32 {
        let Place::Spot {
            to_world,
            cos_cutoff,
            ..
        } = &c.place
        else {
            panic!()
        };
        let a = to_world.inverse();
        let w = dv(v).normalize();
        if (a * w).normalize().z <= *cos_cutoff {
            return 0.0;
        }
        (a.determinant().abs() / (a * w).length().powi(3) / (2.0 * PI * (1.0 - cos_cutoff))) as f32
    };
    let env = case("envmap");
    let env_light = &env.scene.lights[env.lights[0]];
    let rect2 = case("rectangle (mesh, two-sided)");
    let n_rect2 = normal_of(rect2);
    let disk = case("disk");
    let n_disk = normal_of(disk);
    let cube = case("cube (mesh, one-sided)");
    let m_cube = frame_of(cube);
    // The cube's faces: area and outward normal.
    let faces: Vec<(f64, DVec3)> = [DVec3::X, DVec3::Y, DVec3::Z]
        .into_iter()
        .flat_map(|e| [e, -e])
        .map(|e| {
            let lin = DMat3::from_mat4(m_cube);
            let n = DMat3::from_mat4(m_cube.inverse()).transpose() * e;
            // Area of the face: |det| · |M⁻ᵀ e| times the object face's area 4.
            (4.0 * lin.determinant().abs() * n.length(), n.normalize())
        })
        .collect();
    let cube_area: f64 = faces.iter().map(|f| f.0).sum();
    let ell = case("ellipsoid");
    let m_ell = frame_of(ell);
    let ell_obj = |s: &EmissionSample| {
        let q = m_ell.inverse().transform_point3(dv(s.ray.o)).normalize();
        Some(Vec3::new(q.x as f32, q.y as f32, q.z as f32))
    };
    // The ellipsoid's direction in the frame of its analytic normal at the origin.
    let ell_local = |s: &EmissionSample| {
        let q = m_ell.inverse().transform_point3(dv(s.ray.o)).normalize();
        let n = (DMat3::from_mat4(m_ell.inverse()).transpose() * q).normalize();
        let f = Frame::from_normal(Vec3::new(n.x as f32, n.y as f32, n.z as f32));
        Some(f.to_local(s.ray.d).normalize())
    };
    let cosine = |n: DVec3, sides: f64| {
        move |v: Vec3| {
            let c = dv(v).dot(n);
            let c = if sides > 1.0 { c.abs() } else { c.max(0.0) };
            (c / (sides * PI)) as f32
        }
    };

    let mut results: Vec<(&str, Chi2Result)> = vec![
        (
            "point",
            chi2_emission(case("point"), 1, false, dir, uniform),
        ),
        (
            "spot",
            chi2_emission(case("spot"), 2, false, dir, |v| cone(case("spot"), v)),
        ),
        (
            "spot, scaled frame",
            chi2_emission(case("spot, scaled frame"), 3, false, dir, |v| {
                cone(case("spot, scaled frame"), v)
            }),
        ),
        (
            "constant",
            chi2_emission(case("constant"), 4, false, dir, uniform),
        ),
        (
            "envmap (the travel direction against pdf_li of its reverse)",
            chi2_emission(env, 5, false, dir, |v| {
                env_light.pdf_li(&env.scene, &Receiver::at(Vec3::ZERO), -v, None)
            }),
        ),
        (
            "cube (the faces' cosine lobes by area)",
            chi2_emission(cube, 6, false, dir, |v| {
                let w = dv(v);
                let p: f64 = faces
                    .iter()
                    .map(|(a, n)| a / cube_area * w.dot(*n).max(0.0) / PI)
                    .sum();
                p as f32
            }),
        ),
        (
            "rectangle, two-sided (|cos|/2π)",
            chi2_emission(rect2, 7, false, dir, cosine(n_rect2, 2.0)),
        ),
        (
            "disk (cos/π)",
            chi2_emission(disk, 8, false, dir, cosine(n_disk, 1.0)),
        ),
        (
            "sphere (uniform over its points' cosine lobes)",
            chi2_emission(case("sphere"), 9, false, dir, uniform),
        ),
        (
            "ellipsoid (object-sphere point, uniform)",
            chi2_emission(ell, 10, true, ell_obj, uniform),
        ),
        (
            "ellipsoid (direction about the analytic normal, cos/π)",
            chi2_emission(ell, 11, false, ell_local, cosine(DVec3::Z, 1.0)),
        ),
        (
            "directional (disk position)",
            chi2_disk(case("directional"), 12),
        ),
        ("constant (disk position)", chi2_disk(case("constant"), 13)),
    ];
    assert_eq!(results.len(), CHI2);
    let mut failures = Vec::new();
    for (name, r) in results.drain(..) {
        println!("{name}: {}", r.message);
        if !r.passed {
            failures.push(format!("{name}: {}", r.message));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// `pdf_dir` of the environment map is the density `sample_li` samples the reversed
/// direction with, and its weight the radiance seen back along the ray over the densities.
/// To 1 %: `pdf_li` and `environment` find the map's uv again from the direction, which near
/// the poles (acos of a y near 1, in f32) moves sin θ by a few 0.1 %.
#[test]
fn envmap_pdf_dir_is_its_pdf_li() {
    let cases = cases(Mode::Rgb);
    let env = cases.iter().find(|c| c.name == "envmap").unwrap();
    let light = &env.scene.lights[env.lights[0]];
    let mut rng = Pcg32::new(17, 0xe5);
    for _ in 0..10_000 {
        let Some(s) = emit(env, &mut rng, &RgbMode) else {
            continue;
        };
        let pdf = light.pdf_li(&env.scene, &Receiver::at(Vec3::ZERO), -s.ray.d, None);
        assert!(
            (s.pdf_dir - pdf).abs() <= 1e-2 * pdf,
            "pdf_dir {} vs pdf_li {pdf} along {}",
            s.pdf_dir,
            s.ray.d
        );
        let le = light.environment(-s.ray.d, &RgbMode);
        let want = le / (s.pdf_pos * s.pdf_dir);
        assert!(
            (s.weight - want).abs().max_element() <= 1e-2 * want.max_element(),
            "weight {} vs {want}",
            s.weight
        );
    }
}

/// Whether `got` is `want` to a relative `tol`.
fn rel_close(got: f32, want: f32, tol: f32) -> bool {
    (got - want).abs() <= tol * want.abs()
}

/// `pdf_le` gives back, for 2000 rays of every case's `sample_le`, that sample's `pdf_pos` and
/// `pdf_dir` (to 10⁻³) from its unoffset origin `p`, normal `n` and direction; `p` is the ray's
/// origin for the lights without a surface and within the offset of it for area lights.
#[test]
fn pdf_le_gives_the_densities_of_sample_le() {
    let mut failures = Vec::new();
    for (k, case) in cases(Mode::Rgb).iter().enumerate() {
        let mut rng = Pcg32::new(400 + k as u64, 0xe6);
        let (mut checked, mut worst) = (0, (0f32, 0f32));
        for _ in 0..2000 {
            let i = (rng.next_f32() * case.lights.len() as f32) as usize;
            let light = &case.scene.lights[case.lights[i.min(case.lights.len() - 1)]];
            let (u_pos, u_dir) = (rng.next_vec2(), rng.next_vec2());
            let Some(s) = light.sample_le(&case.scene, u_pos, u_dir, &RgbMode) else {
                continue;
            };
            checked += 1;
            let off = (s.p - s.ray.o).length();
            let bound = match case.place {
                Place::Surface { .. } => 1e-4 * (1.0 + s.p.abs().max_element()),
                _ => 0.0,
            };
            if off > bound {
                failures.push(format!("{}: p {} is {off} from ray.o", case.name, s.p));
                break;
            }
            let (pdf_pos, pdf_dir) = light.pdf_le(&case.scene, s.p, s.n, s.ray.d);
            let (e_pos, e_dir) = (
                (pdf_pos - s.pdf_pos).abs() / s.pdf_pos,
                (pdf_dir - s.pdf_dir).abs() / s.pdf_dir,
            );
            worst = (worst.0.max(e_pos), worst.1.max(e_dir));
            if !rel_close(pdf_pos, s.pdf_pos, 1e-3) || !rel_close(pdf_dir, s.pdf_dir, 1e-3) {
                failures.push(format!(
                    "{}: pdf_le ({pdf_pos}, {pdf_dir}) but sample_le drew ({}, {}) from {} along {}",
                    case.name, s.pdf_pos, s.pdf_dir, s.p, s.ray.d
                ));
                break;
            }
        }
        println!(
            "{}: {checked} rays, largest relative differences {:.1e} (pos), {:.1e} (dir)",
            case.name, worst.0, worst.1
        );
        if checked < 1900 {
            failures.push(format!("{}: only {checked} of 2000 rays", case.name));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// ∫ f(ω) dω over the sphere by the midpoint rule on an equal-area grid of `nz` × `nphi`
/// cells in (cos θ, φ).
fn sphere_integral(nz: usize, nphi: usize, f: impl Fn(Vec3) -> f32) -> f64 {
    let mut sum = 0f64;
    for i in 0..nz {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / nz as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let mut ring = 0f64;
        for j in 0..nphi {
            let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
            let d = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            ring += f(d) as f64;
        }
        sum += ring;
    }
    sum * 4.0 * PI / (nz * nphi) as f64
}

/// `pdf_le`'s direction density is normalised: its integral over the sphere (midpoint rule,
/// 1024 × 2048 cells in (cos θ, φ)) is 1 to 10⁻², for the spots (rigid and scaled frame, where
/// the Jacobian matters), the environment map, the constant and point lights, and the area
/// lights at an emitted ray's origin: two-sided rectangle, one-sided disk, a cube face,
/// the ellipsoid.
#[test]
fn pdf_le_direction_density_integrates_to_one() {
    let cases = cases(Mode::Rgb);
    let mut failures = Vec::new();
    for name in [
        "point",
        "spot",
        "spot, scaled frame",
        "spot, CENG795 falloff",
        "constant",
        "envmap",
        "cube (mesh, one-sided)",
        "rectangle (mesh, two-sided)",
        "disk",
        "ellipsoid",
    ] {
        let case = cases.iter().find(|c| c.name == name).unwrap();
        let light = &case.scene.lights[case.lights[0]];
        // An origin and normal of the light's own (area lights read them).
        let s = light
            .sample_le(
                &case.scene,
                Vec2::new(0.3, 0.6),
                Vec2::new(0.2, 0.7),
                &RgbMode,
            )
            .unwrap();
        let integral = sphere_integral(1024, 2048, |d| light.pdf_le(&case.scene, s.p, s.n, d).1);
        println!("{name}: ∫ pdf_dir dω = {integral:.5}");
        if (integral - 1.0).abs() > 1e-2 {
            failures.push(format!("{name}: ∫ pdf_dir dω = {integral}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// `pdf_le` is (0, 0) for rays `sample_le` never draws: outside a spot's cutoff cone (of its
/// own frame, rigid or scaled; just inside it is positive), behind a one-sided emitter (cube,
/// disk, ellipsoid, sphere: the reflected direction and one grazing 0.5° behind; on both sides
/// of a two-sided one it is |cos|/2π), and for a directional light off its direction (along
/// it: (1/πR², 1)).
#[test]
fn pdf_le_is_zero_where_sample_le_never_emits() {
    let cases = cases(Mode::Rgb);
    let case = |name: &str| cases.iter().find(|c| c.name == name).unwrap();
    let fv = |v: DVec3| Vec3::new(v.x as f32, v.y as f32, v.z as f32);
    let mut failures: Vec<String> = Vec::new();
    // A failure unless `got` is (0, 0), or `want` to 10⁻⁴.
    let expect = |what: String, got: (f32, f32), want: Option<(f32, f32)>| {
        let ok = match want {
            None => got == (0.0, 0.0),
            Some(w) => rel_close(got.0, w.0, 1e-4) && rel_close(got.1, w.1, 1e-4),
        };
        (!ok).then(|| format!("{what}: {got:?}, expected {want:?}"))
    };

    // Spots: local directions at 39.5° (inside the 40° cutoff) and 40.5°, 90°, 180° (outside)
    // carried to the world by the frame.
    for name in ["spot", "spot, scaled frame", "spot, CENG795 falloff"] {
        let c = case(name);
        let Place::Spot { to_world, .. } = &c.place else {
            panic!()
        };
        let light = &c.scene.lights[0];
        for phi in [0.0f64, 1.0, 2.5, 4.0] {
            for deg in [39.5f64, 40.5, 90.0, 180.0] {
                let t = deg.to_radians();
                let local = DVec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos());
                let d = fv((*to_world * local).normalize());
                let got = light.pdf_le(&c.scene, Vec3::ZERO, Vec3::ZERO, d);
                if deg < 40.0 {
                    if !(got.0 == 1.0 && got.1 > 0.0) {
                        failures.push(format!("{name}: {deg}° inside the cone: {got:?}"));
                    }
                } else {
                    failures.extend(expect(format!("{name}: {deg}°, φ = {phi}"), got, None));
                }
            }
        }
    }

    // Area lights at a ray's origin: the reflected direction (behind the emitting side) and
    // a grazing one 0.5° behind it (both sides of a two-sided light emit: |cos|/2π).
    for name in [
        "cube (mesh, one-sided)",
        "disk",
        "ellipsoid",
        "sphere",
        "rectangle (mesh, two-sided)",
    ] {
        let c = case(name);
        let light = &c.scene.lights[0];
        let mut rng = Pcg32::new(31, 0xe7);
        for _ in 0..100 {
            let Some(s) = light.sample_le(&c.scene, rng.next_vec2(), rng.next_vec2(), &RgbMode)
            else {
                continue;
            };
            let back = s.ray.d - 2.0 * s.n.dot(s.ray.d) * s.n;
            let (sin, cos) = 0.5f32.to_radians().sin_cos();
            let grazing = (Frame::from_normal(s.n).s * cos - s.n * sin).normalize();
            let two_sided = name.contains("two-sided");
            for d in [back, grazing] {
                let got = light.pdf_le(&c.scene, s.p, s.n, d);
                let want = two_sided.then(|| (s.pdf_pos, s.n.dot(d).abs() / (2.0 * PI as f32)));
                failures.extend(expect(format!("{name}: behind along {d}"), got, want));
            }
        }
    }

    // Directional: its direction, then others.
    {
        let c = case("directional");
        let Place::Infinite {
            direction: Some(dir),
            ..
        } = c.place
        else {
            panic!()
        };
        let light = &c.scene.lights[0];
        let r = box_radius();
        failures.extend(expect(
            "directional along its direction".into(),
            light.pdf_le(&c.scene, Vec3::ZERO, Vec3::ZERO, fv(dir)),
            Some(((1.0 / (PI * r * r)) as f32, 1.0)),
        ));
        let f = Frame::from_normal(fv(dir));
        for off in [0.01f32, 0.1, 1.0, 3.0] {
            let d = (fv(dir) * off.cos() + f.s * off.sin()).normalize();
            failures.extend(expect(
                format!("directional {off} rad off its direction"),
                light.pdf_le(&c.scene, Vec3::ZERO, Vec3::ZERO, d),
                None,
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
