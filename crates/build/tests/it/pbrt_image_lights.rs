//! pbrt-v4's `projection` and `goniometric` lights end to end: a light 2 units above a
//! diffuse plane (ρ = 0.5) seen by an orthographic camera, every pixel against
//! ρ/π · I(ω)·cos θ / r², with I(ω) from pbrt-v4's rule written out here (its light frame with
//! the y flip or the y–z swap, the pinhole's screen or the equal-area square, nearest pixel).
//! Direct light from a delta light on a plane is deterministic up to the pixel jitter: pixels
//! whose footprint, grown by a fifth, stays inside one texel of the light's image must
//! agree within 1 %, and
//! pixels see several texels (the image's orientation is in view).

use build::{BuildOptions, render_desc};
use glam::{Vec2, Vec3};
use render::film::Image;
use render::sampling::warp::equal_area_sphere_to_square;

const RES: usize = 32;

fn load(name: &str, light: &str, image: &Image) -> scene::SceneDesc {
    let dir =
        std::env::temp_dir().join(format!("penumbra-pbrt-light-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    render::image_io::write_image(&dir.join("light.pfm"), image).unwrap();
    let text = format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\n\
         Film \"rgb\" \"integer xresolution\" {RES} \"integer yresolution\" {RES} \"string filename\" \"x.exr\"\n\
         PixelFilter \"box\"\nSampler \"independent\" \"integer pixelsamples\" 16\n\
         Integrator \"path\" \"integer maxdepth\" 1\nWorldBegin\n\
         AttributeBegin\n{light}\nAttributeEnd\n\
         Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"point3 P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] \"integer indices\" [0 1 2 0 2 3]\n"
    );
    let path = dir.join("scene.pbrt");
    std::fs::write(&path, text).unwrap();
    let desc = match scene::load(&path, &scene::LoadOptions::default()).unwrap() {
        scene::Document::Scene(s) => *s,
        scene::Document::Test(_) => panic!(),
    };
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    desc
}

fn render(name: &str, light: &str, image: &Image) -> Image {
    let desc = load(name, light, image);
    let out = render_desc(&desc, &BuildOptions::default()).unwrap();
    out.film.develop()
}

/// An image whose every texel differs: (x + 1, y + 1, x·y) / n.
fn texels(w: u32, h: u32) -> Image {
    let mut img = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let v = Vec3::new((x + 1) as f32, (y + 1) as f32, (x * y) as f32 + 0.5);
            img.set(x, y, (v / 4.0).into());
        }
    }
    img
}

/// Compares `img` with `intensity(d)` (d from the light at (0, 0, 2) to the plane point),
/// returning how many pixels were compared and how many texels they showed.
fn check(img: &Image, intensity: impl Fn(Vec3) -> Option<(Vec3, (u32, u32))>) -> (usize, usize) {
    let px = 2.0 / RES as f32;
    let (mut compared, mut texels) = (0, std::collections::HashSet::new());
    for j in 0..RES {
        for i in 0..RES {
            let mut want = Vec3::ZERO;
            let mut seen = std::collections::HashSet::new();
            for k in 0..25 {
                // pbrt's LookAt down −z puts world +x at the image's left.
                let x = 1.0 - (i as f32 + ((k % 5) as f32 + 0.5) / 5.0) * px;
                let y = 1.0 - (j as f32 + ((k / 5) as f32 + 0.5) / 5.0) * px;
                let d = Vec3::new(x, y, -2.0);
                let (i_w, texel) = intensity(d.normalize()).unwrap_or((Vec3::ZERO, (u32::MAX, 0)));
                seen.insert(texel);
                let r2 = d.length_squared();
                want += 0.5 / std::f32::consts::PI * i_w * (2.0 / r2.sqrt()) / r2 / 25.0;
            }
            // Away from texel borders: the footprint grown by a fifth shows one texel.
            for k in 0..121 {
                let x = 1.0 - (i as f32 - 0.2 + 1.4 * (k % 11) as f32 / 10.0) * px;
                let y = 1.0 - (j as f32 - 0.2 + 1.4 * (k / 11) as f32 / 10.0) * px;
                let d = Vec3::new(x, y, -2.0).normalize();
                seen.insert(intensity(d).map_or((u32::MAX, 0), |t| t.1));
            }
            if seen.len() != 1 {
                continue;
            }
            texels.extend(seen);
            compared += 1;
            let got = Vec3::from(img.pixels[j * RES + i]);
            assert!(
                (got - want).abs().max_element() <= 0.01 * want.max_element() + 1e-5,
                "pixel ({i}, {j}): {got} vs {want}"
            );
        }
    }
    (compared, texels.len())
}

#[test]
fn projection_light_is_pbrts() {
    let image = texels(8, 4);
    // The light looks down −z (its +y towards world −y); tan(fov/2) = 1/2.
    let fov = 2.0 * 0.5f32.atan().to_degrees();
    let img = render(
        "projection",
        &format!(
            "Translate 0 0 2\nRotate 180 1 0 0\nLightSource \"projection\" \"string filename\" \"light.pfm\" \"float fov\" {fov} \"float scale\" 3"
        ),
        &image,
    );
    let (n, seen) = check(&img, |d| {
        // World → light (the inverse of the rotation), then pbrt-v4's y flip.
        let l = Vec3::new(d.x, -d.y, -d.z);
        let w = Vec3::new(l.x, -l.y, l.z);
        let half = Vec2::new(2.0, 1.0);
        let s = Vec2::new(w.x, w.y) / (w.z * 0.5);
        if w.z < 1e-3 || s.x.abs() > half.x || s.y.abs() > half.y {
            return None;
        }
        let uv = (s + half) / (2.0 * half);
        let (x, y) = ((uv.x * 8.0) as u32, (uv.y * 4.0) as u32);
        Some((Vec3::from(image.get(x.min(7), y.min(3))) * 3.0, (x, y)))
    });
    println!("{n} pixels, {seen} texels");
    assert!(n > 500 && seen >= 8, "{n} pixels, {seen} texels");
}

#[test]
fn goniometric_light_is_pbrts() {
    let image = texels(16, 16);
    let img = render(
        "goniometric",
        "Translate 0 0 2\nLightSource \"goniometric\" \"string filename\" \"light.pfm\" \"rgb I\" [1 2 3] \"float scale\" 2",
        &image,
    );
    let (n, seen) = check(&img, |d| {
        // pbrt-v4 swaps the light's y and z before the equal-area map.
        let w = Vec3::new(d.x, d.z, d.y);
        let uv = equal_area_sphere_to_square(w.into());
        let (x, y) = ((uv.x * 16.0) as u32, (uv.y * 16.0) as u32);
        let t = Vec3::from(image.get(x.min(15), y.min(15)));
        let grey = (t.x + t.y + t.z) / 3.0;
        Some((Vec3::new(1.0, 2.0, 3.0) * 2.0 * grey, (x, y)))
    });
    println!("{n} pixels, {seen} texels");
    assert!(n > 300 && seen >= 4, "{n} pixels, {seen} texels");
}

/// Photons: the mean weight of `sample_le` over 2¹⁸ samples (fixed seed) is ∫ I dω, taken
/// here by a 1024² midpoint rule on the equal-area square (every cell the same solid angle);
/// z-tested per channel, α = 0.001 Šidák-corrected over 2 lights × 3 channels (|z| < 3.76).
/// `pdf_le` gives back each sample's densities.
#[test]
fn photons_carry_the_integral_of_the_intensity() {
    use render::lights::Light;
    use render::spectral::lanes::RgbMode;
    use render::stats::Pcg32;
    let fov = 2.0 * 0.5f32.atan().to_degrees();
    for (k, light) in [
        format!("Rotate 30 1 1 0\nLightSource \"projection\" \"string filename\" \"light.pfm\" \"float fov\" {fov}"),
        "Rotate 30 1 1 0\nLightSource \"goniometric\" \"string filename\" \"light.pfm\" \"rgb I\" [1 2 3]".to_string(),
    ]
    .iter()
    .enumerate()
    {
        let desc = load(&format!("photons{k}"), light, &texels(8, 8));
        let scene = build::build(&desc, &BuildOptions::default()).unwrap().scene;
        let (i, Light::ImagePoint(l)) = scene
            .lights
            .iter()
            .enumerate()
            .find(|(_, l)| matches!(l, Light::ImagePoint(_)))
            .unwrap()
        else {
            unreachable!()
        };
        let n = 1024;
        let mut want = glam::DVec3::ZERO;
        for c in 0..n * n {
            let uv = render::math::Vec2::new(
                ((c % n) as f32 + 0.5) / n as f32,
                ((c / n) as f32 + 0.5) / n as f32,
            );
            let w = render::sampling::warp::equal_area_square_to_sphere(uv);
            want += Vec3::from(l.intensity(w)).as_dvec3();
        }
        want *= 4.0 * std::f64::consts::PI / (n * n) as f64;
        let mut rng = Pcg32::new(7 + k as u64, 3);
        let count = 1 << 18;
        let (mut sum, mut sum2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for _ in 0..count {
            let (u_pos, u_dir) = (rng.next_vec2(), rng.next_vec2());
            let Some(s) = scene.lights[i].sample_le(&scene, u_pos, u_dir, &RgbMode) else {
                continue;
            };
            let w = Vec3::from(s.weight).as_dvec3();
            sum += w;
            sum2 += w * w;
            let (pp, pd) = scene.lights[i].pdf_le(&scene, s.p, s.n, s.ray.d);
            assert!((pp - s.pdf_pos).abs() < 1e-4 && (pd - s.pdf_dir).abs() < 1e-4 * s.pdf_dir);
        }
        let c = count as f64;
        let mean = sum / c;
        let var = (sum2 / c - mean * mean) * (c / (c - 1.0));
        for ch in 0..3 {
            let z = (mean[ch] - want[ch]) / (var[ch] / c).sqrt();
            println!("light {k} channel {ch}: {:.4} vs {:.4} (z = {z:.2})", mean[ch], want[ch]);
            assert!(z.abs() < 3.76, "light {k} channel {ch}: z = {z}");
        }
    }
}
