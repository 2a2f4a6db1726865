//! Runs Nori's statistical test files (`<test type="ttest">`, `<test type="chi2test">`),
//! as `penumbra test` does.
//!
//! - t-test of scenes: `sample_count` camera samples of each scene (pixels chosen uniformly),
//!   their luminance (Nori's weights 0.212671, 0.715160, 0.072169) compared with the reference
//!   by Student's t-test.
//! - t-test of BSDFs: for each incident angle θ (wo = (sin θ, 0, cos θ)), the mean luminance of
//!   `sample().weight` (the albedo) against the reference.
//! - χ² test of BSDFs: `test_count` incident directions drawn cosine-weighted, each a χ² test
//!   of `sample` against `pdf` (`stats::chi2_test`).
//!
//! Every case is tested at the Šidák-corrected level α' = 1 − (1 − α)^(1/cases), α being the
//! file's `significanceLevel` (Nori's default 0.01).

use rayon::prelude::*;
use scene::{MaterialId, SceneDesc, TestDesc, TestKind};

use crate::{BuildError, BuildOptions, Built, build};
use render::bsdf::{Bsdf, TransportMode};
use render::integrators::UnsupportedIntegrator;
use render::math::{UVec2, Vec3};
use render::sampling::Sampler;
use render::sampling::warp::square_to_cosine_hemisphere;
use render::stats::{Chi2Config, MeanVar, Pcg32, chi2_test, sidak};
use render::textures::ConstantParams;

#[derive(Clone, Debug)]
pub struct CaseResult {
    pub name: String,
    /// t or χ² statistic.
    pub statistic: f64,
    pub p_value: f64,
    pub passed: bool,
    pub detail: String,
}

#[derive(Clone, Debug)]
pub struct TestReport {
    pub kind: &'static str,
    /// Per-case significance level after the Šidák correction.
    pub case_level: f64,
    pub cases: Vec<CaseResult>,
}

impl TestReport {
    pub fn passed(&self) -> bool {
        self.cases.iter().all(|c| c.passed)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum TestError {
    #[error(transparent)]
    Build(#[from] BuildError),
    #[error(transparent)]
    Integrator(#[from] UnsupportedIntegrator),
    #[error("{0}")]
    Malformed(String),
}

/// Nori's luminance.
fn luminance(c: Vec3) -> f64 {
    (0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z) as f64
}

fn bsdf_of(desc: &SceneDesc, id: MaterialId) -> Result<Bsdf, TestError> {
    let m = desc
        .materials
        .get(id.0 as usize)
        .ok_or_else(|| TestError::Malformed(format!("material {} does not exist", id.0)))?;
    crate::material_kind(&m.material)
        .map(|k| k.bsdf(&ConstantParams, Default::default()))
        .ok_or_else(|| {
            TestError::Malformed(format!(
                "{}: a {} material cannot be tested on its own",
                m.loc,
                m.material.kind_name()
            ))
        })
}

/// Mean and variance of the luminance of `n` camera samples of `desc`.
fn scene_estimate(desc: &SceneDesc, n: u64, seed: u64) -> Result<MeanVar, TestError> {
    let Built {
        scene, integrator, ..
    } = build(desc, &BuildOptions::default())?;
    let (w, h) = (scene.film.width.max(1), scene.film.height.max(1));
    const CHUNK: u64 = 4096;
    let chunks: Vec<MeanVar> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut sampler = Sampler::new(scene::SamplerKind::Independent, 1, seed);
            let mut pick = Pcg32::new(seed ^ 0x9e37_79b9, c);
            let mut mv = MeanVar::default();
            for k in c * CHUNK..((c + 1) * CHUNK).min(n) {
                let px = UVec2::new(
                    (pick.next_u32() % w).min(w - 1),
                    (pick.next_u32() % h).min(h - 1),
                );
                let (_, cray) = render::render::camera_sample(&scene, &mut sampler, px, k as u32);
                let l = render::render::li(&scene, &integrator, &cray, &mut sampler);
                let v = luminance(l.unwrap_or(Vec3::ZERO));
                mv.push(if v.is_finite() { v } else { 0.0 });
            }
            mv
        })
        .collect();
    Ok(chunks
        .into_iter()
        .fold(MeanVar::default(), |a, b| a.merge(&b)))
}

fn t_case(name: String, mv: &MeanVar, reference: f64, level: f64) -> CaseResult {
    let p = mv.t_test(reference);
    let se = (mv.variance() / mv.n.max(1) as f64).sqrt();
    let t = if se > 0.0 {
        (mv.mean - reference) / se
    } else {
        0.0
    };
    CaseResult {
        name,
        statistic: t,
        p_value: p,
        passed: p >= level,
        detail: format!("mean {:.6} (reference {reference:.6}, n {})", mv.mean, mv.n),
    }
}

/// Run every case of a test file.
pub fn run(test: &TestDesc, seed: u64) -> Result<TestReport, TestError> {
    match &test.kind {
        TestKind::TTest {
            significance,
            references,
            angles,
            sample_count,
            scenes,
            bsdfs,
        } => {
            let n_cases = scenes.len() + bsdfs.len() * angles.len().max(1);
            if references.len() < n_cases {
                return Err(TestError::Malformed(format!(
                    "{}: {} reference values for {n_cases} cases",
                    test.loc,
                    references.len()
                )));
            }
            let level = sidak(*significance as f64, n_cases);
            let mut cases = Vec::new();
            for (i, s) in scenes.iter().enumerate() {
                let mv = scene_estimate(s, (*sample_count).max(2) as u64, seed + i as u64)?;
                cases.push(t_case(
                    format!("scene {i}"),
                    &mv,
                    references[i] as f64,
                    level,
                ));
            }
            for (b, (desc, id)) in bsdfs.iter().enumerate() {
                let bsdf = bsdf_of(desc, *id)?;
                for (a, angle) in angles.iter().enumerate() {
                    let theta = angle.to_radians();
                    let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
                    let mut rng = Pcg32::new(seed, (b * angles.len() + a) as u64);
                    let mut mv = MeanVar::default();
                    for _ in 0..(*sample_count).max(2) {
                        let u1 = rng.next_f32();
                        let u2 = rng.next_vec2();
                        let w = bsdf
                            .sample(wo, u1, u2, TransportMode::Radiance)
                            .map_or(0.0, |s| luminance(s.weight));
                        mv.push(w);
                    }
                    let r = references[scenes.len() + b * angles.len() + a] as f64;
                    cases.push(t_case(format!("bsdf {b}, θ = {angle}°"), &mv, r, level));
                }
            }
            Ok(TestReport {
                kind: "t-test",
                case_level: level,
                cases,
            })
        }
        TestKind::Chi2Test {
            significance,
            resolution,
            min_exp_frequency,
            sample_count,
            test_count,
            bsdfs,
        } => {
            let n_cases = bsdfs.len() * (*test_count).max(1) as usize;
            let level = sidak(*significance as f64, n_cases);
            let mut cases = Vec::new();
            for (b, (desc, id)) in bsdfs.iter().enumerate() {
                let bsdf = bsdf_of(desc, *id)?;
                let mut rng = Pcg32::new(seed, b as u64);
                for k in 0..(*test_count).max(1) {
                    let wo = square_to_cosine_hemisphere(rng.next_vec2());
                    let cfg = Chi2Config {
                        res: *resolution,
                        sample_count: *sample_count as u64,
                        min_exp_frequency: *min_exp_frequency as f64,
                        significance: level,
                        seed: seed.wrapping_add((b as u64) << 32 | k as u64),
                    };
                    let r = chi2_test(
                        |u2, u1| {
                            bsdf.sample(wo, u1, u2, TransportMode::Radiance)
                                .filter(|s| !s.delta)
                                .map(|s| s.wi)
                        },
                        |wi| bsdf.pdf(wo, wi),
                        &cfg,
                    );
                    cases.push(CaseResult {
                        name: format!("bsdf {b}, wo = ({:.3}, {:.3}, {:.3})", wo.x, wo.y, wo.z),
                        statistic: r.statistic,
                        p_value: r.p_value,
                        passed: r.passed,
                        detail: format!("dof {}; {}", r.dof, r.message),
                    });
                }
            }
            Ok(TestReport {
                kind: "chi2 test",
                case_level: level,
                cases,
            })
        }
    }
}
