//! Shared by the core's integration tests: locating `../shared/assets`
//! (or `$LODGEN_ASSETS`), a minimal OBJ reader (`v`/`f` lines only; the
//! core has no I/O, and the full readers live in the `lodgen` crate) and a
//! mesh's edges. Each test binary uses part of it.
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

/// `fins` strips of `rows` × `chain` quads sharing one chain of `chain + 1`
/// vertices along x: each chain edge has `fins` faces (a non-manifold edge,
/// as where beetle.obj's panels meet its body). Fin `i` leaves the chain at
/// angle `2π i / fins` (plus `twist`) around x and bends a little (so its
/// vertices are not all coplanar); `noise` jitters every vertex but the
/// chain's ends (seeded, deterministic).
pub fn fins(
    fins: u32,
    chain: u32,
    rows: u32,
    twist: f32,
    noise: f32,
    seed: u64,
) -> lodgen_pm::Mesh {
    let mut s = seed;
    let mut jitter = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        noise * (((s >> 40) as f32 / (1u64 << 24) as f32) - 0.5)
    };
    let mut positions: Vec<[f32; 3]> = (0..=chain)
        .map(|j| {
            let end = j == 0 || j == chain;
            let (a, b) = if end {
                (0.0, 0.0)
            } else {
                (jitter(), jitter())
            };
            [j as f32, a, b]
        })
        .collect();
    let mut triangles = Vec::new();
    let at = |i: u32, r: u32, j: u32| {
        if r == 0 {
            j
        } else {
            chain + 1 + (i * rows + r - 1) * (chain + 1) + j
        }
    };
    for i in 0..fins {
        let angle = std::f32::consts::TAU * i as f32 / fins as f32 + twist;
        let (sin, cos) = angle.sin_cos();
        for r in 1..=rows {
            for j in 0..=chain {
                let d = r as f32;
                let bend = 0.15 * d * d / rows as f32 * ((j as f32) * 0.7).sin();
                let (u, w) = (d + jitter(), bend + jitter());
                positions.push([j as f32 + jitter(), u * cos - w * sin, u * sin + w * cos]);
            }
        }
        for r in 0..rows {
            for j in 0..chain {
                let (a, b) = (at(i, r, j), at(i, r, j + 1));
                let (c, d) = (at(i, r + 1, j), at(i, r + 1, j + 1));
                triangles.push([a, b, d]);
                triangles.push([a, d, c]);
            }
        }
    }
    lodgen_pm::Mesh {
        positions,
        triangles,
    }
}

/// Each edge of `m` (a sorted vertex pair) with the number of faces using it,
/// in edge order.
pub fn edge_uses(m: &lodgen_pm::Mesh) -> Vec<((u32, u32), usize)> {
    let mut e: Vec<(u32, u32)> = m
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    e.sort_unstable();
    e.chunk_by(|a, b| a == b)
        .map(|run| (run[0], run.len()))
        .collect()
}

/// The edges of `m` with three or more faces, as sorted vertex pairs.
pub fn edges_of_three_faces(m: &lodgen_pm::Mesh) -> Vec<(u32, u32)> {
    edge_uses(m)
        .into_iter()
        .filter(|&(_, n)| n >= 3)
        .map(|(e, _)| e)
        .collect()
}

/// A shared test mesh, welded and cleaned by `prepare` (`None` as for
/// [`shared_asset_text`]).
pub fn shared_mesh(name: &str) -> Option<lodgen_pm::Mesh> {
    let (p, idx) = read_obj(&shared_asset_text(name)?);
    Some(
        lodgen_pm::prepare(&p, &idx)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .mesh,
    )
}
