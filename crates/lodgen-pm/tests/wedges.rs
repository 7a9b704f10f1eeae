//! Wedges and feature edges: seams stay seams, hard edges stay hard, and the
//! log's wedge payload replays exactly.

mod common;

use lodgen_pm::shapes;
use lodgen_pm::{simplify, simplify_with_wedges, Mesh, Simplified, Simplifier, SimplifyOptions};

/// A coarse size at which an unconstrained simplification of the test
/// grids has long crossed their seam or crease lines.
const COARSE: usize = 24;

/// Unweld `mesh` by `chart(triangle)`: every chart gets its own copy of the
/// vertices it uses, so edges between charts are seams. Returns positions,
/// indices and the chart of each unwelded vertex.
fn unweld(mesh: &Mesh, chart: impl Fn(usize) -> u32) -> (Vec<[f32; 3]>, Vec<u32>, Vec<u32>) {
    let mut ids = std::collections::BTreeMap::new();
    let (mut pos, mut idx, mut charts) = (Vec::new(), Vec::new(), Vec::new());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let c = chart(t);
        for &v in tri {
            let id = *ids.entry((c, v)).or_insert_with(|| {
                pos.push(mesh.positions[v as usize]);
                charts.push(c);
                pos.len() as u32 - 1
            });
            idx.push(id);
        }
    }
    (pos, idx, charts)
}

/// A 16×16 grid cut by a UV seam along x = 0.5 (left and right charts).
fn seamed_grid() -> (Vec<[f32; 3]>, Vec<u32>, Vec<u32>) {
    let g = shapes::grid(16, 16, |x, y| 0.05 * (3.0 * x).sin() * (2.0 * y).cos());
    let left = |t: usize| {
        let tri = g.triangles[t];
        let cx: f32 = tri.iter().map(|&v| g.positions[v as usize][0]).sum::<f32>() / 3.0;
        u32::from(cx > 0.5)
    };
    unweld(&g, left)
}

fn check_charts(out: &Simplified, pos: &[[f32; 3]], charts: &[u32], k: usize) {
    let mut c = out.pm.cursor();
    c.seek(k);
    let m = c.mesh();
    let w = c.wedges().expect("wedges tracked");
    assert_eq!(w.len(), m.triangles.len());
    for (t, (tri, wt)) in m.triangles.iter().zip(w).enumerate() {
        let ch = charts[wt[0] as usize];
        assert!(
            wt.iter().all(|&x| charts[x as usize] == ch),
            "after {k} splits triangle {t} spans two charts: {wt:?}"
        );
        // a corner whose vertex did not move keeps a wedge of that vertex
        for (&v, &x) in tri.iter().zip(wt) {
            let p = m.positions[v as usize];
            if pos.contains(&p) && p[0] == 0.5 {
                assert_eq!(p, pos[x as usize], "after {k} splits a seam wedge moved");
            }
        }
    }
}

#[test]
fn uv_seam_stays_a_seam_at_every_level() {
    let (pos, idx, charts) = seamed_grid();
    let out = simplify_with_wedges(&pos, &idx, &[], 0, &SimplifyOptions::DEFAULT).unwrap();
    assert!(out.pm.base.triangles.len() < COARSE);
    for k in 0..=out.pm.len() {
        check_charts(&out, &pos, &charts, k);
    }
    // the seam vertices never leave x = 0.5
    let mut c = out.pm.cursor();
    for k in 0..=out.pm.len() {
        c.seek(k);
        let w = c.wedges().unwrap();
        let mut seen = vec![[false; 2]; c.mesh().positions.len()];
        for (tri, wt) in c.mesh().triangles.iter().zip(w) {
            for (&v, &x) in tri.iter().zip(wt) {
                seen[v as usize][charts[x as usize] as usize] = true;
            }
        }
        for (v, s) in seen.iter().enumerate() {
            if s[0] && s[1] {
                assert_eq!(
                    c.mesh().positions[v][0],
                    0.5,
                    "seam vertex {v} moved at {k}"
                );
            }
        }
    }
    // without wedges, the same grid at the same size crosses the seam line
    let opts = SimplifyOptions::DEFAULT.with_target_triangles(COARSE);
    let plain = simplify(&pos, &idx, &opts).unwrap().pm.base;
    assert!(plain.triangles.iter().any(|t| {
        let xs = t.map(|v| plain.positions[v as usize][0]);
        xs.iter().any(|&x| x > 0.5) && xs.iter().any(|&x| x < 0.5)
    }));
}

#[test]
fn cube_with_hard_normals_keeps_six_flat_faces() {
    let n = 6;
    let cube = shapes::cube([-1.0; 3], [1.0; 3], n);
    let per_face = (2 * n * n) as usize;
    let (pos, idx, charts) = unweld(&cube, |t| (t / per_face) as u32);
    let out = simplify_with_wedges(&pos, &idx, &[], 0, &SimplifyOptions::DEFAULT).unwrap();
    assert_eq!(out.pm.base.triangles.len(), 12, "two triangles per face");
    check_charts(&out, &pos, &charts, 0);
    let c = out.pm.cursor();
    let mut faces = [0; 6];
    for (tri, wt) in c.mesh().triangles.iter().zip(c.wedges().unwrap()) {
        let face = charts[wt[0] as usize] as usize;
        faces[face] += 1;
        // flat: the three corners lie on the face's plane
        let p = tri.map(|v| c.mesh().positions[v as usize]);
        let axis = (0..3)
            .find(|&a| p[0][a] == p[1][a] && p[1][a] == p[2][a])
            .expect("triangle on a cube face");
        assert_eq!(p[0][axis].abs(), 1.0);
    }
    assert_eq!(faces, [2; 6]);
}

#[test]
fn replay_restores_wedges_exactly() {
    let (pos, idx, _) = seamed_grid();
    let out = simplify_with_wedges(&pos, &idx, &[], 0, &SimplifyOptions::DEFAULT).unwrap();
    let pm = &out.pm;
    // fully refined: every corner has its input wedge again
    let mut c = pm.cursor();
    c.seek(pm.len());
    for (t, w) in c.wedges().unwrap().iter().enumerate() {
        let input = out.triangle_map[pm.triangle_origin[t] as usize] as usize;
        assert_eq!(*w, [idx[3 * input], idx[3 * input + 1], idx[3 * input + 2]]);
    }
    // coarsening one split at a time retraces refining
    let mut states = Vec::new();
    let mut r = pm.cursor();
    for k in 0..=pm.len() {
        r.seek(k);
        states.push(r.wedges().unwrap().to_vec());
    }
    for k in (0..=pm.len()).rev() {
        c.seek(k);
        assert_eq!(c.wedges().unwrap(), &states[k][..], "at {k}");
    }
}

/// Every corner's wedge at every split count, and the fully refined
/// corners checked against the input's (`idx`, one wedge id per corner).
fn wedge_states(out: &Simplified, idx: &[u32]) -> Vec<Vec<[u32; 3]>> {
    let pm = &out.pm;
    let mut c = pm.cursor();
    let mut states = Vec::new();
    for k in 0..=pm.len() {
        c.seek(k);
        states.push(c.wedges().unwrap().to_vec());
    }
    for (t, w) in states[pm.len()].iter().enumerate() {
        let input = out.triangle_map[pm.triangle_origin[t] as usize] as usize;
        assert_eq!(*w, [idx[3 * input], idx[3 * input + 1], idx[3 * input + 2]]);
    }
    // coarsening one split at a time retraces refining
    for k in (0..=pm.len()).rev() {
        c.seek(k);
        assert_eq!(c.wedges().unwrap(), &states[k][..], "at {k}");
    }
    states
}

#[test]
fn one_wedge_per_vertex_is_stored_per_vertex_and_replays_exactly() {
    // no seam: each vertex keeps one wedge at every step, and the log holds
    // one wedge per vertex instead of every split's edits
    let m = shapes::torus(1.0, 0.3, 40, 24);
    let idx = m.indices();
    let opts = SimplifyOptions::DEFAULT.with_target_ratio(0.05);
    let out = simplify_with_wedges(&m.positions, &idx, &[], 0, &opts).unwrap();
    let log = out.pm.wedges.as_ref().unwrap();
    assert!(log.per_vertex.is_some() && log.splits.is_empty());
    let states = wedge_states(&out, &idx);
    // the same log with every split's edits written out replays the same
    let mut explicit = out.clone();
    let splits = (out.pm.splits.iter().enumerate())
        .map(|(i, s)| log.split(i, s).into_owned())
        .collect();
    let w = explicit.pm.wedges.as_mut().unwrap();
    (w.splits, w.per_vertex) = (splits, None);
    assert_eq!(wedge_states(&explicit, &idx), states);
    // a seam: explicit edits
    let (pos, idx, _) = seamed_grid();
    let out = simplify_with_wedges(&pos, &idx, &[], 0, &SimplifyOptions::DEFAULT).unwrap();
    assert!(out.pm.wedges.as_ref().unwrap().per_vertex.is_none());
    wedge_states(&out, &idx);
}

#[test]
fn explicit_feature_edges_hold_a_crease() {
    // a flat grid with a declared hard edge along y = 0.5
    let g = shapes::grid(12, 12, |_, _| 0.0);
    let mut line = Vec::new();
    for i in 0..12u32 {
        line.push((6 * 13 + i, 6 * 13 + i + 1));
    }
    let opts = SimplifyOptions::DEFAULT.with_target_triangles(COARSE);
    let mut s = Simplifier::new(&g, &opts).unwrap();
    s.set_feature_edges(&line);
    s.run();
    let snap = s.snapshot();
    // the crease is still made of edges: every triangle lies on one side
    for (_, t) in &snap.triangles {
        let ys = t.map(|v| snap.positions[v as usize][1]);
        assert!(
            ys.iter().all(|&y| y >= 0.5) || ys.iter().all(|&y| y <= 0.5),
            "{ys:?}"
        );
    }
    // without the feature edges nothing holds the line: the grid goes down
    // to its two corner triangles, which cross it
    assert_eq!(s.triangle_count(), COARSE);
    let mut plain =
        Simplifier::new(&g, &SimplifyOptions::DEFAULT.with_target_triangles(2)).unwrap();
    plain.run();
    assert_eq!(plain.triangle_count(), 2);
    let snap = plain.snapshot();
    assert!(snap.triangles.iter().any(|(_, t)| {
        let ys = t.map(|v| snap.positions[v as usize][1]);
        ys.iter().any(|&y| y > 0.5) && ys.iter().any(|&y| y < 0.5)
    }));
}

/// Without a seam, wedges change nothing but the log: `simplify_with_wedges`
/// with one wedge per vertex makes `simplify`'s contractions, open borders
/// included (they stay constraint planes, not feature lines their vertices
/// may only slide along, which cost positions-only beetle on the command
/// line 14.6 % Hausdorff at 41 triangles against 6.1 %).
#[test]
fn one_wedge_per_vertex_simplifies_as_positions_only() {
    let grid = shapes::grid(24, 24, |x, y| 0.1 * (5.0 * x).sin() * (4.0 * y).cos());
    let mut cases = vec![(grid, 0.02)];
    cases.extend(common::shared_mesh("beetle.obj").map(|m| (m, 0.02)));
    for (m, ratio) in cases {
        let idx = m.indices();
        let opts = SimplifyOptions::DEFAULT.with_target_ratio(ratio);
        let plain = simplify(&m.positions, &idx, &opts).unwrap();
        let wedged = simplify_with_wedges(&m.positions, &idx, &[], 0, &opts).unwrap();
        assert_eq!(wedged.stop, plain.stop);
        assert_eq!(wedged.pm.base, plain.pm.base);
        assert_eq!(wedged.pm.splits, plain.pm.splits);
        assert!(plain.pm.wedges.is_none());
        assert!(wedged.pm.wedges.as_ref().unwrap().per_vertex.is_some());
        wedge_states(&wedged, &idx);
    }
}

/// A UV sphere as Blender and most tools export it: `seg` segments, `rings` rings, every pole
/// triangle with a wedge of its own at the pole (the pole's UV is the middle of its segment),
/// one wedge per other vertex. Unwelded positions and indices, as `simplify_with_wedges`
/// takes them, and the welded mesh.
fn uv_sphere(seg: u32, rings: u32) -> (Vec<[f32; 3]>, Vec<u32>, Mesh) {
    let ring = |r: u32, s: u32| 1 + (r - 1) * seg + s % seg;
    let mut pos = vec![[0.0, 1.0, 0.0]];
    for r in 1..rings {
        let th = std::f64::consts::PI * f64::from(r) / f64::from(rings);
        for s in 0..seg {
            let ph = 2.0 * std::f64::consts::PI * f64::from(s) / f64::from(seg);
            let p = [th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()];
            pos.push(p.map(|x| x as f32));
        }
    }
    pos.push([0.0, -1.0, 0.0]);
    let south = pos.len() as u32 - 1;
    let mut welded = Vec::new();
    for s in 0..seg {
        welded.push([0, ring(1, s + 1), ring(1, s)]);
        welded.push([ring(rings - 1, s), ring(rings - 1, s + 1), south]);
        for r in 1..rings - 1 {
            let [a, b] = [ring(r, s), ring(r, s + 1)];
            let [c, d] = [ring(r + 1, s + 1), ring(r + 1, s)];
            welded.extend([[a, b, c], [a, c, d]]);
        }
    }
    let mesh = Mesh {
        positions: pos.clone(),
        triangles: welded.clone(),
    };
    let (mut unwelded, mut idx) = (pos.clone(), Vec::new());
    for t in &welded {
        for &v in t {
            if v == 0 || v == south {
                // a pole: a wedge of its own in each of its triangles
                unwelded.push(pos[v as usize]);
                idx.push(unwelded.len() as u32 - 1);
            } else {
                idx.push(v);
            }
        }
    }
    (unwelded, idx, mesh)
}

/// The ring vertices next to a pole each end one seam (the pole's wedges differ across every
/// edge to it). Held in place, they starved the rest of the sphere: 32 × 16 at 134 of 960
/// triangles was 14.7 % of the diagonal from the sphere, against 1.2 % without the pole's
/// wedges. Removed along their seam into the pole, or folded onto the next seam, they let the
/// sphere simplify about as its positions alone do.
#[test]
fn a_uv_sphere_with_a_wedge_per_pole_triangle_simplifies_like_its_positions() {
    let (pos, idx, sphere) = uv_sphere(32, 16);
    let target = 134;
    let hausdorff = |m: &Mesh| {
        lodgen_pm::metric::measure(
            lodgen_pm::metric::MeshRef::new(&sphere.positions, &sphere.triangles),
            lodgen_pm::metric::MeshRef::new(&m.positions, &m.triangles),
            &lodgen_pm::metric::MeasureOptions::DEFAULT,
        )
        .expect("measurable")
        .hausdorff_percent()
    };
    let opts = SimplifyOptions::DEFAULT
        .with_target_triangles(target)
        .with_topology_change(lodgen_pm::TopologyChange::Never);
    let textured = simplify_with_wedges(&pos, &idx, &[], 0, &opts)
        .unwrap()
        .pm
        .base;
    let plain = simplify(&sphere.positions, &sphere.triangles.concat(), &opts)
        .unwrap()
        .pm
        .base;
    assert_eq!(textured.triangles.len(), target);
    let (t, p) = (hausdorff(&textured), hausdorff(&plain));
    assert!(t < 2.0 * p, "with the poles' wedges {t} %, without {p} %");
}
