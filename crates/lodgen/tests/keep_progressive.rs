//! `BuildOptions::keep_progressive = false` and `keep_input = false` (the
//! CLI without `--progressive`) free the progressive mesh and the input
//! geometry before the levels are measured: every level, error and
//! coverage must be those of a build that keeps them.

use lodgen::lod::{build_lods_isolated, build_one, BuildOptions, LevelRequest};
use lodgen::scene::{Primitive, Scene, SourceMesh};

/// A torus with UVs from its positions (wedges, a fitted attribute).
fn torus() -> SourceMesh {
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 40, 20);
    let texcoords = m.positions.iter().map(|p| [p[0], p[1] * 0.5]).collect();
    SourceMesh {
        name: "torus".into(),
        primitives: vec![Primitive {
            indices: m.indices(),
            positions: m.positions,
            texcoords: Some(texcoords),
            ..Primitive::default()
        }],
    }
}

/// The torus with levels from the whole mesh down to 5 %.
#[test]
fn freeing_the_progressive_mesh_changes_no_level() {
    let mesh = torus();
    let levels = lodgen::cli::parse_levels("100%,50%,10%,5%").unwrap();
    for measured in [true, false] {
        let kept = BuildOptions {
            levels: LevelRequest::Specs(levels.clone()),
            measured,
            ..BuildOptions::default()
        };
        let freed = BuildOptions {
            keep_progressive: false,
            ..kept.clone()
        };
        let a = build_one(0, &mesh, &kept, &mut |_| {}).unwrap();
        let b = build_one(0, &mesh, &freed, &mut |_| {}).unwrap();
        assert!(!a.simplified.pm.is_empty() && !a.simplified.vertex_map.is_empty());
        assert!(b.simplified.pm.is_empty() && b.simplified.vertex_map.is_empty());
        assert_eq!(a.level_splits, b.level_splits);
        assert_eq!(a.lod.levels.len(), 4);
        for (la, lb) in a.lod.levels.iter().zip(&b.lod.levels) {
            assert_eq!(la.primitives, lb.primitives);
            assert_eq!(la.hausdorff.to_bits(), lb.hausdorff.to_bits());
            assert_eq!(la.rms.to_bits(), lb.rms.to_bits());
            assert_eq!(la.screen_coverage.to_bits(), lb.screen_coverage.to_bits());
        }
        assert_eq!(a.lod.levels[0].hausdorff, 0.0);
        if measured {
            assert!(a.lod.levels[3].hausdorff > 0.0 && a.lod.levels[3].rms > 0.0);
        }
    }
}

/// The torus and a mesh whose triangles all repeat a corner (kept
/// unsimplified): without `keep_input` the torus's input positions and
/// indices are freed in the scene, its chain unchanged; the other mesh
/// keeps its geometry, written as it is.
#[test]
fn freeing_the_input_changes_no_level_and_keeps_unsimplified_meshes() {
    let flat = SourceMesh {
        name: "flat".into(),
        primitives: vec![Primitive {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            indices: vec![0, 0, 1, 1, 2, 2],
            ..Primitive::default()
        }],
    };
    let scene = Scene {
        meshes: vec![torus(), flat.clone()],
        ..Scene::default()
    };
    let kept = BuildOptions {
        levels: LevelRequest::Specs(lodgen::cli::parse_levels("100%,50%,10%").unwrap()),
        ..BuildOptions::default()
    };
    let freed = BuildOptions {
        keep_input: false,
        keep_progressive: false,
        ..kept.clone()
    };
    let (mut a, mut b) = (scene.clone(), scene.clone());
    let built_a = build_lods_isolated(&mut a, &kept, &mut |_| {}).unwrap();
    let built_b = build_lods_isolated(&mut b, &freed, &mut |_| {}).unwrap();
    let (la, lb) = (built_a.lods(), built_b.lods());
    assert_eq!(la.len(), 2);
    for (ma, mb) in la.iter().zip(&lb) {
        assert_eq!(ma.levels.len(), mb.levels.len());
        for (x, y) in ma.levels.iter().zip(&mb.levels) {
            assert_eq!(x.primitives, y.primitives);
            assert_eq!(x.hausdorff.to_bits(), y.hausdorff.to_bits());
            assert_eq!(x.rms.to_bits(), y.rms.to_bits());
        }
    }
    assert_eq!(built_b.warnings.len(), 1);
    assert_eq!(
        built_b.unsimplified[0].levels[0].primitives,
        flat.primitives
    );
    assert_eq!(built_b.builds[0].input_triangles, 1600);
    assert_eq!(a.meshes, scene.meshes);
    let p = &b.meshes[0].primitives[0];
    assert!(p.positions.is_empty() && p.indices.is_empty());
    assert_eq!(p.texcoords, scene.meshes[0].primitives[0].texcoords);
    assert_eq!(b.meshes[1], flat);
}

/// A positions-only mesh of one primitive (a scan's shape): without
/// `keep_input` its input is freed before the simplification runs and its
/// levels' primitives are made from their meshes after the measurement;
/// every level, error and coverage must be those of a build that keeps
/// the input and extracts the levels as usual. (Fails when the deferred
/// primitives number their vertices otherwise than the extraction, or
/// when the input is not freed.)
#[test]
fn a_positions_only_mesh_freed_early_changes_no_level() {
    let torus = lodgen_pm::shapes::torus(1.0, 0.35, 60, 24);
    let mesh = SourceMesh {
        name: "scan".into(),
        primitives: vec![Primitive {
            material: Some(0),
            indices: torus.indices(),
            positions: torus.positions,
            ..Primitive::default()
        }],
    };
    let scene = Scene {
        meshes: vec![mesh],
        ..Scene::default()
    };
    for measured in [true, false] {
        let kept = BuildOptions {
            levels: LevelRequest::Specs(lodgen::cli::parse_levels("100%,50%,10%,2%").unwrap()),
            measured,
            ..BuildOptions::default()
        };
        let freed = BuildOptions {
            keep_input: false,
            keep_progressive: false,
            ..kept.clone()
        };
        let (mut a, mut b) = (scene.clone(), scene.clone());
        let built_a = build_lods_isolated(&mut a, &kept, &mut |_| {}).unwrap();
        let built_b = build_lods_isolated(&mut b, &freed, &mut |_| {}).unwrap();
        assert!(built_a.warnings.is_empty() && built_b.warnings.is_empty());
        let (la, lb) = (built_a.lods(), built_b.lods());
        assert_eq!(la[0].levels.len(), 4);
        for (x, y) in la[0].levels.iter().zip(&lb[0].levels) {
            assert_eq!(x.primitives, y.primitives);
            assert_eq!(x.hausdorff.to_bits(), y.hausdorff.to_bits());
            assert_eq!(x.rms.to_bits(), y.rms.to_bits());
            assert_eq!(x.screen_coverage.to_bits(), y.screen_coverage.to_bits());
        }
        // (Debug text: unmeasured reports hold NaN means)
        let errors = |b: &lodgen::lod::SceneBuild| format!("{:?}", b.builds[0].errors);
        assert_eq!(errors(&built_a), errors(&built_b));
        assert!(built_b.builds[0].simplified.vertex_map.is_empty());
        let p = &b.meshes[0].primitives[0];
        assert!(p.positions.is_empty() && p.indices.is_empty());
        assert_eq!(a.meshes, scene.meshes);
    }
}

/// A positions-only sphere at the edge of the `f32` range: its levels'
/// positions overflow, so their measurement fails and the mesh is written
/// unsimplified. Freed early, its input is given back from the welded
/// mesh: the same triangles (corner positions), not an empty primitive.
/// (Fails when the failed build does not restore the input.)
#[test]
fn a_mesh_freed_early_whose_levels_fail_is_written_as_its_welded_input() {
    let m = lodgen_pm::shapes::icosphere(2);
    let scale = 3.3e38
        / m.positions
            .iter()
            .flatten()
            .fold(0f32, |a, &x| a.max(x.abs()));
    let mesh = SourceMesh {
        name: "huge".into(),
        primitives: vec![Primitive {
            indices: m.indices(),
            positions: m.positions.iter().map(|p| p.map(|x| x * scale)).collect(),
            ..Primitive::default()
        }],
    };
    let scene = Scene {
        meshes: vec![mesh.clone()],
        ..Scene::default()
    };
    let opts = BuildOptions {
        levels: LevelRequest::Specs(lodgen::cli::parse_levels("50%,10%").unwrap()),
        keep_input: false,
        keep_progressive: false,
        ..BuildOptions::default()
    };
    let mut b = scene.clone();
    let built = build_lods_isolated(&mut b, &opts, &mut |_| {}).unwrap();
    assert_eq!(built.warnings.len(), 1, "the levels' measurement fails");
    let written = &built.unsimplified[0].levels[0].primitives;
    // each triangle as its corners' position bits, rotated to start at the least
    let triangles = |p: &Primitive| {
        let mut ts: Vec<[[u32; 3]; 3]> = p
            .indices
            .chunks_exact(3)
            .map(|t| {
                let c = [0, 1, 2].map(|k| p.positions[t[k] as usize].map(f32::to_bits));
                let r = (0..3).min_by_key(|&r| c[r]).unwrap();
                [c[r], c[(r + 1) % 3], c[(r + 2) % 3]]
            })
            .collect();
        ts.sort_unstable();
        ts
    };
    assert_eq!(written.len(), 1);
    assert!(!written[0].indices.is_empty());
    assert_eq!(triangles(&written[0]), triangles(&mesh.primitives[0]));
    assert_eq!(b.meshes[0].primitives, written.clone());
}
