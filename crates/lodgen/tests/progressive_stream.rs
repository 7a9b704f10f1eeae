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
    replays_exactly(&knot());
}

/// beetle.obj: its coarse levels close triangular holes (a split then
/// reopens one), and the stream still replays every level.
#[test]
fn a_file_whose_levels_close_holes_replays_exactly_from_its_stream() {
    if let Some(beetle) = lodgen::assets::shared_asset("beetle.obj") {
        replays_exactly(&beetle);
    }
}

/// Every level of `input` written with `--progressive --quantize
/// --compress meshopt` is the stream's replay to that level, and the file's
/// dequantization node is the stream's grid, bit for bit (beetle's y centre
/// was one ulp off when the JSON the writer re-reads to add the stream was
/// parsed without serde_json's `float_roundtrip`).
fn replays_exactly(input: &Path) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
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
    let built = build_file(input, &out, &args, &mut |_| {}).unwrap();
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

/// spot.obj (UVs): every corner of the finest level replayed from the
/// stream has the file level's grid point and texture coordinate (through
/// the channel's encoding: spot's UVs leave [0, 1], so unorm16 over their
/// range, within half a step of the file's `f32`), and every level the
/// file's triangles.
#[test]
fn the_finest_level_of_a_textured_file_replays_its_attributes_exactly() {
    let Some(spot) = lodgen::assets::shared_asset("spot.obj") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("spot.glb");
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
    let built = build_file(&spot, &out, &args, &mut |_| {}).unwrap();
    let mb = &built.builds[0];
    let grid: Grid = lodgen::progressive::level_grid(&mb.lod);
    let (_, stream) = lodgen::progressive::read_file(&out).unwrap().unwrap();
    let layout = lodgen_pm::stream::decode_header(&stream)
        .unwrap()
        .wedges
        .expect("spot streams its wedges");
    let (uv, n) = {
        let d = lodgen_pm::stream::decode_with_attributes(&stream).unwrap();
        let a = d.attributes.clone().unwrap();
        let (at, n) = a.channel("TEXCOORD_0").expect("a UV channel");
        assert_eq!(n, 2);
        let enc = layout.encodings[layout
            .channels
            .iter()
            .position(|c| c.name == "TEXCOORD_0")
            .unwrap()];
        // spot's UVs leave [0, 1] (from −0.052): unorm16 over their range
        let lodgen_pm::stream::AttrEncoding::Unorm16Range(r) = enc else {
            panic!("spot's UVs as {enc:?}");
        };
        assert!(r.offset < 0.0 && r.scale > 1.0, "{r:?}");
        ((d, a, at, enc), n)
    };
    let (d, a, at, enc) = uv;
    let mut cursor = d.pm.cursor();
    for (k, level) in mb.lod.levels.iter().enumerate() {
        cursor.seek(d.levels[k]);
        let m = cursor.mesh();
        let w = cursor.wedges().unwrap();
        // corners as (grid point, UV bits); the UV only on the finest level
        // (coarser file levels hold fitted values, the stream source ones)
        let with_uv = k == 0;
        let corner = |q: [u16; 3], uv: [f32; 2]| {
            let uv = if with_uv {
                let step = match enc {
                    lodgen_pm::stream::AttrEncoding::Unorm16Range(r) => r.scale / 65535.0,
                    _ => 0.0,
                };
                for x in uv {
                    let err = (enc.round_trip(x) - x).abs();
                    assert!(err <= step * 0.5 + 1e-7, "UV {x}: off by {err}");
                }
                uv.map(|x| enc.round_trip(x).to_bits())
            } else {
                [0; 2]
            };
            (q, uv)
        };
        let mut got: Vec<_> = m
            .triangles
            .iter()
            .zip(w)
            .map(|(t, tw)| {
                let c: [_; 3] = [0, 1, 2].map(|i| {
                    let v = a.wedge(tw[i]);
                    corner(
                        grid.quantize(m.positions[t[i] as usize]),
                        [v[at], v[at + n - 1]],
                    )
                });
                rotate(c)
            })
            .collect();
        let mut want: Vec<_> = level
            .primitives
            .iter()
            .flat_map(|p| {
                let uvs = p.texcoords.as_ref().expect("the level has UVs");
                p.indices.chunks_exact(3).map(move |t| {
                    rotate([0, 1, 2].map(|i| {
                        let v = t[i] as usize;
                        corner(grid.quantize(p.positions[v]), uvs[v])
                    }))
                })
            })
            .collect();
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(got.len(), want.len(), "level {k}: triangle count");
        assert!(got == want, "level {k}: corners differ");
    }
}

/// A triangle rotated to start at its smallest corner (orientation kept).
fn rotate<T: Ord + Copy>(t: [T; 3]) -> [T; 3] {
    let r = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
    [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
}
