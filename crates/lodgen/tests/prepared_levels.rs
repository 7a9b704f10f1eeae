//! Levels prepared for the writer while the build goes on
//! (`BuildOptions::level_ready`, `gltf_out::PreparedLevels`): the build
//! hands over each level's primitives exactly as its chain then holds them,
//! and the writer given prepared levels writes the bytes it writes without.

mod support;

use std::sync::{Arc, Mutex};

use lodgen::gltf_out::{
    write_lods, write_lods_prepared, Compression, PreparedLevels, WriteOptions,
};
use lodgen::lod::{build_lods_isolated, BuildOptions, LevelHook, LevelRequest};
use lodgen::scene::{Material, Primitive, Scene, SourceMesh};
use support::written::*;

/// A scene of one positions-only torus of `2 · a · b` triangles.
fn torus_scene(a: u32, b: u32) -> Scene {
    let m = lodgen_pm::shapes::torus(1.0, 0.35, a, b);
    Scene {
        meshes: vec![SourceMesh {
            name: "torus".into(),
            primitives: vec![Primitive {
                material: Some(0),
                indices: m.indices(),
                positions: m.positions,
                ..Primitive::default()
            }],
        }],
        materials: vec![Material {
            name: "grey".into(),
            base_color: Some([0.5, 0.5, 0.5, 1.0]),
        }],
        ..Scene::default()
    }
}

/// A level handed over: mesh, level, its primitives.
type Level = (usize, usize, Vec<Primitive>);

type Handed = Arc<Mutex<Vec<Level>>>;

/// Builds `scene` (input freed, as the CLI does) with a hook that records
/// every level it is given; returns the levels handed over and the scene's
/// chains.
fn build_recording(scene: &mut Scene) -> (Vec<Level>, Vec<lodgen::scene::LodMesh>) {
    let handed: Handed = Arc::default();
    let record = Arc::clone(&handed);
    let opts = BuildOptions {
        levels: LevelRequest::Specs(lodgen::cli::parse_levels("50%,10%,2%").unwrap()),
        keep_input: false,
        keep_progressive: false,
        level_ready: Some(LevelHook(Arc::new(move |mesh, level, p: &[Primitive]| {
            record.lock().unwrap().push((mesh, level, p.to_vec()));
        }))),
        ..BuildOptions::default()
    };
    let built = build_lods_isolated(scene, &opts, &mut |_| {}).unwrap();
    assert!(built.warnings.is_empty());
    let mut handed = handed.lock().unwrap().clone();
    handed.sort_by_key(|h| (h.0, h.1));
    (handed, built.lods())
}

/// A small mesh (levels measured side by side) hands over every level; a
/// large scan (its levels' primitives made after each is measured, levels
/// measured one after the other) every level but the last measured. Each
/// handed level is the chain's level, primitive for primitive. (Fails when
/// a level is handed under another's index, before its primitives are
/// final, or not at all.)
#[test]
fn the_levels_handed_over_are_the_written_ones() {
    // 2,400 triangles, then 133,120 (above the side-by-side limit of
    // 8 clusters of 16,384)
    for (a, b, expected) in [(60, 20, vec![0, 1, 2]), (512, 130, vec![0, 1])] {
        let mut scene = torus_scene(a, b);
        let (handed, lods) = build_recording(&mut scene);
        let levels: Vec<usize> = handed.iter().map(|h| h.1).collect();
        assert_eq!(levels, expected, "torus {a} x {b}");
        for (mesh, level, primitives) in &handed {
            assert_eq!(*mesh, 0);
            assert!(!primitives.is_empty() && !primitives[0].indices.is_empty());
            assert!(
                primitives == &lods[0].levels[*level].primitives,
                "torus {a} x {b}, level {level}"
            );
        }
    }
}

fn all_files(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().into_string().unwrap(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

/// Every level prepared ahead gives the bytes of the plain write (GLB and
/// glTF, plain and quantized + compressed), and the writer takes them (none
/// left); a level prepared from other primitives (another level's: other
/// index counts) is not used. (Fails when the prepared levels differ from
/// the writer's own, or are ignored.)
#[test]
fn prepared_levels_write_the_same_bytes() {
    let (positions, indices) = icosphere(4, 2.0, [1.0, -3.0, 0.5]);
    let prim = Primitive {
        material: Some(0),
        positions,
        indices,
        ..Primitive::default()
    };
    let scene = one_mesh_scene("ball", prim.clone(), "red", [1.0, 0.0, 0.0, 1.0]);
    let lod = chain("ball", 0, prim, &[0.5, 0.1]);
    let compressed = WriteOptions {
        quantize: true,
        compression: Compression::Meshopt,
    };
    for (name, opts) in [
        ("p.glb", WriteOptions::default()),
        ("p.gltf", WriteOptions::default()),
        ("p.glb", compressed),
    ] {
        let (a, b, c) = (scratch("prep-a"), scratch("prep-b"), scratch("prep-c"));
        write_lods(&a.join(name), &scene, std::slice::from_ref(&lod), &opts).unwrap();
        let ready = PreparedLevels::for_scene(&scene);
        for (k, level) in lod.levels.iter().enumerate() {
            ready.prepare(0, k, &level.primitives);
        }
        let chains = std::slice::from_ref(&lod);
        write_lods_prepared(&b.join(name), &scene, chains, &opts, false, Some(&ready)).unwrap();
        assert!(ready.is_empty(), "{name}: every prepared level taken");
        // level 0 prepared from level 1's primitives: not taken for level 0
        let stale = PreparedLevels::for_scene(&scene);
        stale.prepare(0, 0, &lod.levels[1].primitives);
        write_lods_prepared(&c.join(name), &scene, chains, &opts, false, Some(&stale)).unwrap();
        let (fa, fb, fc) = (all_files(&a), all_files(&b), all_files(&c));
        assert!(!fa.is_empty());
        assert!(fa == fb, "{name} {opts:?}: prepared ahead");
        assert!(fa == fc, "{name} {opts:?}: a stale level");
    }
}

/// What a caller adds before the write (`write_lods_added`, how `lodgen
/// --progressive` adds its stream) is in the file and its side files are
/// written beside it; when the addition fails, an existing output and the
/// directory stay exactly as they were (no file written, no temporary file
/// left). (Fails when the output is written before the addition, as the
/// stream once was added to a file already in place.)
#[test]
fn an_addition_is_written_with_the_file_or_nothing_is() {
    let (positions, indices) = icosphere(3, 1.0, [0.0; 3]);
    let prim = Primitive {
        material: Some(0),
        positions,
        indices,
        ..Primitive::default()
    };
    let scene = one_mesh_scene("ball", prim.clone(), "red", [1.0, 0.0, 0.0, 1.0]);
    let lod = chain("ball", 0, prim, &[0.5]);
    let chains = std::slice::from_ref(&lod);
    let opts = WriteOptions::default();
    for name in ["a.glb", "a.gltf"] {
        let dir = scratch("added");
        let out = dir.join(name);
        let plain = std::cell::Cell::new(0);
        let add = |path: &std::path::Path, mut bytes: Vec<u8>| {
            plain.set(bytes.len());
            bytes.extend_from_slice(b"    ");
            let side = path.with_file_name("a.extra.bin");
            Ok((bytes, vec![(side, b"extra".to_vec())]))
        };
        lodgen::gltf_out::write_lods_added(&out, &scene, chains, &opts, false, None, Some(&add))
            .unwrap();
        let written = std::fs::read(&out).unwrap();
        assert!(written.ends_with(b"    ") && written.len() == plain.get() + 4);
        assert_eq!(std::fs::read(dir.join("a.extra.bin")).unwrap(), b"extra");
        // an existing output, then a failing addition
        std::fs::write(&out, b"old output").unwrap();
        let before = all_files(&dir);
        let fail = |_: &std::path::Path, _: Vec<u8>| Err("no room for the stream".to_string());
        let err = lodgen::gltf_out::write_lods_added(
            &out,
            &scene,
            chains,
            &opts,
            false,
            None,
            Some(&fail),
        )
        .unwrap_err();
        assert!(err.to_string().contains("no room for the stream"), "{err}");
        assert!(all_files(&dir) == before, "{name}: the directory changed");
    }
}
