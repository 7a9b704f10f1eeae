//! Batch mode's manifest (`--out-dir DIR/.lodgen-manifest.json`): what
//! each output was built from, so a re-run skips unchanged files; and
//! [`Running`], the manifest kept up to date while a batch runs, so a batch
//! interrupted (Ctrl-C) keeps the files it finished.

use crate::cli;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The manifest's file name inside `--out-dir`.
pub const MANIFEST: &str = ".lodgen-manifest.json";

/// One manifest entry: what an output was built from.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct ManifestEntry {
    pub input: String,
    pub input_hash: String,
    pub options_hash: String,
    /// BLAKE3 of the output as written (a damaged or replaced output is
    /// rebuilt; empty in manifests of earlier versions: rebuilt too).
    #[serde(default)]
    pub output_hash: String,
    /// The file's report when it was built (shown again when skipped).
    pub report: serde_json::Value,
}

/// `DIR/.lodgen-manifest.json`: output path (relative, `/`-separated) →
/// what it was built from.
#[derive(Serialize, Deserialize, Clone, Debug, Default, PartialEq)]
pub struct Manifest {
    pub lodgen_version: String,
    pub outputs: BTreeMap<String, ManifestEntry>,
}

impl Manifest {
    /// The manifest in `dir`, empty when there is none or it is unreadable
    /// (then every file is rebuilt).
    pub fn load(dir: &Path) -> Manifest {
        std::fs::read(dir.join(MANIFEST))
            .ok()
            .and_then(|b| serde_json::from_slice::<Manifest>(&b).ok())
            .filter(|m| m.lodgen_version == env!("CARGO_PKG_VERSION"))
            .unwrap_or_default()
    }

    pub fn save(&self, dir: &Path) -> Result<()> {
        let path = dir.join(MANIFEST);
        cli::write_atomically(&path, serde_json::to_string_pretty(self)?.as_bytes())
            .with_context(|| format!("writing the manifest {}", path.display()))
    }
}

/// The manifest of a running batch: each built file recorded as it ends,
/// and saved after the first and then at most once per [`Running::EVERY`]
/// (the batch saves the final manifest at its end).
pub struct Running<'a> {
    dir: &'a Path,
    state: Mutex<(Manifest, Option<Instant>)>,
}

impl<'a> Running<'a> {
    /// The longest a finished file goes unrecorded on disk.
    pub const EVERY: Duration = Duration::from_secs(1);

    pub fn new(dir: &'a Path, manifest: &Manifest) -> Running<'a> {
        Running {
            dir,
            state: Mutex::new((manifest.clone(), None)),
        }
    }

    /// Records the output `key` built as `entry`; saves when due (a failed
    /// save is left to the final one to report).
    pub fn built(&self, key: &str, entry: &ManifestEntry) {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        let (manifest, saved) = &mut *state;
        manifest.outputs.insert(key.to_string(), entry.clone());
        if saved.is_none_or(|t| t.elapsed() >= Self::EVERY) {
            manifest.lodgen_version = env!("CARGO_PKG_VERSION").to_string();
            let _ = manifest.save(self.dir);
            *saved = Some(Instant::now());
        }
    }
}
