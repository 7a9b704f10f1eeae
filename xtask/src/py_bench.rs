//! `cargo xtask bench --python [--batch] [--quick]`: the Python package's
//! targets (issue 17), printed by the scripts in crates/lodgen/python/bench:
//! `lodgen.simplify` on the bunny to 2 % against the same call in Rust
//! (`examples/simplify_timing`), pyfqmr and fast-simplification, every
//! output measured with `lodgen.measure`; with `--batch`, the batch mode's
//! `--jobs 2` / `--jobs 1` wall-time ratio on generated meshes and the
//! re-run with nothing changed.
//!
//! The venv is `target/bench-venv` (made when missing; numpy, pyfqmr and
//! fast-simplification from the package registry, then the package from
//! the checkout, built in release by maturin), or `$LODGEN_PYTHON`.

use anyhow::{ensure, Context, Result};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn run(what: &str, cmd: &mut Command) -> Result<()> {
    eprintln!("bench --python: {what}");
    let status = cmd
        .stdin(Stdio::null())
        .status()
        .with_context(|| format!("running {what}"))?;
    ensure!(status.success(), "{what} failed ({status})");
    Ok(())
}

fn imports(python: &Path, modules: &str) -> bool {
    Command::new(python)
        .args(["-c", &format!("import {modules}")])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The venv's python with numpy and the peers, and lodgen installed from
/// this checkout (rebuilt every time: the bench measures this source).
fn bench_python(root: &Path) -> Result<PathBuf> {
    let python = match std::env::var_os("LODGEN_PYTHON") {
        Some(p) => PathBuf::from(p),
        None => {
            let venv = root.join("target/bench-venv");
            let python = venv.join("bin/python");
            if !python.exists() {
                run(
                    "python3 -m venv target/bench-venv",
                    Command::new("python3").args(["-m", "venv"]).arg(&venv),
                )?;
            }
            python
        }
    };
    if !imports(&python, "numpy, pyfqmr, fast_simplification") {
        // a peer that does not install is left out of the table by the script
        let _ = run(
            "pip install numpy pyfqmr fast-simplification",
            Command::new(&python).args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
                "numpy",
                "pyfqmr",
                "fast-simplification",
            ]),
        );
    }
    run(
        "pip install ./crates/lodgen (maturin, release)",
        Command::new(&python)
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
                "--force-reinstall",
                "--no-deps",
            ])
            .arg(root.join("crates/lodgen"))
            .current_dir(root),
    )?;
    Ok(python)
}

pub fn run_python(args: &[String]) -> Result<()> {
    if let Some(other) = args
        .iter()
        .find(|a| !matches!(a.as_str(), "--python" | "--quick" | "--batch"))
    {
        anyhow::bail!("unknown bench --python option {other:?} (expected --quick or --batch)");
    }
    let quick = args.iter().any(|a| a == "--quick");
    let batch = args.iter().any(|a| a == "--batch");
    let root = crate::workspace_root();
    let assets = crate::shared_assets()?;
    let python = bench_python(&root)?;
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    run(
        "cargo build --release -p lodgen --bin lodgen --example simplify_timing",
        Command::new(&cargo)
            .args(["build", "--release", "-p", "lodgen", "--bin", "lodgen"])
            .args(["--example", "simplify_timing"])
            .current_dir(&root),
    )?;
    let bench = root.join("crates/lodgen/python/bench");
    run(
        "bench_python.py",
        Command::new(&python)
            .arg(bench.join("bench_python.py"))
            .arg(assets.join("bunny.obj"))
            .args(["--rounds", if quick { "3" } else { "9" }])
            .env("LODGEN_ASSETS", &assets),
    )?;
    if batch {
        let dir = root.join("target/bench-batch");
        let count = if quick { "40" } else { "200" };
        run(
            "bench_batch.py",
            Command::new(&python)
                .arg(bench.join("bench_batch.py"))
                .args(["--count", count, "--rounds", if quick { "1" } else { "3" }])
                .arg("--dir")
                .arg(&dir)
                .arg("--lodgen")
                .arg(root.join("target/release/lodgen")),
        )?;
    }
    Ok(())
}
