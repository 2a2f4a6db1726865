//! Photon density estimation against the analytic irradiance (issue 22, acceptance 3): a point
//! light of intensity I at height h above a black diffuse plane gives the plane the
//! irradiance E(x) = I·cos θ / r² = I·h / (d² + h²)^{3/2} at distance d from the foot of the
//! light. The photon map's estimate at x with a fixed radius R is an unbiased estimate of E
//! averaged by the kernel over the disk of radius R around x (the kernel's bias); that
//! average is computed by quadrature, the estimate is z-tested against it, and the bias
//! itself is shown to shrink with R towards E.
//!
//! Significance: 16 z-tests (4 points × 2 radii × 2 kernels), Šidák-corrected to α = 0.01
//! overall: |z| < 3.42 each. Photons are traced with a fixed seed.

use build::{BuildOptions, build};
use render::integrators::photon::{Kernel, Lookup, PhotonConfig, PhotonMaps};
use render::math::Vec3;

const I: f32 = 10.0;
const H: f32 = 1.0;

const SCENE: &str = r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 3, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="point">
        <point name="position" x="0" y="1" z="0"/>
        <rgb name="intensity" value="10, 10, 10"/>
    </emitter>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="-90"/><scale value="20"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    </shape>
</scene>"#;

fn irradiance(d: f64) -> f64 {
    I as f64 * H as f64 / (d * d + (H * H) as f64).powf(1.5)
}

fn kernel_weight(kernel: Kernel, d2: f64, r2: f64) -> f64 {
    let base = 1.0 / (std::f64::consts::PI * r2);
    match kernel {
        Kernel::Box => base,
        Kernel::Cone => 3.0 * (1.0 - (d2 / r2).sqrt()).max(0.0) * base,
        Kernel::Epanechnikov => 2.0 * (1.0 - d2 / r2).max(0.0) * base,
    }
}

/// ∫ K(u)·E(x + u) du over the disk of radius `r` around (x, 0, 0) (midpoint rule in polar
/// coordinates).
fn kernel_average(kernel: Kernel, x: f64, r: f64) -> f64 {
    let (nr, nt) = (400, 400);
    let mut s = 0.0;
    for i in 0..nr {
        let rho = (i as f64 + 0.5) / nr as f64 * r;
        for j in 0..nt {
            let t = (j as f64 + 0.5) / nt as f64 * std::f64::consts::TAU;
            let (px, pz) = (x + rho * t.cos(), rho * t.sin());
            let w = kernel_weight(kernel, rho * rho, r * r);
            s += w * irradiance((px * px + pz * pz).sqrt()) * rho;
        }
    }
    s * (r / nr as f64) * (std::f64::consts::TAU / nt as f64)
}

#[test]
fn photon_irradiance_matches_the_point_light() {
    let desc = scene::load_xml_text("photon-density", SCENE).expect("scene loads");
    let scene = build(&desc, &BuildOptions::default())
        .expect("scene builds")
        .scene;
    let cfg = PhotonConfig {
        photons: 4_000_000,
        // Final gathering keeps every photon, direct ones included, in the global map.
        final_gather: 1,
        ..PhotonConfig::default()
    };
    let maps = PhotonMaps::build(&scene, &cfg, 11);
    let map = maps.global.as_ref().expect("photons stored");
    let n = maps.emitted as f64;
    let z_max = 3.42;
    for kernel in [Kernel::Box, Kernel::Epanechnikov] {
        for x in [0.0, 0.5, 1.0, 2.0] {
            let exact = irradiance(x);
            let mut bias = Vec::new();
            for r in [0.2f32, 0.1] {
                let (sum, sq) =
                    map.irradiance_sums(Lookup::Radius(r), kernel, Vec3::new(x as f32, 0.0, 0.0));
                let est = sum.x as f64 / n;
                let sigma = (sq.x as f64).sqrt() / n;
                let expected = kernel_average(kernel, x, r as f64);
                let z = (est - expected) / sigma;
                eprintln!(
                    "{kernel:?} x = {x}, R = {r}: estimate {est:.5} ± {sigma:.5}, kernel average \
                     {expected:.5}, E {exact:.5}, z = {z:.2}"
                );
                assert!(z.abs() < z_max, "{kernel:?} at x = {x}, R = {r}: z = {z}");
                bias.push((expected - exact).abs());
            }
            // The kernel's bias shrinks with the radius (about as R²) and vanishes with it.
            assert!(
                bias[1] <= 0.3 * bias[0] + 1e-9,
                "{kernel:?} at {x}: bias {bias:?}"
            );
            let tiny = (kernel_average(kernel, x, 0.01) - exact).abs() / exact;
            assert!(
                tiny < 1e-3,
                "{kernel:?} at {x}: kernel average at R = 0.01 off by {tiny}"
            );
        }
    }
}

/// The part of a ball that a point in a medium sees (`Enclosure`, which keeps volume
/// estimates from darkening at a medium's boundary): over random turns of its cells each
/// probe ray's direction is uniform on the sphere, so its share of the ball is an unbiased
/// estimate of ∫ min(1, t(ω)/r)³ dω / 4π. Above a plane at height h < r that is
/// 1 − (1 − h/r)²(2 + h/r)/4 (the ball less its cap below the plane). z-test of the mean over
/// 4000 turns at each of 4 heights, α = 0.001 Šidák-corrected over the 4: |z| < 3.48.
#[test]
fn enclosure_share_of_a_ball_above_a_plane() {
    use render::integrators::photon::Enclosure;
    use render::sampling::Sampler;
    use scene::SamplerKind;
    let desc = scene::load_xml_text("photon-density", SCENE).expect("scene loads");
    let scene = build(&desc, &BuildOptions::default())
        .expect("scene builds")
        .scene;
    let mut rng = Sampler::new(SamplerKind::Independent, 1, 5);
    let r = 1.0f32;
    for h in [0.05f32, 0.3, 0.6, 0.9] {
        let want = 1.0 - (1.0 - h as f64).powi(2) * (2.0 + h as f64) / 4.0;
        let shares: Vec<f64> = (0..4000)
            .map(|_| {
                let u = [rng.next_1d(), rng.next_1d(), rng.next_1d()];
                Enclosure::probe(&scene, Vec3::new(0.1, h, -0.2), r, u).fraction(r) as f64
            })
            .collect();
        let n = shares.len() as f64;
        let mean = shares.iter().sum::<f64>() / n;
        let var = shares.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let z = (mean - want) / (var / n).sqrt().max(1e-9);
        eprintln!("h = {h}: share {mean:.5} (expected {want:.5}), z = {z:.2}");
        assert!(z.abs() < 3.48, "h = {h}: {mean} vs {want} (z = {z})");
    }
}
