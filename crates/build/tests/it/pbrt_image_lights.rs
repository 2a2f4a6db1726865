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

fn render(name: &str, light: &str, image: &Image) -> Image {
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
