//! Per-level attribute fit (`lodgen_pm::attrfit`): a level's values follow
//! the input's attribute field at the level's own positions, and seams keep
//! their input values.

use lodgen_pm::attrfit::{fit, Channel, Level, Source};

/// One channel per component range, bounded.
fn channels(ranges: &[std::ops::Range<usize>]) -> Vec<Channel> {
    ranges
        .iter()
        .map(|r| Channel {
            components: r.clone(),
            bounded: true,
        })
        .collect()
}
use lodgen_pm::shapes;

/// A flat 8×8 grid on [0, 1]², z = 0.
fn source_grid() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let g = shapes::grid(8, 8, |_, _| 0.0);
    (g.positions, g.triangles)
}

/// Source vertex (i, j) of the 8×8 grid.
fn sv(i: u32, j: u32) -> u32 {
    j * 9 + i
}

#[test]
fn a_linear_field_is_reproduced_at_moved_vertices() {
    let (pos, tris) = source_grid();
    let field = |p: [f32; 3]| 2.0 * p[0] + 3.0 * p[1] + 1.0;
    let values: Vec<f32> = pos.iter().map(|&p| field(p)).collect();
    // a coarse level: the square's corners and an off-grid centre vertex
    // whose wedge is the source vertex (4, 4) at (0.5, 0.5)
    let lpos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.37, 0.61, 0.0],
    ];
    let ltris: [[u32; 3]; 4] = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
    let corner_wedge = [sv(0, 0), sv(8, 0), sv(8, 8), sv(0, 8), sv(4, 4)];
    let lwedges: Vec<[u32; 3]> = ltris
        .iter()
        .map(|t| t.map(|v| corner_wedge[v as usize]))
        .collect();
    let out = fit(
        Source {
            positions: &pos,
            triangles: &tris,
            values: &values,
            dims: 1,
        },
        Level {
            positions: &lpos,
            triangles: &ltris,
            wedges: &lwedges,
        },
        &channels(std::slice::from_ref(&(0..1))),
    );
    for (v, &p) in lpos.iter().enumerate() {
        let got = out.get(v as u32, corner_wedge[v]).unwrap()[0];
        assert!(
            (got - field(p)).abs() < 2e-3,
            "vertex {v}: {got} instead of {}",
            field(p)
        );
    }
    // the wedge's own value would be 3.5 at the centre, the field says 3.57
    assert!((values[sv(4, 4) as usize] - field(lpos[4])).abs() > 0.05);
}

#[test]
fn a_seam_keeps_its_input_values_where_the_sides_differ() {
    // two charts, x ≤ 0.5 and x ≥ 0.5; channel 0 jumps by 10 across the
    // seam, channel 1 is continuous
    let (pos, tris) = source_grid();
    let n = pos.len() as u32;
    let right = |t: &[u32; 3]| t.iter().map(|&v| pos[v as usize][0]).sum::<f32>() > 1.5;
    let wedge_tris: Vec<[u32; 3]> = tris
        .iter()
        .map(|t| t.map(|v| if right(t) { v + n } else { v }))
        .collect();
    let mut wpos = pos.clone();
    wpos.extend_from_slice(&pos);
    let values: Vec<f32> = (0..2 * n)
        .flat_map(|w| {
            let p = pos[(w % n) as usize];
            let jump = if w >= n { 10.0 } else { 0.0 };
            [p[0] + p[1] + jump, 2.0 * p[0] + 3.0 * p[1]]
        })
        .collect();
    // level: two quads meeting at the seam; the seam vertex at (0.5, 0)
    // carries the wedges of the source vertex at (0.5, 0.125)
    let lpos = [
        [0.0, 0.0, 0.0],
        [0.5, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let ltris: [[u32; 3]; 4] = [[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]];
    let left = [sv(0, 0), sv(4, 1), 0, sv(0, 8), sv(4, 8), 0];
    let rightw = [0, sv(4, 1) + n, sv(8, 0) + n, 0, sv(4, 8) + n, sv(8, 8) + n];
    let lwedges: Vec<[u32; 3]> = ltris
        .iter()
        .enumerate()
        .map(|(t, tri)| {
            tri.map(|v| {
                if t < 2 {
                    left[v as usize]
                } else {
                    rightw[v as usize]
                }
            })
        })
        .collect();
    let out = fit(
        Source {
            positions: &wpos,
            triangles: &wedge_tris,
            values: &values,
            dims: 2,
        },
        Level {
            positions: &lpos,
            triangles: &ltris,
            wedges: &lwedges,
        },
        &channels(&[0..1, 1..2]),
    );
    for w in [sv(4, 1), sv(4, 1) + n] {
        let got = out.get(1, w).unwrap();
        let input = &values[2 * w as usize..2 * w as usize + 2];
        // the discontinuous channel: exactly the input's, on both sides
        assert_eq!(got[0].to_bits(), input[0].to_bits(), "wedge {w}");
        // the continuous one: fitted to the vertex's real place, 1.0
        // (the wedge's own value is 1.375), the same on both sides
        assert!((got[1] - 1.0).abs() < 2e-3, "wedge {w}: {}", got[1]);
    }
    assert_eq!(
        out.get(1, sv(4, 1)).unwrap()[1].to_bits(),
        out.get(1, sv(4, 1) + n).unwrap()[1].to_bits()
    );
}

#[test]
fn samples_never_cross_into_another_chart() {
    // chart A: the unit square at z = 0, value 0; chart B: a smaller square
    // 0.01 above its middle, value 100. In the level, A has moved up to
    // z = 0.02 (as a coarse level may), so A's samples under B are nearer
    // to B's level triangles than to A's: they must not count for B.
    let square = |lo: f32, hi: f32, z: f32| [[lo, lo, z], [hi, lo, z], [hi, hi, z], [lo, hi, z]];
    let mut pos = square(0.0, 1.0, 0.0).to_vec();
    pos.extend(square(0.25, 0.75, 0.01));
    let quad = |o: u32| [[o, o + 1, o + 2], [o, o + 2, o + 3]];
    let mut tris = quad(0).to_vec();
    tris.extend(quad(4));
    let values = [0.0, 0.0, 0.0, 0.0, 100.0, 100.0, 100.0, 100.0];
    let mut lpos = square(0.0, 1.0, 0.02).to_vec();
    lpos.extend(square(0.25, 0.75, 0.01));
    let out = fit(
        Source {
            positions: &pos,
            triangles: &tris,
            values: &values,
            dims: 1,
        },
        Level {
            positions: &lpos,
            triangles: &tris,
            wedges: &tris,
        },
        &channels(std::slice::from_ref(&(0..1))),
    );
    for v in 4..8 {
        let got = out.get(v, v).unwrap()[0];
        assert!((got - 100.0).abs() < 1e-3, "vertex {v}: {got}");
    }
}

#[test]
fn bounded_channels_never_extrapolate() {
    // a step from 0 to 1 across x = 0.5, fitted by one linear ramp over the
    // square: least squares overshoots to about −0.25 and 1.25 at the ends
    let (pos, tris) = source_grid();
    let values: Vec<f32> = pos
        .iter()
        .map(|p| if p[0] >= 0.5 { 1.0 } else { 0.0 })
        .collect();
    let lpos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let ltris: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];
    let corner_wedge = [sv(0, 0), sv(8, 0), sv(8, 8), sv(0, 8)];
    let lwedges: Vec<[u32; 3]> = ltris
        .iter()
        .map(|t| t.map(|v| corner_wedge[v as usize]))
        .collect();
    let run = |bounded: bool| {
        fit(
            Source {
                positions: &pos,
                triangles: &tris,
                values: &values,
                dims: 1,
            },
            Level {
                positions: &lpos,
                triangles: &ltris,
                wedges: &lwedges,
            },
            &[Channel {
                components: 0..1,
                bounded,
            }],
        )
    };
    let (free, bounded) = (run(false), run(true));
    let at =
        |f: &lodgen_pm::attrfit::Fitted, v: usize| f.get(v as u32, corner_wedge[v]).unwrap()[0];
    assert!(
        at(&free, 0) < -0.1 && at(&free, 1) > 1.1,
        "{} {}",
        at(&free, 0),
        at(&free, 1)
    );
    for v in 0..4 {
        let x = at(&bounded, v);
        assert!((0.0..=1.0).contains(&x), "vertex {v}: {x}");
    }
}
