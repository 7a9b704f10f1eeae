//! Where the shared test meshes are, for tests, examples and the xtask:
//! `$LODGEN_ASSETS`, else `../shared/assets` beside the workspace. The meshes
//! are never copied into the repository.

use std::path::PathBuf;

/// The folder that should hold `bunny.obj`, `cow.obj`, … (it may not exist).
pub fn shared_assets_dir() -> PathBuf {
    std::env::var_os("LODGEN_ASSETS")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets"))
}

/// The path of a shared test mesh, for tests: `None` (with a notice on
/// stderr) when it is missing, unless `CI=true`, where a missing mesh is a
/// failure.
pub fn shared_asset(name: &str) -> Option<PathBuf> {
    let path = shared_assets_dir().join(name);
    if path.exists() {
        Some(path)
    } else if std::env::var("CI").as_deref() == Ok("true") {
        panic!(
            "test mesh {} is missing (CI=true); set LODGEN_ASSETS",
            path.display()
        );
    } else {
        eprintln!("notice: {} not found; skipping this test", path.display());
        None
    }
}
