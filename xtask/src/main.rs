//! `cargo xtask <task>`: project automation (alias in `.cargo/config.toml`).

use std::path::PathBuf;

mod attributes;
mod bench;
mod compare;
mod draco;
mod e2e;
mod fuzz;
mod golden;
mod layout;
mod markers;
mod py_bench;
mod quality;
mod render;
mod stream_bench;
mod test;

const USAGE: &str = "usage: cargo xtask <task> [args]

tasks:
  test [CARGO-TEST-ARGS]  run every test: cargo test, glTF-Validator, Babylon.js MSFT_lod check
  draco [DIR]             Draco round trip of every LOD level in DIR (default target/test-out)
  fuzz [--cases N] [--seed S]
                          mutated OBJ/PLY/SMF/GLB files through read, build, write, inspect (default 2000 cases, seed 1);
                          a failing case is stored in tests/fuzz-regressions/
  golden                  regenerate assets/golden/ (bunny and cow LOD summaries) and assets/knot.obj
  bench [--quick] [--e2e] [--huge]
                          lodgen vs meshopt on the bunny and a ~1M-triangle subdivided bunny,
                          then end to end (the lodgen binary vs a meshopt program; + 4.4M);
                          --e2e: the end-to-end rows only; --huge: + the 17.8M mesh (one run)
  bench --python [--batch] [--quick]
                          lodgen.simplify from Python vs the same call in Rust, pyfqmr, fast-simplification
                          (bunny to 2 %, venv target/bench-venv or $LODGEN_PYTHON); --batch: --jobs 2 / --jobs 1
                          on 200 generated meshes and the re-run with nothing changed
  stream-bench [--quick] [--runs N]
                          time to first pixel / full detail, progressive vs plain meshopt file, three.js in
                          headless Chromium over a throttled 10 Mbit/s, 50 ms line (bunny, 1.1M bunny)
  compare [--meshes bunny,cow,fandisk] [--no-render]
                          every method + meshopt at 50/10/2%: docs/compare.md, docs/compare.png, docs/renders/
  quality [--quick] [--meshes a,b] [--no-peers] [--greedy] [--reach-off] [--fresh]
                          lodgen vs meshopt, MeshLab, Open3D, pyfqmr, fast-simplification (Python
                          peers in target/quality-venv) at 50/10/2%: docs/quality.md, docs/quality.png
                          (peers re-run only where lodgen's triangle count moved; --fresh: all)

  layout                  files ≤ 800 lines, functions ≤ 120 lines outside tests, no module cycles
                          (crates/*/src, xtask/src); no merge-conflict markers in any text file
  attributes [--mesh NAME] [--half-edge] [--reach-off] [--attribute-weights=LIST]
                          UV / normal error of lodgen vs meshopt simplify_with_attributes on a shared
                          mesh (default spot; beetle: its own hard-edged normals)";

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((task, rest)) = args.split_first() else {
        eprintln!("{USAGE}");
        std::process::exit(2);
    };
    // `cargo xtask TASK --help` prints the usage instead of running TASK (`test` passes its
    // arguments on to `cargo test`, whose own help they then ask for).
    if task != "test" && rest.iter().any(|a| a == "-h" || a == "--help") {
        println!("{USAGE}");
        return Ok(());
    }
    match task.as_str() {
        "test" => test::run(rest),
        "draco" => draco::run(rest),
        "golden" => golden::run(rest),
        "fuzz" => fuzz::run(rest),
        "bench" => bench::run(rest),
        "attributes" => attributes::run(rest),
        "bench-child" => bench::child(rest),
        "compare" => compare::run(rest),
        "stream-bench" => stream_bench::run(rest),
        "layout" => layout::run(rest),
        "quality" => quality::run(rest),
        "help" | "-h" | "--help" => {
            println!("{USAGE}");
            Ok(())
        }
        other => {
            eprintln!("unknown task `{other}`\n{USAGE}");
            std::process::exit(2);
        }
    }
}

/// For the tasks that time things: when this is the dev build (what the
/// `cargo xtask` alias builds, opt-level 1 for the workspace's crates),
/// run `task` from the release build instead and return `true` once it
/// succeeded; `false` when this already is the release build.
pub fn rerun_in_release(task: &str, args: &[String]) -> anyhow::Result<bool> {
    if !cfg!(debug_assertions) {
        return Ok(false);
    }
    eprintln!("{task}: running the release build of xtask (times of the dev build mislead)");
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = std::process::Command::new(cargo)
        .args(["run", "--release", "--quiet", "-p", "xtask", "--", task])
        .args(args)
        .current_dir(workspace_root())
        .status()?;
    anyhow::ensure!(status.success(), "the release {task} failed ({status})");
    Ok(true)
}

/// The workspace root (the parent of `xtask/`).
pub fn workspace_root() -> PathBuf {
    let xtask = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    xtask.parent().map(PathBuf::from).unwrap_or(xtask)
}

/// `../shared/assets` beside the workspace, or `$LODGEN_ASSETS`.
pub fn shared_assets() -> anyhow::Result<PathBuf> {
    let dir = lodgen::assets::shared_assets_dir();
    anyhow::ensure!(
        dir.join("bunny.obj").exists(),
        "test meshes not found in {} (set LODGEN_ASSETS to the folder holding bunny.obj)",
        dir.display()
    );
    Ok(dir)
}
