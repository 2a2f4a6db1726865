//! Dispersion through the whole renderer in spectral mode (issue 21, acceptance 3): a
//! collimated beam through a BK7 prism lands where Snell's law with the Sellmeier index puts
//! it, per wavelength band, within one pixel (`scenes/dispersion/bk7-prism.xml`).
//!
//! Isolating a band: the path tracer runs in a colour mode of this test, [`Band`], which is
//! spectral mode with the four wavelengths drawn uniformly (stratified) in the band instead of
//! over the visible range, and which hands the film the band's energy ∫ L dλ rather than a
//! colour. The renderer is otherwise untouched (the same `path::li_in`, camera samples and
//! scene), and the measurement is direct: every camera sample's film position, weighted by
//! its energy. The alternative — centroids of the output colour channels against the
//! channels' analytic centroids — would read each position through a colour-matching
//! function with a negative lobe (sRGB's red between 440 and 540 nm), whose centroid is a
//! ratio of small signed integrals, and through the XYZ → sRGB matrix; it tests the same
//! optics with worse conditioning and no separation by wavelength.

use std::path::Path;

use build::{BuildOptions, build};
use glam::{DVec3, UVec2};
use rayon::prelude::*;
use render::integrators::{Integrator, path};
use render::math::Vec3;
use render::sampling::{Sampler, Samples};
use render::spectral::lanes::{ColorMode, PathMode, SpectralMode};
use render::spectral::{
    RgbIlluminantSpectrum, RgbToSpectrumTable, SampledSpectrum, SampledWavelengths, Spectrum,
};
use render::textures::{ColorRef, Params, TexCoord};
use render::world::Scene;
use scene::{Dispersion, Document, LoadOptions, RenderMode};

/// Spectral mode with the path's wavelengths uniform in [LO, HI] nm; its estimate, as every
/// channel of the "colour", is the band's energy ∫ L(λ) dλ.
#[derive(Clone)]
struct Band<const LO: u32, const HI: u32>(SpectralMode<'static>);

impl<const LO: u32, const HI: u32> ColorMode for Band<LO, HI> {
    type C = SampledSpectrum;
    fn albedo(&self, rgb: Vec3) -> SampledSpectrum {
        self.0.albedo(rgb)
    }
    fn unbounded(&self, rgb: Vec3) -> SampledSpectrum {
        self.0.unbounded(rgb)
    }
    fn illuminant(&self, rgb: Vec3) -> SampledSpectrum {
        self.0.illuminant(rgb)
    }
    fn spectrum(&self, f: impl Fn(f32) -> f32, rgb: Vec3) -> SampledSpectrum {
        self.0.spectrum(f, rgb)
    }
    fn albedo_at<P: Params + ?Sized>(&self, p: &P, r: &ColorRef, at: TexCoord) -> SampledSpectrum {
        self.0.albedo_at(p, r, at)
    }
    fn illuminant_at<P: Params + ?Sized>(
        &self,
        p: &P,
        r: &ColorRef,
        at: TexCoord,
    ) -> SampledSpectrum {
        self.0.illuminant_at(p, r, at)
    }
    fn smooth_eta(&self, dispersive: Option<&dyn Fn(f32) -> f32>, rgb_value: f32) -> f32 {
        self.0.smooth_eta(dispersive, rgb_value)
    }
    fn lane_ior(&self, dispersive: Option<&dyn Fn(f32) -> f32>, rgb_value: f32) -> SampledSpectrum {
        self.0.lane_ior(dispersive, rgb_value)
    }
}

impl<const LO: u32, const HI: u32> PathMode for Band<LO, HI> {
    const SPECTRAL: bool = true;

    fn start(sampler: &mut impl Samples) -> Self {
        Self::from_u(sampler.next_1d())
    }
    fn from_u(u: f32) -> Self {
        let wl = SampledWavelengths::sample_uniform(u, LO as f32, HI as f32);
        Band(SpectralMode::new(wl, RgbToSpectrumTable::srgb()))
    }
    fn terminated(&self) -> bool {
        self.0.terminated()
    }
    fn terminate(&self) -> Self {
        Band(self.0.terminate())
    }
    fn to_rgb(&self, c: SampledSpectrum) -> Vec3 {
        // Mean over the lanes of value/pdf (terminated lanes have pdf 0 and count 0).
        Vec3::splat(c.safe_div(self.0.wavelengths().pdf()).average())
    }
    fn live_max(&self, c: SampledSpectrum) -> f32 {
        self.0.live_max(c)
    }
    fn hero(&self, u: f32) -> usize {
        self.0.hero(u)
    }
    fn hero_weight(&self, ratio: SampledSpectrum) -> f32 {
        self.0.hero_weight(ratio)
    }
}

// The scene's geometry (bk7-prism.xml and prism.obj).
const D_IN: [f64; 3] = [0.943_227_819_822_601_1, 0.332_146_473_581_615_4, 0.0];
const SQRT3_2: f64 = 0.866_025_403_784_438_6;
/// Outward normals of the entry (left) and exit (right) faces.
const N_ENTRY: [f64; 3] = [-SQRT3_2, 0.5, 0.0];
const N_EXIT: [f64; 3] = [SQRT3_2, 0.5, 0.0];
/// The light's angular radius (radius 60 at distance 10⁵).
const LIGHT_ANGULAR_RADIUS: f64 = 60.0 / 1e5;

/// Refraction of direction `d` through a surface whose normal on `d`'s side is `n`, from
/// index ratio `eta` = n_incident / n_transmitted, and the Fresnel transmittance (unpolarised).
fn refract(d: DVec3, n: DVec3, eta: f64) -> (DVec3, f64) {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    assert!(k > 0.0, "total internal reflection in the prism");
    let cos_t = k.sqrt();
    let t = eta * d + (eta * cos_i - cos_t) * n;
    // n_i cos_i vs n_t cos_t with n_t/n_i = 1/eta.
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (eta * cos_t - cos_i) / (eta * cos_t + cos_i);
    (t, 1.0 - 0.5 * (rs * rs + rp * rp))
}

/// The beam's direction after the prism at `lambda` (nm), and its transmittance through
/// both faces.
fn exit_beam(bk7: &Dispersion, lambda: f64) -> (DVec3, f64) {
    let n = bk7.ior(lambda);
    let (inside, t1) = refract(DVec3::from(D_IN), DVec3::from(N_ENTRY), 1.0 / n);
    let (out, t2) = refract(inside, -DVec3::from(N_EXIT), n);
    (out, t1 * t2)
}

/// Where the beam of `lambda` lands on the film (pixels, x): the pinhole's projection of
/// the direction back along the beam.
fn landing_x(scene: &Scene, bk7: &Dispersion, lambda: f64) -> f64 {
    let (d, _) = exit_beam(bk7, lambda);
    let d = -d;
    let uv = scene.camera.film_uv(
        scene.camera.position(),
        Vec3::new(d.x as f32, d.y as f32, d.z as f32),
    );
    uv.x as f64 * scene.film.width as f64
}

/// The analytic landing position of a band: the centroid of the landing positions weighted
/// by what reaches the film at each wavelength (the light's spectrum times the two faces'
/// transmittance), by the midpoint rule at 0.05 nm.
fn analytic_centroid(scene: &Scene, bk7: &Dispersion, lo: f64, hi: f64) -> f64 {
    let light = RgbIlluminantSpectrum::new(RgbToSpectrumTable::srgb(), Vec3::splat(100.0));
    let steps = ((hi - lo) / 0.05) as usize;
    let (mut sx, mut sw) = (0.0, 0.0);
    for k in 0..steps {
        let l = lo + (k as f64 + 0.5) * (hi - lo) / steps as f64;
        let w = light.eval(l as f32) as f64 * exit_beam(bk7, l).1;
        sx += w * landing_x(scene, bk7, l);
        sw += w;
    }
    sx / sw
}

struct Measured {
    centroid: f64,
    /// Standard error of the centroid (delta method over the samples).
    stderr: f64,
    hits: u64,
    /// Energy landing farther than the light's image radius + 1 pixel outside the band's
    /// analytic extent, as a fraction of the band's.
    stray: f64,
}

/// Renders the band [LO, HI] over the rows the light's image can reach and the columns the
/// band can (widened by 20 pixels each side) with `spp` samples per pixel.
fn measure<const LO: u32, const HI: u32>(
    scene: &Scene,
    integrator: &Integrator,
    bk7: &Dispersion,
    spp: u32,
) -> Measured {
    let Integrator::Path(cfg) = integrator else {
        panic!("the prism scene is path traced");
    };
    let (a, b) = (
        landing_x(scene, bk7, LO as f64),
        landing_x(scene, bk7, HI as f64),
    );
    let (x_lo, x_hi) = (a.min(b), a.max(b));
    let pixel_angle = 2.8f64.to_radians() / scene.film.width as f64;
    let reach = LIGHT_ANGULAR_RADIUS / pixel_angle + 1.0;
    let c0 = (x_lo - 20.0).floor().max(0.0) as u32;
    let c1 = ((x_hi + 20.0).ceil() as u32).min(scene.film.width);
    let mid = scene.film.height / 2;
    let r0 = mid.saturating_sub(reach.ceil() as u32 + 2);
    let r1 = (mid + reach.ceil() as u32 + 2).min(scene.film.height);
    let template = Sampler::new(scene.sampler.kind, spp, 11);
    // (energy, film x) of every sample that brought light; the image is a pure function of
    // (pixel, sample index), whichever thread renders it.
    let rows: Vec<(u64, Vec<(f64, f64)>)> = (r0..r1)
        .into_par_iter()
        .map(|y| {
            let mut sampler = template.clone();
            let mut hits = Vec::new();
            let mut n = 0u64;
            for x in c0..c1 {
                for i in 0..spp {
                    let (p_film, cray) =
                        render::render::camera_sample(scene, &mut sampler, UVec2::new(x, y), i);
                    let l = path::li_in::<Band<LO, HI>>(scene, &cray, &mut sampler, cfg).x;
                    n += 1;
                    if l > 0.0 {
                        hits.push((l as f64, p_film.x as f64));
                    }
                }
            }
            (n, hits)
        })
        .collect();
    let n: u64 = rows.iter().map(|r| r.0).sum();
    let hits: Vec<(f64, f64)> = rows.into_iter().flat_map(|r| r.1).collect();
    let e: f64 = hits.iter().map(|h| h.0).sum();
    let centroid = hits.iter().map(|h| h.0 * h.1).sum::<f64>() / e;
    // The centroid is a ratio of means, c = mean(l·x)/mean(l): by the delta method its
    // variance is Var(l·(x − c)) / (n·mean(l)²), over all n samples (misses count 0).
    let mean_l = e / n as f64;
    let var = hits
        .iter()
        .map(|h| (h.0 * (h.1 - centroid)).powi(2))
        .sum::<f64>()
        / n as f64;
    let stray: f64 = hits
        .iter()
        .filter(|h| h.1 < x_lo - reach || h.1 > x_hi + reach)
        .map(|h| h.0)
        .sum();
    Measured {
        centroid,
        stderr: (var / n as f64).sqrt() / mean_l,
        hits: hits.len() as u64,
        stray: stray / e + 0.0,
    }
}

fn prism_scene() -> (Scene, Integrator) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/dispersion/bk7-prism.xml");
    let Document::Scene(desc) = scene::load(&path, &LoadOptions::default()).unwrap() else {
        panic!("not a scene");
    };
    let built = build(
        &desc,
        &BuildOptions {
            mode: RenderMode::Spectral,
            ..Default::default()
        },
    )
    .unwrap();
    (built.scene, built.integrator)
}

/// Six 50 nm bands over 400–700 nm: each lands within one pixel of Snell's law's place.
#[test]
fn bk7_prism_bands_land_where_snell_puts_them() {
    let (scene, integrator) = prism_scene();
    let bk7 = Dispersion::named("glass-BK7").unwrap();
    let spp = 512;
    let mut results = Vec::new();
    macro_rules! band {
        ($lo:literal, $hi:literal) => {
            results.push((
                $lo,
                $hi,
                measure::<$lo, $hi>(&scene, &integrator, &bk7, spp),
                analytic_centroid(&scene, &bk7, $lo as f64, $hi as f64),
            ))
        };
    }
    band!(400, 450);
    band!(450, 500);
    band!(500, 550);
    band!(550, 600);
    band!(600, 650);
    band!(650, 700);
    let mut failures = Vec::new();
    let mut prev: Option<f64> = None;
    for (lo, hi, m, expect) in &results {
        let off = m.centroid - expect;
        println!(
            "{lo}-{hi} nm: landed at x = {:.3} ± {:.3} px ({} hits), Snell: {expect:.3} px, \
             off by {off:+.3} px (z = {:+.2}); stray energy {:.1e}",
            m.centroid,
            m.stderr,
            m.hits,
            off / m.stderr,
            m.stray
        );
        if off.abs() >= 1.0 || m.hits < 1000 || m.stray > 1e-3 {
            failures.push(format!("{lo}-{hi} nm: off by {off:.3} px"));
        }
        // The bands are resolved from each other: consecutive bands land more than 10
        // pixels apart (the d-line index everywhere, as RGB uses, would put them together).
        if let Some(p) = prev {
            assert!(
                (m.centroid - p).abs() > 10.0,
                "{lo}-{hi} nm is not resolved"
            );
        }
        prev = Some(m.centroid);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
