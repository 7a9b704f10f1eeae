//! `metric::Reference::renumbered`: a reference built over the welded input (before the
//! simplification numbers the original its own way), renumbered, is the reference built over
//! the renumbered mesh, bit for bit; anything it cannot vouch for is refused.

use lodgen_pm::metric::{MeasureOptions, MeshRef, Reference};
use lodgen_pm::{prepare, shapes, simplify, Mesh, SimplifyOptions};

fn r(m: &Mesh) -> MeshRef<'_> {
    MeshRef::new(&m.positions, &m.triangles)
}

/// `new[origin[i]] = i`.
fn inverse(origin: &[u32]) -> Vec<u32> {
    let mut new = vec![u32::MAX; origin.len()];
    for (i, &o) in origin.iter().enumerate() {
        new[o as usize] = i as u32;
    }
    new
}

/// Measures and closest points of the renumbered reference equal a fresh build's over the
/// progressive mesh's numbering of the original (fails when the hierarchy's triangle ids or
/// the sample set's vertices are left in the welded numbering, or the mesh not switched).
#[test]
fn renumbered_reference_is_the_one_built_over_the_renumbered_mesh() {
    let knot = shapes::torus_knot(2, 3, 160, 12, 0.05);
    let indices: Vec<u32> = knot.triangles.iter().flatten().copied().collect();
    let welded = prepare(&knot.positions, &indices).unwrap().mesh;
    let out = simplify(
        &knot.positions,
        &indices,
        &SimplifyOptions::DEFAULT.with_target_ratio(0.02),
    )
    .unwrap();
    let pm = &out.pm;
    let full = pm.mesh_at_splits(pm.len());
    let (vnew, tnew) = (inverse(&pm.vertex_origin), inverse(&pm.triangle_origin));
    // (the two numberings differ, else the test proves nothing)
    assert!(vnew.iter().enumerate().any(|(i, &n)| i as u32 != n));
    assert!(tnew.iter().enumerate().any(|(i, &n)| i as u32 != n));

    let fresh = Reference::new(r(&full)).unwrap();
    let renumbered = Reference::new(r(&welded))
        .unwrap()
        .renumbered(r(&full), &vnew, &tnew)
        .expect("no two triangles or vertices of the knot share a Morton code");
    let opts = MeasureOptions::DEFAULT;
    for k in [0, pm.len() / 10, pm.len() / 2] {
        let level = pm.mesh_at_splits(k);
        assert_eq!(
            renumbered.measure(r(&level), &opts).unwrap(),
            fresh.measure(r(&level), &opts).unwrap(),
            "level at {k} splits"
        );
    }
    assert_eq!(renumbered.diagonal(), fresh.diagonal());
    for p in full.positions.iter().step_by(97) {
        let q = p.map(|x| f64::from(x) * 1.07 + 0.01);
        assert_eq!(
            renumbered.bvh().closest_point(q),
            fresh.bvh().closest_point(q)
        );
    }
}

/// A mesh that is not the renumbering the maps say, or whose order along the curve would
/// follow the numbering (two triangles with one centroid code), is refused (fails when the
/// maps or the ties are not checked).
#[test]
fn renumbering_refuses_what_it_cannot_vouch_for() {
    let m = shapes::icosphere(2);
    let n = (m.positions.len(), m.triangles.len());
    let identity = |k: usize| (0..k as u32).collect::<Vec<u32>>();
    let build = || Reference::new(r(&m)).unwrap();
    assert!(build()
        .renumbered(r(&m), &identity(n.0), &identity(n.1))
        .is_some());
    // two vertices swapped in the map but not in the mesh
    let mut swapped = identity(n.0);
    swapped.swap(0, 1);
    assert!(build()
        .renumbered(r(&m), &swapped, &identity(n.1))
        .is_none());
    // a map that is not one to one
    let mut twice = identity(n.1);
    twice[1] = 0;
    assert!(build().renumbered(r(&m), &identity(n.0), &twice).is_none());
    // a triangle's corners rotated
    let mut rotated = m.clone();
    rotated.triangles[3].rotate_left(1);
    assert!(build()
        .renumbered(r(&rotated), &identity(n.0), &identity(n.1))
        .is_none());
    // the same triangle twice, corners rotated: one centroid code
    let mut tied = m.clone();
    let t = tied.triangles[0];
    tied.triangles.push([t[1], t[2], t[0]]);
    let k = tied.triangles.len();
    let reference = Reference::new(r(&tied)).unwrap();
    assert!(reference
        .renumbered(r(&tied), &identity(n.0), &identity(k))
        .is_none());
}
