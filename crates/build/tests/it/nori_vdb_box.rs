//! Nori's heterogeneous media are placed by a user-given bounding box (the extended-Nori
//! write-up): the grid's active voxels fill `bboxMin`..`bboxMax`, whatever the file's own
//! placement. `plume.vdb` holds the voxels of `plume-density.vol`, inactive where they are 0,
//! so its active box is the `.vol`'s voxels [1, 63] × [0, 63] × [0, 61]: a point of the
//! `.vdb` medium must read what the `.vol` medium (same box) reads at the point the `.vol`'s
//! placement gives that voxel position.

use base::testing::shared_dir;
use build::{BuildOptions, build};
use render::geometry::Ray;
use render::math::Vec3;
use render::media::MediumKind;

fn medium(dir: &std::path::Path, file: &str) -> render::media::Heterogeneous {
    let xml = format!(
        r#"<scene>
    <integrator type="volpath"/>
    <camera type="perspective"><integer name="width" value="4"/><integer name="height" value="4"/></camera>
    <mesh type="sphere">
        <point name="center" value="0, 1, 0"/><float name="radius" value="3"/>
        <bsdf type="null"/>
        <medium type="heterogeneous">
            <string name="filename" value="{}"/>
            <point name="bboxMin" value="-1, 0, -2"/>
            <point name="bboxMax" value="1, 4, 2"/>
        </medium>
    </mesh>
</scene>"#,
        dir.join(file).display()
    );
    let desc = scene::load_xml_text(&format!("nori-box-{file}"), &xml).unwrap();
    let built = build(&desc, &BuildOptions::default()).unwrap();
    match &built.scene.media[0].kind {
        MediumKind::Heterogeneous(h) => (**h).clone(),
        k => panic!("{k:?}"),
    }
}

#[test]
fn a_vdb_grid_fills_the_nori_bounding_box_as_the_vol_grid_does() {
    let Some(dir) = shared_dir("references/scenes") else {
        return;
    };
    let (vol, vdb) = (medium(&dir, "plume-density.vol"), medium(&dir, "plume.vdb"));
    let (lo_box, hi_box) = (Vec3::new(-1.0, 0.0, -2.0), Vec3::new(1.0, 4.0, 2.0));
    // The active box in the .vol's [0,1]³, and its size in voxels.
    let (a, b) = (
        Vec3::new(1.0, 0.0, 0.0) / 64.0,
        Vec3::new(64.0, 64.0, 62.0) / 64.0,
    );
    let n = (b - a) * 64.0;
    let at =
        |m: &render::media::Heterogeneous, p: Vec3| m.sigma_t_along(&Ray::new(p, Vec3::X), 0.0);
    let mut nonzero = 0;
    for i in 0..20_000u32 {
        // Quasi-random points between the active box's outermost voxel centres (where a
        // trilinear lookup of the dense box and of the full grid see the same voxels).
        let r = |k: u32| {
            ((i as f64 + 0.5) * [0.7548776662, 0.5698402910, 0.4301597090][k as usize]).fract()
                as f32
        };
        let u = Vec3::new(r(0), r(1), r(2));
        let u = (Vec3::splat(0.5) + u * (n - Vec3::ONE)) / n;
        let p = lo_box + u * (hi_box - lo_box);
        let q = lo_box + (a + u * (b - a)) * (hi_box - lo_box);
        let (want, got) = (at(&vol, q), at(&vdb, p));
        assert!(
            (want - got).abs() <= 1e-4 * (1.0 + want.abs()),
            "{got} vs {want} at {p}"
        );
        nonzero += usize::from(want > 0.0);
    }
    assert!(
        nonzero > 1000,
        "the points cross the plume ({nonzero} inside)"
    );
}
