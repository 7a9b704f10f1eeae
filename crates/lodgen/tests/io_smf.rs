//! SMF reader and `read_scene` dispatch.

use std::path::{Path, PathBuf};

use lodgen::io::{detect_format, read_scene, read_smf, ErrorKind, Format};

#[test]
fn smf_vertices_faces_and_ignored_commands() {
    let text =
        "# QSlim output\nbegin\nbind n vertex\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 7 7 7\n\
        n 0 0 1\nc 1 0 0\nr 0 0\nt 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\nset vertex_correction 0\n\
        f 1 2 3\nf 1 3 4 # comment\nf 4 3 2 1\nend\n";
    let s = read_smf(text.as_bytes(), Path::new("model.smf")).unwrap();
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.meshes[0].name, "model");
    let p = &s.meshes[0].primitives[0];
    assert_eq!(p.positions.len(), 4, "the unused vertex 5 is dropped");
    assert_eq!(p.indices, vec![0, 1, 2, 0, 2, 3, 3, 2, 1, 3, 1, 0]);
    assert!(p.normals.is_none() && p.texcoords.is_none());
}

#[test]
fn smf_errors_name_the_line() {
    let bad = |t: &str| read_smf(t.as_bytes(), Path::new("m.smf")).unwrap_err();
    let e = bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    assert_eq!(
        e.to_string(),
        "m.smf:4: face refers to vertex 4, but only 3 are defined"
    );
    let e = bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    assert_eq!(e.line(), Some(4));
    let e = bad("v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(e.line(), Some(2));
    assert!(matches!(*e.kind, ErrorKind::NonFinite { .. }));
    let e = bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n");
    assert_eq!(e.line(), Some(4));
    assert_eq!(*bad("v 0 0 0\n").kind, ErrorKind::EmptyMesh);
}

/// `bytes` in a file named `name` of `dir`.
fn temp(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn dispatch_by_extension_case_insensitive_and_by_content() {
    let tri = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    assert_eq!(detect_format(Path::new("a.OBJ"), tri), Some(Format::Obj));
    assert_eq!(detect_format(Path::new("a.Smf"), tri), Some(Format::Smf));
    assert_eq!(detect_format(Path::new("a.PLY"), b"x"), Some(Format::Ply));
    assert_eq!(detect_format(Path::new("a.GLB"), b"x"), Some(Format::Gltf));
    assert_eq!(detect_format(Path::new("a.gltf"), b"x"), Some(Format::Gltf));
    assert_eq!(
        detect_format(Path::new("a.bin"), b"glTF\x02\0\0\0"),
        Some(Format::Gltf)
    );
    assert_eq!(
        detect_format(Path::new("a.obj"), b"ply\nformat ascii 1.0\n"),
        Some(Format::Ply)
    );
    assert_eq!(
        detect_format(Path::new("a"), b"  {\"asset\":{}}"),
        Some(Format::Gltf)
    );
    assert_eq!(detect_format(Path::new("a.stl"), b"solid x"), None);

    let dir = tempfile::tempdir().unwrap();
    let p = temp(&dir, "upper.SMF", tri);
    let s = read_scene(&p).unwrap();
    assert_eq!(s.meshes[0].name, "upper");
    assert_eq!(s.meshes[0].primitives[0].triangle_count(), 1);

    let p = temp(&dir, "mesh.stl", b"solid x\nendsolid\n");
    let e = read_scene(&p).unwrap_err();
    assert_eq!(*e.kind, ErrorKind::UnknownFormat);
    assert_eq!(
        e.to_string(),
        format!(
            "{}: unknown format (expected .obj, .ply, .smf, .gltf or .glb)",
            p.display()
        )
    );
}

#[test]
fn missing_file_is_an_io_error_with_its_cause() {
    let p = Path::new("/nonexistent/lodgen/x.obj");
    let e = read_scene(p).unwrap_err();
    assert_eq!(*e.kind, ErrorKind::Io);
    assert_eq!(e.to_string(), "/nonexistent/lodgen/x.obj: cannot read file");
    let cause = std::error::Error::source(&e).expect("the io::Error is the source");
    assert!(cause.downcast_ref::<std::io::Error>().is_some());
}
