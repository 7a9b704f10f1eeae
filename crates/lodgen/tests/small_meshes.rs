//! Small meshes never fail a file: a level is never empty, `--min-triangles`
//! floors every level, and a scene's quads and cards are written whole next
//! to the meshes that are simplified. Outputs are also copied to
//! `$LODGEN_TEST_OUT` (when set) for the glTF-Validator run of `cargo xtask test`.

mod support;

use std::io::Read;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use support::{lodgen, publish};

/// A named object: positions and triangles.
type Object<'a> = (&'a str, Vec<[f32; 3]>, Vec<[u32; 3]>);

/// One OBJ object per (name, positions, triangles).
fn write_obj(path: &Path, objects: &[Object<'_>]) {
    let objects: Vec<support::ObjObject<'_>> = objects
        .iter()
        .map(|(n, p, t)| (*n, p.as_slice(), t.as_slice()))
        .collect();
    std::fs::write(path, support::obj_text(&objects)).unwrap();
}

fn quad() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    (
        vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

fn torus() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 48, 24);
    (m.positions, m.triangles)
}

/// Build `input` into `dir/out.glb` with a report; the report.
fn build(dir: &Path, input: &Path, extra: &[&str]) -> (Output, serde_json::Value) {
    let out = dir.join("out.glb");
    let report = dir.join("out.json");
    let mut args = vec![
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = lodgen(&args);
    assert!(
        o.status.success(),
        "lodgen failed on {}: {}",
        input.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.is_file());
    let r = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    (o, r)
}

/// Triangle count of every level of mesh `m` in a report.
fn levels(r: &serde_json::Value, m: usize) -> Vec<u64> {
    r["meshes"][m]["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["triangles"].as_u64().unwrap())
        .collect()
}

#[test]
fn one_triangle_a_quad_and_two_far_triangles_are_written_whole() {
    let dir = tempfile::tempdir().unwrap();
    let (qp, qt) = quad();
    let cases: [Object<'_>; 3] = [
        (
            "triangle",
            vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]],
            vec![[0, 1, 2]],
        ),
        ("quad", qp, qt),
        (
            "far",
            vec![
                [0., 0., 0.],
                [1., 0., 0.],
                [0., 1., 0.],
                [100., 0., 0.],
                [101., 0., 0.],
                [100., 1., 0.],
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        ),
    ];
    for (name, p, t) in cases {
        let input = dir.path().join(format!("{name}.obj"));
        let n = t.len() as u64;
        write_obj(&input, &[(name, p, t)]);
        let (o, r) = build(dir.path(), &input, &[]);
        // the three default levels coincide with the whole mesh: one level
        assert_eq!(levels(&r, 0), vec![n], "{name}");
        let table = String::from_utf8_lossy(&o.stdout);
        assert!(
            table.contains("note: 3 of 3 requested levels ask for fewer than 8 triangles"),
            "{name}: {table}"
        );
        assert_eq!(r["meshes"][0]["notes"].as_array().unwrap().len(), 1);
        publish(&dir.path().join("out.glb"), &format!("small-{name}.glb"));
    }
}

#[test]
fn a_quad_beside_a_large_mesh_does_not_fail_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scene.obj");
    let (tp, tt) = torus();
    let (qp, qt) = quad();
    let full = tt.len() as u64;
    write_obj(&input, &[("torus", tp, tt), ("card", qp, qt)]);
    let (_, r) = build(dir.path(), &input, &[]);
    let meshes = r["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 2);
    let torus = levels(&r, 0);
    assert_eq!(torus.len(), 3);
    assert_eq!(torus[0], full / 2);
    assert!(meshes[0]["notes"].as_array().unwrap().is_empty());
    assert_eq!(levels(&r, 1), vec![2]);
    publish(&dir.path().join("out.glb"), "small-scene.glb");
}

#[test]
fn min_triangles_floors_every_level() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("torus.obj");
    let (tp, tt) = torus();
    write_obj(&input, &[("torus", tp, tt)]);
    // 1 % of 2,304 triangles is 23: above the floor of 1, below one of 200
    let (_, low) = build(
        dir.path(),
        &input,
        &["--levels", "50%,1%", "--min-triangles", "1"],
    );
    let low = levels(&low, 0);
    assert!(low[1] <= 23, "{low:?}");
    let (o, high) = build(
        dir.path(),
        &input,
        &["--levels", "50%,1%", "--min-triangles", "200"],
    );
    let high = levels(&high, 0);
    assert_eq!(high.len(), 2);
    assert!((200..400).contains(&high[1]), "{high:?}");
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("1 of 2 requested levels ask for fewer than 200 triangles"));
    // a floor above the mesh keeps it whole
    let (_, whole) = build(dir.path(), &input, &["--min-triangles", "100000"]);
    assert_eq!(levels(&whole, 0), vec![2304]);
}

#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_table_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("torus.obj");
    let (tp, tt) = torus();
    write_obj(&input, &[("torus", tp, tt)]);
    let out = dir.path().join("out.glb");
    let mut child = Command::new(env!("CARGO_BIN_EXE_lodgen"))
        .args([input.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // the reader goes away before the table is printed (as `| head -0` would)
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    child.wait().unwrap();
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.is_file(), "the output is written before the table");
}
