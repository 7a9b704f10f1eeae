//! Shared by the core's integration tests: locating `../shared/assets`
//! (or `$LODGEN_ASSETS`), a minimal OBJ reader (`v`/`f` lines only; the
//! core has no I/O, and the full readers live in the `lodgen` crate) and a
//! mesh's directed edges. Each test binary uses part of it.
#![allow(dead_code)]

use std::path::PathBuf;

/// The text of a shared test mesh: `None` with a notice when missing,
/// a panic when missing under `CI=true`.
pub fn shared_asset_text(name: &str) -> Option<String> {
    let dir = std::env::var_os("LODGEN_ASSETS")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets")
        });
    let path = dir.join(name);
    match std::fs::read_to_string(&path) {
        Ok(t) => Some(t),
        Err(e) if std::env::var("CI").as_deref() == Ok("true") => {
            panic!(
                "test mesh {} missing (CI=true): {e}; set LODGEN_ASSETS",
                path.display()
            )
        }
        Err(_) => {
            eprintln!(
                "notice: {} not found; skipping the test on real meshes",
                path.display()
            );
            None
        }
    }
}

/// `v`/`f` lines only: enough for the shared test meshes.
pub fn read_obj(text: &str) -> (Vec<[f32; 3]>, Vec<u32>) {
    let (mut p, mut idx) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f32> = it.take(3).map(|x| x.parse().unwrap()).collect();
                p.push([c[0], c[1], c[2]]);
            }
            Some("f") => {
                let f: Vec<u32> = it
                    .map(|x| x.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for k in 1..f.len() - 1 {
                    idx.extend_from_slice(&[f[0], f[k], f[k + 1]]);
                }
            }
            _ => {}
        }
    }
    (p, idx)
}

/// The directed edges of `m`'s triangles, sorted (a repeat is a face
/// reversed next to its neighbour or an edge of three faces; an edge
/// without its reverse is open).
pub fn directed_edges(m: &lodgen_pm::Mesh) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = m
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    e.sort_unstable();
    e
}
