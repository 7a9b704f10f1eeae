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
