//! pbrt-v4's MIP-mapped texture filtering, driven by the camera's per-pixel footprint: a
//! plane seen at a grazing angle under a fine texel checkerboard (512², repeated 8 times).
//! Far away many texels fall in a pixel: trilinear and EWA lookups (and pbrt-v4's bilinear
//! one, which reads the level the footprint picks) average them, so 4 spp
//! renders vary far less from seed to seed than bilinear ones (under a directional light,
//! whose light sampling adds no noise of its own), while the image mean stays
//! that of bilinear lookups (within 1 %; filtering only moves where in the pixel the texture
//! is averaged). Fixed seeds; 8 renders each.

use build::{BuildOptions, render_desc};
use render::film::Image;
use render::image_io::write_image;
use render::math::Vec3;
use scene::{Texture, TextureFilter};

fn scene(dir: &std::path::Path) -> scene::SceneDesc {
    let n = 512u32;
    let mut img = Image::new(n, n);
    for y in 0..n {
        for x in 0..n {
            img.set(x, y, Vec3::splat(if (x + y) % 2 == 0 { 0.9 } else { 0.1 }));
        }
    }
    let path = dir.join("checker.exr");
    write_image(&path, &img).unwrap();
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0.6, 0" target="0, 0, 6" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/>
            <rfilter type="box"/></film>
    </sensor>
    <emitter type="directional">
        <vector name="direction" x="0" y="-1" z="0"/><rgb name="irradiance" value="3"/>
    </emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="20"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse">
            <texture name="reflectance" type="bitmap">
                <string name="filename" value="{}"/>
                <transform name="to_uv"><scale value="8"/></transform>
            </texture>
        </bsdf>
    </shape>
</scene>"#,
        path.display()
    );
    *scene::load_xml_text("mip", &xml).unwrap()
}

/// Mean of the image and mean over pixels of the variance between seeds.
fn stats(desc: &scene::SceneDesc, filter: TextureFilter, mipmapped: bool) -> (f64, f64) {
    let mut desc = desc.clone();
    for t in &mut desc.textures {
        if let Texture::Bitmap {
            filter: f,
            mipmapped: m,
            ..
        } = &mut t.texture
        {
            (*f, *m) = (filter, mipmapped);
        }
    }
    let images: Vec<Image> = (0..8)
        .map(|seed| {
            let opts = BuildOptions {
                spp: Some(4),
                seed: Some(40 + seed),
                ..Default::default()
            };
            render_desc(&desc, &opts).unwrap().film.develop()
        })
        .collect();
    let n = images[0].pixels.len();
    let (mut mean, mut var) = (0f64, 0f64);
    for i in 0..n {
        let v: Vec<f64> = images.iter().map(|im| im.pixels[i].x as f64).collect();
        let m = v.iter().sum::<f64>() / v.len() as f64;
        mean += m;
        var += v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
    }
    (mean / n as f64, var / n as f64)
}

#[test]
fn mip_filtering_averages_far_texels_and_keeps_the_mean() {
    let dir = std::env::temp_dir().join(format!("penumbra-mip-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let desc = scene(&dir);
    let (m_bi, v_bi) = stats(&desc, TextureFilter::Bilinear, false);
    // pbrt-v4's bilinear filter reads the level the footprint picks, too.
    for (filter, mipmapped) in [
        (TextureFilter::Trilinear, false),
        (TextureFilter::Ewa, false),
        (TextureFilter::Bilinear, true),
    ] {
        let (m, v) = stats(&desc, filter, mipmapped);
        println!(
            "{filter:?} (mipmapped {mipmapped}): mean {m:.4} (bilinear {m_bi:.4}), variance {v:.3e} (bilinear {v_bi:.3e})"
        );
        assert!(
            (m / m_bi - 1.0).abs() < 0.01,
            "{filter:?}: mean {m} vs {m_bi}"
        );
        assert!(
            v < 0.25 * v_bi,
            "{filter:?}: variance {v} vs bilinear {v_bi}"
        );
    }
}
