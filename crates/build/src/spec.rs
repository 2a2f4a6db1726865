//! The command line's spellings of scene overrides, shared by the `penumbra` command and the
//! Python package so that both turn the same words into the same scene: `--integrator`'s
//! `NAME[:ARGS]` ([`parse_integrator`]), `--filter KIND` ([`parse_filter`]), `--mode`
//! ([`parse_mode`]) and the rule that a replacement integrator keeps the scene's path length
//! ([`keep_scene_max_depth`]); and how both name a render and split it into shards
//! ([`identity`], [`shard_items`]).

use scene::IntegratorDesc;

/// Give `integrator` (a replacement for the scene's) the scene integrator's `max_depth`:
/// `--integrator sppm` keeps the scene's path length (a scene's max_depth is part of what its
/// reference shows).
pub fn keep_scene_max_depth(scene_integrator: &IntegratorDesc, integrator: &mut IntegratorDesc) {
    let Some(m) = max_depth_of(scene_integrator) else {
        return;
    };
    match integrator {
        IntegratorDesc::Path(d) => d.max_depth = m,
        IntegratorDesc::VolPath { max_depth, .. } => *max_depth = m,
        IntegratorDesc::Sppm(d) => d.max_depth = m,
        IntegratorDesc::Photon(d) => d.max_depth = m,
        IntegratorDesc::Ptracer { max_depth, .. } => *max_depth = m,
        IntegratorDesc::Bdpt { max_depth, .. } => *max_depth = m,
        IntegratorDesc::Mlt { max_depth, .. } => *max_depth = m,
        _ => {}
    }
}

/// The longest path a scene's integrator allows, in Mitsuba's terms (−1: unbounded).
pub fn max_depth_of(i: &IntegratorDesc) -> Option<i32> {
    match i {
        IntegratorDesc::Path(p) => Some(p.max_depth),
        IntegratorDesc::VolPath { max_depth, .. } => Some(*max_depth),
        IntegratorDesc::Sppm(d) => Some(d.max_depth),
        IntegratorDesc::Photon(d) => Some(d.max_depth),
        IntegratorDesc::Ptracer { max_depth, .. } => Some(*max_depth),
        IntegratorDesc::Bdpt { max_depth, .. } => Some(*max_depth),
        IntegratorDesc::Mlt { max_depth, .. } => Some(*max_depth),
        _ => None,
    }
}

pub fn parse_integrator(s: &str) -> Result<IntegratorDesc, String> {
    let (name, arg) = s.split_once(':').unwrap_or((s, ""));
    Ok(match name {
        "normals" => IntegratorDesc::Normals,
        "albedo" => IntegratorDesc::Albedo,
        "depth" => IntegratorDesc::Depth,
        "ao" => IntegratorDesc::AmbientOcclusion {
            samples: if arg.is_empty() {
                1
            } else {
                arg.parse()
                    .map_err(|_| format!("ao:N expects a sample count, found '{arg}'"))?
            },
            length: None,
        },
        "sppm" | "ppm" => IntegratorDesc::Sppm({
            // Positional fields, an empty one keeps its default.
            let usage = if name == "ppm" {
                "ppm[:PHOTONS[,RADIUS[,EYE_SAMPLES]]]"
            } else {
                "sppm[:PHOTONS[,RADIUS]]"
            };
            let mut d = scene::SppmDesc::default();
            let fields: Vec<&str> = if arg.is_empty() {
                vec![]
            } else {
                arg.split(',').collect()
            };
            let max_fields = if name == "ppm" { 3 } else { 2 };
            if fields.len() > max_fields {
                return Err(format!("{usage}: too many fields in '{arg}'"));
            }
            let field = |k: usize| fields.get(k).copied().filter(|f| !f.is_empty());
            if let Some(n) = field(0) {
                d.photons =
                    Some(n.parse().ok().filter(|&n: &u64| n > 0).ok_or_else(|| {
                        format!("{usage}: PHOTONS must be a count > 0, found '{n}'")
                    })?);
            }
            if let Some(r) = field(1) {
                d.initial_radius = Some(
                    r.parse()
                        .ok()
                        .filter(|&r: &f32| r > 0.0 && r.is_finite())
                        .ok_or_else(|| format!("{usage}: RADIUS must be > 0, found '{r}'"))?,
                );
            }
            if name == "ppm" {
                d.fixed_eye_samples = Some(match field(2) {
                    None => 4,
                    Some(e) => e.parse().ok().filter(|&e: &u32| e > 0).ok_or_else(|| {
                        format!("{usage}: EYE_SAMPLES must be a count > 0, found '{e}'")
                    })?,
                });
            }
            d
        }),
        "path" if arg.is_empty() => IntegratorDesc::Path(scene::PathDesc::default()),
        "volpath" if arg.is_empty() => IntegratorDesc::VolPath {
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
            equiangular: true,
            transmittance: Default::default(),
            sample_emission: false,
        },
        "bdpt" => IntegratorDesc::Bdpt {
            max_depth: -1,
            visualize_strategies: arg == "strategies",
            visualize_weights: match arg {
                "" | "strategies" => false,
                "weights" => true,
                _ => {
                    return Err(format!(
                        "bdpt[:strategies|:weights]: expected 'strategies' (one unweighted image \
                         per strategy) or 'weights' (MIS-weighted), found '{arg}'"
                    ));
                }
            },
        },
        "mlt" => {
            // Positional fields, an empty one keeps its default.
            let usage = "mlt[:DIRECT_SAMPLES[,kelemen|multiplexed]]";
            let fields: Vec<&str> = if arg.is_empty() {
                vec![]
            } else {
                arg.split(',').collect()
            };
            if fields.len() > 2 {
                return Err(format!("{usage}: too many fields in '{arg}'"));
            }
            let field = |k: usize| fields.get(k).copied().filter(|f| !f.is_empty());
            IntegratorDesc::Mlt {
                max_depth: -1,
                bootstrap: 100_000,
                chains: 1000,
                large_step: 0.3,
                sigma: 0.01,
                direct_samples: match field(0) {
                    None => 16,
                    Some(d) => d.parse().ok().filter(|&d: &i32| d >= -1).ok_or_else(|| {
                        format!("{usage}: DIRECT_SAMPLES must be a count ≥ 0 or -1, found '{d}'")
                    })?,
                },
                multiplexed: match field(1) {
                    None | Some("multiplexed") => true,
                    Some("kelemen") => false,
                    Some(v) => {
                        return Err(format!(
                            "{usage}: expected 'kelemen' (a state is a whole BDPT sample) or \
                             'multiplexed' (one strategy, the default), found '{v}'"
                        ));
                    }
                },
            }
        }
        "ptracer" if arg.is_empty() => IntegratorDesc::Ptracer {
            max_depth: -1,
            hide_emitters: false,
        },
        "photon" => IntegratorDesc::Photon({
            let usage = "photon[:PHOTONS[,GATHER[,K]]]";
            let mut d = scene::PhotonDesc::default();
            let fields: Vec<&str> = if arg.is_empty() {
                vec![]
            } else {
                arg.split(',').collect()
            };
            if fields.len() > 3 {
                return Err(format!("{usage}: too many fields in '{arg}'"));
            }
            let field = |k: usize| fields.get(k).copied().filter(|f| !f.is_empty());
            let count = |f: &str, what: &str, min: u64| {
                f.parse::<u64>()
                    .ok()
                    .filter(|&n| n >= min)
                    .ok_or_else(|| format!("{usage}: {what} must be a count ≥ {min}, found '{f}'"))
            };
            if let Some(n) = field(0) {
                d.photons = count(n, "PHOTONS", 1)?;
            }
            if let Some(g) = field(1) {
                d.final_gather = count(g, "GATHER", 0)?.min(1 << 16) as u32;
            }
            if let Some(k) = field(2) {
                let k = count(k, "K", 1)?.min(1 << 20) as u32;
                d.global.k = Some(k);
                d.caustic.k = Some(k);
            }
            d
        }),
        _ => {
            return Err(format!(
                "unknown integrator '{name}' (expected normals, albedo, depth, ao[:N], \
                 photon[:PHOTONS[,GATHER[,K]]], sppm[:PHOTONS[,RADIUS]], \
                 ppm[:PHOTONS[,RADIUS[,EYE_SAMPLES]]], path, volpath, ptracer, bdpt[:strategies|:weights], \
                 mlt[:DIRECT_SAMPLES[,kelemen|multiplexed]])"
            ));
        }
    })
}

/// The identity of a render (shards and checkpoints, `render::film::state`): the loaded
/// scene (after every parameter and override), what else changes the image (`what`: the
/// build options, samples per pixel, tile size, chunk) and the program's version, hashed
/// from their `Debug` text (streamed: no copy of the meshes). The same on every machine
/// for the same inputs; the CLI and the Python package compute it alike.
pub fn identity(desc: &scene::SceneDesc, what: &impl std::fmt::Debug) -> u64 {
    use std::fmt::Write;
    let mut h = render::film::state::Fnv::default();
    let _ = write!(
        h,
        "{} {} {:?} {:?}",
        env!("CARGO_PKG_VERSION"),
        render::film::state::FORMAT,
        desc,
        what
    );
    h.0
}

/// Shard `i` of `count` of a render's `n` work items: the i-th of `count` nearly equal
/// consecutive ranges (they cover `0..n` once).
pub fn shard_items(i: u32, count: u32, n: u64) -> std::ops::Range<u64> {
    let at = |k: u32| (n as u128 * k as u128 / count.max(1) as u128) as u64;
    at(i.min(count))..at((i + 1).min(count))
}

/// `--mode`: `rgb`, `spectral` or a Mitsuba 3 variant name, which selects its colour part.
pub fn parse_mode(s: &str) -> Result<scene::RenderMode, String> {
    match s {
        "rgb" => Ok(scene::RenderMode::Rgb),
        "spectral" => Ok(scene::RenderMode::Spectral),
        v => scene::RenderMode::from_mitsuba_variant(v).ok_or_else(|| {
            format!(
                "expected rgb, spectral or a Mitsuba variant ending in _rgb or _spectral \
                 (scalar_rgb, llvm_ad_spectral, ...), found '{v}'"
            )
        }),
    }
}

/// `--filter KIND`: a reconstruction filter with Mitsuba's defaults.
pub fn parse_filter(s: &str) -> Result<scene::FilterDesc, String> {
    use scene::FilterDesc as F;
    match s {
        "box" => Ok(F::Box { radius: 0.5 }),
        "tent" => Ok(F::Tent { radius: 1.0 }),
        "gaussian" => Ok(F::Gaussian {
            stddev: 0.5,
            radius: 2.0,
        }),
        "mitchell" => Ok(F::Mitchell {
            b: 1.0 / 3.0,
            c: 1.0 / 3.0,
            radius: 2.0,
        }),
        "lanczos" => Ok(F::Lanczos {
            radius: 3.0,
            tau: 3.0,
        }),
        _ => Err(format!(
            "expected box, tent, gaussian, mitchell or lanczos, found '{s}'"
        )),
    }
}
