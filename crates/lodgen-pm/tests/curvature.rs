//! The curvature-adaptive methods (Ceballos, Hernández & Prieto): what the
//! paper states about its operators, the border rule, the classification,
//! and the vertex-split log's replay invariant for every method.

mod common;

use lodgen_pm::adaptive::{
    boundary_vertices, classify, normal_deviation, threshold_value, Repairs,
};
use lodgen_pm::shapes::{cube, grid, torus_knot};
use lodgen_pm::{
    prepare, simplify_method, Adaptive, AdaptiveOptions, AdaptiveStop, Mesh, MeshError, Method,
    SimplifyOptions, StopReason, Threshold,
};

const ADAPTIVE: [Method; 3] = [Method::Edge, Method::HalfEdge, Method::Triangle];

fn run(mesh: &Mesh, method: Method, opts: SimplifyOptions) -> Adaptive {
    simplify_method(
        &mesh.positions,
        &mesh.indices(),
        method,
        &opts,
        &AdaptiveOptions::DEFAULT,
    )
    .expect("valid mesh")
}

/// Welded ids of the base mesh's vertices, with their positions there.
fn base_vertices(out: &Adaptive) -> Vec<(u32, [f32; 3])> {
    let pm = &out.simplified.pm;
    pm.base
        .positions
        .iter()
        .enumerate()
        .map(|(i, &p)| (pm.vertex_origin[i], p))
        .collect()
}

/// A flat 48 × 48 grid with a small wedge in the middle: a ramp 4 cells
/// long and 5 wide rising 0.03 per cell, dropping back over one cell. Every
/// wedge vertex is within three rings of a crease, so its region normal
/// differs from its own (a symmetric bump's apex would read as flat: θ
/// measures deviation, not height), and the wedge is small enough to be in
/// the top 2σ of the θ distribution.
fn flat_with_bump() -> Mesh {
    let n = 48.0;
    grid(48, 48, |x, y| {
        let (i, j) = ((x * n).round(), (y * n).round());
        if (23.0..=26.0).contains(&i) && (22.0..=26.0).contains(&j) {
            0.03 * (i - 22.0)
        } else {
            0.0
        }
    })
}

#[test]
fn bump_vertices_are_high_curvature_in_the_fixture() {
    // the precondition of the next test: the default classification puts
    // every bump vertex in the high class and most flat ones in the low
    let m = flat_with_bump();
    let theta = normal_deviation(&m, 3);
    let border = boundary_vertices(&m);
    let interior: Vec<usize> = (0..m.positions.len()).filter(|&v| !border[v]).collect();
    let vals: Vec<f64> = interior.iter().map(|&v| theta[v]).collect();
    let (high, limit) = classify(&vals, Threshold::Sigma(2.0));
    let bump: Vec<usize> = (0..interior.len())
        .filter(|&i| m.positions[interior[i]][2] > 0.0)
        .collect();
    assert!(bump.len() >= 9, "{} bump vertices", bump.len());
    for &i in &bump {
        assert!(high[i], "bump vertex θ={} ≤ {limit}", vals[i]);
    }
    let flat_high = (0..interior.len())
        .filter(|&i| high[i] && m.positions[interior[i]][2] == 0.0)
        .count();
    assert!(flat_high * 10 < interior.len(), "{flat_high} flat high");
}

#[test]
fn adaptive_methods_remove_only_flat_vertices_until_the_flat_is_exhausted() {
    let m = flat_with_bump();
    let prepared = prepare(&m.positions, &m.indices()).unwrap();
    let welded = &prepared.mesh;
    let border = boundary_vertices(welded);
    let flat_interior = (0..welded.positions.len())
        .filter(|&v| !border[v] && welded.positions[v][2] == 0.0)
        .count();
    for method in ADAPTIVE {
        let out = run(
            &m,
            method,
            SimplifyOptions::DEFAULT.with_target_triangles(0),
        );
        let base = base_vertices(&out);
        // every bump vertex is still there, where it was
        for (v, p) in welded.positions.iter().enumerate() {
            if p[2] > 0.0 {
                let kept = base.iter().find(|b| b.0 as usize == v);
                assert_eq!(kept.map(|b| b.1), Some(*p), "{method}: bump vertex {v}");
            }
        }
        // every split restores a flat vertex, and no split moved a bump one
        for s in &out.simplified.pm.splits {
            assert_eq!(s.p0[2], 0.0, "{method}: removed {:?}", s.p0);
            assert_eq!(s.p1[2], 0.0, "{method}: moved {:?}", s.p1);
        }
        // it stopped early (nothing removable, or nothing removable legally)
        // having removed 95 % of the flat interior
        assert_ne!(out.report.stop, AdaptiveStop::Target, "{method}");
        let flat_left = base
            .iter()
            .filter(|&&(v, p)| !border[v as usize] && p[2] == 0.0)
            .count();
        assert!(
            flat_left * 20 < flat_interior,
            "{method}: {flat_left} of {flat_interior} flat interior vertices left"
        );
    }
}

#[test]
fn boundary_vertices_keep_their_position_under_every_method() {
    let g = grid(16, 16, |x, y| {
        let inner = x > 0.0 && x < 1.0 && y > 0.0 && y < 1.0;
        if inner {
            0.05 * ((x * 17.0).sin() * (y * 13.0).cos())
        } else {
            0.0
        }
    });
    let prepared = prepare(&g.positions, &g.indices()).unwrap();
    let welded = &prepared.mesh;
    let border = boundary_vertices(welded);
    assert_eq!(border.iter().filter(|&&b| b).count(), 64);
    for method in Method::ALL {
        let out = run(&g, method, SimplifyOptions::DEFAULT.with_target_ratio(0.2));
        let base = base_vertices(&out);
        for &(v, p) in &base {
            if !border[v as usize] {
                continue;
            }
            if method.is_adaptive() {
                assert_eq!(p, welded.positions[v as usize], "{method}: vertex {v}");
            } else {
                // the QEM methods move a border vertex only along the
                // border (optimal placement held by the constraint planes;
                // corners never move: see `simplify.rs`)
                let off_line = [p[0], 1.0 - p[0], p[1], 1.0 - p[1]]
                    .into_iter()
                    .map(f32::abs)
                    .fold(f32::INFINITY, f32::min);
                assert!(
                    off_line <= 0.005 && p[2].abs() <= 0.005,
                    "{method}: vertex {v} left the border: {p:?}"
                );
            }
        }
        if method.is_adaptive() {
            let kept = base.iter().filter(|b| border[b.0 as usize]).count();
            assert_eq!(kept, 64, "{method}: border vertices removed");
        }
        assert!(out.simplified.stats.collapses > 0, "{method} did nothing");
    }
}

#[test]
fn interior_counts_follow_the_paper() {
    // edge and half-edge collapse: −1 vertex, −2 triangles; triangle
    // collapse: −2 vertices, −4 triangles (§2.2)
    let g = grid(6, 6, |_, _| 0.0);
    let (nv, nt) = (g.positions.len(), g.triangles.len());
    for (method, dv, dt, splits) in [
        (Method::Edge, 1, 2, 1),
        (Method::HalfEdge, 1, 2, 1),
        (Method::Triangle, 2, 4, 2),
    ] {
        let out = run(
            &g,
            method,
            SimplifyOptions::DEFAULT.with_target_triangles(nt - dt),
        );
        let pm = &out.simplified.pm;
        assert_eq!(pm.base.positions.len(), nv - dv, "{method}");
        assert_eq!(pm.base.triangles.len(), nt - dt, "{method}");
        assert_eq!(pm.splits.len(), splits, "{method}");
        assert!(pm.splits.iter().all(|s| s.faces.len() == 2), "{method}");
        assert_eq!(out.report.operations, 1, "{method}");
        assert_eq!(out.report.stop, AdaptiveStop::Target, "{method}");
    }
}

#[test]
fn triangle_collapse_puts_the_three_vertices_at_the_centroid() {
    let g = grid(6, 6, |_, _| 0.0);
    let nt = g.triangles.len();
    let out = run(
        &g,
        Method::Triangle,
        SimplifyOptions::DEFAULT.with_target_triangles(nt - 4),
    );
    let s = &out.simplified.pm.splits;
    // coarse → fine: the second contraction's split comes first
    let (second, first) = (&s[0], &s[1]);
    assert_eq!(first.v1, second.v1, "both splits restore around one vertex");
    assert_eq!(second.p_merged, first.p_merged);
    assert_eq!(second.p1, first.p_merged);
    let c = [0, 1, 2].map(|k| (first.p0[k] + first.p1[k] + second.p0[k]) / 3.0);
    for k in 0..3 {
        assert!(
            (c[k] - first.p_merged[k]).abs() < 1e-6,
            "{c:?} vs {:?}",
            first.p_merged
        );
    }
}

#[test]
fn half_edge_collapse_keeps_input_positions() {
    let g = grid(12, 12, |x, y| 0.02 * (x * 9.0).sin() * (y * 7.0).cos());
    let out = run(
        &g,
        Method::HalfEdge,
        SimplifyOptions::DEFAULT.with_target_ratio(0.3),
    );
    for p in &out.simplified.pm.base.positions {
        assert!(g.positions.contains(p), "{p:?} is not an input position");
    }
}

#[test]
fn threshold_classification_on_a_synthetic_distribution() {
    // 95 vertices at 0.1 rad, 5 at 1.0: mean 0.145, σ ≈ 0.196, mean + 2σ ≈
    // 0.537, so exactly the five are high
    let mut theta = vec![0.1; 95];
    theta.extend_from_slice(&[1.0; 5]);
    let (high, limit) = classify(&theta, Threshold::Sigma(2.0));
    assert!((limit - 0.537).abs() < 1e-3, "{limit}");
    assert_eq!(high.iter().filter(|&&h| h).count(), 5);
    assert!(high[95..].iter().all(|&h| h));
    // median of ten distinct values: the lower five are removable
    let ten: Vec<f64> = (0..10).rev().map(f64::from).collect();
    let (high, limit) = classify(&ten, Threshold::Median);
    assert_eq!(limit, 4.0);
    assert_eq!(
        high,
        [true, true, true, true, true, false, false, false, false, false]
    );
    // fractions: 30 % removable; 0 % means nothing is; 100 % everything
    let (high, _) = classify(&ten, Threshold::Fraction(0.3));
    assert_eq!(high.iter().filter(|&&h| !h).count(), 3);
    assert!(classify(&ten, Threshold::Fraction(0.0))
        .0
        .iter()
        .all(|&h| h));
    assert!(classify(&ten, Threshold::Fraction(1.0))
        .0
        .iter()
        .all(|&h| !h));
    // σ-thresholds degrade gracefully: constant θ, NaN, empty
    assert_eq!(threshold_value(&[0.3; 4], Threshold::Sigma(2.0)), 0.3);
    assert!(classify(&[0.3; 4], Threshold::Sigma(2.0))
        .0
        .iter()
        .all(|&h| !h));
    assert_eq!(threshold_value(&[], Threshold::Median), 0.0);
    assert!(classify(&[f64::NAN, 0.1], Threshold::Median).0[0]);
}

#[test]
fn normal_deviation_is_zero_on_a_plane_and_positive_on_a_crease() {
    let flat = grid(4, 4, |_, _| 0.0);
    assert!(normal_deviation(&flat, 3).iter().all(|&t| t.abs() < 1e-9));
    // a roof: vertices next to the ridge lean against a region that spans
    // both slopes
    let roof = grid(8, 8, |x, _| 0.5 - (x - 0.5).abs());
    let theta = normal_deviation(&roof, 3);
    let near_ridge = (0..roof.positions.len())
        .filter(|&v| (roof.positions[v][0] - 0.625).abs() < 1e-6)
        .collect::<Vec<_>>();
    assert!(!near_ridge.is_empty());
    for v in near_ridge {
        assert!(theta[v] > 0.05, "θ = {}", theta[v]);
    }
}

#[test]
fn every_method_replays_exactly() {
    let meshes = [
        torus_knot(2, 3, 48, 10, 0.05),
        cube([0.0; 3], [1.0; 3], 5),
        flat_with_bump(),
    ];
    for (i, m) in meshes.iter().enumerate() {
        let prepared = prepare(&m.positions, &m.indices()).unwrap();
        for method in Method::ALL {
            for ratio in [0.5, 0.1] {
                let out = run(m, method, SimplifyOptions::DEFAULT.with_target_ratio(ratio));
                let pm = &out.simplified.pm;
                assert_eq!(
                    pm.full_in_input_order(),
                    prepared.mesh,
                    "mesh {i}, {method}, {ratio}"
                );
                // every prefix is a mesh without repeated corners
                let mut c = pm.cursor();
                loop {
                    for t in &c.mesh().triangles {
                        assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "{method}");
                    }
                    if c.refine(1) == 0 {
                        break;
                    }
                }
                let target = (ratio * prepared.mesh.triangles.len() as f64).floor() as usize;
                let reached = pm.base.triangles.len();
                assert_eq!(out.simplified.stats.output_triangles, reached);
                if out.simplified.stop == StopReason::Target {
                    // a triangle collapse removes four at once
                    assert!(
                        reached <= target && reached + 4 > target,
                        "{method}: {reached}"
                    );
                } else {
                    assert!(reached > target);
                }
            }
        }
    }
}

#[test]
fn runs_are_deterministic() {
    let m = torus_knot(2, 3, 40, 8, 0.05);
    for method in Method::ALL {
        let a = run(&m, method, SimplifyOptions::DEFAULT.with_target_ratio(0.2));
        let b = run(&m, method, SimplifyOptions::DEFAULT.with_target_ratio(0.2));
        assert_eq!(a.simplified.pm, b.simplified.pm, "{method}");
    }
}

#[test]
fn algorithm_5_defects_never_survive() {
    // after any run, no two live triangles share their three vertices and
    // no triangle is flipped against the input orientation of its region
    let m = torus_knot(2, 3, 64, 12, 0.08);
    for method in ADAPTIVE {
        let out = run(&m, method, SimplifyOptions::DEFAULT.with_target_ratio(0.05));
        let base = &out.simplified.pm.base;
        let mut keys: Vec<[u32; 3]> = base
            .triangles
            .iter()
            .map(|t| {
                let mut k = *t;
                k.sort_unstable();
                k
            })
            .collect();
        keys.sort_unstable();
        assert!(keys.windows(2).all(|w| w[0] != w[1]), "{method}: a spike");
        // consistently oriented: no directed edge used twice (a reversed
        // face next to its neighbours reuses one)
        let e = common::directed_edges(base);
        assert!(
            e.windows(2).all(|w| w[0] != w[1]),
            "{method}: reversed face"
        );
        assert!(out.report.operations > 0, "{method}");
        let r: Repairs = out.report.repaired;
        assert!(r.total() <= out.report.prevented.total() + out.report.operations);
    }
}

#[test]
fn bad_input_is_an_error_for_every_method() {
    let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    for method in Method::ALL {
        let r = simplify_method(
            &p,
            &[0, 1, 7],
            method,
            &SimplifyOptions::DEFAULT,
            &AdaptiveOptions::DEFAULT,
        );
        assert!(matches!(
            r,
            Err(MeshError::IndexOutOfRange { index: 7, .. })
        ));
        let r = simplify_method(
            &p,
            &[0, 1],
            method,
            &SimplifyOptions::DEFAULT,
            &AdaptiveOptions::DEFAULT,
        );
        assert!(matches!(r, Err(MeshError::IndexCount(2))));
        // odd options do not panic either
        let odd = AdaptiveOptions::DEFAULT
            .with_k_ring(0)
            .with_threshold(Threshold::Fraction(f64::NAN))
            .with_hybrid_weight(f64::INFINITY);
        let out = simplify_method(&p, &[0, 1, 2], method, &SimplifyOptions::DEFAULT, &odd).unwrap();
        if method.is_adaptive() {
            // all three vertices are on the border: nothing may move
            assert_eq!(out.simplified.pm.base.triangles.len(), 1);
            assert_eq!(out.report.stop, AdaptiveStop::Locked);
        }
    }
}

#[test]
fn method_names_round_trip() {
    for m in Method::ALL {
        assert_eq!(m.name().parse::<Method>(), Ok(m));
    }
    assert!("quadric".parse::<Method>().is_err());
}
