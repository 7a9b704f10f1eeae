//! The browser checks' prerequisites and runner: node, Chromium
//! (`/usr/bin/chromium` or `LODGEN_CHROMIUM`) and npm packages in
//! `tests/js/node_modules`; a `tests/js` script run with node, its output
//! returned.

use std::process::Command;

use super::{root, tools_required};

/// What is missing of node, Chromium and the npm `packages`.
pub fn missing_tools(packages: &[&str]) -> Vec<String> {
    let mut missing = Vec::new();
    if Command::new("node").arg("--version").output().is_err() {
        missing.push("node".to_string());
    }
    let chromium = std::env::var("LODGEN_CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    if !std::path::Path::new(&chromium).exists() {
        missing.push(chromium);
    }
    for pkg in packages {
        let p = root().join("tests/js/node_modules").join(pkg);
        if !p.exists() {
            missing.push(format!("{} (npm ci in tests/js)", p.display()));
        }
    }
    missing
}

/// Whether the browser test `what` can run: `true` when nothing of
/// node, Chromium and `packages` is missing; otherwise a notice and
/// `false`, or a failure when [`tools_required`] (`CI=true`,
/// `LODGEN_BROWSER_TEST=1`).
pub fn ready(what: &str, packages: &[&str]) -> bool {
    let missing = missing_tools(packages);
    if missing.is_empty() {
        return true;
    }
    assert!(
        !tools_required(),
        "LODGEN_BROWSER_TEST=1 or CI=true, but missing for {what}: {missing:?}"
    );
    eprintln!("{what} skipped, missing: {missing:?}");
    false
}

/// Runs `node tests/js/<script> args…`; fails the test (with the log) when
/// it exits non-zero, else returns its output.
pub fn run_script(script: &str, args: &[&str]) -> String {
    let result = Command::new("node")
        .arg(root().join("tests/js").join(script))
        .args(args)
        .output()
        .expect("running node");
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&result.stdout),
        String::from_utf8_lossy(&result.stderr)
    );
    eprintln!("{log}");
    assert!(result.status.success(), "{script} failed:\n{log}");
    log
}
