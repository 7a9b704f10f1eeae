//! Batch mode as users run it: `lodgen INPUT... --out-dir DIR`: mixed inputs
//! with a broken file, the relative layout, the summary table and report,
//! a re-run that skips everything, `--force`, changed inputs and options,
//! globs, and bytes equal to single-file runs.

mod support;

use std::path::{Path, PathBuf};
use std::process::Output;

fn lodgen(args: &[&str], cwd: &Path) -> Output {
    support::lodgen_in(args, cwd)
}

fn obj_text(m: &lodgen_pm::Mesh) -> String {
    support::obj_text(&[("", &m.positions, &m.triangles)])
}

fn ply_text(m: &lodgen_pm::Mesh) -> String {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        m.positions.len(),
        m.triangles.len()
    );
    for p in &m.positions {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &m.triangles {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    s
}

/// in/torus.obj, in/parts/sphere.ply, in/parts/deep/small.obj (a torus),
/// in/parts/broken.obj (an index out of range), in/notes.txt (ignored).
fn mixed_inputs(root: &Path) -> PathBuf {
    let dir = root.join("in");
    std::fs::create_dir_all(dir.join("parts/deep")).unwrap();
    let torus = lodgen_pm::shapes::torus(1.0, 0.35, 48, 24);
    std::fs::write(dir.join("torus.obj"), obj_text(&torus)).unwrap();
    let sphere = lodgen_pm::shapes::icosphere(3);
    std::fs::write(dir.join("parts/sphere.ply"), ply_text(&sphere)).unwrap();
    let small = lodgen_pm::shapes::torus(2.0, 0.5, 24, 12);
    std::fs::write(dir.join("parts/deep/small.obj"), obj_text(&small)).unwrap();
    std::fs::write(
        dir.join("parts/broken.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
    )
    .unwrap();
    std::fs::write(dir.join("notes.txt"), "not a mesh\n").unwrap();
    dir
}

fn read_report(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

fn statuses(r: &serde_json::Value) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = r["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["input"].as_str().unwrap().replace('\\', "/"),
                f["status"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    v.sort();
    v
}

fn outputs(out: &Path) -> Vec<String> {
    let mut v: Vec<String> = walk(out)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "glb"))
        .map(|p| {
            p.strip_prefix(out)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/")
        })
        .collect();
    v.sort();
    v
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

#[test]
fn a_directory_with_a_broken_file_builds_the_others_and_fails() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    mixed_inputs(root);
    let o = lodgen(
        &[
            "in",
            "--out-dir",
            "out",
            "--jobs",
            "2",
            "--report",
            "r.json",
        ],
        root,
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "a failed file fails the run");
    assert!(
        stderr.contains("1 of 4 files failed"),
        "stderr says how many failed: {stderr}"
    );
    // The broken file's message is the single-file CLI's.
    let single = lodgen(&["in/parts/broken.obj", "-o", "single.glb"], root);
    let single_err = String::from_utf8_lossy(&single.stderr);
    assert!(
        single_err.contains("in/parts/broken.obj:4:"),
        "{single_err}"
    );
    let line = single_err
        .lines()
        .find(|l| l.contains("in/parts/broken.obj:4:"))
        .unwrap()
        .trim()
        .trim_start_matches("error: ")
        .to_string();
    assert!(
        stdout.contains(&line),
        "the table names the failure: {stdout}"
    );
    assert_eq!(
        outputs(&root.join("out")),
        ["parts/deep/small.glb", "parts/sphere.glb", "torus.glb"],
        "the relative layout is kept, the broken file writes nothing"
    );
    assert!(!root.join("out/parts/broken.glb").exists());
    let r = read_report(&root.join("r.json"));
    assert_eq!(
        statuses(&r),
        [
            ("in/parts/broken.obj".into(), "failed".into()),
            ("in/parts/deep/small.obj".into(), "built".into()),
            ("in/parts/sphere.ply".into(), "built".into()),
            ("in/torus.obj".into(), "built".into()),
        ]
    );
    assert_eq!(r["built"], 3);
    assert_eq!(r["failed"], 1);
    // Every row of the summary table: levels reached and an error measured.
    let torus = r["files"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["input"].as_str().unwrap().ends_with("torus.obj"))
        .unwrap();
    let levels = torus["report"]["meshes"][0]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    assert!(stdout.contains("torus.obj"), "{stdout}");
    assert!(
        stdout.contains("4 files: 3 built, 0 unchanged, 1 failed"),
        "{stdout}"
    );
    let tris: Vec<String> = levels
        .iter()
        .map(|l| l["triangles"].as_u64().unwrap().to_string())
        .collect();
    assert!(
        stdout.contains(&format!("2304 → {}", tris.join(" / "))),
        "{stdout}"
    );
}

#[test]
fn outputs_are_the_bytes_of_single_file_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    mixed_inputs(root);
    std::fs::remove_file(root.join("in/parts/broken.obj")).unwrap();
    let o = lodgen(&["in", "--out-dir", "out", "-j", "3", "-q"], root);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (input, output) in [
        ("in/torus.obj", "out/torus.glb"),
        ("in/parts/sphere.ply", "out/parts/sphere.glb"),
        ("in/parts/deep/small.obj", "out/parts/deep/small.glb"),
    ] {
        let o = lodgen(&[input, "-o", "single.glb", "-q"], root);
        assert!(o.status.success());
        assert_eq!(
            std::fs::read(root.join("single.glb")).unwrap(),
            std::fs::read(root.join(output)).unwrap(),
            "{output} differs from the single-file run"
        );
    }
}

#[test]
fn a_rerun_skips_everything_and_force_rebuilds() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    mixed_inputs(root);
    std::fs::remove_file(root.join("in/parts/broken.obj")).unwrap();
    let first = lodgen(&["in", "--out-dir", "out", "--report", "r1.json"], root);
    assert!(first.status.success());
    assert_eq!(read_report(&root.join("r1.json"))["built"], 3);
    let mtime = |p: &str| std::fs::metadata(root.join(p)).unwrap().modified().unwrap();
    let before = mtime("out/torus.glb");

    let again = lodgen(&["in", "--out-dir", "out", "--report", "r2.json"], root);
    assert!(again.status.success());
    let r2 = read_report(&root.join("r2.json"));
    assert_eq!(r2["skipped"], 3, "{r2}");
    assert_eq!(r2["built"], 0);
    assert_eq!(
        mtime("out/torus.glb"),
        before,
        "a skipped output is untouched"
    );
    // A skipped file still reports what it was built with.
    assert!(String::from_utf8_lossy(&again.stdout).contains("unchanged"));
    assert_eq!(
        r2["files"][0]["report"]["meshes"][0]["levels"]
            .as_array()
            .map(Vec::len),
        Some(3)
    );

    let forced = lodgen(
        &["in", "--out-dir", "out", "--force", "--report", "r3.json"],
        root,
    );
    assert!(forced.status.success());
    assert_eq!(read_report(&root.join("r3.json"))["built"], 3);

    // A changed input rebuilds that file only; changed options rebuild all.
    let torus = lodgen_pm::shapes::torus(1.0, 0.3, 40, 20);
    std::fs::write(root.join("in/torus.obj"), obj_text(&torus)).unwrap();
    let changed = lodgen(&["in", "--out-dir", "out", "--report", "r4.json"], root);
    assert!(changed.status.success());
    let r4 = read_report(&root.join("r4.json"));
    assert_eq!(
        (r4["built"].as_u64(), r4["skipped"].as_u64()),
        (Some(1), Some(2))
    );
    let options = lodgen(
        &[
            "in",
            "--out-dir",
            "out",
            "--levels",
            "30%",
            "--report",
            "r5.json",
        ],
        root,
    );
    assert!(options.status.success());
    assert_eq!(read_report(&root.join("r5.json"))["built"], 3);

    // A deleted output is rebuilt even though the manifest lists it.
    std::fs::remove_file(root.join("out/parts/sphere.glb")).unwrap();
    let deleted = lodgen(
        &[
            "in",
            "--out-dir",
            "out",
            "--levels",
            "30%",
            "--report",
            "r6.json",
        ],
        root,
    );
    assert!(deleted.status.success());
    let r6 = read_report(&root.join("r6.json"));
    assert_eq!(
        (r6["built"].as_u64(), r6["skipped"].as_u64()),
        (Some(1), Some(2))
    );
    assert!(root.join("out/parts/sphere.glb").exists());

    // So is a damaged one (its bytes are not the ones the manifest recorded).
    let good = std::fs::read(root.join("out/torus.glb")).unwrap();
    std::fs::write(root.join("out/torus.glb"), b"garbage").unwrap();
    let args = [
        "in",
        "--out-dir",
        "out",
        "--levels",
        "30%",
        "--report",
        "r7.json",
    ];
    assert!(lodgen(&args, root).status.success());
    let r7 = read_report(&root.join("r7.json"));
    assert_eq!(
        (r7["built"].as_u64(), r7["skipped"].as_u64()),
        (Some(1), Some(2))
    );
    assert_eq!(std::fs::read(root.join("out/torus.glb")).unwrap(), good);

    // The same levels spelled otherwise are the same options.
    let args = [
        "in",
        "--out-dir",
        "out",
        "--levels",
        "0.3,30%",
        "--report",
        "r8.json",
    ];
    assert!(lodgen(&args, root).status.success());
    assert_eq!(read_report(&root.join("r8.json"))["skipped"], 3);
}

/// What a walk or a command line can name more than once or not at all: a
/// file reached twice (a directory and a glob over it) is built once; a
/// link to nothing fails alone and a link back up the tree is not followed
/// round, the others are built; no input at all is an error, not an empty
/// batch. (Fails when one of them stops the batch, or builds a file twice.)
#[test]
fn links_repeats_and_no_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    mixed_inputs(root);
    std::fs::remove_file(root.join("in/parts/broken.obj")).unwrap();
    let o = lodgen(
        &[
            "in",
            "in/parts/*.ply",
            "--out-dir",
            "o1",
            "--report",
            "r1.json",
        ],
        root,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r1 = read_report(&root.join("r1.json"));
    assert_eq!(r1["files"].as_array().map(Vec::len), Some(3), "{r1}");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("/nonexistent/mesh.obj", root.join("in/dangling.obj")).unwrap();
        std::os::unix::fs::symlink("..", root.join("in/parts/up")).unwrap();
        let o = lodgen(&["in", "--out-dir", "o2", "--report", "r2.json"], root);
        assert_eq!(o.status.code(), Some(1));
        let r2 = read_report(&root.join("r2.json"));
        let s = statuses(&r2);
        assert_eq!(s.len(), 4, "{s:?}");
        assert!(
            s.contains(&("in/dangling.obj".into(), "failed".into())),
            "{s:?}"
        );
        assert_eq!(
            outputs(&root.join("o2")),
            ["parts/deep/small.glb", "parts/sphere.glb", "torus.glb"]
        );
    }
    let o = lodgen(&["--out-dir", "o3"], root);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no input mesh given"));
    assert!(!root.join("o3").exists());
}

#[test]
fn globs_and_files_keep_their_relative_paths() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    mixed_inputs(root);
    let o = lodgen(
        &[
            "in/parts/**/*.obj",
            "in/parts/sphere.ply",
            "--out-dir",
            "out",
            "-q",
        ],
        root,
    );
    // broken.obj matches the glob: the run fails, the others are built.
    assert!(!o.status.success());
    assert_eq!(outputs(&root.join("out")), ["deep/small.glb", "sphere.glb"]);

    // Two inputs writing the same output fail, each alone; the others are
    // built.
    let clash = lodgen(
        &[
            "in/torus.obj",
            "in/parts/deep/small.obj",
            "in/parts/sphere.ply",
            "--out-dir",
            "o2",
        ],
        root,
    );
    assert!(clash.status.success(), "different names do not clash");
    std::fs::write(
        root.join("in/parts/torus.ply"),
        ply_text(&lodgen_pm::shapes::torus(1.0, 0.35, 8, 6)),
    )
    .unwrap();
    let clash = lodgen(
        &[
            "in/torus.obj",
            "in/parts/torus.ply",
            "in/parts/sphere.ply",
            "--out-dir",
            "o3",
        ],
        root,
    );
    assert!(!clash.status.success());
    assert!(String::from_utf8_lossy(&clash.stderr).contains("would both write"));
    assert!(String::from_utf8_lossy(&clash.stderr).contains("2 of 3 files failed"));
    assert_eq!(outputs(&root.join("o3")), ["sphere.glb"]);

    let none = lodgen(&["in/*.stl", "--out-dir", "o4"], root);
    assert!(!none.status.success());
    assert!(String::from_utf8_lossy(&none.stderr).contains("matches no file"));
}

#[test]
fn an_output_directory_inside_the_input_is_not_read_back() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    mixed_inputs(root);
    std::fs::remove_file(root.join("in/parts/broken.obj")).unwrap();
    for _ in 0..2 {
        let o = lodgen(&["in", "--out-dir", "in/lods", "--report", "r.json"], root);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(
            read_report(&root.join("r.json"))["files"]
                .as_array()
                .unwrap()
                .len(),
            3
        );
    }
}

#[test]
fn a_changed_companion_file_rebuilds_its_input() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    std::fs::create_dir_all(root.join("src")).unwrap();
    // An OBJ with a material library, and a .gltf with external buffers.
    let torus = lodgen_pm::shapes::torus(1.0, 0.35, 24, 12);
    std::fs::write(
        root.join("src/a.obj"),
        format!("mtllib a.mtl\nusemtl red\n{}", obj_text(&torus)),
    )
    .unwrap();
    std::fs::write(root.join("src/a.mtl"), "newmtl red\nKd 1 0 0\n").unwrap();
    std::fs::write(root.join("t.obj"), obj_text(&torus)).unwrap();
    // (one level: a file of MSFT_lod chains would be made again from its
    // finest levels, with warnings)
    let o = lodgen(
        &["t.obj", "-o", "src/b.gltf", "--levels", "100%", "-q"],
        root,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bins: Vec<PathBuf> = walk(&root.join("src"))
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "bin"))
        .collect();
    assert!(!bins.is_empty());

    let run = |name: &str| {
        let o = lodgen(&["src", "--out-dir", "out", "--report", name], root);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = read_report(&root.join(name));
        (r["built"].as_u64().unwrap(), r["skipped"].as_u64().unwrap())
    };
    assert_eq!(run("r1.json"), (2, 0));
    assert_eq!(run("r2.json"), (0, 2));
    std::fs::write(root.join("src/a.mtl"), "newmtl red\nKd 0 0 1\n").unwrap();
    assert_eq!(run("r3.json"), (1, 1), "a changed .mtl rebuilds its .obj");
    // The same bytes again in a buffer: unchanged; other bytes: rebuilt.
    let bin = &bins[0];
    let bytes = std::fs::read(bin).unwrap();
    std::fs::write(bin, &bytes).unwrap();
    assert_eq!(run("r4.json"), (0, 2));
    let mut changed = bytes.clone();
    changed[0] ^= 1;
    std::fs::write(bin, &changed).unwrap();
    assert_eq!(run("r5.json"), (1, 1), "a changed .bin rebuilds its .gltf");
}

/// An output directory where the manifest cannot be written (here: a
/// directory in its place) still gets the table and the report, then the
/// error, and a non-zero exit code.
#[test]
fn a_manifest_that_cannot_be_written_keeps_the_table_and_report() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let dir = root.join("in");
    std::fs::create_dir_all(&dir).unwrap();
    let torus = lodgen_pm::shapes::torus(1.0, 0.35, 24, 12);
    std::fs::write(dir.join("torus.obj"), obj_text(&torus)).unwrap();
    std::fs::create_dir_all(root.join("out/.lodgen-manifest.json/x")).unwrap();
    let o = lodgen(&["in", "--out-dir", "out", "--report", "r.json"], root);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert!(stderr.contains("error: writing the manifest"), "{stderr}");
    assert!(stdout.contains("1 built"), "the table: {stdout}");
    let r = read_report(&root.join("r.json"));
    assert_eq!(
        statuses(&r),
        [("in/torus.obj".to_string(), "built".to_string())]
    );
    assert!(root.join("out/torus.glb").is_file());
}
