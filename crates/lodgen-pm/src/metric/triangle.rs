//! Exact point–triangle distance in `f64`: C. Ericson, *Real-Time Collision Detection*,
//! Morgan Kaufmann 2005, §5.1.5 "Closest point on triangle to point" (Voronoi-region tests, no
//! square roots), made robust for zero-area triangles by falling back to the three edges.
//! Pure geometry: depends on nothing.

/// `a - b`
#[inline(always)]
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a · b`
#[inline(always)]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a × b`
#[inline(always)]
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a + t * d`
#[inline(always)]
fn along(a: [f64; 3], d: [f64; 3], t: f64) -> [f64; 3] {
    [a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]]
}

/// Squared Euclidean distance between two points.
#[inline(always)]
pub fn distance_squared(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

#[inline(always)]
pub(crate) fn widen(p: [f32; 3]) -> [f64; 3] {
    [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
}

/// Closest point to `p` on the segment `a`–`b` (a point when `a == b`).
#[inline]
fn closest_point_on_segment(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    if len2 <= 0.0 {
        return a;
    }
    let t = (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0);
    along(a, ab, t)
}

/// Closest point to `p` on whichever of the three edges is nearest; used for zero-area triangles,
/// where the barycentric solve of the face region divides by zero.
#[cold]
fn closest_point_on_edges(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let mut best = closest_point_on_segment(p, a, b);
    let mut best_d2 = distance_squared(p, best);
    for (u, v) in [(b, c), (c, a)] {
        let q = closest_point_on_segment(p, u, v);
        let d2 = distance_squared(p, q);
        if d2 < best_d2 {
            best = q;
            best_d2 = d2;
        }
    }
    best
}

/// The point of triangle `a b c` (the filled triangle, not only its edges) closest to `p`.
///
/// Ericson's Voronoi-region walk (*Real-Time Collision Detection* §5.1.5): vertex regions, then
/// edge regions, then the face, using only dot products. Each edge-region denominator is
/// mathematically the squared edge length and the face denominator the squared doubled area, so
/// they vanish only on degenerate triangles; those cases take the exact edge fallback instead of
/// dividing by zero. Works for any finite input, including all three corners equal.
#[inline]
pub fn closest_point_on_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a; // vertex region A
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b; // vertex region B
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let den = d1 - d3;
        if den > 0.0 {
            return along(a, ab, d1 / den); // edge region AB
        }
        return closest_point_on_edges(p, a, b, c);
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c; // vertex region C
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let den = d2 - d6;
        if den > 0.0 {
            return along(a, ac, d2 / den); // edge region AC
        }
        return closest_point_on_edges(p, a, b, c);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let den = (d4 - d3) + (d5 - d6);
        if den > 0.0 {
            return along(b, sub(c, b), (d4 - d3) / den); // edge region BC
        }
        return closest_point_on_edges(p, a, b, c);
    }
    let den = va + vb + vc;
    if den <= 0.0 || !den.is_finite() {
        return closest_point_on_edges(p, a, b, c);
    }
    let v = vb / den;
    let w = vc / den;
    [
        a[0] + ab[0] * v + ac[0] * w,
        a[1] + ab[1] * v + ac[1] * w,
        a[2] + ab[2] * v + ac[2] * w,
    ] // face region
}

/// `if c { x } else { y }` for points, without a branch.
#[inline(always)]
fn pick(c: bool, x: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    let m = 0u64.wrapping_sub(u64::from(c));
    std::array::from_fn(|i| f64::from_bits((x[i].to_bits() & m) | (y[i].to_bits() & !m)))
}

/// [`closest_point_on_triangle`], bit for bit, with every region's point computed and the
/// answer selected without branches (the region of a triangle near a query is not
/// predictable); degenerate triangles still take the edge fallback.
#[inline(always)]
pub(crate) fn closest_point_on_triangle_flat(
    p: [f64; 3],
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
) -> [f64; 3] {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    let vc = d1 * d4 - d3 * d2;
    let vb = d5 * d2 - d1 * d6;
    let va = d3 * d6 - d5 * d4;
    let in_a = (d1 <= 0.0) & (d2 <= 0.0);
    let in_b = (d3 >= 0.0) & (d4 <= d3);
    let in_ab = (vc <= 0.0) & (d1 >= 0.0) & (d3 <= 0.0);
    let in_c = (d6 >= 0.0) & (d5 <= d6);
    let in_ac = (vb <= 0.0) & (d2 >= 0.0) & (d6 <= 0.0);
    let in_bc = (va <= 0.0) & ((d4 - d3) >= 0.0) & ((d5 - d6) >= 0.0);
    let den_ab = d1 - d3;
    let den_ac = d2 - d6;
    let den_bc = (d4 - d3) + (d5 - d6);
    let den = va + vb + vc;
    // the region the branching version takes, in its order
    let take_ab = !in_a & !in_b & in_ab;
    let take_c = !in_a & !in_b & !in_ab & in_c;
    let take_ac = !in_a & !in_b & !in_ab & !in_c & in_ac;
    let take_bc = !in_a & !in_b & !in_ab & !in_c & !in_ac & in_bc;
    let face = !in_a & !in_b & !in_ab & !in_c & !in_ac & !in_bc;
    let degenerate = (take_ab & (den_ab <= 0.0))
        | (take_ac & (den_ac <= 0.0))
        | (take_bc & (den_bc <= 0.0))
        | (face & (den <= 0.0 || !den.is_finite()));
    if degenerate {
        return closest_point_on_edges(p, a, b, c);
    }
    let v = vb / den;
    let w = vc / den;
    let mut q = [
        a[0] + ab[0] * v + ac[0] * w,
        a[1] + ab[1] * v + ac[1] * w,
        a[2] + ab[2] * v + ac[2] * w,
    ];
    q = pick(take_bc, along(b, sub(c, b), (d4 - d3) / den_bc), q);
    q = pick(take_ac, along(a, ac, d2 / den_ac), q);
    q = pick(take_c, c, q);
    q = pick(take_ab, along(a, ab, d1 / den_ab), q);
    q = pick(in_b & !in_a, b, q);
    pick(in_a, a, q)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The branch-free closest point is the branching one bit for bit, in every region and on
    /// degenerate triangles (fails when a region's priority or formula differs).
    #[test]
    fn flat_closest_point_matches_the_branching_one() {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
        };
        let mut regions = std::collections::BTreeSet::new();
        for k in 0..200_000 {
            let mut t: [[f64; 3]; 4] = std::array::from_fn(|_| std::array::from_fn(|_| next()));
            match k % 7 {
                5 => t[2] = t[1],                                // two corners equal
                6 => t[2] = along(t[0], sub(t[1], t[0]), 0.375), // collinear
                _ => {}
            }
            let [p, a, b, c] = t;
            let q = closest_point_on_triangle(p, a, b, c);
            let f = closest_point_on_triangle_flat(p, a, b, c);
            assert_eq!(
                q.map(f64::to_bits),
                f.map(f64::to_bits),
                "p {p:?} at {a:?} {b:?} {c:?}"
            );
            regions.insert([q == a, q == b, q == c].map(u8::from));
        }
        assert!(regions.len() >= 4, "corner and other regions all reached");
    }
}
