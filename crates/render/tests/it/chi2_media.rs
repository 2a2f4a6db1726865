//! χ² goodness-of-fit of the media's sampling routines against their densities: the phase
//! functions' directions (isotropic; Henyey–Greenstein for g ∈ {−0.9, −0.5, 0, 0.5, 0.9};
//! Rayleigh; tables with a forward peak, with zeros and of two nodes; blends of them; with a
//! tilted `wo`), a homogeneous medium's free-flight distances (each hero channel), and
//! equiangular distances towards a point light (the light before, beside and beyond the
//! segment, near and far from its line), and points of an emission grid drawn by its radiance;
//! Mitsuba's `sggx` phase function for several S.
//! α = 0.01, Šidák-corrected over the cases of each test; fixed seeds.

use render::math::Mat4;
use render::math::{Vec2, Vec3};
use render::media::grid::VoxelGrid;
use std::sync::Arc;

use render::media::phase::{BlendPhase, SggxPhase, TabulatedPhase};
use render::media::{EmissionSampler, Flight, Homogeneous, Phase};
use render::sampling::Equiangular;
use render::stats::{Chi2Config, chi2_test, chi2_test_2d, sidak};

fn cfg(seed: u64, significance: f64) -> Chi2Config {
    Chi2Config {
        res: 16,
        sample_count: 300_000,
        min_exp_frequency: 5.0,
        significance,
        seed,
    }
}

#[test]
fn phase_function_sampling_matches_its_density() {
    let wo = Vec3::new(0.3, -0.4, 0.866).normalize();
    let mut phases = vec![Phase::Isotropic];
    phases.extend([-0.9f32, -0.5, 0.0, 0.5, 0.9].map(|g| Phase::HenyeyGreenstein { g }));
    phases.push(Phase::Rayleigh);
    let table = |v: &[f32]| Phase::Tabulated(Arc::new(TabulatedPhase::new(v).unwrap()));
    let peaked = table(&[0.05, 0.1, 0.2, 0.4, 1.0, 3.0, 12.0]);
    phases.extend([
        peaked.clone(),
        table(&[0.0, 0.0, 2.0, 0.5, 0.0, 1.0]),
        table(&[3.0, 1.0]),
    ]);
    for (weight, first) in [
        (0.3, Phase::HenyeyGreenstein { g: -0.6 }),
        (0.8, Phase::Rayleigh),
    ] {
        phases.push(Phase::Blend(Arc::new(BlendPhase {
            weight,
            first,
            second: peaked.clone(),
        })));
    }
    let a = sidak(0.01, phases.len());
    let failed: Vec<String> = phases
        .iter()
        .enumerate()
        .filter_map(|(i, phase)| {
            let r = chi2_test(
                |u, _| Some(phase.sample(wo, u).0),
                |wi| phase.eval(wo, wi),
                &cfg(40 + i as u64, a),
            );
            (!r.passed).then(|| format!("{phase:?}: {}", r.message))
        })
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// Mitsuba's `sggx` (specular SGGX microflakes): visible normals reflected, against
/// D(h)/(4σ(wo)), for S isotropic, general, flake-like (normals near z: a surface-like
/// medium) and fibre-like (normals across z), each for a `wo` along z and a tilted one; and
/// a blend with it (its sample through the blend's rescaled number). α = 0.01,
/// Šidák-corrected over the cases; fixed seeds.
#[test]
fn sggx_sampling_matches_its_density() {
    let sggx = |s: [f32; 6]| Phase::Sggx(Arc::new(SggxPhase::new(s).unwrap()));
    let mut phases = vec![
        sggx([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]),
        sggx([1.0, 0.5, 0.2, 0.1, 0.05, 0.0]),
        sggx([0.02, 0.02, 1.0, 0.0, 0.0, 0.0]),
        sggx([1.0, 0.8, 0.01, 0.3, 0.02, -0.05]),
    ];
    phases.push(Phase::Blend(Arc::new(BlendPhase {
        weight: 0.6,
        first: Phase::HenyeyGreenstein { g: 0.4 },
        second: phases[2].clone(),
    })));
    let wos = [Vec3::Z, Vec3::new(0.3, -0.4, 0.866).normalize()];
    let a = sidak(0.01, phases.len() * wos.len());
    let mut failed = Vec::new();
    for (i, phase) in phases.iter().enumerate() {
        for (j, &wo) in wos.iter().enumerate() {
            let r = chi2_test(
                |u, _| Some(phase.sample(wo, u).0),
                |wi| phase.eval(wo, wi),
                &cfg(700 + 10 * i as u64 + j as u64, a),
            );
            eprintln!("sggx case {i}, wo {j}: p = {:.4}", r.p_value);
            if !r.passed {
                failed.push(format!("{phase:?}, wo {wo}: {}", r.message));
            }
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// Distances sampled with each hero channel follow σt,h·e^{−σt,h·t} on [0, d_max), and the
/// mass e^{−σt,h·d_max} of "pass" is spread uniformly over [d_max, d_max + 1) by an
/// independent uniform. The 2D test's second coordinate is a dummy uniform so that the
/// generic 2D χ² can be used.
#[test]
fn free_flight_distances_match_their_density() {
    let m = Homogeneous::new(Vec3::new(0.5, 1.5, 4.0), Vec3::splat(0.7));
    let d_max = 1.0f32;
    let a = sidak(0.01, 3);
    for hero in 0..3 {
        let s = m.sigma_t[hero];
        let r = chi2_test_2d(
            |u, v| {
                let x = match m.sample(d_max, u.x, hero) {
                    Flight::Scatter { d, .. } => d,
                    Flight::Pass { .. } => d_max + v,
                };
                Some(Vec2::new(x, u.y))
            },
            |p| {
                if p.x < d_max {
                    s * (-s * p.x).exp()
                } else if p.x < d_max + 1.0 {
                    // The pass mass spread over [d_max, d_max + 1).
                    (-s * d_max).exp()
                } else {
                    0.0
                }
            },
            Vec2::ZERO,
            Vec2::new(d_max + 1.0, 1.0),
            &cfg(60 + hero as u64, a),
        );
        assert!(r.passed, "hero {hero}: {}", r.message);
    }
}

/// Equiangular distances on a segment of length `end` follow h/((b − a)(h² + (t − Δ)²)):
/// cases with the light's foot Δ before the segment, inside it and beyond it, close to the
/// line (a sharp peak) and far from it.
#[test]
fn equiangular_distances_match_their_density() {
    let (o, d) = (
        Vec3::new(0.2, -0.1, 0.4),
        Vec3::new(1.0, 2.0, -0.5).normalize(),
    );
    let side = d.cross(Vec3::Z).normalize();
    let cases = [
        (-0.5f32, 0.5f32, 2.0f32),
        (0.3, 0.05, 1.0),
        (1.2, 0.4, 3.0),
        (4.0, 1.0, 3.0),
    ];
    let a = sidak(0.01, cases.len());
    for (k, &(delta, h, end)) in cases.iter().enumerate() {
        let q = o + d * delta + side * h;
        let e = Equiangular::new(o, d, end, q).unwrap();
        let r = chi2_test_2d(
            |u, _| {
                let t = e.sample(u.x);
                (0.0..end).contains(&t).then(|| Vec2::new(t, u.y))
            },
            |p| e.pdf(p.x),
            Vec2::ZERO,
            Vec2::new(end, 1.0),
            &cfg(80 + k as u64, a),
        );
        assert!(r.passed, "Δ {delta}, h {h}, end {end}: {}", r.message);
    }
    // A light on the line has no equiangular distribution.
    assert_eq!(Equiangular::new(o, d, 1.0, o + d * 0.5), None);
}

/// Points drawn by an emission grid's sampler (8 × 6 × 4 voxels, some dark, under a rotated,
/// scaled placement) follow the density it reports: the 3D unit-cube coordinates are folded
/// into 2D as (x, (z cell + y)/n_z), where the density is the sampler's own pdf at the cell's
/// z centre times |det to_world| (the density in unit coordinates); and every sample's
/// reported density equals `pdf` at its point.
#[test]
fn emission_grid_points_match_their_density() {
    // A hot spot near one corner, nothing in a far slab: the sampler's weights (the largest
    // value around each voxel) vary along every axis.
    let res = [8usize, 6, 4];
    let n = res.iter().product::<usize>();
    let data: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y, z) = (i % 8, (i / 8) % 6, i / 48);
            if z == 3 && x > 4 {
                return 0.0;
            }
            let r2 = (x as f32 - 1.0).powi(2) + (y as f32 - 4.0).powi(2) + (z as f32).powi(2);
            (-r2 / 6.0).exp()
        })
        .collect();
    let grid = VoxelGrid {
        res,
        channels: 1,
        data: data.clone(),
        trilinear: true,
        zero_outside: false,
    };
    let to_world = Mat4::from_translation(Vec3::new(1.0, -2.0, 0.5).into())
        * Mat4::from_rotation_y(0.7)
        * Mat4::from_scale(Vec3::new(2.0, 0.5, 3.0).into());
    let sampler = EmissionSampler::new(&grid, to_world, |i| data[i]).unwrap();
    let to_unit = to_world.inverse();
    let det = to_world.determinant().abs();
    let nz = res[2] as f32;
    let r = chi2_test_2d(
        |u, v| {
            let (p, pdf) = sampler.sample(u.x, Vec2::new(u.y, v), (u.x * 7919.0).fract())?;
            let want = sampler.pdf(p);
            assert!((pdf - want).abs() <= 1e-4 * want, "{pdf} vs {want}");
            let q = to_unit.transform_point3a(p);
            let zc = ((q.z * nz) as usize).min(res[2] - 1) as f32;
            Some(Vec2::new(q.x, (zc + q.y) / nz))
        },
        |xy| {
            let zc = ((xy.y * nz) as usize).min(res[2] - 1) as f32;
            let q = Vec3::new(xy.x, xy.y * nz - zc, (zc + 0.5) / nz);
            sampler.pdf(to_world.transform_point3a(q)) * det
        },
        Vec2::ZERO,
        Vec2::ONE,
        &cfg(90, 0.01),
    );
    assert!(r.passed, "{}", r.message);
}
