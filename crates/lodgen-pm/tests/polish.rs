//! The polish of a level's vertices (`lodgen_pm::polish`): closer to the
//! original, no face turned over, and the same bits for any thread count.

use lodgen_pm::metric::{ErrorReport, MeasureOptions, MeshRef, Reference};
use lodgen_pm::polish::Original;
use lodgen_pm::shapes::torus;
use lodgen_pm::{polish, polish_clusters, prepare, simplify, Mesh, PolishOptions, SimplifyOptions};

/// The welded original and its level at `ratio`, cut from the log (the
/// log's own positions, not lifted: `SimplifyOptions::lift` already moves
/// the chords' vertices, so the polish is tested from the chords).
fn level_of(m: &Mesh, ratio: f64) -> (Mesh, Mesh) {
    let p = prepare(&m.positions, &m.indices()).unwrap().mesh;
    let out = simplify(
        &p.positions,
        &p.indices(),
        &SimplifyOptions::DEFAULT
            .with_target_ratio(ratio)
            .with_lift(false),
    )
    .unwrap();
    let mut c = out.pm.cursor();
    c.seek(
        out.pm
            .splits_for_triangles((ratio * p.triangles.len() as f64) as usize),
    );
    let level = c.mesh().clone();
    (p, level)
}

fn normal(m: &Mesh, t: [u32; 3]) -> [f64; 3] {
    let [a, b, c] = t.map(|v| m.positions[v as usize].map(f64::from));
    let (u, v) = (
        [0, 1, 2].map(|k| b[k] - a[k]),
        [0, 1, 2].map(|k| c[k] - a[k]),
    );
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// The polished level's RMS below `rms_factor` × the level's, its
/// Hausdorff distance at most 2 % above, and no face turned over (the
/// back-off keeps each within 60° of itself).
fn assert_closer_and_unflipped(
    level: &Mesh,
    polished: &Mesh,
    before: &ErrorReport,
    after: &ErrorReport,
    rms_factor: f64,
) {
    assert!(
        after.rms() < rms_factor * before.rms(),
        "RMS {} -> {}",
        before.rms_percent(),
        after.rms_percent()
    );
    assert!(
        after.hausdorff() <= before.hausdorff() * 1.02,
        "Hausdorff {} -> {}",
        before.hausdorff_percent(),
        after.hausdorff_percent()
    );
    for &t in &level.triangles {
        let (a, b) = (normal(level, t), normal(polished, t));
        let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
        assert!(dot > 0.0, "face {t:?} flipped");
    }
}

/// A torus at 10 %: curved everywhere, so every level face is a chord the
/// polish can improve. Fails when `polish` leaves the level as it is (RMS
/// equal), or moves it away from the original.
#[test]
fn polished_level_is_closer_and_keeps_its_faces() {
    let (orig, level) = level_of(&torus(1.0, 0.35, 96, 48), 0.1);
    let reference = Reference::new(MeshRef::new(&orig.positions, &orig.triangles)).unwrap();
    let mopts = MeasureOptions::DEFAULT.with_min_samples(200_000);
    let before = reference
        .measure(MeshRef::new(&level.positions, &level.triangles), &mopts)
        .unwrap();
    let mut polished = level.clone();
    let stats = polish(
        MeshRef::new(&orig.positions, &orig.triangles),
        reference.bvh(),
        &mut polished,
        &PolishOptions::DEFAULT,
    );
    let after = reference
        .measure(
            MeshRef::new(&polished.positions, &polished.triangles),
            &mopts,
        )
        .unwrap();
    assert!(stats.moved > 0, "{stats:?}");
    assert_eq!(polished.triangles, level.triangles, "topology unchanged");
    assert_closer_and_unflipped(&level, &polished, &before, &after, 0.8);
}

/// The same bits with one thread and with four. Fails if the pairs were
/// summed in the order the threads finish them.
#[test]
fn polish_is_the_same_for_any_thread_count() {
    let (orig, level) = level_of(&torus(1.0, 0.35, 64, 32), 0.1);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let reference = Reference::new(MeshRef::new(&orig.positions, &orig.triangles)).unwrap();
            let mut m = level.clone();
            polish(
                MeshRef::new(&orig.positions, &orig.triangles),
                reference.bvh(),
                &mut m,
                &PolishOptions::DEFAULT,
            );
            m.positions
        })
    };
    let one = run(1);
    assert_ne!(one, level.positions);
    assert_eq!(one, run(4));
}

/// A welded torus of `n` × `m` × 2 triangles simplified to 10 %: the
/// result and its full mesh (the original in the log's numbering).
fn torus_to_a_tenth(n: u32, m: u32) -> (lodgen_pm::Simplified, Mesh) {
    let (orig, _) = level_of(&torus(1.0, 0.35, n, m), 0.1);
    let out = simplify(
        &orig.positions,
        &orig.indices(),
        &SimplifyOptions::DEFAULT.with_target_ratio(0.1),
    )
    .unwrap();
    let full = out.pm.mesh_at_splits(out.pm.len());
    (out, full)
}

/// Every original vertex's representative is a vertex of the level, a
/// level vertex its own, and level triangle `t` is original triangle `t`
/// with its corners replaced by their representatives (what
/// `polish_clusters` starts its walks from). Fails when a representative
/// is taken from the wrong end of a split (`v0` for `v1`) or splits below
/// the level are followed.
#[test]
fn representatives_map_the_original_onto_the_level() {
    let (out, full) = torus_to_a_tenth(48, 24);
    for k in [0, out.pm.len() / 3, out.pm.len() - 1, out.pm.len()] {
        let level = out.pm.mesh_at_splits(k);
        let rep = out.pm.representatives(k);
        assert_eq!(rep.len(), full.positions.len());
        let n = level.positions.len();
        for (v, &r) in rep.iter().enumerate() {
            assert!((r as usize) < n, "vertex {v} -> {r} at split {k}");
            if v < n {
                assert_eq!(r as usize, v, "a level vertex is its own");
            }
        }
        for (t, (lt, ft)) in level.triangles.iter().zip(&full.triangles).enumerate() {
            assert_eq!(
                *lt,
                ft.map(|v| rep[v as usize]),
                "triangle {t} at split {k}"
            );
        }
    }
}

/// `polish_clusters` (the pairs from the simplification, no hierarchy) on
/// the torus at 10 %: closer to the original, same faces, none turned
/// over, and the same bits for one thread and four. Fails when it leaves
/// the level as it is or moves it away.
#[test]
fn clusters_polish_is_closer_and_deterministic() {
    let (out, full) = torus_to_a_tenth(96, 48);
    let k = out.pm.splits_for_triangles(full.triangles.len() / 10);
    let level = out.pm.mesh_at_splits(k);
    let rep = out.pm.representatives(k);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let original = Original::new(MeshRef::new(&full.positions, &full.triangles));
            let mut m = level.clone();
            let stats = polish_clusters(&original, &mut m, &rep, &PolishOptions::CLUSTERS);
            (m, stats)
        })
    };
    let (polished, stats) = run(1);
    assert!(stats.moved > 0, "{stats:?}");
    assert_eq!(polished.triangles, level.triangles, "topology unchanged");
    assert_eq!(polished.positions, run(4).0.positions);
    let reference = Reference::new(MeshRef::new(&full.positions, &full.triangles)).unwrap();
    let mopts = MeasureOptions::DEFAULT.with_min_samples(200_000);
    let err = |m: &Mesh| {
        reference
            .measure(MeshRef::new(&m.positions, &m.triangles), &mopts)
            .unwrap()
    };
    let (before, after) = (err(&level), err(&polished));
    assert_closer_and_unflipped(&level, &polished, &before, &after, 0.85);
}

/// `level` (of `original`, which `reference` was made from) after
/// `fix_worst` with `rounds` rounds (the default measurement), what the fix
/// reported, and its options.
fn fixed(
    reference: &Reference,
    original: &Mesh,
    level: &Mesh,
    rounds: u32,
) -> (
    Mesh,
    lodgen_pm::polish::WorstFix,
    lodgen_pm::polish::WorstOptions,
) {
    use lodgen_pm::polish::{fix_worst, WorstOptions};
    let mut fixed = level.clone();
    let opts = WorstOptions {
        rounds,
        ..WorstOptions::DEFAULT
    };
    let fix = fix_worst(
        reference,
        MeshRef::new(&original.positions, &original.triangles),
        &mut fixed,
        &MeasureOptions::DEFAULT,
        &opts,
    )
    .unwrap();
    (fixed, fix, opts)
}

/// `fix_worst`: the error it returns is a measurement of the level as it
/// leaves it, the Hausdorff distance never rises, the RMS stays within its
/// bound, only positions change, and on a coarse knot the worst spot falls.
#[test]
fn fix_worst_lowers_the_maximum_and_reports_a_measurement() {
    // (a noisy knot: a symmetric torus's level has its maximum at several places, equal to
    // the last bit, and moving one leaves the figure where it was)
    let knot = lodgen_pm::shapes::torus_knot(2, 3, 120, 16, 0.01);
    let (original, level) = level_of(&knot, 0.1);
    let reference = Reference::new(MeshRef::new(&original.positions, &original.triangles)).unwrap();
    let mopts = MeasureOptions::DEFAULT;
    let (fixed, fix, opts) = fixed(&reference, &original, &level, 3);
    let again = reference
        .measure(MeshRef::new(&fixed.positions, &fixed.triangles), &mopts)
        .unwrap();
    assert_eq!(fix.error, again);
    let before = reference
        .measure(MeshRef::new(&level.positions, &level.triangles), &mopts)
        .unwrap();
    assert_eq!(fix.before, before);
    assert_eq!(fixed.triangles, level.triangles);
    assert!(fix.kept >= 1, "no round kept");
    assert!(
        fix.error.hausdorff() < before.hausdorff(),
        "H {} -> {}",
        before.hausdorff_percent(),
        fix.error.hausdorff_percent()
    );
    assert!(fix.error.rms() <= before.rms() * opts.rms_growth);
    let moved = (0..level.positions.len())
        .filter(|&v| level.positions[v] != fixed.positions[v])
        .count();
    // (each round moves at most the four corners at each of its spots: the
    // maximum, and the climbs' ends of both directions)
    let spots = 1 + 2 * lodgen_pm::metric::Spots::CAPACITY;
    assert!(
        moved > 0 && moved <= 4 * spots * fix.kept as usize,
        "{moved} vertices moved"
    );
}

/// `fix_worst` on a level whose worst spot is repeated: a symmetric knot's
/// level has its maximum at several places its symmetry makes equal, so a
/// move at one of them leaves the level's Hausdorff distance where it was.
/// The spots about as far as the maximum are fixed together in one round
/// (`Spots`, from the measurement's max-seeking climbs): the distance falls
/// and several separate places move. Fails when only the one spot is fixed.
#[test]
fn fix_worst_fixes_equal_spots_together() {
    let knot = lodgen_pm::shapes::torus_knot(2, 3, 120, 16, 0.0);
    let (original, level) = level_of(&knot, 0.1);
    let reference = Reference::new(MeshRef::new(&original.positions, &original.triangles)).unwrap();
    let mopts = MeasureOptions::DEFAULT;
    let before = reference
        .measure(MeshRef::new(&level.positions, &level.triangles), &mopts)
        .unwrap();
    let far = [before.a_to_b, before.b_to_a]
        .iter()
        .flat_map(|d| d.spots.as_slice().to_vec())
        .filter(|s| s.1 >= 0.95 * before.hausdorff())
        .count();
    assert!(far >= 2, "the level has {far} spots near its maximum");
    let (fixed, fix, _) = fixed(&reference, &original, &level, 1);
    assert_eq!(fix.kept, 1, "no round kept");
    // (one spot alone: 1.0152 % before and after, to the last bits; together: 0.9446 %)
    assert!(
        fix.error.hausdorff() < 0.99 * before.hausdorff(),
        "H {} -> {}",
        before.hausdorff_percent(),
        fix.error.hausdorff_percent()
    );
    let moved: Vec<usize> = (0..level.positions.len())
        .filter(|&v| level.positions[v] != fixed.positions[v])
        .collect();
    assert!(moved.len() > 4, "{} vertices moved", moved.len());
}
