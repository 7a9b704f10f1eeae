//! PLY reader: ascii and both binary byte orders, every scalar type,
//! properties and elements that must be skipped, strips, located errors.

use std::path::Path;

use lodgen::io::{read_ply, read_scene, ErrorKind, Location, ReadError};
use lodgen::scene::{Primitive, Scene};

fn ply(bytes: &[u8]) -> Scene {
    read_ply(bytes, Path::new("t.ply")).unwrap_or_else(|e| panic!("{e}"))
}

fn ply_err(bytes: &[u8]) -> ReadError {
    match read_ply(bytes, Path::new("bad.ply")) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

fn prim(s: &Scene) -> &Primitive {
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.meshes[0].primitives.len(), 1);
    &s.meshes[0].primitives[0]
}

/// Appends `v` encoded as PLY type `ty`.
fn put(out: &mut Vec<u8>, ty: &str, v: f64, big: bool) {
    let mut b: Vec<u8> = match ty {
        "char" | "int8" => vec![v as i8 as u8],
        "uchar" | "uint8" => vec![v as u8],
        "short" | "int16" => (v as i16).to_le_bytes().to_vec(),
        "ushort" | "uint16" => (v as u16).to_le_bytes().to_vec(),
        "int" | "int32" => (v as i32).to_le_bytes().to_vec(),
        "uint" | "uint32" => (v as u32).to_le_bytes().to_vec(),
        "float" | "float32" => (v as f32).to_le_bytes().to_vec(),
        "double" | "float64" => v.to_le_bytes().to_vec(),
        _ => panic!("type {ty}"),
    };
    if big {
        b.reverse();
    }
    out.extend_from_slice(&b);
}

/// The expected mesh of the binary tests: a unit quad (two triangles) with
/// normals and texture coordinates.
const QUAD: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];

/// A binary PLY with types chosen to exercise every scalar type, an
/// element before `vertex`, per-vertex properties and lists to skip, a
/// face list to skip and a trailing unknown element.
fn binary_quad(big: bool) -> Vec<u8> {
    let format = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let header = format!(
        "ply\nformat {format} 1.0\ncomment made by a test\nobj_info x\n\
         element camera 2\nproperty double view_x\nproperty list uint8 int16 junk\n\
         element vertex 4\nproperty float x\nproperty double y\nproperty int16 z\n\
         property uchar red\nproperty list ushort uint flags\nproperty char nx\nproperty int8 ny\nproperty float nz\n\
         property float32 texture_u\nproperty float64 texture_v\nproperty uint32 confidence\n\
         element face 1\nproperty list uchar int vertex_indices\nproperty list int float junk_list\n\
         element edge 1\nproperty int vertex1\nproperty uint16 vertex2\n\
         end_header\n"
    );
    let mut out = header.into_bytes();
    for c in 0..2 {
        put(&mut out, "double", c as f64, big);
        put(&mut out, "uint8", 2.0, big);
        put(&mut out, "int16", -1.0, big);
        put(&mut out, "int16", -2.0, big);
    }
    for (i, p) in QUAD.iter().enumerate() {
        put(&mut out, "float", p[0], big);
        put(&mut out, "double", p[1], big);
        put(&mut out, "int16", p[2], big);
        put(&mut out, "uchar", 200.0, big);
        put(&mut out, "ushort", 3.0, big);
        for k in 0..3 {
            put(&mut out, "uint", k as f64, big);
        }
        put(&mut out, "char", 0.0, big);
        put(&mut out, "int8", -1.0, big);
        put(&mut out, "float", 0.0, big);
        put(&mut out, "float32", p[0], big);
        put(&mut out, "float64", p[1], big);
        put(&mut out, "uint32", i as f64, big);
    }
    put(&mut out, "uchar", 4.0, big);
    for i in 0..4 {
        put(&mut out, "int", i as f64, big);
    }
    put(&mut out, "int", 2.0, big);
    put(&mut out, "float", 9.0, big);
    put(&mut out, "float", 9.0, big);
    put(&mut out, "int", 0.0, big);
    put(&mut out, "uint16", 1.0, big);
    out
}

fn check_quad(s: &Scene) {
    let p = prim(s);
    let expected: Vec<[f32; 3]> = QUAD.iter().map(|q| q.map(|x| x as f32)).collect();
    assert_eq!(p.positions, expected);
    assert_eq!(p.indices, vec![0, 1, 2, 0, 2, 3]);
    assert_eq!(p.normals.as_deref(), Some(&[[0.0, -1.0, 0.0]; 4][..]));
    // v is flipped to glTF's convention.
    let uv: Vec<[f32; 2]> = QUAD
        .iter()
        .map(|q| [q[0] as f32, 1.0 - q[1] as f32])
        .collect();
    assert_eq!(p.texcoords.as_deref(), Some(&uv[..]));
    assert_eq!(s.meshes[0].name, "t");
}

#[test]
fn binary_little_endian() {
    check_quad(&ply(&binary_quad(false)));
}

#[test]
fn binary_big_endian() {
    check_quad(&ply(&binary_quad(true)));
}

#[test]
fn ascii_with_skipped_properties_and_elements() {
    let text = "ply\r\nformat ascii 1.0\r\ncomment hi\r\n\
        element vertex 5\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n\
        property float confidence\r\nproperty list uchar int neighbours\r\n\
        property float nx\r\nproperty float ny\r\nproperty float nz\r\nproperty float s\r\nproperty float t\r\n\
        element face 2\r\nproperty list uchar uint vertex_index\r\nproperty uchar flags\r\n\
        element material 1\r\nproperty float shininess\r\n\
        end_header\r\n\
        0 0 0 0.5 2 1 2 0 0 1 0 0\r\n\
        1 0 0 0.5 0 0 0 1 1 0\r\n\
        \r\n\
        1 1 0 0.5 1 4 0 0 1 1 1\r\n\
        9 9 9 0.5 0 0 0 1 0.5 0.5\r\n\
        0 1 0 0.5 0 0 0 1 0 1\r\n\
        4 0 1 2 4 7\r\n\
        3 4 2 0 7\r\n\
        0.25\r\n";
    let s = ply(text.as_bytes());
    let p = prim(&s);
    // Vertex 3 (9 9 9) is unused and dropped; numbering by first use.
    assert_eq!(
        p.positions,
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0]
        ]
    );
    assert_eq!(p.indices, vec![0, 1, 2, 0, 2, 3, 3, 2, 0]);
    assert_eq!(
        p.texcoords.as_deref(),
        Some(&[[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]][..])
    );
    assert_eq!(p.normals.as_deref(), Some(&[[0.0, 0.0, 1.0]; 4][..]));
}

#[test]
fn tristrips_with_restarts() {
    let text = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
        element tristrips 1\nproperty list int int vertex_indices\nend_header\n\
        0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 2 0\n\
        8 0 1 2 3 -1 2 3 4\n";
    let p = prim(&ply(text.as_bytes())).clone();
    assert_eq!(p.indices, vec![0, 1, 2, 1, 3, 2, 2, 3, 4]);
}

#[test]
fn read_scene_sniffs_the_ply_header() {
    let path = std::env::temp_dir().join(format!("lodgen-io-ply-{}.dat", std::process::id()));
    std::fs::write(&path, binary_quad(false)).unwrap();
    let s = read_scene(&path);
    std::fs::remove_file(&path).unwrap();
    check_quad_positions(&s.unwrap());
}

fn check_quad_positions(s: &Scene) {
    assert_eq!(prim(s).positions.len(), 4);
    assert_eq!(prim(s).triangle_count(), 2);
}

#[test]
fn truncated_binary_names_the_element() {
    let full = binary_quad(false);
    // Cut inside the face list: 4 bytes of the edge, 10 of the face's junk
    // list and 2 of its last index.
    let e = ply_err(&full[..full.len() - 6 - 13 - 2]);
    assert_eq!(
        e.location,
        Location::Element {
            element: "face".to_owned(),
            index: 0
        }
    );
    assert!(matches!(*e.kind, ErrorKind::Truncated(_)), "{e}");
    assert!(
        e.to_string()
            .starts_with("bad.ply: face 0: file ends early"),
        "{e}"
    );
    // Cut inside the vertices.
    let e = ply_err(&full[..full.len() - 60]);
    assert!(
        matches!(&e.location, Location::Element { element, index: 3 } if element == "vertex"),
        "{e}"
    );
}

#[test]
fn binary_index_out_of_range_names_the_face() {
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
        element face 2\nproperty list uchar int vertex_indices\nend_header\n";
    let mut out = header.as_bytes().to_vec();
    for v in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            put(&mut out, "float", x, false);
        }
    }
    for face in [[0, 1, 2], [0, 1, 3]] {
        put(&mut out, "uchar", 3.0, false);
        for i in face {
            put(&mut out, "int", i as f64, false);
        }
    }
    let e = ply_err(&out);
    assert_eq!(
        e.to_string(),
        "bad.ply: face 1: face refers to vertex 3, but only 3 are defined"
    );
}

#[test]
fn binary_nan_names_the_vertex() {
    let header = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
        element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let mut out = header.as_bytes().to_vec();
    for v in [[0.0, 0.0, 0.0], [1.0, f64::NAN, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            put(&mut out, "float", x, true);
        }
    }
    put(&mut out, "uchar", 3.0, true);
    for i in 0..3 {
        put(&mut out, "int", i as f64, true);
    }
    let e = ply_err(&out);
    assert_eq!(
        e.location,
        Location::Element {
            element: "vertex".to_owned(),
            index: 1
        }
    );
    assert!(matches!(*e.kind, ErrorKind::NonFinite { .. }), "{e}");
}

/// A vertex no face uses may be invalid (NaN or infinite: a range scan's missing pixels,
/// often its first ones): it is left out with the other unused vertices, in ascii and
/// binary. Only a used one fails the file (`binary_nan_names_the_vertex`).
#[test]
fn an_invalid_vertex_no_face_uses_is_left_out() {
    let head = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let text = format!(
        "{}nan nan nan\n0 0 0\n1 0 0\n0 1 0\n3 1 2 3\n",
        head("ascii")
    );
    let p = prim(&ply(text.as_bytes())).clone();
    assert_eq!(
        p.positions,
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    );
    assert_eq!(p.indices, [0, 1, 2]);
    let mut bin = head("binary_little_endian").into_bytes();
    for v in [[f64::NAN; 3], [0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            put(&mut bin, "float", x, false);
        }
    }
    put(&mut bin, "uchar", 3.0, false);
    for i in 1..4 {
        put(&mut bin, "int", i as f64, false);
    }
    assert_eq!(prim(&ply(&bin)).positions, p.positions);
}

/// Data after the last element the header declares (a face count too small) is a warning,
/// in ascii and binary: its faces were dropped without a word.
#[test]
fn data_after_the_declared_elements_is_a_warning() {
    let text = format!("{ASCII_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n");
    let w = &ply(text.as_bytes()).warnings;
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].message.starts_with("1 line after the last element"),
        "{w:?}"
    );
    assert!(
        ply(format!("{ASCII_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n").as_bytes())
            .warnings
            .is_empty()
    );
    let head = ASCII_HEAD.replace("ascii", "binary_little_endian");
    let mut bin = head.into_bytes();
    for v in [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            put(&mut bin, "float", x, false);
        }
    }
    for _ in 0..2 {
        put(&mut bin, "uchar", 3.0, false);
        for i in 0..3 {
            put(&mut bin, "int", i as f64, false);
        }
    }
    let w = &ply(&bin).warnings;
    assert!(
        w.len() == 1 && w[0].message.starts_with("13 bytes after"),
        "{w:?}"
    );
}

const ASCII_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
    element face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn ascii_errors_name_the_line() {
    // Header is 9 lines; vertices on lines 10-12, the face on line 13.
    let e = ply_err(format!("{ASCII_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n").as_bytes());
    assert_eq!(
        e.to_string(),
        "bad.ply:13: face refers to vertex 5, but only 3 are defined"
    );
    let e = ply_err(format!("{ASCII_HEAD}0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n").as_bytes());
    assert_eq!(e.line(), Some(11));
    assert!(matches!(*e.kind, ErrorKind::NonFinite { .. }), "{e}");
    let e = ply_err(format!("{ASCII_HEAD}0 0 0\n1 0\n0 1 0\n3 0 1 2\n").as_bytes());
    assert_eq!(e.line(), Some(11));
    let e = ply_err(format!("{ASCII_HEAD}0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n").as_bytes());
    assert_eq!(e.line(), Some(11));
    let e = ply_err(format!("{ASCII_HEAD}0 0 0\n1 0 0\n0 1 0\n").as_bytes());
    assert!(matches!(*e.kind, ErrorKind::Truncated(_)), "{e}");
    let e = ply_err(format!("{ASCII_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n").as_bytes());
    assert_eq!(e.line(), Some(13));
}

#[test]
fn header_errors() {
    let e = ply_err(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
    assert!(matches!(*e.kind, ErrorKind::Truncated(_)), "{e}");
    let e = ply_err(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty quad x\nend_header\n");
    assert_eq!(e.line(), Some(4));
    let e = ply_err(b"ply\nformat ebcdic 1.0\nend_header\n");
    assert_eq!(e.line(), Some(2));
    let e = ply_err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n");
    assert!(e.to_string().contains("no `z` property"), "{e}");
    let e = ply_err(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
    assert_eq!(*e.kind, ErrorKind::EmptyMesh);
}

/// Every prefix and a few thousand single-byte corruptions of a binary
/// file give `Ok` or a `ReadError`, never a panic (overflow checks are on in
/// test builds).
#[test]
fn truncations_and_corruptions_never_panic() {
    for big in [false, true] {
        let full = binary_quad(big);
        for len in 0..full.len() {
            let _ = read_ply(&full[..len], Path::new("cut.ply"));
        }
        let mut seed = 0x2545_f491_u32;
        for _ in 0..3000 {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            let mut bytes = full.clone();
            let at = seed as usize % bytes.len();
            bytes[at] = (seed >> 24) as u8;
            let _ = read_ply(&bytes, Path::new("flip.ply"));
        }
    }
}

/// Vertex colours (`red green blue`, optional `alpha`) become `COLOR_0` in
/// [0, 1]: integers full-range, floats as they are; ascii and binary agree.
#[test]
fn vertex_colours_are_read() {
    let head = |format: &str, ty: &str, alpha: bool| {
        let a = if alpha {
            format!("property {ty} alpha\n")
        } else {
            String::new()
        };
        format!(
            "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nproperty {ty} red\nproperty {ty} green\nproperty {ty} blue\n{a}\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let rgb = [[255.0, 0.0, 0.0], [0.0, 255.0, 51.0], [255.0, 255.0, 255.0]];
    let want = vec![
        [1.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.2, 1.0],
        [1.0, 1.0, 1.0, 1.0],
    ];
    // ascii, uchar, no alpha
    let mut text = head("ascii", "uchar", false);
    for (i, c) in rgb.iter().enumerate() {
        text += &format!("{i} {} 0 {} {} {}\n", i % 2, c[0], c[1], c[2]);
    }
    text += "3 0 1 2\n";
    assert_eq!(prim(&ply(text.as_bytes())).colors, Some(want.clone()));
    // `diffuse_red`… (Stanford's scans): the same colours
    let diffuse = text.replace(" red\n", " diffuse_red\n");
    let diffuse = diffuse.replace(" green\n", " diffuse_green\n");
    let diffuse = diffuse.replace(" blue\n", " diffuse_blue\n");
    assert!(diffuse.contains("diffuse_green"));
    assert_eq!(prim(&ply(diffuse.as_bytes())).colors, Some(want.clone()));
    // binary, both endiannesses, through the record loop and the fast path
    for big in [false, true] {
        let format = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut b = head(format, "uchar", false).into_bytes();
        for (i, c) in rgb.iter().enumerate() {
            for v in [i as f64, (i % 2) as f64, 0.0] {
                put(&mut b, "float", v, big);
            }
            for &v in c {
                put(&mut b, "uchar", v, big);
            }
        }
        put(&mut b, "uchar", 3.0, big);
        for v in [0.0, 1.0, 2.0] {
            put(&mut b, "int", v, big);
        }
        assert_eq!(prim(&ply(&b)).colors, Some(want.clone()), "big {big}");
    }
    // float colours with alpha, as they are
    let mut text = head("ascii", "float", true);
    text += "0 0 0 0.5 0.25 1 0.5\n1 0 0 0 0 0 1\n0 1 0 1 1 1 0\n3 0 1 2\n";
    assert_eq!(
        prim(&ply(text.as_bytes())).colors,
        Some(vec![
            [0.5, 0.25, 1.0, 0.5],
            [0.0, 0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0, 0.0]
        ])
    );
    // no colours: none
    let mut text = head("ascii", "uchar", false).replace("property uchar red\n", "");
    text += "0 0 0 0 0\n1 0 0 0 0\n0 1 0 0 0\n3 0 1 2\n";
    assert_eq!(prim(&ply(text.as_bytes())).colors, None);
}
