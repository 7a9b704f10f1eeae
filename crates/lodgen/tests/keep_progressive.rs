//! `BuildOptions::keep_progressive = false` (the CLI without
//! `--progressive`) frees the progressive mesh before the levels are
//! measured: every level, error and coverage must be those of a build that
//! keeps it.

use lodgen::lod::{build_one, BuildOptions, LevelRequest};
use lodgen::scene::{Primitive, SourceMesh};

/// A torus with UVs from its positions (wedges, a fitted attribute), and
/// levels from the whole mesh down to 5 %.
#[test]
fn freeing_the_progressive_mesh_changes_no_level() {
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 40, 20);
    let texcoords = m.positions.iter().map(|p| [p[0], p[1] * 0.5]).collect();
    let mesh = SourceMesh {
        name: "torus".into(),
        primitives: vec![Primitive {
            indices: m.indices(),
            positions: m.positions,
            texcoords: Some(texcoords),
            ..Primitive::default()
        }],
    };
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
