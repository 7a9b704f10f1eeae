//! OBJ reader: face forms, relative indices, polygons, objects and
//! materials, MTL colours, and located errors.

use std::path::Path;

use lodgen::io::{read_obj, read_obj_with_materials, ErrorKind, Location, ReadError};
use lodgen::scene::{Primitive, Scene};

fn obj(text: &str) -> Scene {
    read_obj(text.as_bytes(), Path::new("test.obj")).unwrap_or_else(|e| panic!("{e}"))
}

fn obj_err(text: &str) -> ReadError {
    match read_obj(text.as_bytes(), Path::new("bad.obj")) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

fn only_prim(scene: &Scene) -> &Primitive {
    assert_eq!(scene.meshes.len(), 1);
    assert_eq!(scene.meshes[0].primitives.len(), 1);
    &scene.meshes[0].primitives[0]
}

const QUAD_V: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

#[test]
fn face_form_v() {
    let s = obj(&format!("{QUAD_V}f 1 2 3\n"));
    let p = only_prim(&s);
    assert_eq!(
        p.positions,
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]
    );
    assert_eq!(p.indices, vec![0, 1, 2]);
    assert!(p.normals.is_none() && p.texcoords.is_none());
    assert_eq!(s.meshes[0].name, "test");
    assert_eq!(p.material, None);
}

#[test]
fn face_form_v_vt() {
    let s = obj(&format!("{QUAD_V}vt 0.25 0.5\nvt 1 0\nf 1/1 2/2 3/1\n"));
    let p = only_prim(&s);
    // OBJ v is flipped to glTF's top-left origin.
    assert_eq!(
        p.texcoords.as_deref(),
        Some(&[[0.25, 0.5], [1.0, 1.0], [0.25, 0.5]][..])
    );
    assert!(p.normals.is_none());
}

#[test]
fn face_form_v_vn() {
    let s = obj(&format!("{QUAD_V}vn 0 0 1\nvn 0 0 -1\nf 1//1 2//2 3//1\n"));
    let p = only_prim(&s);
    assert_eq!(
        p.normals.as_deref(),
        Some(&[[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]][..])
    );
    assert!(p.texcoords.is_none());
}

#[test]
fn face_form_v_vt_vn() {
    let s = obj(&format!(
        "{QUAD_V}vt 0 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/2/1\n"
    ));
    let p = only_prim(&s);
    assert_eq!(
        p.texcoords.as_deref(),
        Some(&[[0.0, 1.0], [1.0, 0.0], [1.0, 0.0]][..])
    );
    assert_eq!(p.normals.as_deref().map(<[_]>::len), Some(3));
}

#[test]
fn corners_with_different_attributes_become_distinct_vertices() {
    // Two triangles share positions 1 and 3, but position 3 carries a
    // different UV in each: 4 positions used, 5 primitive vertices.
    let s = obj(&format!(
        "{QUAD_V}vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\nf 1/1 2/2 3/3\nf 1/1 3/5 4/4\n"
    ));
    let p = only_prim(&s);
    assert_eq!(p.positions.len(), 5);
    assert_eq!(p.indices, vec![0, 1, 2, 0, 3, 4]);
    assert_eq!(p.positions[2], p.positions[3]);
}

#[test]
fn negative_indices_are_relative() {
    let s = obj("v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -1 -2 -3\n");
    let p = only_prim(&s);
    assert_eq!(
        p.positions,
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [5.0, 5.0, 5.0]
        ]
    );
    assert_eq!(p.indices, vec![0, 1, 2, 3, 2, 1]);
}

#[test]
fn polygons_are_fan_triangulated() {
    let s = obj("v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n");
    let p = only_prim(&s);
    assert_eq!(p.indices, vec![0, 1, 2, 0, 2, 3, 0, 3, 4]);
}

#[test]
fn unused_vertices_are_dropped_in_first_use_order() {
    let s = obj("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 4 0 0\nf 5 2 4\n");
    let p = only_prim(&s);
    assert_eq!(
        p.positions,
        vec![[4.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]]
    );
    assert_eq!(p.indices, vec![0, 1, 2]);
}

#[test]
fn materials_become_primitives_and_objects_become_meshes() {
    let text = "mtllib none.mtl\n\
        v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
        o first\nusemtl red\nf 1 2 3\nusemtl blue\nf 2 4 3\nusemtl red\nf 1 3 4\n\
        g ignored group\ns 1\nl 1 2\nvp 0.5\n\
        o second\nf 1 2 4\n";
    let s = obj(text);
    assert_eq!(s.meshes.len(), 2);
    assert_eq!(s.meshes[0].name, "first");
    assert_eq!(s.meshes[1].name, "second");
    let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["red", "blue"]);
    assert!(s.materials.iter().all(|m| m.base_color.is_none()));
    let first = &s.meshes[0].primitives;
    assert_eq!(first.len(), 2);
    assert_eq!(first[0].material, Some(0));
    assert_eq!(first[0].triangle_count(), 2);
    assert_eq!(first[1].material, Some(1));
    assert_eq!(first[1].triangle_count(), 1);
    // The material state carries over into the next object.
    assert_eq!(s.meshes[1].primitives.len(), 1);
    assert_eq!(s.meshes[1].primitives[0].material, Some(0));
    assert_eq!(s.meshes[1].primitives[0].positions.len(), 3);
}

#[test]
fn faces_before_the_first_object_use_the_file_stem() {
    let s = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no empty\no named\nf 3 2 1\n");
    let names: Vec<&str> = s.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["test", "named"]);
}

#[test]
fn mtl_kd_becomes_base_color() {
    let text = "mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl skin\nf 1 2 3\nusemtl glass\nf 1 3 2\nusemtl nowhere\nf 2 1 3\n";
    let mut asked = Vec::new();
    let s = read_obj_with_materials(text.as_bytes(), Path::new("m.obj"), |name| {
        asked.push(name.to_owned());
        match name {
            "a.mtl" => Some(
                b"newmtl skin\nKd 0.5 0.25 1\n# comment\nnewmtl glass\nKd 0 0 1\nd 0.5\n".to_vec(),
            ),
            _ => None,
        }
    })
    .unwrap();
    assert_eq!(asked, ["a.mtl", "b.mtl"]);
    assert_eq!(s.materials[0].name, "skin");
    assert_eq!(s.materials[0].base_color, Some([0.5, 0.25, 1.0, 1.0]));
    assert_eq!(s.materials[1].base_color, Some([0.0, 0.0, 1.0, 0.5]));
    assert_eq!(s.materials[2].name, "nowhere");
    assert_eq!(s.materials[2].base_color, None);
}

#[test]
fn mtllib_is_read_from_beside_the_obj() {
    let dir = std::env::temp_dir().join(format!("lodgen-io-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("c.mtl"), "newmtl m\nKd 1 0 0\n").unwrap();
    let obj_path = dir.join("c.OBJ");
    std::fs::write(
        &obj_path,
        "mtllib c.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    )
    .unwrap();
    let s = lodgen::io::read_scene(&obj_path);
    std::fs::remove_dir_all(&dir).unwrap();
    let s = s.unwrap();
    assert_eq!(s.materials[0].base_color, Some([1.0, 0.0, 0.0, 1.0]));
}

/// What an OBJ's materials lose is said: a missing library and each texture
/// map of a used material are warnings naming them (an unused material's
/// maps are not), and with `--strict` an error. (Fails when they are dropped
/// silently.)
#[test]
fn missing_libraries_and_texture_maps_are_warnings() {
    let text = "mtllib a.mtl gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl skin\nf 1 2 3\n";
    let mtl = b"newmtl skin\nKd 1 1 1\nmap_Kd skin diffuse.png\nnewmtl unused\nmap_Kd u.png\n";
    let s = read_obj_with_materials(text.as_bytes(), Path::new("m.obj"), |name| {
        (name == "a.mtl").then(|| mtl.to_vec())
    })
    .unwrap();
    let w: Vec<String> = s.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(
        w[0].starts_with("mtllib gone.mtl: material library not found"),
        "{w:?}"
    );
    assert!(
        w[1].starts_with("material `skin`: map_Kd diffuse.png:"),
        "{w:?}"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.obj");
    std::fs::write(&path, text).unwrap();
    std::fs::write(dir.path().join("a.mtl"), mtl).unwrap();
    let strict = lodgen::io::ReadOptions { strict: true };
    let e = lodgen::io::read_scene_with(&path, &strict).unwrap_err();
    assert!(
        e.to_string().contains("gone.mtl") && e.to_string().contains("--strict"),
        "{e}"
    );
    assert_eq!(lodgen::io::read_scene(&path).unwrap().warnings.len(), 2);
}

/// A file saved with a UTF-8 byte order mark (Windows tools) reads as
/// without it. (Fails when the mark hides the first line's statement.)
#[test]
fn a_byte_order_mark_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bom.obj");
    std::fs::write(&path, "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let s = lodgen::io::read_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(only_prim(&s).positions[0], [0.0, 0.0, 0.0]);
    assert_eq!(only_prim(&s).indices, vec![0, 1, 2]);
}

#[test]
fn crlf_comments_and_extra_components() {
    let s = obj(
        "# header\r\nv 0 0 0 1\r\nv 1 0 0 0.5 0.5 0.5\r\nv 0 1 0\r\n\r\nf 1 2 3 # trailing\r\n",
    );
    assert_eq!(only_prim(&s).indices, vec![0, 1, 2]);
}

#[test]
fn vertex_zero_names_the_line() {
    let e = obj_err("v 0 0 0\nv 1 0 0\nv 0 1 0\n# comment\nf 0 1 2\n");
    assert_eq!(
        e.to_string(),
        "bad.obj:5:3: face refers to vertex 0 (OBJ indices start at 1)"
    );
    assert_eq!(e.location, Location::Column { line: 5, column: 3 });
}

#[test]
fn index_out_of_range_names_the_line() {
    let e = obj_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n");
    assert_eq!(e.line(), Some(5));
    assert!(
        matches!(
            *e.kind,
            ErrorKind::IndexOutOfRange {
                index: 4,
                count: 3,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        "bad.obj:5:7: face refers to vertex 4, but only 3 are defined"
    );
    let e = obj_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 -2 -1\n");
    assert_eq!(e.line(), Some(4));
    let e = obj_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/2 2/1 3/1\n");
    assert_eq!(e.line(), Some(5));
    assert!(e.to_string().contains("texture coordinate 2"), "{e}");
    let e = obj_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n");
    assert!(
        e.to_string()
            .starts_with("bad.obj:4:6: face refers to normal 1"),
        "{e}"
    );
}

#[test]
fn non_finite_coordinates_name_the_line() {
    let e = obj_err("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(e.line(), Some(2));
    assert!(matches!(*e.kind, ErrorKind::NonFinite { .. }), "{e}");
    let e = obj_err("v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n");
    assert_eq!(e.line(), Some(3));
    let e = obj_err("v 0 0 0\nvn 0 0 -inf\n");
    assert_eq!(e.line(), Some(2));
    // file, line and column of the bad number, as a scan's single bad
    // vertex is found (`file:line:column`, 1-based)
    let e = obj_err("v 0 0 0\n  v 1.5   nan 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(
        e.location,
        Location::Column {
            line: 2,
            column: 11
        }
    );
    assert_eq!(
        e.to_string(),
        "bad.obj:2:11: vertex coordinate is not finite (NaN)"
    );
    let e = obj_err("v 0 0 0\nv 1 0 0\nv 0 1 1e39\nf 1 2 3\n");
    assert_eq!(
        e.to_string(),
        "bad.obj:3:7: vertex coordinate is not finite (inf)"
    );
    let e = obj_err("v 0 0 0\nv 1 x 0\n");
    assert_eq!(e.location, Location::Column { line: 2, column: 5 });
}

#[test]
fn malformed_lines_name_the_line() {
    assert_eq!(obj_err("v 0 0\nv 1 0 0\n").line(), Some(1));
    assert_eq!(obj_err("v 0 0 0\nv 1 x 0\n").line(), Some(2));
    assert_eq!(obj_err("v 0 0 0\nv 1 0 0\nf 1 2\n").line(), Some(3));
    assert_eq!(
        obj_err("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 a 3\n").line(),
        Some(4)
    );
}

#[test]
fn no_faces_is_an_empty_mesh() {
    let e = obj_err("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    assert_eq!(*e.kind, ErrorKind::EmptyMesh);
    assert_eq!(e.to_string(), "bad.obj: no triangles in the file");
    assert_eq!(*obj_err("").kind, ErrorKind::EmptyMesh);
}

#[test]
fn truncated_file_fails_on_the_cut_line() {
    // A file cut in the middle of a face line leaves a face of two corners.
    // (A cut exactly at a line end cannot be told from a shorter file.)
    let full = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    let cut = &full[..full.len() - 3];
    assert_eq!(obj_err(cut).line(), Some(6));
    // Cut inside a vertex line.
    let e = obj_err(&full[..20]);
    assert_eq!(e.line(), Some(3));
}

/// Every prefix of a file using every statement gives `Ok` or a
/// `ReadError`, never a panic.
#[test]
fn every_prefix_is_handled() {
    let text = "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n\
        o a\nusemtl m\nf 1/1/1 2/2/1 3/1/1 4/2/1\nf -1//1 -2//1 -3//1\ng g\ns off\nf 1/2 3/1 4/2\n";
    for len in 0..text.len() {
        let _ = read_obj(&text.as_bytes()[..len], Path::new("cut.obj"));
    }
}

/// `v x y z r g b` (MeshLab's and scanners' vertex colours) become COLOR_0, alpha 1:
/// components above 1 read as 0–255, a `v` without a colour white, `v x y z w` no colour, a
/// comment no colour. They were dropped without a word.
#[test]
fn vertex_colours_after_the_coordinates_are_read() {
    let s = obj(
        "v 0 0 0 1 0 0\nv 1 0 0 0 255 0\nv 0 1 0\nv 1 1 0 1.0 # w\nv 1 1 1 0 0 0.5\n\
                 f 1 2 3\nf 2 4 3\nf 2 5 4\n",
    );
    let p = only_prim(&s);
    let colors = p.colors.as_ref().expect("COLOR_0");
    let at = |x: [f32; 3]| colors[p.positions.iter().position(|&q| q == x).unwrap()];
    assert_eq!(at([0.0, 0.0, 0.0]), [1.0, 0.0, 0.0, 1.0]);
    assert_eq!(at([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0, 1.0]);
    assert_eq!(at([0.0, 1.0, 0.0]), [1.0, 1.0, 1.0, 1.0]);
    assert_eq!(at([1.0, 1.0, 0.0]), [1.0, 1.0, 1.0, 1.0]);
    assert_eq!(at([1.0, 1.0, 1.0]), [0.0, 0.0, 0.5, 1.0]);
    // no colour anywhere: none
    assert!(
        only_prim(&obj("v 0 0 0 1\nv 1 0 0\nv 0 1 0 # x y z\nf 1 2 3\n"))
            .colors
            .is_none()
    );
}
