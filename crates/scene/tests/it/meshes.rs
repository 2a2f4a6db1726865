//! OBJ and PLY readers: quirks, round trips, error locations, and every mesh shipped with the
//! shared test scenes.

use std::path::{Path, PathBuf};

use scene::formats::obj::{parse_obj, parse_obj_groups, read_obj};
use scene::formats::ply::{parse_ply, read_ply, write_ply};
use scene::{LoadError, TriMesh, Vec2, Vec3};

fn temp_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("penumbra-meshes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn obj(text: &str) -> TriMesh {
    parse_obj(text, Path::new("t.obj")).unwrap_or_else(|e| panic!("{e}"))
}

fn obj_err(text: &str) -> LoadError {
    match parse_obj(text, Path::new("t.obj")) {
        Ok(m) => panic!("expected an error, got {} triangles", m.triangle_count()),
        Err(e) => e,
    }
}

/// Assert an error's line and column and that its message contains `needle`.
#[track_caller]
fn assert_at(e: &LoadError, line: u32, col: u32, needle: &str) {
    assert_eq!((e.loc.line, e.loc.col), (line, col), "{e}");
    assert!(e.message.contains(needle), "'{e}' lacks '{needle}'");
}

/// Triangles as position triples, to compare meshes independently of vertex numbering.
fn triangles(m: &TriMesh) -> Vec<[Vec3; 3]> {
    m.indices
        .iter()
        .map(|t| t.map(|i| m.positions[i as usize]))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// OBJ

#[test]
fn obj_polygons_are_fan_triangulated() {
    let m = obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n");
    assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    assert_eq!(m.positions.len(), 5);
    assert!(m.normals.is_empty() && m.uvs.is_empty());
}

#[test]
fn obj_negative_indices_are_relative() {
    let m = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -4 -3 -1\n");
    assert_eq!(
        triangles(&m),
        vec![
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::ZERO, Vec3::X, Vec3::splat(5.0)]
        ]
    );
}

#[test]
fn obj_corner_forms_and_deduplication() {
    // Two triangles sharing an edge; the shared positions use the same normal but different
    // uvs on one corner, so exactly one position is duplicated.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
                vt 0 0\nvt 1 0\nvt 0 1 0.5\nvt 1 1\nvt 0.25 0.25\n\
                vn 0 0 1\n\
                f 1/1/1 2/2/1 3/3/1\n\
                f 2/2/1 4/4/1 3/5/1\n";
    let m = obj(text);
    assert_eq!(m.indices.len(), 2);
    assert_eq!(
        m.positions.len(),
        5,
        "(3, uv 3) and (3, uv 5) are distinct vertices"
    );
    assert_eq!(m.normals, vec![Vec3::Z; 5]);
    assert_eq!(m.uvs.len(), 5);
    assert_eq!(m.indices[0], [0, 1, 2]);
    assert_eq!(m.indices[1], [1, 3, 4]);
    assert_eq!(m.uvs[2], Vec2::new(0.0, 1.0), "third vt component ignored");
    assert_eq!(m.uvs[4], Vec2::new(0.25, 0.25));

    // `v//vn`: normals only.
    let m = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 -1\nf 1//1 2//1 3//2\n");
    assert_eq!(m.normals, vec![Vec3::Z, Vec3::Z, Vec3::NEG_Z]);
    assert!(m.uvs.is_empty());

    // `v/vt`: uvs only.
    let m = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.5\nf 1/1 2/1 3/1\n");
    assert_eq!(m.uvs, vec![Vec2::splat(0.5); 3]);
    assert!(m.normals.is_empty());
}

#[test]
fn obj_uv_reference_without_vt_lines_is_ignored() {
    // As in COMP30019's wolf.obj: `f v/vt` with no `vt` line anywhere.
    let m = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1477 2/169 3/119 \n");
    assert_eq!(m.indices, vec![[0, 1, 2]]);
    assert!(m.uvs.is_empty());
}

#[test]
fn obj_partial_attributes_are_dropped_for_the_whole_mesh() {
    // The second face has no normals: normals are dropped, and corners that only differed by
    // normal merge back into one vertex per position.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvn 1 0 0\n\
                f 1//1 2//1 3//1\nf 2//2 4//2 3//2\nf 1 2 4\n";
    let m = obj(text);
    assert!(m.normals.is_empty());
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.indices, vec![[0, 1, 2], [1, 3, 2], [0, 1, 3]]);
}

#[test]
fn obj_whitespace_comments_and_ignored_keywords() {
    let text = "# header comment\r\n\
                mtllib scene.mtl\r\n\
                o thing\r\n\
                g group one\r\n\
                s off\r\n\
                usemtl red # trailing comment\r\n\
                v\t0 0 0\t1.0 0.5 0.2 0.1\r\n\
                v  1 0 0 # comment\r\n\
                \tv 0 1 0\r\n\
                \r\n\
                weird keyword 1 2 3\r\n\
                l 1 2\r\n\
                f 1 2 3 # a triangle\r\n\
                f\t1\t2\t3\t\r\n";
    let m = obj(text);
    assert_eq!(m.indices, vec![[0, 1, 2], [0, 1, 2]]);
    assert_eq!(m.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
}

#[test]
fn obj_material_per_triangle() {
    let text = "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
                f 1 2 3\nusemtl red\nf 1 2 3 4\nusemtl  light blue \nf 1 2 3\nusemtl red\nf 2 4 3\n";
    let o = parse_obj_groups(text, Path::new("m.obj")).unwrap();
    assert_eq!(o.mtllibs.len(), 1);
    assert_eq!(o.mtllibs[0].name, "a.mtl");
    let names: Vec<&str> = o.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["red", "light blue"]);
    assert_eq!(o.materials[0].loc.line, 7);
    assert_eq!(
        o.triangle_materials,
        vec![None, Some(0), Some(0), Some(1), Some(0)]
    );
    assert_eq!(o.triangle_materials.len(), o.mesh.triangle_count());
}

#[test]
fn obj_errors_are_located() {
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    assert_at(
        &obj_err(&format!("{tri}f 1 2 4\n")),
        4,
        7,
        "vertex index 4 out of range",
    );
    assert_at(&obj_err(&format!("{tri}f 1 2 -4\n")), 4, 7, "out of range");
    assert_at(&obj_err(&format!("{tri}f 1 0 2\n")), 4, 5, "index 0");
    assert_at(
        &obj_err(&format!("{tri}vt 0 0\nf 1/1 2/2 3/1\n")),
        5,
        9,
        "texture coordinate index 2",
    );
    assert_at(
        &obj_err(&format!("{tri}vn 0 0 1\nf 1//1 2//1 3//3\n")),
        5,
        16,
        "normal index 3",
    );
    assert_at(&obj_err("v 0 nan 0\n"), 1, 5, "not a finite");
    assert_at(&obj_err("v 0 0 inf\n"), 1, 7, "not a finite");
    assert_at(
        &obj_err("# big\nv 1e39 0 0\n"),
        2,
        3,
        "'1e39' is not a finite",
    );
    assert_at(&obj_err("vn 0 0 -1e40\n"), 1, 8, "not a finite");
    assert_at(&obj_err("v 0 0,5 0\n"), 1, 5, "invalid number '0,5'");
    assert_at(&obj_err("v 0 0\n"), 1, 6, "needs 3 numbers, found 2");
    assert_at(
        &obj_err(&format!("{tri}f 1 2\n")),
        4,
        1,
        "face has 2 vertices",
    );
    assert_at(
        &obj_err(&format!("{tri}  f\n")),
        4,
        3,
        "face has 0 vertices",
    );
    assert_at(
        &obj_err(&format!("{tri}f 1 2 x\n")),
        4,
        7,
        "invalid vertex index 'x'",
    );
    assert_at(
        &obj_err(&format!("{tri}f 1 2 3/1/1/1\n")),
        4,
        7,
        "more than three",
    );
    assert_at(&obj_err("v 0 \u{e9} 0\n"), 1, 5, "invalid number '\u{e9}'");
    let e = obj_err(&format!("{tri}f 1 2 9\n"));
    assert_eq!(
        e.to_string(),
        "t.obj:4:7: vertex index 9 out of range (3 defined so far)"
    );
}

#[test]
fn obj_corrupted_text_never_panics() {
    let base = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n\
                f 1/1/1 2/2/1 3/1/1 4/2/1\nf -1//1 -2//1 -3//1\nusemtl x\nf 1/2 2/1 4/1\n";
    let alphabet = b"0123456789 /-.#\t\nvtnfe";
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut loaded = 0;
    for _ in 0..2000 {
        let mut data = base.as_bytes().to_vec();
        for _ in 0..1 + next() % 3 {
            let at = (next() % data.len() as u64) as usize;
            data[at] = alphabet[(next() % alphabet.len() as u64) as usize];
        }
        let text = String::from_utf8(data).unwrap();
        if let Ok(m) = parse_obj(&text, Path::new("t.obj")) {
            let n = m.positions.len();
            assert!(m.indices.iter().flatten().all(|&i| (i as usize) < n));
            loaded += 1;
        }
    }
    assert!(loaded > 0);
}

#[test]
fn obj_read_from_file_and_missing_file() {
    let path = temp_path("quad.obj");
    std::fs::write(
        &path,
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n# caf\xe9 latin-1\nf 1 2 3 4\n",
    )
    .unwrap();
    assert_eq!(read_obj(&path).unwrap().triangle_count(), 2);
    let missing = temp_path("does-not-exist.obj");
    let e = read_obj(&missing).unwrap_err();
    assert_eq!(e.loc.line, 0);
    assert!(e.to_string().starts_with(&missing.display().to_string()));
}

// ---------------------------------------------------------------------------------------------
// PLY

fn ply_err(data: &[u8]) -> LoadError {
    match parse_ply(data, Path::new("t.ply")) {
        Ok(m) => panic!("expected an error, got {} triangles", m.triangle_count()),
        Err(e) => e,
    }
}

fn ply(data: &[u8]) -> TriMesh {
    parse_ply(data, Path::new("t.ply")).unwrap_or_else(|e| panic!("{e}"))
}

/// A small mesh with every attribute: a unit square split in two plus a lone triangle.
fn sample_mesh() -> TriMesh {
    TriMesh {
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-0.5, 0.25, 3.0e-7),
        ],
        normals: vec![Vec3::Z, Vec3::Z, Vec3::Z, Vec3::Z, Vec3::new(0.6, 0.0, 0.8)],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.125, -2.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3], [3, 4, 0]],
    }
}

#[test]
fn ply_round_trip() {
    let full = sample_mesh();
    let cases = [
        ("full.ply", full.clone()),
        (
            "positions.ply",
            TriMesh {
                normals: vec![],
                uvs: vec![],
                ..full.clone()
            },
        ),
        (
            "uvs.ply",
            TriMesh {
                normals: vec![],
                ..full.clone()
            },
        ),
        ("empty.ply", TriMesh::default()),
    ];
    for (name, mesh) in cases {
        let path = temp_path(name);
        write_ply(&path, &mesh).unwrap();
        assert_eq!(read_ply(&path).unwrap(), mesh, "{name}");
    }
    let bad = TriMesh {
        indices: vec![[0, 1, 9]],
        ..full
    };
    assert!(write_ply(&temp_path("bad.ply"), &bad).is_err());
}

#[test]
fn ply_ascii_with_extras() {
    // Double coordinates, colours, s/t uvs, an edge element, a quad, a face flag, a comment,
    // and values spread over lines in an unusual way.
    let text = "ply\nformat ascii 1.0\ncomment hello\nobj_info x\n\
                element vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
                property uchar red\nproperty float s\nproperty float t\n\
                element edge 1\nproperty int vertex1\nproperty int vertex2\n\
                element face 2\nproperty uchar flags\nproperty list uchar int vertex_index\n\
                property list uchar float texcoord\n\
                end_header\n\
                0 0 0 255 0 0\n1 0 0 0 1 0\n1 1 0 0 1 1\n0 1 0 7 0 1\n\
                0 1\n\
                1 4 0 1 2 3 0\n\
                0 3 3 2\n1 6 0 0 0 0 0 0\n";
    let m = ply(text.as_bytes());
    assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
    assert_eq!(m.uvs[2], Vec2::new(1.0, 1.0));
    assert!(m.normals.is_empty());
    assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
}

#[test]
fn ply_uv_name_variants() {
    for (u, v) in [
        ("u", "v"),
        ("s", "t"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ] {
        let text = format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nproperty float {u}\nproperty float {v}\nelement face 1\n\
             property list uchar uint vertex_indices\nend_header\n\
             0 0 0 0.5 0.25\n1 0 0 0 0\n0 1 0 0 0\n3 0 1 2\n"
        );
        let m = ply(text.as_bytes());
        assert_eq!(m.uvs[0], Vec2::new(0.5, 0.25), "{u} {v}");
    }
}

/// A hand-built binary PLY: header text plus body bytes.
struct Bin {
    big: bool,
    body: Vec<u8>,
}

impl Bin {
    fn f32(&mut self, v: f32) -> &mut Self {
        self.body.extend_from_slice(&if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
        self
    }
    fn f64(&mut self, v: f64) -> &mut Self {
        self.body.extend_from_slice(&if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
        self
    }
    fn u8(&mut self, v: u8) -> &mut Self {
        self.body.push(v);
        self
    }
    fn u16(&mut self, v: u16) -> &mut Self {
        self.body.extend_from_slice(&if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
        self
    }
    fn i16(&mut self, v: i16) -> &mut Self {
        self.body.extend_from_slice(&if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
        self
    }
    fn u32(&mut self, v: u32) -> &mut Self {
        self.body.extend_from_slice(&if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
        self
    }
    fn i32(&mut self, v: i32) -> &mut Self {
        self.body.extend_from_slice(&if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
        self
    }
}

/// A big- or little-endian file exercising the generic binary paths: a variable-size vertex
/// (with a list property), mixed scalar types, a custom element with lists before the faces,
/// a face element with an extra property and a ushort count.
fn mixed_binary(big: bool) -> Vec<u8> {
    let format = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let header = format!(
        "ply\nformat {format} 1.0\nelement vertex 4\nproperty double x\nproperty float y\n\
         property int16 z\nproperty list uint8 float32 weights\nproperty float nx\n\
         property float ny\nproperty float nz\nproperty uchar alpha\n\
         element material 2\nproperty list int uchar name\nproperty float roughness\n\
         element face 2\nproperty list ushort uint32 vertex_indices\nproperty short flags\n\
         end_header\n"
    );
    let mut b = Bin {
        big,
        body: header.into_bytes(),
    };
    for (i, &(x, y, z)) in [(0.0, 0.0, 0), (1.0, 0.0, 0), (1.0, 1.0, 0), (0.0, 1.0, -2)]
        .iter()
        .enumerate()
    {
        b.f64(x).f32(y as f32).i16(z);
        b.u8(i as u8);
        for k in 0..i {
            b.f32(k as f32);
        }
        b.f32(0.0).f32(0.0).f32(1.0).u8(255);
    }
    b.i32(3).u8(b'a').u8(b'b').u8(b'c').f32(0.5);
    b.i32(0).f32(0.25);
    b.u16(4).u32(0).u32(1).u32(2).u32(3).i16(-1);
    b.u16(3).u32(3).u32(2).u32(1).i16(7);
    b.body
}

#[test]
fn ply_binary_generic_paths_both_endiannesses() {
    for big in [false, true] {
        let data = mixed_binary(big);
        let path = temp_path(if big { "mixed_be.ply" } else { "mixed_le.ply" });
        std::fs::write(&path, &data).unwrap();
        let m = read_ply(&path).unwrap();
        assert_eq!(
            m.indices,
            vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]],
            "big={big}"
        );
        assert_eq!(m.positions[3], Vec3::new(0.0, 1.0, -2.0));
        assert_eq!(m.normals, vec![Vec3::Z; 4]);
        assert!(m.uvs.is_empty());
    }
}

/// A fixed-size vertex layout with the triangle fast path and a polygon in the middle.
fn fast_binary(big: bool, faces: &[&[u32]]) -> Vec<u8> {
    let format = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let header = format!(
        "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nproperty uchar red\nproperty float u\nproperty float v\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        faces.len()
    );
    let mut b = Bin {
        big,
        body: header.into_bytes(),
    };
    for (i, p) in [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
        .iter()
        .enumerate()
    {
        b.f32(p[0])
            .f32(p[1])
            .f32(0.0)
            .u8(9)
            .f32(i as f32)
            .f32(-(i as f32));
    }
    for f in faces {
        b.u8(f.len() as u8);
        for &i in *f {
            b.u32(i);
        }
    }
    b.body
}

#[test]
fn ply_binary_fast_paths_both_endiannesses() {
    for big in [false, true] {
        let m = ply(&fast_binary(big, &[&[0, 1, 2], &[0, 1, 2, 3], &[3, 2, 1]]));
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 1, 2], [0, 2, 3], [3, 2, 1]]);
        assert_eq!(m.uvs[3], Vec2::new(3.0, -3.0));
        assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
    }
}

#[test]
fn ply_index_errors() {
    for big in [false, true] {
        let e = ply_err(&fast_binary(big, &[&[0, 1, 2], &[0, 4, 2]]));
        assert!(
            e.message.contains("face 1: vertex index 4 out of range"),
            "{e}"
        );
        assert!(e.message.contains("byte offset"), "{e}");
        assert_eq!(e.loc.line, 0);
        let e = ply_err(&fast_binary(big, &[&[0, 1, 2], &[0, 1, 2, u32::MAX]]));
        assert!(e.message.contains("vertex index -1 out of range"), "{e}");
        let e = ply_err(&fast_binary(big, &[&[0, 1, u32::MAX]]));
        assert!(e.message.contains("vertex index -1 out of range"), "{e}");
        let e = ply_err(&fast_binary(big, &[&[0, 1]]));
        assert!(e.message.contains("face 0: face has 2 vertices"), "{e}");
    }
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                end_header\n0 0 0\n1 0 0\n0 1 0\n3 0  1 3\n";
    let e = ply_err(text.as_bytes());
    assert_at(&e, 13, 8, "vertex index 3 out of range");
}

#[test]
fn ply_non_finite_values() {
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                end_header\n";
    for bad in ["nan", "inf", "1e39", "-1e300"] {
        let text = format!("{head}0 0 0\n1 {bad} 0\n0 1 0\n3 0 1 2\n");
        let e = ply_err(text.as_bytes());
        assert_at(&e, 11, 3, "vertex 1: property 'y' is not a finite");
    }
    let mut data = fast_binary(false, &[&[0, 1, 2]]);
    let header_len = data.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // Vertex 2's y (stride 21 bytes, y at offset 4).
    data[header_len + 2 * 21 + 4..][..4].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = ply_err(&data);
    assert!(
        e.message.contains("vertex 2: the position is not finite"),
        "{e}"
    );
    assert!(
        e.message
            .contains(&format!("byte offset {}", header_len + 42)),
        "{e}"
    );
}

#[test]
fn ply_every_truncation_is_an_error() {
    for data in [
        mixed_binary(false),
        mixed_binary(true),
        fast_binary(false, &[&[0, 1, 2], &[0, 1, 2, 3]]),
    ] {
        let header_len = data.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        for len in 0..data.len() {
            let e = parse_ply(&data[..len], Path::new("t.ply"));
            assert!(e.is_err(), "prefix of {len} bytes loaded");
            if len > header_len {
                let e = e.unwrap_err();
                assert!(e.message.contains("truncated"), "{len}: {e}");
            }
        }
    }
}

#[test]
fn ply_corrupted_bytes_never_panic() {
    // Deterministic byte overwrites (xorshift); every outcome is fine except a panic or a hang.
    let ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                 property float z\nproperty list uchar float w\nelement face 2\n\
                 property list uchar int vertex_indices\nend_header\n\
                 0 0 0 0\n1 0 0 1 5\n1 1 0 0\n0 1 0 2 1 1\n4 0 1 2 3\n3 2 1 0\n";
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for base in [
        mixed_binary(false),
        mixed_binary(true),
        fast_binary(false, &[&[0, 1, 2], &[0, 1, 2, 3], &[3, 2, 1]]),
        ascii.as_bytes().to_vec(),
    ] {
        let mut loaded = 0;
        for _ in 0..1000 {
            let mut data = base.clone();
            for _ in 0..1 + next() % 4 {
                let at = (next() % data.len() as u64) as usize;
                data[at] = next() as u8;
            }
            if parse_ply(&data, Path::new("t.ply")).is_ok() {
                loaded += 1;
            }
        }
        // Overwrites of bytes that do not matter (unused values) leave loadable files.
        assert!(loaded > 0);
    }
}

#[test]
fn ply_lying_header_counts() {
    // Billions of vertices and faces announced, a few bytes delivered: a prompt error, no
    // giant allocation.
    for (v, f) in [
        ("4000000000", "1"),
        ("3", "18446744073709551615"),
        ("100", "100"),
    ] {
        let mut data = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {v}\nproperty float x\n\
             property float y\nproperty float z\nelement face {f}\n\
             property list uchar int vertex_indices\nend_header\n"
        )
        .into_bytes();
        for x in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            data.extend_from_slice(&x.to_le_bytes());
        }
        data.push(3);
        for i in [0u32, 1, 2] {
            data.extend_from_slice(&i.to_le_bytes());
        }
        let e = ply_err(&data);
        assert!(
            e.message.contains("truncated") || e.message.contains("too many"),
            "{e}"
        );
    }
    // The same for ascii.
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 99999999999\n\
                property list uchar int vertex_indices\nend_header\n\
                0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let e = ply_err(text.as_bytes());
    assert!(e.message.contains("face 1: unexpected end of file"), "{e}");
    // Property-less elements take no space whatever their count (and must not be looped over).
    let text = "ply\nformat ascii 1.0\nelement nothing 18446744073709551615\nend_header\n";
    assert_eq!(ply(text.as_bytes()).triangle_count(), 0);
    // A list length far beyond the file.
    let text = b"ply\nformat binary_little_endian 1.0\nelement junk 1\n\
                property list int float values\nend_header\n\xff\xff\xff\x7f";
    assert!(ply_err(text).message.contains("truncated"));
}

#[test]
fn ply_header_errors() {
    let cases: [(&str, u32, &str); 8] = [
        ("plx\n", 1, "not a PLY file"),
        (
            "ply\nformat binary_middle_endian 1.0\nend_header\n",
            2,
            "unknown PLY format",
        ),
        (
            "ply\nformat ascii 2.0\nend_header\n",
            2,
            "unsupported PLY version",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n",
            3,
            "invalid element count",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\nend_header\n",
            4,
            "not an integer",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nend_header\n",
            3,
            "lacks scalar x, y and z",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar float vertex_indices\nend_header\n",
            7,
            "not a list of integers",
        ),
        (
            "ply\nformat ascii 1.0\nbogus\nend_header\n",
            3,
            "unknown PLY header keyword",
        ),
    ];
    for (text, line, needle) in cases {
        let e = ply_err(text.as_bytes());
        assert_eq!(e.loc.line, line, "{e}");
        assert!(e.message.contains(needle), "'{e}' lacks '{needle}'");
    }
    assert!(
        ply_err(b"ply\nelement vertex 0\nend_header\n")
            .message
            .contains("no 'format'")
    );
}

#[test]
fn ply_without_faces_is_an_empty_mesh() {
    let text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                property float z\nend_header\n0 0 0\n1 1 1\n";
    let m = ply(text.as_bytes());
    assert_eq!(m.positions.len(), 2);
    assert_eq!(m.triangle_count(), 0);
}

// ---------------------------------------------------------------------------------------------
// Real files

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            walk(&path, out);
        } else {
            out.push(path);
        }
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

#[test]
fn every_shared_scene_mesh_loads() {
    let root = std::env::var_os("PENUMBRA_SCENES")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/work/shared/scenes"));
    if !root.is_dir() {
        println!("skipped: {} is absent", root.display());
        return;
    }
    let mut files = Vec::new();
    walk(&root, &mut files);
    files.sort();
    let mut failures = Vec::new();
    let mut count = 0;
    for path in files {
        let result = match extension(&path).as_str() {
            "obj" => read_obj(&path),
            "ply" => read_ply(&path),
            _ => continue,
        };
        count += 1;
        match result {
            Ok(m) if m.triangle_count() > 0 => {
                let n = m.positions.len();
                assert!(
                    m.normals.is_empty() || m.normals.len() == n,
                    "{}",
                    path.display()
                );
                assert!(m.uvs.is_empty() || m.uvs.len() == n, "{}", path.display());
                assert!(m.indices.iter().flatten().all(|&i| (i as usize) < n));
            }
            Ok(_) => failures.push(format!("{}: no triangles", path.display())),
            Err(e) => failures.push(e.to_string()),
        }
    }
    println!("{count} meshes checked under {}", root.display());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn malformed_cli_fixtures_fail_to_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cli/tests/malformed");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            name.starts_with("mesh_") && name.ends_with(".xml")
        })
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 7, "{} mesh fixtures", scenes.len());
    for scene in scenes {
        let xml = std::fs::read_to_string(&scene).unwrap();
        let doc = roxmltree::Document::parse(&xml).unwrap();
        let shape = doc.descendants().find(|n| n.has_tag_name("shape")).unwrap();
        let file = shape
            .descendants()
            .find(|n| n.attribute("name") == Some("filename"))
            .and_then(|n| n.attribute("value"))
            .unwrap();
        assert!(!file.ends_with(".xml"));
        let mesh = dir.join(file);
        let result = match shape.attribute("type") {
            Some("obj") => read_obj(&mesh),
            Some("ply") => read_ply(&mesh),
            other => panic!("{}: shape type {other:?}", scene.display()),
        };
        let e = result.expect_err(&format!("{} loaded", mesh.display()));
        println!("{}: {e}", scene.display());
        let text = e.to_string();
        assert!(text.starts_with(&mesh.display().to_string()), "{text}");
        if extension(&mesh) == "obj" && mesh.exists() {
            assert!(e.loc.line > 0 && e.loc.col > 0, "{text}");
        }
    }
}
