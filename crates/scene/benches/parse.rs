//! Scene parsing must be linear in the file size (issue 18): loads generated Mitsuba XML,
//! CENG795 JSON and XML, and COLLADA scenes of 16k, 64k and 256k shapes and prints the time
//! per shape; the ratio of the largest to the smallest must stay near 1 (it was ~16× per 4×
//! more shapes when every diagnostic position was found by scanning from the file start).
//!
//! Run with `cargo bench -p penumbra-scene --bench parse` (`-- 4096 16384` for other sizes).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

fn mitsuba(n: usize) -> String {
    let mut s = String::from("<scene version=\"3.0.0\">\n");
    for i in 0..n {
        let (x, y) = ((i % 512) as f32, (i / 512) as f32);
        writeln!(
            s,
            "  <shape type=\"sphere\" id=\"s{i}\">\n    <float name=\"radius\" value=\"0.25\"/>\n    \
             <transform name=\"to_world\"><translate x=\"{x}\" y=\"{y}\" z=\"0\"/></transform>\n  \
             </shape>"
        )
        .unwrap();
    }
    s.push_str("</scene>\n");
    s
}

fn ceng795_vertices(n: usize) -> String {
    let mut v = String::new();
    for i in 0..n {
        write!(v, "{} {} 0 ", i % 512, i / 512).unwrap();
    }
    v
}

const CENG_CAMERA_XML: &str = "<Cameras><Camera id=\"1\"><Position>0 0 10</Position>\
    <Gaze>0 0 -1</Gaze><Up>0 1 0</Up><NearPlane>-1 1 -1 1</NearPlane>\
    <NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>\
    <ImageName>x.png</ImageName></Camera></Cameras>";

fn ceng795_xml(n: usize) -> String {
    let mut s = format!(
        "<Scene>\n{CENG_CAMERA_XML}\n<Materials><Material id=\"1\">\
         <DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>\n\
         <VertexData>{}</VertexData>\n<Objects>\n",
        ceng795_vertices(n)
    );
    for i in 0..n {
        writeln!(
            s,
            "<Sphere id=\"{}\"><Material>1</Material><Center>{}</Center><Radius>0.25</Radius></Sphere>",
            i + 1,
            i + 1
        )
        .unwrap();
    }
    s.push_str("</Objects>\n</Scene>\n");
    s
}

fn ceng795_json(n: usize) -> String {
    let spheres: Vec<String> = (0..n)
        .map(|i| {
            format!(
                "{{\"_id\": \"{}\", \"Material\": \"1\", \"Center\": \"{}\", \"Radius\": \"0.25\"}}",
                i + 1,
                i + 1
            )
        })
        .collect();
    format!(
        "{{\"Scene\": {{\"Cameras\": {{\"Camera\": {{\"_id\": \"1\", \"Position\": \"0 0 10\", \
         \"Gaze\": \"0 0 -1\", \"Up\": \"0 1 0\", \"NearPlane\": \"-1 1 -1 1\", \
         \"NearDistance\": \"1\", \"ImageResolution\": \"8 8\", \"ImageName\": \"x.png\"}}}}, \
         \"Materials\": {{\"Material\": {{\"_id\": \"1\", \"DiffuseReflectance\": \"1 1 1\"}}}}, \
         \"VertexData\": {{\"_data\": \"{}\"}}, \"Objects\": {{\"Sphere\": [\n{}\n]}}}}}}",
        ceng795_vertices(n),
        spheres.join(",\n")
    )
}

fn collada(n: usize) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<COLLADA><asset><up_axis>Y_UP</up_axis></asset>\n\
         <library_geometries><geometry id=\"tri\"><mesh>\
         <source id=\"p\"><float_array id=\"pa\" count=\"9\">0 0 0 1 0 0 0 1 0</float_array>\
         <technique_common><accessor source=\"#pa\" count=\"3\" stride=\"3\"/></technique_common>\
         </source><vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices>\
         <triangles count=\"1\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>0 1 2</p>\
         </triangles></mesh></geometry></library_geometries>\n\
         <library_visual_scenes><visual_scene id=\"s\">\n",
    );
    for i in 0..n {
        writeln!(
            s,
            "<node id=\"n{i}\"><matrix>1 0 0 {} 0 1 0 {} 0 0 1 0 0 0 0 1</matrix>\
             <instance_geometry url=\"#tri\"/></node>",
            i % 512,
            i / 512
        )
        .unwrap();
    }
    s.push_str(
        "</visual_scene></library_visual_scenes>\n\
         <scene><instance_visual_scene url=\"#s\"/></scene></COLLADA>\n",
    );
    s
}

fn time_load(path: &Path) -> f64 {
    let t = Instant::now();
    match scene::load(path, &scene::LoadOptions::default()) {
        Ok(scene::Document::Scene(d)) => assert!(!d.shapes.is_empty()),
        Ok(_) => panic!("{}: not a scene", path.display()),
        Err(e) => panic!("{e}"),
    }
    t.elapsed().as_secs_f64()
}

fn main() {
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sizes = if sizes.is_empty() {
        vec![16_384, 65_536, 262_144]
    } else {
        sizes
    };
    let dir = std::env::temp_dir().join(format!("penumbra-parse-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp folder");
    type Gen = fn(usize) -> String;
    let formats: [(&str, &str, Gen); 4] = [
        ("Mitsuba XML", "xml", mitsuba),
        ("CENG795 XML", "xml", ceng795_xml),
        ("CENG795 JSON", "json", ceng795_json),
        ("COLLADA", "dae", collada),
    ];
    println!("format         shapes     MB    load s   µs/shape   ratio to smallest");
    for (name, ext, make) in formats {
        let mut first = None;
        for &n in &sizes {
            let path = dir.join(format!("scene-{n}.{ext}"));
            let text = make(n);
            std::fs::write(&path, &text).expect("write the scene");
            let secs = time_load(&path);
            let per = secs / n as f64 * 1e6;
            let base = *first.get_or_insert(per);
            println!(
                "{name:<14} {n:>7} {:>6.1} {secs:>9.3} {per:>10.2} {:>10.2}",
                text.len() as f64 / 1e6,
                per / base
            );
            let _ = std::fs::remove_file(&path);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
