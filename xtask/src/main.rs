//! `cargo xtask <task>`: project automation (alias in `.cargo/config.toml`).

use std::path::PathBuf;

mod draco;
mod test;

const USAGE: &str = "usage: cargo xtask <task> [args]

tasks:
  test [CARGO-TEST-ARGS]  run every test: cargo test, glTF-Validator, Babylon.js MSFT_lod check
  draco [DIR]             Draco round trip of every LOD level in DIR (default target/test-out)";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((task, rest)) = args.split_first() else {
        eprintln!("{USAGE}");
        std::process::exit(2);
    };
    let result = match task.as_str() {
        "test" => test::run(rest),
        "draco" => draco::run(rest),
        "help" | "-h" | "--help" => {
            println!("{USAGE}");
            Ok(())
        }
        other => {
            eprintln!("unknown task `{other}`\n{USAGE}");
            std::process::exit(2);
        }
    };
    if let Err(e) = result {
        eprintln!("xtask {task}: error: {e:#}");
        std::process::exit(1);
    }
}

/// The workspace root (the parent of `xtask/`).
pub fn workspace_root() -> PathBuf {
    let xtask = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    xtask.parent().map(PathBuf::from).unwrap_or(xtask)
}
