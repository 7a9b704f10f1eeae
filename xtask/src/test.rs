//! `cargo xtask test [CARGO-TEST-ARGS]`: the project's single "run all tests" command.
//!
//! 0. `cargo xtask layout`'s rules (file and function lengths, module
//!    cycles), in-process.
//! 1. `cargo test --workspace` with `LODGEN_TEST_OUT=<root>/target/test-out`
//!    (emptied first); Rust tests write every glTF they produce there. The
//!    property tests (proptest) run from a fixed seed, [`PROPTEST_SEED`],
//!    unless `PROPTEST_RNG_SEED` is set: the same cases on every run, so a
//!    CI result is reproducible (plain `cargo test` draws a new seed each
//!    run; `PROPTEST_RNG_SEED=N PROPTEST_CASES=M cargo xtask test`
//!    explores).
//! 2. `cargo xtask fuzz --cases 3000 --seed 1` in-process (mutated input
//!    files through read, build, write, inspect; see `fuzz.rs`).
//! 3. Khronos glTF-Validator on everything in that directory
//!    (`node tests/js/validate.mjs [--require] target/test-out`).
//! 4. Babylon.js in headless Chromium for every `NAME.report.json` there that
//!    has a sibling `NAME.glb` (`node tests/js/babylon-lod.mjs`).
//!
//! 4. The Python package's tests: `pip install ./crates/lodgen` (so the module
//!    tested is the current source) into the venv `bash .ci/run` makes
//!    (`target/ci-venv`, or the Python of `LODGEN_PYTHON`, which must have
//!    pytest, numpy, trimesh and dask[distributed]), then pytest on
//!    `crates/lodgen/python/tests`. The command the tests compare the module
//!    with is the `lodgen` step 1 built (`target/debug/lodgen`, or the
//!    directory of the profile its arguments chose: [`step1_binary`]): no
//!    release build of the binary (3 minutes of CI), and the comparisons then also
//!    check that the optimised module and the unoptimised command write the
//!    same bytes.
//!
//! Outputs are required (no glTF file, or no report/.glb pair, is a failure)
//! when `LODGEN_REQUIRE_GLTF=1`, or, when that variable is unset, as soon as
//! any Rust source under `crates/` mentions `LODGEN_TEST_OUT`, i.e. once tests
//! write outputs. `LODGEN_REQUIRE_GLTF=0` turns the requirement off.
//!
//! `npm ci` runs in `tests/js` when its `node_modules` is missing. When node,
//! npm or Chromium (`/usr/bin/chromium`, or `LODGEN_CHROMIUM`) is missing the
//! browser/JS checks fail under `CI=true` and are skipped with a notice
//! otherwise. Child output is streamed; the exit status is non-zero if
//! anything failed.

use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{bail, Context, Result};

use crate::workspace_root;

/// The environment variable through which Rust tests learn where to write glTF files.
const TEST_OUT_ENV: &str = "LODGEN_TEST_OUT";
const REQUIRE_ENV: &str = "LODGEN_REQUIRE_GLTF";

#[derive(Clone, Copy, PartialEq, Eq)]
enum Outcome {
    Passed,
    Failed,
    Skipped,
}

struct Step {
    name: String,
    outcome: Outcome,
    secs: f64,
    note: String,
}

#[derive(Default)]
struct Steps(Vec<Step>);

impl Steps {
    fn record(&mut self, name: &str, outcome: Outcome, secs: f64, note: &str) {
        let word = match outcome {
            Outcome::Passed => "ok",
            Outcome::Failed => "FAILED",
            Outcome::Skipped => "skipped",
        };
        let sep = if note.is_empty() { "" } else { ": " };
        println!("<== {name}: {word} ({secs:.1} s){sep}{note}");
        self.0.push(Step {
            name: name.to_string(),
            outcome,
            secs,
            note: note.to_string(),
        });
    }

    /// Runs `cmd` with inherited stdio and records its outcome.
    fn run(&mut self, name: &str, cmd: &mut Command) -> Outcome {
        println!("==> {name}: {}", describe(cmd));
        let t = Instant::now();
        let (outcome, note) = match cmd.status() {
            Ok(s) if s.success() => (Outcome::Passed, String::new()),
            Ok(s) => (Outcome::Failed, format!("exited with {s}")),
            Err(e) => (Outcome::Failed, format!("could not start: {e}")),
        };
        self.record(name, outcome, t.elapsed().as_secs_f64(), &note);
        outcome
    }

    /// A missing tool: a failure on CI, a skipped step with a notice elsewhere.
    fn missing(&mut self, name: &str, ci: bool, why: &str) {
        if ci {
            self.record(
                name,
                Outcome::Failed,
                0.0,
                &format!("{why} (required because CI=true)"),
            );
        } else {
            println!("NOTICE: {name} skipped: {why}. CI (CI=true) fails here instead.");
            self.record(name, Outcome::Skipped, 0.0, why);
        }
    }

    fn count(&self, o: Outcome) -> usize {
        self.0.iter().filter(|s| s.outcome == o).count()
    }
}

fn describe(cmd: &Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    if let Some(dir) = cmd.get_current_dir() {
        s.push_str(&format!("   (in {})", dir.display()));
    }
    s
}

fn is_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1")
}

/// Whether `program --version` runs.
fn tool_works(program: &str) -> bool {
    Command::new(program)
        .arg("--version")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

pub fn chromium_path() -> PathBuf {
    std::env::var_os("LODGEN_CHROMIUM")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/bin/chromium"))
}

/// Files under `dir` (recursively, sorted) whose name satisfies `keep`.
pub fn files_under(dir: &Path, keep: &dyn Fn(&str) -> bool) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    if !dir.is_dir() {
        return Ok(out);
    }
    let mut entries: Vec<_> = fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .collect::<std::io::Result<_>>()
        .with_context(|| format!("reading {}", dir.display()))?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let path = e.path();
        let ty = e.file_type()?;
        if ty.is_dir() {
            out.extend(files_under(&path, keep)?);
        } else if ty.is_file() && keep(&e.file_name().to_string_lossy()) {
            out.push(path);
        }
    }
    Ok(out)
}

/// Whether missing test outputs are a failure (see the module docs).
fn outputs_required(root: &Path) -> Result<(bool, String)> {
    if let Ok(v) = std::env::var(REQUIRE_ENV) {
        let on = matches!(v.as_str(), "1" | "true" | "yes");
        return Ok((on, format!("{REQUIRE_ENV}={v}")));
    }
    let sources = files_under(&root.join("crates"), &|n| n.ends_with(".rs"))?;
    for src in sources {
        let text =
            fs::read_to_string(&src).with_context(|| format!("reading {}", src.display()))?;
        if text.contains(TEST_OUT_ENV) {
            let rel = src.strip_prefix(root).unwrap_or(&src).display().to_string();
            return Ok((true, format!("{rel} writes to {TEST_OUT_ENV}")));
        }
    }
    Ok((
        false,
        format!("no test under crates/ uses {TEST_OUT_ENV} yet and {REQUIRE_ENV} is unset"),
    ))
}

/// The `lodgen` binary `cargo test` built for its CLI tests with the extra
/// arguments `args`: in the directory of the profile they chose (`--release`,
/// `--profile NAME`), `target/debug` by default. (A plain `cargo build`
/// would link another one: test builds unify the dev-dependencies' features.)
fn step1_binary(root: &Path, args: &[String]) -> PathBuf {
    let mut dir = "debug".to_string();
    let mut it = args.iter().take_while(|a| *a != "--");
    while let Some(a) = it.next() {
        if a == "--release" || a == "-r" {
            dir = "release".into();
        } else if let Some(p) = a.strip_prefix("--profile=") {
            dir = profile_dir(p);
        } else if a == "--profile" {
            if let Some(p) = it.next() {
                dir = profile_dir(p);
            }
        }
    }
    root.join("target").join(dir).join("lodgen")
}

/// Cargo's output directory for profile `p` (`dev` and `test` share `debug`,
/// `bench` shares `release`).
fn profile_dir(p: &str) -> String {
    match p {
        "dev" | "test" => "debug".into(),
        "bench" => "release".into(),
        other => other.into(),
    }
}

/// Step 4: install the Python package from the checkout into the test venv
/// and run pytest against `bin`, the `lodgen` that step 1 built.
fn python_tests(root: &Path, bin: &Path, ci: bool, steps: &mut Steps) {
    let python = std::env::var_os("LODGEN_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/ci-venv/bin/python"));
    let ready = Command::new(&python)
        .args(["-c", "import pytest, numpy, trimesh, distributed"])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ready {
        let why = format!(
            "{} with pytest, numpy, trimesh and dask[distributed] not found (bash .ci/run makes \
             target/ci-venv; or set LODGEN_PYTHON)",
            python.display()
        );
        steps.missing("Python package tests", ci, &why);
        return;
    }
    let mut pip = Command::new(&python);
    pip.args([
        "-m",
        "pip",
        "install",
        "--quiet",
        "--disable-pip-version-check",
    ])
    .arg(root.join("crates/lodgen"))
    .stdin(Stdio::null())
    .current_dir(root);
    if steps.run("pip install ./crates/lodgen", &mut pip) != Outcome::Passed {
        return;
    }
    let mut pytest = Command::new(&python);
    pytest
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(root.join("crates/lodgen/python/tests"))
        .env("LODGEN_BIN", bin)
        .stdin(Stdio::null())
        .current_dir(root.join("target"));
    steps.run("pytest crates/lodgen/python/tests", &mut pytest);
}

/// The property tests' seed under `cargo xtask test` (when
/// `PROPTEST_RNG_SEED` is unset).
const PROPTEST_SEED: u64 = 23;

pub fn run(cargo_test_args: &[String]) -> Result<()> {
    let root = workspace_root();
    let out = root.join("target").join("test-out");
    let ci = is_ci();
    let mut steps = Steps::default();
    let t_all = Instant::now();

    if out.exists() {
        fs::remove_dir_all(&out).with_context(|| format!("emptying {}", out.display()))?;
    }
    fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;

    // 0. The layout rules (files ≤ 800 lines, functions ≤ 120, no module
    // cycles; `cargo xtask layout` lists the problems).
    let t_layout = Instant::now();
    match crate::layout::check_workspace(&root) {
        Ok(problems) if problems.is_empty() => steps.record(
            "layout",
            Outcome::Passed,
            t_layout.elapsed().as_secs_f64(),
            "",
        ),
        Ok(problems) => steps.record(
            "layout",
            Outcome::Failed,
            t_layout.elapsed().as_secs_f64(),
            &problems.join("; "),
        ),
        Err(e) => steps.record(
            "layout",
            Outcome::Failed,
            t_layout.elapsed().as_secs_f64(),
            &format!("{e:#}"),
        ),
    }

    // 1. Rust tests.
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| OsString::from("cargo"));
    let mut cargo_test = Command::new(cargo);
    cargo_test
        .args(["test", "--workspace"])
        .args(cargo_test_args)
        .env(TEST_OUT_ENV, &out)
        .current_dir(&root);
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        cargo_test.env("PROPTEST_RNG_SEED", PROPTEST_SEED.to_string());
    }
    steps.run("cargo test", &mut cargo_test);

    // 2. A fixed-seed fuzz budget (about half a minute; `cargo xtask fuzz
    // --cases N --seed S` for a long run).
    let t_fuzz = Instant::now();
    match crate::fuzz::run(&["--cases".into(), "3000".into(), "--seed".into(), "1".into()]) {
        Ok(()) => steps.record(
            "fuzz (3000 cases, seed 1)",
            Outcome::Passed,
            t_fuzz.elapsed().as_secs_f64(),
            "",
        ),
        Err(e) => steps.record(
            "fuzz (3000 cases, seed 1)",
            Outcome::Failed,
            t_fuzz.elapsed().as_secs_f64(),
            &format!("{e:#}"),
        ),
    }

    // 3. JS checks on what the Rust tests wrote.
    js_checks(&root, &out, ci, &mut steps)?;

    // 4. The Python package.
    python_tests(&root, &step1_binary(&root, cargo_test_args), ci, &mut steps);

    print_summary(&steps, t_all.elapsed().as_secs_f64())
}

/// glTF-Validator on every glTF file in `out` and Babylon.js's MSFT_lod
/// loader on every report / .glb pair (after `npm ci` when needed).
fn js_checks(root: &Path, out: &Path, ci: bool, steps: &mut Steps) -> Result<()> {
    let js = root.join("tests").join("js");
    let (require, why) = outputs_required(root)?;
    println!(
        "xtask test: test outputs in {} are {} ({why})",
        out.display(),
        if require { "required" } else { "optional" }
    );
    let gltf_files = files_under(out, &|n| n.ends_with(".glb") || n.ends_with(".gltf"))?;
    let pairs: Vec<(PathBuf, PathBuf)> = files_under(out, &|n| n.ends_with(".report.json"))?
        .into_iter()
        .filter_map(|report| {
            let name = report.file_name()?.to_string_lossy().into_owned();
            let glb = report.with_file_name(format!("{}.glb", name.strip_suffix(".report.json")?));
            glb.is_file().then_some((glb, report))
        })
        .collect();
    println!(
        "xtask test: {} glTF file(s), {} report/.glb pair(s) in {}",
        gltf_files.len(),
        pairs.len(),
        out.display()
    );

    let node_ready = if !tool_works("node") {
        steps.missing(
            "JS checks",
            ci,
            "node is not installed (apt-get install nodejs npm)",
        );
        false
    } else if js.join("node_modules").is_dir() {
        true
    } else if !tool_works("npm") {
        steps.missing("npm ci", ci, "npm is not installed (apt-get install npm)");
        false
    } else {
        let mut npm = Command::new("npm");
        npm.args(["ci", "--no-audit", "--no-fund"]).current_dir(&js);
        steps.run("npm ci", &mut npm) == Outcome::Passed
    };

    if node_ready {
        let mut validate = Command::new("node");
        validate.arg(js.join("validate.mjs"));
        if require {
            validate.arg("--require");
        }
        validate.arg(out).current_dir(root);
        steps.run("glTF-Validator", &mut validate);

        let chromium = chromium_path();
        if pairs.is_empty() {
            let why = format!(
                "no NAME.report.json with a sibling NAME.glb in {}",
                out.display()
            );
            if require {
                steps.record("Babylon.js MSFT_lod", Outcome::Failed, 0.0, &why);
            } else {
                println!("NOTICE: Babylon.js MSFT_lod check skipped: {why}.");
                steps.record("Babylon.js MSFT_lod", Outcome::Skipped, 0.0, &why);
            }
        } else if !chromium.is_file() {
            let why = format!(
                "{} not found (apt-get install chromium, or set LODGEN_CHROMIUM)",
                chromium.display()
            );
            steps.missing("Babylon.js MSFT_lod", ci, &why);
        } else {
            for (glb, report) in &pairs {
                let rel = glb.strip_prefix(out).unwrap_or(glb).display().to_string();
                steps.run(
                    &format!("Babylon.js MSFT_lod {rel}"),
                    Command::new("node")
                        .arg(js.join("babylon-lod.mjs"))
                        .arg(glb)
                        .arg(report)
                        .current_dir(root),
                );
            }
        }
    }

    Ok(())
}

/// Prints one line per step and the totals; fails when a step failed.
fn print_summary(steps: &Steps, secs: f64) -> Result<()> {
    println!("\nxtask test summary ({:.1} s):", secs);
    for s in &steps.0 {
        let word = match s.outcome {
            Outcome::Passed => "ok     ",
            Outcome::Failed => "FAILED ",
            Outcome::Skipped => "skipped",
        };
        let sep = if s.note.is_empty() { "" } else { ": " };
        println!("  {word} {:>6.1} s  {}{sep}{}", s.secs, s.name, s.note);
    }
    let (passed, failed, skipped) = (
        steps.count(Outcome::Passed),
        steps.count(Outcome::Failed),
        steps.count(Outcome::Skipped),
    );
    println!("xtask-test: {passed} passed, {failed} failed, {skipped} skipped");
    if failed > 0 {
        bail!("{failed} check(s) failed");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pytest step compares the module with the binary step 1 built:
    /// the profile directory follows `cargo test`'s own arguments, and
    /// nothing after `--` (the test binaries' arguments) counts.
    #[test]
    fn step1_binary_follows_the_profile_arguments() {
        let root = Path::new("/r");
        let bin = |args: &[&str]| {
            let args: Vec<String> = args.iter().map(|a| a.to_string()).collect();
            step1_binary(root, &args)
        };
        assert_eq!(bin(&[]), Path::new("/r/target/debug/lodgen"));
        assert_eq!(
            bin(&["-p", "lodgen", "golden"]),
            Path::new("/r/target/debug/lodgen")
        );
        assert_eq!(bin(&["--release"]), Path::new("/r/target/release/lodgen"));
        assert_eq!(bin(&["-r"]), Path::new("/r/target/release/lodgen"));
        assert_eq!(
            bin(&["--profile", "test"]),
            Path::new("/r/target/debug/lodgen")
        );
        assert_eq!(
            bin(&["--profile=bench"]),
            Path::new("/r/target/release/lodgen")
        );
        assert_eq!(bin(&["--profile", "ci"]), Path::new("/r/target/ci/lodgen"));
        assert_eq!(
            bin(&["--", "--release"]),
            Path::new("/r/target/debug/lodgen")
        );
    }
}
