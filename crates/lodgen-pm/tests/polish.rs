//! The polish of a level's vertices (`lodgen_pm::polish`): closer to the
//! original, no face turned over, and the same bits for any thread count.

use lodgen_pm::metric::{MeasureOptions, MeshRef, Reference};
use lodgen_pm::shapes::torus;
use lodgen_pm::{polish, prepare, simplify, Mesh, PolishOptions, SimplifyOptions};

/// The welded original and its level at `ratio`, cut from the log.
fn level_of(m: &Mesh, ratio: f64) -> (Mesh, Mesh) {
    let p = prepare(&m.positions, &m.indices()).unwrap().mesh;
    let out = simplify(
        &p.positions,
        &p.indices(),
        &SimplifyOptions::DEFAULT.with_target_ratio(ratio),
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
    assert!(
        after.rms() < 0.8 * before.rms(),
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
    // no face turned over (the back-off keeps each within 60° of itself)
    for &t in &level.triangles {
        let (a, b) = (normal(&level, t), normal(&polished, t));
        let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
        assert!(dot > 0.0, "face {t:?} flipped");
    }
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
