//! Candidate pairs (GH97 §3.2): every edge, plus every non-edge vertex pair
//! closer than the user's threshold τ, found with a uniform grid of cell τ
//! (never O(n²)).
//!
//! Owns pair discovery only; costs live in `collapse`.

/// Distances up to `τ · (1 + TAU_SLACK)` count as "within τ", so that a gap
/// written as 0.01 in a file but stored as 0.0100000007 in `f32` still merges
/// at τ = 0.01.
pub const TAU_SLACK: f64 = 1e-6;

/// Sorted, deduplicated `(a, b)` with `a < b` for every triangle edge (the
/// set-up builds its list from the fans; this is the reference for tests).
#[cfg(test)]
pub fn edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

fn within(a: &[f32; 3], b: &[f32; 3], tau: f64) -> bool {
    let d2: f64 = (0..3)
        .map(|i| {
            let d = f64::from(a[i]) - f64::from(b[i]);
            d * d
        })
        .sum();
    let t = tau * (1.0 + TAU_SLACK);
    d2 <= t * t
}

/// Every pair `(a, b)`, `a < b`, of vertices at distance ≤ τ that is not in
/// `edges` (which must be sorted), sorted. Uses a uniform grid with cells of
/// size τ, so each vertex only looks at its 27 neighbouring cells.
pub fn near_pairs(positions: &[[f32; 3]], edges: &[(u32, u32)], tau: f64) -> Vec<(u32, u32)> {
    if tau.is_nan() || tau <= 0.0 || positions.len() < 2 {
        return Vec::new();
    }
    let (lo, hi) = positions.iter().fold(
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                [0, 1, 2].map(|i| lo[i].min(f64::from(p[i]))),
                [0, 1, 2].map(|i| hi[i].max(f64::from(p[i]))),
            )
        },
    );
    // Cap the grid resolution so a tiny τ on a large mesh cannot make cell
    // coordinates overflow; cells only get larger, which stays correct.
    let extent = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
    let cell = tau.max(extent / f64::from(1u32 << 20));
    let cell_of = |p: &[f32; 3]| -> [i64; 3] {
        [0, 1, 2].map(|i| ((f64::from(p[i]) - lo[i]) / cell).floor() as i64)
    };
    // Sort vertices by cell; a cell's vertices are then one run.
    let mut by_cell: Vec<([i64; 3], u32)> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| (cell_of(p), i as u32))
        .collect();
    by_cell.sort_unstable();
    let find_run = |c: [i64; 3]| -> &[([i64; 3], u32)] {
        let start = by_cell.partition_point(|e| e.0 < c);
        let end = start + by_cell[start..].partition_point(|e| e.0 == c);
        &by_cell[start..end]
    };
    let mut out = Vec::new();
    for (i, p) in positions.iter().enumerate() {
        let c = cell_of(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    for &(_, j) in find_run([c[0] + dx, c[1] + dy, c[2] + dz]) {
                        if j as usize > i && within(p, &positions[j as usize], tau) {
                            let pair = (i as u32, j);
                            if edges.binary_search(&pair).is_err() {
                                out.push(pair);
                            }
                        }
                    }
                }
            }
        }
    }
    out.sort_unstable();
    out
}

/// The O(n²) reference for [`near_pairs`], for tests.
#[cfg(test)]
pub fn near_pairs_brute_force(
    positions: &[[f32; 3]],
    edges: &[(u32, u32)],
    tau: f64,
) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    if tau.is_nan() || tau <= 0.0 {
        return out;
    }
    for i in 0..positions.len() {
        for j in i + 1..positions.len() {
            let pair = (i as u32, j as u32);
            if within(&positions[i], &positions[j], tau) && edges.binary_search(&pair).is_err() {
                out.push(pair);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn grid_pair_finder_equals_brute_force(
            pts in prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 2..120),
            tau in 0.0f64..0.6,
        ) {
            let tris: Vec<[u32; 3]> = (0..pts.len() as u32 / 3).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
            let e = edges(&tris);
            prop_assert_eq!(near_pairs(&pts, &e, tau), near_pairs_brute_force(&pts, &e, tau));
        }
    }
}
