//! `penumbra info`: what was loaded.

use std::collections::BTreeMap;
use std::path::Path;

use scene::{
    DirectionSampling, Document, FilterDesc, FovAxis, IntegratorDesc, MisHeuristic, NoriIntegrator,
    PathDesc, Projection, RussianRoulette, SamplerKind, SceneDesc, Shape, TestKind,
};

use crate::Failure;

fn count<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let mut m: BTreeMap<&str, usize> = BTreeMap::new();
    for n in names {
        *m.entry(n).or_default() += 1;
    }
    if m.is_empty() {
        return "none".into();
    }
    m.iter()
        .map(|(k, v)| format!("{v} {k}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn axis_name(a: FovAxis) -> &'static str {
    match a {
        FovAxis::X => "horizontal",
        FovAxis::Y => "vertical",
        FovAxis::Diagonal => "diagonal",
        FovAxis::Smaller => "smaller side",
        FovAxis::Larger => "larger side",
    }
}

fn sampler(k: SamplerKind) -> &'static str {
    match k {
        SamplerKind::Independent => "independent",
        SamplerKind::Stratified => "stratified",
        SamplerKind::Halton => "halton",
        SamplerKind::Sobol => "sobol",
        SamplerKind::MultiJitter { .. } => "multijitter",
    }
}

fn filter(f: &FilterDesc) -> String {
    match *f {
        FilterDesc::Box { radius } => format!("box (radius {radius})"),
        FilterDesc::Tent { radius } => format!("tent (radius {radius})"),
        FilterDesc::Gaussian { stddev, radius } => {
            format!("gaussian (stddev {stddev}, radius {radius})")
        }
        FilterDesc::Mitchell { b, c, radius } => {
            format!("mitchell (B {b}, C {c}, radius {radius})")
        }
        FilterDesc::Lanczos { radius, tau } => format!("lanczos (radius {radius}, tau {tau})"),
    }
}

fn depth(d: i64) -> String {
    if d < 0 {
        "unbounded".into()
    } else {
        d.to_string()
    }
}

fn path(p: &PathDesc) -> String {
    let mut parts = vec![format!("max depth {}", depth(p.max_depth.into()))];
    parts.push(match p.rr {
        RussianRoulette::Off => "no Russian roulette".into(),
        RussianRoulette::Throughput { from_depth } => {
            format!("Russian roulette by throughput from depth {from_depth}")
        }
        RussianRoulette::Fixed { after, q } => {
            format!("Russian roulette with q = {q} after {after} segments")
        }
    });
    if p.nee {
        let mis = match p.mis {
            MisHeuristic::Balance => "balance",
            MisHeuristic::Power => "power",
        };
        let lights = if p.all_lights {
            "every emitter"
        } else {
            "one emitter"
        };
        parts.push(format!(
            "next-event estimation ({} sample(s) of {lights}, {mis} heuristic)",
            p.light_samples
        ));
    } else {
        parts.push("no next-event estimation".into());
    }
    if p.directions == DirectionSampling::UniformHemisphere {
        parts.push("uniform hemisphere directions".into());
    }
    if p.splitting > 1 {
        parts.push(format!("splitting {}× at the first vertex", p.splitting));
    }
    if p.hide_emitters {
        parts.push("emitters hidden from the camera".into());
    }
    format!("path tracer: {}", parts.join(", "))
}

fn integrator(i: &IntegratorDesc) -> String {
    match i {
        IntegratorDesc::Normals => "normals (AOV)".into(),
        IntegratorDesc::Albedo => "albedo (AOV)".into(),
        IntegratorDesc::Depth => "depth (AOV)".into(),
        IntegratorDesc::AmbientOcclusion { samples, length } => format!(
            "ambient occlusion, {samples} ray(s){}",
            length
                .map(|l| format!(" of length {l}"))
                .unwrap_or_default()
        ),
        IntegratorDesc::Direct {
            emitter_samples,
            bsdf_samples,
        } => {
            format!("direct illumination ({emitter_samples} emitter, {bsdf_samples} BSDF samples)")
        }
        IntegratorDesc::Path(p) => path(p),
        IntegratorDesc::VolPath {
            max_depth,
            rr_depth,
            hide_emitters,
            ..
        } => format!(
            "volumetric path tracer: max depth {}, Russian roulette after {rr_depth}{}",
            depth(*max_depth as i64),
            if *hide_emitters {
                ", emitters hidden from the camera"
            } else {
                ""
            }
        ),
        IntegratorDesc::Mlt {
            max_depth,
            bootstrap,
            chains,
            large_step,
            sigma,
            direct_samples,
            multiplexed,
        } => format!(
            "Metropolis light transport (mlt, {}): max depth {max_depth}, {bootstrap} bootstrap \
             samples{}, {chains} chains, large steps {large_step}, sigma {sigma}, {}",
            if *multiplexed {
                "multiplexed over BDPT's strategies"
            } else {
                "Kelemen's, whole BDPT samples"
            },
            if *multiplexed { " per depth" } else { "" },
            match direct_samples {
                d if *d < 0 => "direct illumination by the chains too".to_string(),
                0 => "direct illumination left out".to_string(),
                d => format!("direct illumination apart at {d} samples per pixel"),
            }
        ),
        IntegratorDesc::Bdpt {
            max_depth,
            visualize_strategies,
            visualize_weights,
        } => format!(
            "bidirectional path tracing (bdpt): max depth {}{}",
            depth(*max_depth as i64),
            match (visualize_strategies, visualize_weights) {
                (_, true) => ", with MIS-weighted per-strategy images",
                (true, false) => ", with unweighted per-strategy images",
                (false, false) => "",
            }
        ),
        IntegratorDesc::Ptracer {
            max_depth,
            hide_emitters,
        } => format!(
            "light tracing (ptracer): max depth {}{}",
            depth(*max_depth as i64),
            if *hide_emitters {
                ", emitters hidden from the camera"
            } else {
                ""
            }
        ),
        IntegratorDesc::Sppm(d) => format!(
            "{}: max depth {}, {} photons per iteration, initial radius {}, alpha {}",
            match d.fixed_eye_samples {
                None => "stochastic progressive photon mapping".to_string(),
                Some(n) => format!("progressive photon mapping, {n} visible points per pixel"),
            },
            depth(d.max_depth as i64),
            d.photons
                .map_or("one per pixel".to_string(), |n| n.to_string()),
            d.initial_radius
                .map_or("guessed".to_string(), |r| r.to_string()),
            d.alpha
        ),
        IntegratorDesc::Photon(d) => {
            let lookup = |l: &scene::PhotonLookupDesc| {
                let r = |r: f32| {
                    if l.relative {
                        format!("{r} of the scene radius")
                    } else {
                        r.to_string()
                    }
                };
                match (l.k, l.radius) {
                    (Some(k), Some(c)) => format!("{k} nearest within {}", r(c)),
                    (Some(k), None) => format!("{k} nearest"),
                    (None, Some(c)) => format!("radius {}", r(c)),
                    (None, None) => "default".to_string(),
                }
            };
            format!(
                "photon mapping: {} photons, global map {}, caustic map {}, {:?} kernel, {}",
                d.photons,
                lookup(&d.global),
                lookup(&d.caustic),
                d.kernel,
                if d.final_gather > 0 {
                    format!("{} final gathering rays", d.final_gather)
                } else {
                    "no final gathering".to_string()
                }
            )
        }
        IntegratorDesc::Whitted { max_depth } => format!("Whitted, max depth {max_depth}"),
        IntegratorDesc::NoriSimple => "Nori simple".into(),
        IntegratorDesc::Nori(n) => format!(
            "Nori {}",
            match n {
                NoriIntegrator::DirectEms => "direct_ems",
                NoriIntegrator::DirectMats => "direct_mats",
                NoriIntegrator::DirectMis => "direct_mis",
                NoriIntegrator::PathMats => "path_mats",
                NoriIntegrator::PathEms => "path_ems",
                NoriIntegrator::PathMis => "path_mis",
            }
        ),
    }
}

fn print_scene(desc: &SceneDesc, indent: &str) {
    let tris: usize = desc
        .shapes
        .iter()
        .map(|s| match &s.shape {
            Shape::Mesh(m) => m.triangle_count(),
            _ => 0,
        })
        .sum();
    println!(
        "{indent}shapes:     {} ({}), {} triangles in meshes",
        desc.shapes.len(),
        count(desc.shapes.iter().map(|s| s.shape.kind_name())),
        tris
    );
    println!(
        "{indent}materials:  {} ({})",
        desc.materials.len(),
        count(desc.materials.iter().map(|m| m.material.kind_name()))
    );
    println!("{indent}textures:   {}", desc.textures.len());
    if !desc.media.is_empty() {
        println!(
            "{indent}media:      {} ({})",
            desc.media.len(),
            count(desc.media.iter().map(|m| m.medium.kind_name()))
        );
    }
    let area = desc.shapes.iter().filter(|s| s.emission.is_some()).count();
    println!(
        "{indent}emitters:   {} area, {}",
        area,
        count(desc.emitters.iter().map(|e| e.emitter.kind_name()))
    );
    match desc.bounds() {
        Some((lo, hi)) => println!("{indent}bounds:     {lo} .. {hi}"),
        None => println!("{indent}bounds:     empty"),
    }
    for (i, s) in desc.sensors.iter().enumerate() {
        let cam = &s.camera;
        let kind = match cam.projection {
            Projection::Perspective { fov, fov_axis } => {
                format!("perspective, fov {fov}° ({})", axis_name(fov_axis))
            }
            Projection::ThinLens {
                fov,
                fov_axis,
                aperture_radius,
                focus_distance,
            } => format!(
                "thin lens, fov {fov}° ({}), aperture radius {aperture_radius}, focus distance {focus_distance}",
                axis_name(fov_axis)
            ),
            Projection::Orthographic => "orthographic".into(),
            Projection::RadianceMeter => "radiancemeter (one ray)".into(),
            Projection::IrradianceMeter { shape } => {
                format!("irradiancemeter on shape {shape}")
            }
            Projection::Window {
                left,
                right,
                bottom,
                top,
            } => format!(
                "perspective through the window [{left}, {right}] x [{bottom}, {top}] at distance 1"
            ),
        };
        println!(
            "{indent}sensor {i}:   {kind}, at {}, {}x{}{}, {} sampler, {} spp, {} filter",
            cam.to_world.w_axis.truncate(),
            s.film.width,
            s.film.height,
            s.film
                .crop
                .map(|c| format!(
                    " (crop {}x{} at {},{})",
                    c.width, c.height, c.offset_x, c.offset_y
                ))
                .unwrap_or_default(),
            sampler(s.sampler.kind),
            s.sampler.spp,
            filter(&s.film.filter),
        );
        // A sensor's own integrator (CENG795 cameras) replaces the scene's.
        if let Some(i) = &s.integrator {
            println!("{indent}  integrator: {}", integrator(i));
        }
    }
    // The scene's integrator only matters to sensors without their own.
    if desc.sensors.is_empty() || desc.sensors.iter().any(|s| s.integrator.is_none()) {
        println!("{indent}integrator: {}", integrator(&desc.integrator));
    }
    for w in &desc.warnings {
        println!("{indent}{w}");
    }
}

pub fn print(path: &Path, doc: &Document) -> Result<(), Failure> {
    println!("{}", path.display());
    match doc {
        Document::Scene(desc) => print_scene(desc, "  "),
        Document::Test(t) => match &t.kind {
            TestKind::TTest {
                references,
                scenes,
                bsdfs,
                angles,
                ..
            } => {
                println!(
                    "  t-test: {} reference value(s), {} scene(s), {} bsdf(s), {} angle(s)",
                    references.len(),
                    scenes.len(),
                    bsdfs.len(),
                    angles.len()
                );
                for (i, s) in scenes.iter().enumerate() {
                    println!("  scene {i}:");
                    print_scene(s, "    ");
                }
            }
            TestKind::Chi2Test { bsdfs, .. } => {
                println!("  chi2 test: {} bsdf(s)", bsdfs.len());
            }
        },
    }
    Ok(())
}
