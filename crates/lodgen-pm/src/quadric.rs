//! Garland–Heckbert quadric error metric (GH97, "Surface Simplification Using
//! Quadric Error Metrics", SIGGRAPH 1997; seeds 000, 002, 003).
//!
//! Owns the [`Quadric`] value type and optimal placement. Knows nothing of
//! meshes, pairs or heaps.

use glam::DVec3;

/// Below this ratio `|det A| / ‖A‖_F³` the 3×3 system is treated as singular.
///
/// Testing `det == 0` is useless in floating point: nearly flat neighbourhoods
/// have tiny but non-zero determinants and their "optimal" point lands far
/// away from the pair. The ratio is scale-invariant (a well-conditioned
/// corner gives ≈ 0.19; a crease gives ≈ 0).
pub const SINGULAR_RATIO: f64 = 1e-5;

/// An optimal point farther than this many pair lengths from the pair's
/// midpoint is distrusted and the segment fallback is used instead. The
/// conditioning test alone lets nearly-parallel planes throw the vertex out.
pub const MAX_OPTIMUM_REACH: f64 = 2.0;

/// A symmetric 4×4 quadric `Q` (10 coefficients) plus the total weight of the
/// planes summed into it, so `eval / weight` is a mean squared distance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Quadric {
    pub a2: f64,
    pub ab: f64,
    pub ac: f64,
    pub ad: f64,
    pub b2: f64,
    pub bc: f64,
    pub bd: f64,
    pub c2: f64,
    pub cd: f64,
    pub d2: f64,
    /// Sum of the weights of the planes (area, or 1 each when uniform).
    pub weight: f64,
}

impl Quadric {
    /// `w · p pᵀ` for the plane `n·x + d = 0`; `n` must be unit length.
    #[inline]
    pub fn from_plane(n: DVec3, d: f64, w: f64) -> Self {
        Quadric {
            a2: w * n.x * n.x,
            ab: w * n.x * n.y,
            ac: w * n.x * n.z,
            ad: w * n.x * d,
            b2: w * n.y * n.y,
            bc: w * n.y * n.z,
            bd: w * n.y * d,
            c2: w * n.z * n.z,
            cd: w * n.z * d,
            d2: w * d * d,
            weight: w,
        }
    }

    /// `vᵀ Q v` with `v = (p, 1)`: the weighted sum of squared distances.
    #[inline]
    pub fn eval(&self, p: DVec3) -> f64 {
        let (x, y, z) = (p.x, p.y, p.z);
        let v = x * (self.a2 * x + 2.0 * (self.ab * y + self.ac * z + self.ad))
            + y * (self.b2 * y + 2.0 * (self.bc * z + self.bd))
            + z * (self.c2 * z + 2.0 * self.cd)
            + self.d2;
        v.max(0.0)
    }

    /// The minimiser of `eval`, or `None` when the 3×3 block is
    /// ill-conditioned (see [`SINGULAR_RATIO`]).
    #[inline]
    pub fn optimize(&self) -> Option<DVec3> {
        let (a, b, c) = (self.a2, self.ab, self.ac);
        let (e, f, i) = (self.b2, self.bc, self.c2);
        // cofactors of the symmetric matrix [[a b c][b e f][c f i]]
        let c00 = e * i - f * f;
        let c01 = c * f - b * i;
        let c02 = b * f - c * e;
        let det = a * c00 + b * c01 + c * c02;
        let norm2 = a * a + e * e + i * i + 2.0 * (b * b + c * c + f * f);
        let norm3 = norm2 * norm2.sqrt();
        if det.is_nan() || det.abs() <= SINGULAR_RATIO * norm3 {
            return None;
        }
        let c11 = a * i - c * c;
        let c12 = b * c - a * f;
        let c22 = a * e - b * b;
        let r = DVec3::new(-self.ad, -self.bd, -self.cd);
        let inv = 1.0 / det;
        let p = DVec3::new(
            (c00 * r.x + c01 * r.y + c02 * r.z) * inv,
            (c01 * r.x + c11 * r.y + c12 * r.z) * inv,
            (c02 * r.x + c12 * r.y + c22 * r.z) * inv,
        );
        p.is_finite().then_some(p)
    }

    /// The best point on the segment `p0–p1` (the fallback of GH97 §4 and of
    /// the seed papers, which compare both ends and the midpoint), returned
    /// with its cost. Along the segment the cost is a convex quadratic in
    /// `t`, so its minimiser clamped to `[0, 1]` is at least as good as the
    /// ends and the midpoint; they are compared only when the quadratic is
    /// flat or the minimiser is not finite.
    #[inline]
    pub fn best_on_segment(&self, p0: DVec3, p1: DVec3) -> (DVec3, f64) {
        let d = p1 - p0;
        let a = d.dot(self.mul3(d));
        if a > 0.0 {
            let b = d.dot(self.mul3(p0)) + d.dot(DVec3::new(self.ad, self.bd, self.cd));
            let t = (-b / a).clamp(0.0, 1.0);
            if t.is_finite() {
                let p = p0 + d * t;
                return (p, self.eval(p));
            }
        }
        let mut best = (p0, self.eval(p0));
        for p in [p1, (p0 + p1) * 0.5] {
            let c = self.eval(p);
            if c < best.1 {
                best = (p, c);
            }
        }
        best
    }

    /// The optimal contraction target for a pair at `p0`, `p1`: the solution
    /// of the 3×3 system when it is well conditioned and near the pair, else
    /// [`Quadric::best_on_segment`].
    #[inline]
    pub fn placement(&self, p0: DVec3, p1: DVec3) -> (DVec3, f64) {
        if let Some(p) = self.optimize() {
            let reach2 = MAX_OPTIMUM_REACH * MAX_OPTIMUM_REACH * (p1 - p0).length_squared();
            if (p - (p0 + p1) * 0.5).length_squared() <= reach2 {
                return (p, self.eval(p));
            }
        }
        self.best_on_segment(p0, p1)
    }

    /// The upper-left 3×3 block times `v`.
    #[inline]
    fn mul3(&self, v: DVec3) -> DVec3 {
        DVec3::new(
            self.a2 * v.x + self.ab * v.y + self.ac * v.z,
            self.ab * v.x + self.b2 * v.y + self.bc * v.z,
            self.ac * v.x + self.bc * v.y + self.c2 * v.z,
        )
    }
}

impl std::ops::Add for Quadric {
    type Output = Quadric;
    #[inline]
    fn add(self, o: Quadric) -> Quadric {
        Quadric {
            a2: self.a2 + o.a2,
            ab: self.ab + o.ab,
            ac: self.ac + o.ac,
            ad: self.ad + o.ad,
            b2: self.b2 + o.b2,
            bc: self.bc + o.bc,
            bd: self.bd + o.bd,
            c2: self.c2 + o.c2,
            cd: self.cd + o.cd,
            d2: self.d2 + o.d2,
            weight: self.weight + o.weight,
        }
    }
}

impl std::ops::AddAssign for Quadric {
    #[inline]
    fn add_assign(&mut self, o: Quadric) {
        *self = *self + o;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(n: DVec3, through: DVec3) -> Quadric {
        let n = n.normalize();
        Quadric::from_plane(n, -n.dot(through), 1.0)
    }

    #[test]
    fn eval_is_squared_distance_to_plane() {
        let q = plane(DVec3::Z, DVec3::new(0.0, 0.0, 1.0));
        assert!((q.eval(DVec3::new(5.0, -3.0, 4.0)) - 9.0).abs() < 1e-12);
    }

    #[test]
    fn three_planes_meet_at_a_corner() {
        let c = DVec3::new(1.0, 2.0, 3.0);
        let q = plane(DVec3::X, c) + plane(DVec3::Y, c) + plane(DVec3::Z, c);
        let p = q.optimize().expect("a corner is well conditioned");
        assert!((p - c).length() < 1e-12);
        assert!(q.eval(p) < 1e-20);
    }

    #[test]
    fn a_single_plane_is_singular_and_falls_back_to_the_segment() {
        let q = plane(DVec3::Z, DVec3::ZERO);
        assert!(q.optimize().is_none());
        let (p, c) = q.placement(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.0, -3.0));
        assert!(c < 1e-20, "the segment crosses the plane: cost {c}");
        assert!(p.z.abs() < 1e-12);
    }

    #[test]
    fn segment_fallback_beats_endpoints_and_midpoint() {
        // plane z = 0.25: best point on the segment z ∈ [0, 1] is z = 0.25.
        let q = plane(DVec3::Z, DVec3::new(0.0, 0.0, 0.25));
        let (p, c) = q.best_on_segment(DVec3::ZERO, DVec3::Z);
        assert!((p.z - 0.25).abs() < 1e-12 && c < 1e-20);
    }
}
