//! A batch's inputs: what the command line names (files, directories
//! walked, glob patterns) and where each output goes, the inputs that would
//! write one output, and the hashes that tell an input or an output
//! unchanged.

use anyhow::{bail, Context, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Extensions a directory walk picks up (lower case).
pub const MESH_EXTENSIONS: [&str; 5] = ["obj", "ply", "smf", "gltf", "glb"];

/// One input of a batch and where its output goes, relative to `--out-dir`.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct BatchInput {
    pub input: PathBuf,
    /// The output's path relative to the output directory.
    pub relative_output: PathBuf,
}

pub(super) fn is_mesh(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| MESH_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

pub(super) fn has_glob_chars(s: &str) -> bool {
    s.contains(['*', '?', '['])
}

fn relative_output(rel: &Path) -> PathBuf {
    rel.with_extension("glb")
}

/// Expand the command line's inputs: files as given, directories walked
/// (sorted, `skip` — the output directory — left out), glob patterns
/// matched. Errors for inputs that name nothing.
pub fn expand_inputs(inputs: &[PathBuf], skip: Option<&Path>) -> Result<Vec<BatchInput>> {
    let skip = skip.and_then(|s| s.canonicalize().ok());
    let mut out = Vec::new();
    for arg in inputs {
        let text = arg.to_string_lossy();
        if arg.is_dir() {
            let mut found = Vec::new();
            let walk = walkdir::WalkDir::new(arg)
                .follow_links(true)
                .sort_by_file_name()
                .into_iter()
                .filter_entry(|e| {
                    skip.as_ref()
                        .is_none_or(|s| e.path().canonicalize().ok().as_ref() != Some(s))
                });
            for entry in walk {
                let entry = match entry {
                    Ok(entry) => entry,
                    // a link back up the tree: what it leads to is walked
                    // where it is
                    Err(e) if e.loop_ancestor().is_some() => continue,
                    // a link to nothing, named as a mesh: an input that
                    // fails alone (it cannot be read), not the batch
                    Err(e) if e.path().is_some_and(|p| p.is_symlink() && is_mesh(p)) => {
                        let path = e.path().unwrap_or(arg).to_path_buf();
                        let rel = path.strip_prefix(arg).unwrap_or(&path).to_path_buf();
                        found.push(BatchInput {
                            input: path,
                            relative_output: relative_output(&rel),
                        });
                        continue;
                    }
                    Err(e) => return Err(e).with_context(|| format!("walking {}", arg.display())),
                };
                if entry.file_type().is_file() && is_mesh(entry.path()) {
                    let rel = entry.path().strip_prefix(arg).unwrap_or(entry.path());
                    found.push(BatchInput {
                        input: entry.path().to_path_buf(),
                        relative_output: relative_output(rel),
                    });
                }
            }
            if found.is_empty() {
                bail!(
                    "{}: no .obj, .ply, .smf, .gltf or .glb files in this directory",
                    arg.display()
                );
            }
            out.extend(found);
        } else if arg.is_file() {
            let name = arg.file_name().map(PathBuf::from).unwrap_or_default();
            out.push(BatchInput {
                input: arg.clone(),
                relative_output: relative_output(&name),
            });
        } else if has_glob_chars(&text) {
            // The pattern's fixed prefix (the directories before the first
            // component with a wildcard) is what outputs are relative to.
            let base: PathBuf = arg
                .components()
                .take_while(|c| !has_glob_chars(&c.as_os_str().to_string_lossy()))
                .collect();
            let mut found = Vec::new();
            for entry in glob::glob(&text).with_context(|| format!("glob pattern {text:?}"))? {
                let path = entry.with_context(|| format!("glob pattern {text:?}"))?;
                let in_skip = skip
                    .as_ref()
                    .is_some_and(|s| path.canonicalize().ok().is_some_and(|p| p.starts_with(s)));
                if path.is_file() && !in_skip {
                    let rel = path.strip_prefix(&base).unwrap_or(&path).to_path_buf();
                    found.push(BatchInput {
                        relative_output: relative_output(&rel),
                        input: path,
                    });
                }
            }
            if found.is_empty() {
                bail!("{text}: the pattern matches no file");
            }
            out.extend(found);
        } else {
            bail!("{}: no such file or directory", arg.display());
        }
    }
    // a file named twice (a directory and a glob over it, or a file inside
    // a directory given too) is built once, where it was first found
    let mut seen = std::collections::BTreeSet::new();
    out.retain(|i| seen.insert(i.input.canonicalize().unwrap_or_else(|_| i.input.clone())));
    Ok(out)
}

pub(super) fn key(rel: &Path) -> String {
    rel.components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("/")
}

/// The files an input refers to and is read with: a `.gltf`'s external
/// buffers and images, an `.obj`'s material libraries.
fn companions(input: &Path, bytes: &[u8]) -> Vec<PathBuf> {
    let dir = input.parent().unwrap_or(Path::new(""));
    let ext = input
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("gltf") => {
            let Ok(doc) = serde_json::from_slice::<serde_json::Value>(bytes) else {
                return Vec::new();
            };
            ["buffers", "images"]
                .iter()
                .filter_map(|k| doc[*k].as_array())
                .flatten()
                .filter_map(|b| b["uri"].as_str())
                .filter(|u| !u.starts_with("data:"))
                .map(|u| dir.join(percent_decode(u)))
                .collect()
        }
        Some("obj") => String::from_utf8_lossy(bytes)
            .lines()
            .filter_map(|l| l.trim_start().strip_prefix("mtllib"))
            .flat_map(|rest| {
                rest.split_whitespace()
                    .map(|n| dir.join(n))
                    .collect::<Vec<_>>()
            })
            .collect(),
        _ => Vec::new(),
    }
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(v) = u8::from_str_radix(&s[i + 1..i + 3], 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// BLAKE3 of the input and the files it refers to (a missing companion
/// hashes as missing, so its appearance changes the hash).
pub fn input_hash(input: &Path) -> std::io::Result<String> {
    let bytes = std::fs::read(input)?;
    let mut h = blake3::Hasher::new();
    h.update(&(bytes.len() as u64).to_le_bytes());
    h.update(&bytes);
    for c in companions(input, &bytes) {
        h.update(c.to_string_lossy().as_bytes());
        match std::fs::read(&c) {
            Ok(b) => {
                h.update(&(b.len() as u64).to_le_bytes());
                h.update(&b);
            }
            Err(_) => {
                h.update(b"missing");
            }
        }
    }
    Ok(h.finalize().to_hex().to_string())
}

/// BLAKE3 of a file's bytes (an output, to tell it unchanged).
pub(super) fn file_hash(path: &Path) -> std::io::Result<String> {
    let mut h = blake3::Hasher::new();
    h.update(&std::fs::read(path)?);
    Ok(h.finalize().to_hex().to_string())
}

/// Per input, why it is not built when another input would write the same
/// output (`rock.obj` and `rock.glb` side by side): both fail, the others
/// are built.
pub(super) fn clashes(inputs: &[BatchInput], out_dir: &Path) -> Vec<Option<String>> {
    let mut by_output: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (k, i) in inputs.iter().enumerate() {
        by_output
            .entry(key(&i.relative_output))
            .or_default()
            .push(k);
    }
    let mut out = vec![None; inputs.len()];
    for ks in by_output.values().filter(|ks| ks.len() > 1) {
        let names: Vec<String> = ks
            .iter()
            .map(|&k| inputs[k].input.display().to_string())
            .collect();
        let output = out_dir.join(&inputs[ks[0]].relative_output);
        for &k in ks {
            let all = if names.len() == 2 { "both" } else { "all" };
            out[k] = Some(format!(
                "{} would {all} write {}; rename one, or build them into different --out-dir",
                names.join(" and "),
                output.display()
            ));
        }
    }
    out
}
