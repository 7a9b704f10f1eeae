//! `lodgen inspect FILE`: reads a `.gltf`/`.glb` and reports its `MSFT_lod`
//! structure (per chain, each level's node, mesh, triangle and vertex counts
//! and screen coverage).
//!
//! This module owns reading the JSON structure only: no buffer data is loaded
//! (counts come from accessor `count`s), so compressed or quantized files are
//! inspected as they are. Every index is checked; a malformed file is an
//! [`InspectError`], never a panic.

use std::fmt;
use std::path::{Path, PathBuf};

use serde_json::Value;

/// Why a file could not be inspected.
#[derive(Debug, thiserror::Error)]
pub enum InspectError {
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a GLB container: {reason}", .path.display())]
    Glb { path: PathBuf, reason: String },
    #[error(
        "{}: not a glTF file: neither the GLB magic `glTF` nor a JSON object at the start \
         (`lodgen inspect` reads .gltf and .glb files; `lodgen measure` compares meshes of any format)",
        .path.display()
    )]
    NotGltf { path: PathBuf },
    #[error("{}: invalid JSON: {source}", .path.display())]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("{}: {pointer}: {reason}", .path.display())]
    Malformed {
        path: PathBuf,
        pointer: String,
        reason: String,
    },
}

/// The LOD structure of one glTF file.
#[derive(Debug, Clone, PartialEq)]
pub struct InspectReport {
    pub path: PathBuf,
    pub extensions_used: Vec<String>,
    pub extensions_required: Vec<String>,
    /// One per node carrying `MSFT_lod`, in node order.
    pub chains: Vec<LodChain>,
    /// Nodes with a mesh that are in no chain.
    pub plain: Vec<InspectLevel>,
    /// Departures from what `MSFT_lod` clients expect.
    pub warnings: Vec<String>,
}

/// One `MSFT_lod` chain, finest level first.
#[derive(Debug, Clone, PartialEq)]
pub struct LodChain {
    pub levels: Vec<InspectLevel>,
}

/// One level (or one plain mesh node).
#[derive(Debug, Clone, PartialEq)]
pub struct InspectLevel {
    pub node: usize,
    pub name: Option<String>,
    pub mesh: Option<usize>,
    pub triangles: u64,
    pub vertices: u64,
    /// This level's `MSFT_screencoverage` value, when present.
    pub screen_coverage: Option<f64>,
    /// Whether the node is reachable from a scene.
    pub in_scene: bool,
}

/// Reads `path` and describes its LOD chains.
pub fn inspect(path: &Path) -> Result<InspectReport, InspectError> {
    let bytes = std::fs::read(path).map_err(|source| InspectError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let json: Value = if bytes.starts_with(b"glTF") {
        // the gltf crate subtracts the header size from the declared length
        // unchecked (a panic below 12)
        let declared = bytes
            .get(8..12)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if declared.is_none_or(|l| l < 12) {
            return Err(InspectError::Glb {
                path: path.to_path_buf(),
                reason: "GLB header: length missing or below 12 bytes".into(),
            });
        }
        let glb = gltf::Glb::from_slice(&bytes).map_err(|e| InspectError::Glb {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        serde_json::from_slice(&glb.json)
    } else {
        // (a UTF-8 byte order mark, as some editors write, before the JSON)
        let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
        if text.iter().find(|b| !b.is_ascii_whitespace()) != Some(&b'{') {
            return Err(InspectError::NotGltf {
                path: path.to_path_buf(),
            });
        }
        serde_json::from_slice(text)
    }
    .map_err(|source| InspectError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    report(path, &json)
}

fn report(path: &Path, root: &Value) -> Result<InspectReport, InspectError> {
    let list = |key: &str| -> Vec<String> {
        root.get(key)
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(|v| v.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut doc = Doc {
        path,
        nodes: array(root, "nodes"),
        meshes: array(root, "meshes"),
        accessors: array(root, "accessors"),
        in_scene: Vec::new(),
    };
    doc.in_scene = doc.scene_membership(array(root, "scenes"))?;

    let mut warnings = Vec::new();
    if list("extensionsRequired").iter().any(|e| e == "MSFT_lod") {
        warnings
            .push("MSFT_lod is in extensionsRequired (clients without it refuse the file)".into());
    }
    let mut chains = Vec::new();
    let mut in_chain = vec![false; doc.nodes.len()];
    for (n, node) in doc.nodes.iter().enumerate() {
        if let Some(chain) = doc.chain(n, node, &mut in_chain, &mut warnings)? {
            chains.push(chain);
        }
    }
    let mut plain = Vec::new();
    for (n, node) in doc.nodes.iter().enumerate() {
        if !in_chain[n] && node.get("mesh").is_some() {
            plain.push(doc.level(n, None)?);
        }
    }
    Ok(InspectReport {
        path: path.to_path_buf(),
        extensions_used: list("extensionsUsed"),
        extensions_required: list("extensionsRequired"),
        chains,
        plain,
        warnings,
    })
}

/// The array `root[key]` (empty when absent or not an array).
fn array<'a>(root: &'a Value, key: &str) -> &'a [Value] {
    root.get(key)
        .and_then(Value::as_array)
        .map_or(&[], Vec::as_slice)
}

/// The parts of the document the report reads, every index checked.
struct Doc<'a> {
    path: &'a Path,
    nodes: &'a [Value],
    meshes: &'a [Value],
    accessors: &'a [Value],
    /// Per node: reachable from a scene.
    in_scene: Vec<bool>,
}

impl Doc<'_> {
    fn malformed(&self, pointer: String, reason: &str) -> InspectError {
        InspectError::Malformed {
            path: self.path.to_path_buf(),
            pointer,
            reason: reason.to_string(),
        }
    }

    fn index(&self, v: &Value, pointer: String, len: usize) -> Result<usize, InspectError> {
        v.as_u64()
            .map(|i| i as usize)
            .filter(|&i| i < len)
            .ok_or_else(|| self.malformed(pointer, "index out of range"))
    }

    /// Nodes reachable from a scene (iterative walk, cycle-safe).
    fn scene_membership(&self, scenes: &[Value]) -> Result<Vec<bool>, InspectError> {
        let nodes = self.nodes;
        let mut in_scene = vec![false; nodes.len()];
        let mut stack = Vec::new();
        for (s, scene) in scenes.iter().enumerate() {
            for (j, n) in scene
                .get("nodes")
                .and_then(Value::as_array)
                .map_or(&[][..], Vec::as_slice)
                .iter()
                .enumerate()
            {
                stack.push(self.index(n, format!("/scenes/{s}/nodes/{j}"), nodes.len())?);
            }
        }
        while let Some(n) = stack.pop() {
            if std::mem::replace(&mut in_scene[n], true) {
                continue;
            }
            if let Some(children) = nodes[n].get("children").and_then(Value::as_array) {
                for (j, c) in children.iter().enumerate() {
                    stack.push(self.index(c, format!("/nodes/{n}/children/{j}"), nodes.len())?);
                }
            }
        }
        Ok(in_scene)
    }

    fn count_of(&self, a: &Value, pointer: String) -> Result<u64, InspectError> {
        let i = self.index(a, pointer.clone(), self.accessors.len())?;
        self.accessors[i]
            .get("count")
            .and_then(Value::as_u64)
            .ok_or_else(|| self.malformed(format!("/accessors/{i}"), "accessor without count"))
    }

    /// Node `n` as a level: its mesh's triangle and vertex counts.
    fn level(&self, n: usize, coverage: Option<f64>) -> Result<InspectLevel, InspectError> {
        let node = &self.nodes[n];
        let mut level = InspectLevel {
            node: n,
            name: node.get("name").and_then(Value::as_str).map(String::from),
            mesh: None,
            triangles: 0,
            vertices: 0,
            screen_coverage: coverage,
            in_scene: self.in_scene[n],
        };
        if let Some(m) = node.get("mesh") {
            let m = self.index(m, format!("/nodes/{n}/mesh"), self.meshes.len())?;
            level.mesh = Some(m);
            let prims = self.meshes[m]
                .get("primitives")
                .and_then(Value::as_array)
                .map_or(&[][..], Vec::as_slice);
            for (p, prim) in prims.iter().enumerate() {
                let at = format!("/meshes/{m}/primitives/{p}");
                let vertices = match prim.get("attributes").and_then(|a| a.get("POSITION")) {
                    Some(a) => self.count_of(a, format!("{at}/attributes/POSITION"))?,
                    None => 0,
                };
                level.vertices += vertices;
                let corners = match prim.get("indices") {
                    Some(a) => self.count_of(a, format!("{at}/indices"))?,
                    None => vertices,
                };
                if prim.get("mode").and_then(Value::as_u64).unwrap_or(4) == 4 {
                    level.triangles += corners / 3;
                }
            }
        }
        Ok(level)
    }

    /// The chain of node `n` when it carries `MSFT_lod`; marks its members
    /// in `in_chain` and adds what clients would trip over to `warnings`.
    fn chain(
        &self,
        n: usize,
        node: &Value,
        in_chain: &mut [bool],
        warnings: &mut Vec<String>,
    ) -> Result<Option<LodChain>, InspectError> {
        let Some(ids) = node.pointer("/extensions/MSFT_lod/ids") else {
            return Ok(None);
        };
        let ids = ids.as_array().ok_or_else(|| {
            self.malformed(
                format!("/nodes/{n}/extensions/MSFT_lod/ids"),
                "not an array",
            )
        })?;
        let coverage: Vec<Option<f64>> = node
            .pointer("/extras/MSFT_screencoverage")
            .and_then(Value::as_array)
            .map(|a| a.iter().map(Value::as_f64).collect())
            .unwrap_or_default();
        let mut members = vec![n];
        for (j, id) in ids.iter().enumerate() {
            members.push(self.index(
                id,
                format!("/nodes/{n}/extensions/MSFT_lod/ids/{j}"),
                self.nodes.len(),
            )?);
        }
        if !coverage.is_empty() && coverage.len() != members.len() {
            warnings.push(format!(
                "node {n}: MSFT_screencoverage has {} values for {} levels",
                coverage.len(),
                members.len()
            ));
        }
        let mut levels = Vec::with_capacity(members.len());
        for (k, &m) in members.iter().enumerate() {
            in_chain[m] = true;
            let level = self.level(m, coverage.get(k).copied().flatten())?;
            if k > 0 && level.in_scene {
                warnings.push(format!(
                    "node {m} (level {k} of node {n}) is in a scene: clients draw it too"
                ));
            }
            levels.push(level);
        }
        Ok(Some(LodChain { levels }))
    }
}

fn label(level: &InspectLevel) -> String {
    match &level.name {
        Some(name) => format!("{} {name:?}", level.node),
        None => level.node.to_string(),
    }
}

impl fmt::Display for InspectReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let none = || "-".to_string();
        writeln!(f, "{}", self.path.display())?;
        writeln!(
            f,
            "extensionsUsed: {}",
            if self.extensions_used.is_empty() {
                none()
            } else {
                self.extensions_used.join(", ")
            }
        )?;
        writeln!(
            f,
            "extensionsRequired: {}",
            if self.extensions_required.is_empty() {
                none()
            } else {
                self.extensions_required.join(", ")
            }
        )?;
        for (c, chain) in self.chains.iter().enumerate() {
            let head = &chain.levels[0];
            writeln!(
                f,
                "LOD chain {c} (node {}): {} levels",
                label(head),
                chain.levels.len()
            )?;
            writeln!(
                f,
                "  {:>5}  {:<28} {:>5} {:>10} {:>10} {:>12}",
                "level", "node", "mesh", "triangles", "vertices", "coverage"
            )?;
            for (k, level) in chain.levels.iter().enumerate() {
                writeln!(
                    f,
                    "  {:>5}  {:<28} {:>5} {:>10} {:>10} {:>12}",
                    k,
                    label(level),
                    level.mesh.map_or_else(none, |m| m.to_string()),
                    level.triangles,
                    level.vertices,
                    level
                        .screen_coverage
                        .map_or_else(none, |c| format!("{c:.4e}")),
                )?;
            }
        }
        if self.chains.is_empty() {
            writeln!(f, "no MSFT_lod chains")?;
        }
        for level in &self.plain {
            writeln!(
                f,
                "mesh node {} without LOD: mesh {}, {} triangles, {} vertices",
                label(level),
                level.mesh.map_or_else(none, |m| m.to_string()),
                level.triangles,
                level.vertices
            )?;
        }
        for w in &self.warnings {
            writeln!(f, "warning: {w}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("lodgen-inspect-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn a_mesh_of_another_format_is_named_not_gltf_and_a_bom_reads() {
        let obj = scratch("cube.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let e = inspect(&obj).unwrap_err();
        assert!(matches!(e, InspectError::NotGltf { .. }), "{e}");
        assert!(e.to_string().contains("not a glTF file"), "{e}");
        let bom = scratch(
            "bom.gltf",
            b"\xEF\xBB\xBF {\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"name\":\"n\"}]}",
        );
        let r = inspect(&bom).unwrap();
        assert!(r.chains.is_empty() && r.plain.is_empty(), "{r:?}");
        let bad = scratch("bad.gltf", b"{\"asset\": ");
        assert!(matches!(inspect(&bad), Err(InspectError::Json { .. })));
        std::fs::remove_dir_all(obj.parent().unwrap()).unwrap();
    }
}
