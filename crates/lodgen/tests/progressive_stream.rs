//! The `LODGEN_progressive` stream of a written file against the file's own
//! levels: replaying the decoded stream to each level's record count gives
//! the level's triangles with the level's positions on the file's
//! `--quantize` grid, exactly.

use clap::Parser;
use lodgen::cli::{build_file, BuildArgs};
use lodgen_pm::stream::{decode, Grid};
use std::path::{Path, PathBuf};

#[derive(Parser)]
struct Options {
    #[command(flatten)]
    build: BuildArgs,
}

fn knot() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/knot.obj")
}

/// Triangles as grid-point triples, each rotated to start at its smallest
/// corner (orientation kept), sorted.
fn canonical(tris: impl Iterator<Item = [[u16; 3]; 3]>) -> Vec<[[u16; 3]; 3]> {
    let mut v: Vec<_> = tris
        .map(|t| {
            let r = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
            [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
        })
        .collect();
    v.sort_unstable();
    v
}

#[test]
fn every_level_of_a_quantized_file_replays_exactly_from_its_stream() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("knot.glb");
    let argv = [
        "lodgen",
        "--levels",
        "100%,50%,10%,2%",
        "--progressive",
        "--quantize",
        "--compress",
        "meshopt",
    ];
    let args = Options::try_parse_from(argv).unwrap().build;
    let built = build_file(&knot(), &out, &args, &mut |_| {}).unwrap();
    let mb = &built.builds[0];
    let grid: Grid = lodgen::progressive::level_grid(&mb.lod);

    // the file's dequantization (node translation + uniform scale) is the grid
    let bytes = std::fs::read(&out).unwrap();
    let (root, _) = lodgen::progressive::parse_glb(&bytes).unwrap();
    let dequant = root["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n.get("scale").is_some())
        .expect("a dequantization node");
    let center: Vec<f64> = serde_json::from_value(dequant["translation"].clone()).unwrap();
    let scale: Vec<f64> = serde_json::from_value(dequant["scale"].clone()).unwrap();
    assert_eq!(center, grid.center.to_vec());
    assert_eq!(scale, vec![grid.half; 3]);

    let (found, stream) = lodgen::progressive::read_file(&out).unwrap().unwrap();
    assert_eq!(found.levels, mb.level_splits);
    let (pm, levels) = decode(&stream).unwrap();
    assert_eq!(levels, mb.level_splits);
    assert_eq!(levels.len(), 4);
    for (k, level) in mb.lod.levels.iter().enumerate() {
        let m = pm.mesh_at_splits(levels[k]);
        let got = canonical(
            m.triangles
                .iter()
                .map(|t| t.map(|v| grid.quantize(m.positions[v as usize]))),
        );
        let want = canonical(level.primitives.iter().flat_map(|p| {
            p.indices
                .chunks_exact(3)
                .map(|t| [0, 1, 2].map(|i| grid.quantize(p.positions[t[i] as usize])))
        }));
        assert_eq!(got.len(), want.len(), "level {k}: triangle count");
        assert!(got == want, "level {k}: triangles differ");
        // and decoded coordinates are the grid points themselves
        for p in &m.positions {
            assert_eq!(grid.dequantize(grid.quantize(*p)), *p);
        }
    }
}
