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
