//! Set-up shared by the lodgen integration tests (each test file says
//! `mod support;`): running the `lodgen` binary, copying outputs to
//! `$LODGEN_TEST_OUT` for the glTF-Validator step of `cargo xtask test`,
//! running that validator in-process when it is installed, and the
//! submodules:
//! - [`gltf`]: glTF / GLB documents built in code (buffers, views,
//!   accessors), and the JSON chunk of a written GLB;
//! - [`written`]: LOD chains made with meshopt and the decoding of written
//!   files (accessors plain, quantized or meshopt-compressed);
//! - [`alloc`]: a per-thread counting allocator (a test file registers it
//!   with `#[global_allocator]`);
//! - [`browser`]: whether node, Chromium and the npm packages are there, and
//!   running a `tests/js` script.
#![allow(dead_code)]

pub mod alloc;
pub mod browser;
pub mod gltf;
pub mod written;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Runs the `lodgen` binary built for this test run.
pub fn lodgen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodgen"))
        .args(args)
        .output()
        .expect("the lodgen binary runs")
}

/// Runs the `lodgen` binary in `cwd`.
pub fn lodgen_in(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodgen"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the lodgen binary runs")
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Standard output as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Copies `file` to `$LODGEN_TEST_OUT/name` when that variable is set.
pub fn publish(file: &Path, name: &str) {
    if let Some(dir) = std::env::var_os("LODGEN_TEST_OUT") {
        let dir = PathBuf::from(dir);
        if let Some(parent) = dir.join(name).parent() {
            std::fs::create_dir_all(parent).unwrap();
        }
        std::fs::copy(file, dir.join(name)).unwrap();
    }
}

/// Whether a missing tool must fail the test: `CI=true` or
/// `LODGEN_BROWSER_TEST=1`.
pub fn tools_required() -> bool {
    std::env::var("LODGEN_BROWSER_TEST").is_ok_and(|v| v == "1")
        || std::env::var("CI").as_deref() == Ok("true")
}

/// Runs the Khronos glTF-Validator (`tests/js/validate.mjs --verbose`) on
/// every glTF file under `dir` and returns its log, which lists each
/// file's error / warning / info / hint counts. Fails the test when a file
/// has errors. `None` (with a notice) when node or the validator is not
/// installed, unless [`tools_required`].
pub fn validate(dir: &Path) -> Option<String> {
    let validator = root().join("tests/js/node_modules/gltf-validator");
    let node = Command::new("node").arg("--version").output().is_ok();
    if !validator.exists() || !node {
        assert!(
            !tools_required(),
            "CI=true, but node or {} is missing (npm ci in tests/js)",
            validator.display()
        );
        eprintln!("gltf-validator not installed (npm ci in tests/js): validation skipped");
        return None;
    }
    let out = Command::new("node")
        .arg(root().join("tests/js/validate.mjs"))
        .arg("--require")
        .arg(dir)
        .output()
        .unwrap();
    let log = stdout(&out) + &stderr(&out);
    eprintln!("{log}");
    assert!(out.status.success(), "gltf-validator:\n{log}");
    Some(log)
}

/// A named object of an OBJ file: name, positions, triangles.
pub type ObjObject<'a> = (&'a str, &'a [[f32; 3]], &'a [[u32; 3]]);

/// OBJ text of `objects`, each an `o NAME` group when the name is not
/// empty, indices continuing across objects.
pub fn obj_text(objects: &[ObjObject<'_>]) -> String {
    let mut s = String::new();
    let mut base = 1;
    for (name, positions, triangles) in objects {
        if !name.is_empty() {
            s += &format!("o {name}\n");
        }
        for p in *positions {
            s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
        for t in *triangles {
            s += &format!("f {} {} {}\n", t[0] + base, t[1] + base, t[2] + base);
        }
        base += positions.len() as u32;
    }
    s
}
