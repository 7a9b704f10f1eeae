//! Garland–Heckbert quadric error metric (GH97, "Surface Simplification Using
//! Quadric Error Metrics", SIGGRAPH 1997; seeds 000, 002, 003).
//!
//! Owns the [`Quadric`] value type and optimal placement, also for eight
//! pairs at once ([`CostLanes`]). Knows nothing of meshes, pairs or heaps.

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

/// [`Quadric::lifted`]'s damping, relative to the planes' total weight.
/// The same step tried inside the simplifier (`docs/quality.md`, "RMS
/// (session 19)") lowered the 50 % levels' RMS alike at 10⁻³, 10⁻² and 10⁻¹
/// (bunny −7 to −9 %, teapot −17 to −18 %); the lift of the written levels,
/// and the lift in the log (`simplify::lift`), were measured at 10⁻² only.
pub const LIFT_DAMPING: f64 = 1e-2;

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

    /// A cost of this quadric (`eval`) as a distance: the root of the mean
    /// squared distance over its planes' weight (of the sum without weight).
    #[inline]
    pub fn distance(&self, cost: f64) -> f64 {
        if self.weight > 0.0 {
            (cost / self.weight).sqrt()
        } else {
            cost.sqrt()
        }
    }

    /// `vᵀ Q v` with `v = (p, 1)`: the weighted sum of squared distances.
    #[inline]
    pub fn eval(&self, p: DVec3) -> f64 {
        eval_at(&self.coefficients(), p.x, p.y, p.z)
    }

    /// `[a2, ab, ac, ad, b2, bc, bd, c2, cd, d2]`.
    #[inline]
    fn coefficients(&self) -> [f64; 10] {
        [
            self.a2, self.ab, self.ac, self.ad, self.b2, self.bc, self.bd, self.c2, self.cd,
            self.d2,
        ]
    }

    /// The minimiser of `eval`, or `None` when the 3×3 block is
    /// ill-conditioned (see [`SINGULAR_RATIO`]).
    #[inline]
    pub fn optimize(&self) -> Option<DVec3> {
        let (singular, [x, y, z]) = solve(&self.coefficients());
        let p = DVec3::new(x, y, z);
        (!singular && p.is_finite()).then_some(p)
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

    /// `s` moved by one damped Newton step towards this quadric's planes:
    /// the minimiser of `vᵀQv + μ‖p − s‖²`, `μ` = [`LIFT_DAMPING`] × the
    /// trace of the 3×3 block (the planes' total weight). Along the
    /// well-determined directions (the normal of a nearly flat patch) the
    /// step goes nearly all the way; along the others (tangents, where the
    /// system is nearly singular) it barely moves, and by at most
    /// `√(eval(s) / μ)`. `None` when the step is not finite or does not
    /// lower the cost (a point already at the minimum).
    pub fn lifted(&self, s: DVec3) -> Option<DVec3> {
        let mu = LIFT_DAMPING * (self.a2 + self.b2 + self.c2);
        if mu.is_nan() || mu <= 0.0 {
            return None;
        }
        // the gradient's half at s; `solve` returns the damped block's
        // inverse times its negation: the step
        let g = self.mul3(s) + DVec3::new(self.ad, self.bd, self.cd);
        let damped = Quadric {
            a2: self.a2 + mu,
            b2: self.b2 + mu,
            c2: self.c2 + mu,
            ..*self
        };
        let (_, [x, y, z]) = solve(&[
            damped.a2, damped.ab, damped.ac, g.x, damped.b2, damped.bc, g.y, damped.c2, g.z, 0.0,
        ]);
        let p = s + DVec3::new(x, y, z);
        (p.is_finite() && self.eval(p) < self.eval(s)).then_some(p)
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

/// [`Quadric::eval`] on the coefficients `[a2, ab, ac, ad, b2, bc, bd, c2,
/// cd, d2]` (shared with [`CostLanes`], so that both do the same operations).
#[inline(always)]
fn eval_at(k: &[f64; 10], x: f64, y: f64, z: f64) -> f64 {
    let [a2, ab, ac, ad, b2, bc, bd, c2, cd, d2] = *k;
    let v = x * (a2 * x + 2.0 * (ab * y + ac * z + ad))
        + y * (b2 * y + 2.0 * (bc * z + bd))
        + z * (c2 * z + 2.0 * cd)
        + d2;
    v.max(0.0)
}

/// [`Quadric::optimize`]'s arithmetic on the coefficients (as in
/// [`eval_at`]): whether the 3×3 block counts as singular (see
/// [`SINGULAR_RATIO`]; the point is then meaningless), and the solution by
/// cofactors.
#[inline(always)]
fn solve(k: &[f64; 10]) -> (bool, [f64; 3]) {
    let (a, b, c) = (k[0], k[1], k[2]);
    let (e, f, i) = (k[4], k[5], k[7]);
    // cofactors of the symmetric matrix [[a b c][b e f][c f i]]
    let c00 = e * i - f * f;
    let c01 = c * f - b * i;
    let c02 = b * f - c * e;
    let det = a * c00 + b * c01 + c * c02;
    let norm2 = a * a + e * e + i * i + 2.0 * (b * b + c * c + f * f);
    let norm3 = norm2 * norm2.sqrt();
    let singular = det.is_nan() || det.abs() <= SINGULAR_RATIO * norm3;
    let c11 = a * i - c * c;
    let c12 = b * c - a * f;
    let c22 = a * e - b * b;
    let (rx, ry, rz) = (-k[3], -k[6], -k[8]);
    let inv = 1.0 / det;
    (
        singular,
        [
            (c00 * rx + c01 * ry + c02 * rz) * inv,
            (c01 * rx + c11 * ry + c12 * rz) * inv,
            (c02 * rx + c12 * ry + c22 * rz) * inv,
        ],
    )
}

/// How many pairs [`CostLanes`] costs at once.
pub const LANES: usize = 8;

/// Up to [`LANES`] pairs to be costed together by [`Quadric::placement`]'s
/// rule, laid out one array per coefficient: the lanes are independent, so
/// the divisions and square roots of one pair overlap with the others'
/// (one pair at a time, costing waits on its own chain of them), and the
/// compiler may pack two lanes per instruction. Every lane computes exactly
/// the operations `placement` does, in the same order (no fused or
/// reassociated arithmetic), so a lane's cost equals `placement`'s to the
/// bit; a lane whose segment fallback has no finite interior minimum is
/// left to `placement` itself (rare).
#[derive(Clone, Debug, Default)]
pub struct CostLanes {
    len: usize,
    /// The 10 coefficients of each lane's summed quadric, in [`Quadric`]'s
    /// field order.
    q: [[f64; LANES]; 10],
    p0: [[f64; LANES]; 3],
    p1: [[f64; LANES]; 3],
}

impl CostLanes {
    /// Lanes in use.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    #[inline]
    pub fn is_full(&self) -> bool {
        self.len == LANES
    }

    /// Add the pair `q` = Q_a + Q_b at `p0`, `p1` (call only when not full).
    #[inline]
    pub fn push(&mut self, q: &Quadric, p0: DVec3, p1: DVec3) {
        let l = self.len;
        let c = [q.a2, q.ab, q.ac, q.ad, q.b2, q.bc, q.bd, q.c2, q.cd, q.d2];
        for (k, v) in c.into_iter().enumerate() {
            self.q[k][l] = v;
        }
        for k in 0..3 {
            self.p0[k][l] = p0[k];
            self.p1[k][l] = p1[k];
        }
        self.len += 1;
    }

    /// The costs of the pushed pairs, as [`Quadric::placement`] gives them,
    /// in push order; empties the lanes. With AVX2 where the processor has
    /// it (the same operations four lanes to an instruction instead of
    /// two: the same bits, as no operation is fused).
    pub fn costs(&mut self) -> [f64; LANES] {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (just checked)
            return unsafe { self.costs_avx2() };
        }
        self.costs_portable()
    }

    /// [`CostLanes::costs`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn costs_avx2(&mut self) -> [f64; LANES] {
        self.costs_portable()
    }

    /// [`CostLanes::costs`] for any processor (inlined into each variant).
    #[inline(always)]
    fn costs_portable(&mut self) -> [f64; LANES] {
        let [a2, ab, ac, ad, b2, bc, bd, c2, cd, d2] = &self.q;
        let [x0, y0, z0] = &self.p0;
        let [x1, y1, z1] = &self.p1;
        let mut out = [0.0; LANES];
        let mut slow = [false; LANES];
        for l in 0..LANES {
            let k = [
                a2[l], ab[l], ac[l], ad[l], b2[l], bc[l], bd[l], c2[l], cd[l], d2[l],
            ];
            let (a, b, c, e, f, i) = (k[0], k[1], k[2], k[4], k[5], k[7]);
            // `optimize`
            let (singular, [px, py, pz]) = solve(&k);
            let finite = px.is_finite() && py.is_finite() && pz.is_finite();
            // `placement`: near enough to the pair?
            let (dx, dy, dz) = (x1[l] - x0[l], y1[l] - y0[l], z1[l] - z0[l]);
            let reach2 = MAX_OPTIMUM_REACH * MAX_OPTIMUM_REACH * (dx * dx + dy * dy + dz * dz);
            let (mx, my, mz) = (
                (x0[l] + x1[l]) * 0.5,
                (y0[l] + y1[l]) * 0.5,
                (z0[l] + z1[l]) * 0.5,
            );
            let (ex, ey, ez) = (px - mx, py - my, pz - mz);
            let optimal = !singular && finite && ex * ex + ey * ey + ez * ez <= reach2;
            // `best_on_segment`, its usual case
            let m3 = |vx: f64, vy: f64, vz: f64| {
                (
                    a * vx + b * vy + c * vz,
                    b * vx + e * vy + f * vz,
                    c * vx + f * vy + i * vz,
                )
            };
            let (mdx, mdy, mdz) = m3(dx, dy, dz);
            let sa = dx * mdx + dy * mdy + dz * mdz;
            let (m0x, m0y, m0z) = m3(x0[l], y0[l], z0[l]);
            let sb = (dx * m0x + dy * m0y + dz * m0z) + (dx * ad[l] + dy * bd[l] + dz * cd[l]);
            let t = (-sb / sa).clamp(0.0, 1.0);
            let (sx, sy, sz) = (x0[l] + dx * t, y0[l] + dy * t, z0[l] + dz * t);
            slow[l] = !(optimal || sa > 0.0 && t.is_finite());
            // `eval` at the chosen point
            let (x, y, z) = if optimal { (px, py, pz) } else { (sx, sy, sz) };
            out[l] = eval_at(&k, x, y, z);
        }
        for l in 0..self.len {
            if slow[l] {
                let c = |k: usize| self.q[k][l];
                let q = Quadric {
                    a2: c(0),
                    ab: c(1),
                    ac: c(2),
                    ad: c(3),
                    b2: c(4),
                    bc: c(5),
                    bd: c(6),
                    c2: c(7),
                    cd: c(8),
                    d2: c(9),
                    weight: 0.0,
                };
                let p = |v: &[[f64; LANES]; 3]| DVec3::new(v[0][l], v[1][l], v[2][l]);
                out[l] = q.placement(p(&self.p0), p(&self.p1)).1;
            }
        }
        self.len = 0;
        out
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
    fn lanes_cost_exactly_what_placement_costs() {
        // well-conditioned corners, creases (segment fallback), single
        // planes, zero quadrics on a zero-length pair (the slow lane), far
        // optima: every kind of lane, more than one batch
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut cases = Vec::new();
        for k in 0..203 {
            let mut q = Quadric::default();
            let planes = k % 5; // 0 to 4 planes
            let c = DVec3::new(rnd(), rnd(), rnd());
            for _ in 0..planes {
                let n = DVec3::new(rnd(), rnd(), rnd());
                let n = if k % 7 == 0 { DVec3::Z } else { n };
                q += plane(n, c + DVec3::new(rnd(), rnd(), rnd()) * 0.1);
            }
            let p0 = DVec3::new(rnd(), rnd(), rnd());
            let p1 = if k % 11 == 0 {
                p0
            } else {
                p0 + DVec3::new(rnd(), rnd(), rnd()) * 0.01
            };
            cases.push((q, p0, p1));
        }
        // optima just inside and just outside MAX_OPTIMUM_REACH
        for s in [1.9, 1.99, 2.01, 2.1] {
            let c = DVec3::new(0.3, -0.2, 0.1);
            let q = plane(DVec3::X, c) + plane(DVec3::Y, c) + plane(DVec3::Z, c);
            let (u, e) = (DVec3::new(0.6, 0.8, 0.0), DVec3::Z);
            let mid = c + u * (s * 0.05);
            cases.push((q, mid - e * 0.025, mid + e * 0.025));
        }
        // `costs` (AVX2 where the processor has it) and the portable
        // variant, both to the bit
        let mut lanes = CostLanes::default();
        let (mut got, mut portable) = (Vec::new(), Vec::new());
        for (q, p0, p1) in &cases {
            lanes.push(q, *p0, *p1);
            if lanes.is_full() {
                portable.extend(lanes.clone().costs_portable());
                got.extend(lanes.costs());
            }
        }
        let n = lanes.len();
        portable.extend(&lanes.clone().costs_portable()[..n]);
        got.extend(&lanes.costs()[..n]);
        assert_eq!(got.len(), cases.len());
        for (((q, p0, p1), c), d) in cases.iter().zip(got).zip(portable) {
            let want = q.placement(*p0, *p1).1.to_bits();
            assert_eq!(c.to_bits(), want, "{q:?} {p0} {p1}");
            assert_eq!(d.to_bits(), want, "portable: {q:?} {p0} {p1}");
        }
    }

    #[test]
    fn a_nearly_flat_cluster_is_lifted_off_its_chord() {
        // tangent planes of a unit sphere at points within 0.02 rad of the
        // pole: nearly flat, so the system counts as singular and the
        // simplifier placed the pair on its chord, inside the sphere; the
        // lift takes that point along the normal to where the planes meet
        // (just outside the sphere), barely sideways
        let mut q = Quadric::default();
        for k in 0..24 {
            let (r, a) = (0.02 * f64::from(k % 3 + 1) / 3.0, f64::from(k) * 0.7);
            let n = DVec3::new(r.sin() * a.cos(), r.sin() * a.sin(), r.cos());
            q += Quadric::from_plane(n, -1.0, 1.0);
        }
        assert!(q.optimize().is_none(), "nearly flat: singular");
        let (p0, p1) = (
            DVec3::new(0.01f64.sin(), 0.0, 0.01f64.cos()),
            DVec3::new(-(0.01f64.sin()), 0.0, 0.01f64.cos()),
        );
        let (s, cs) = q.placement(p0, p1);
        assert!(s.length() < 1.0, "on the chord: {s}");
        let p = q.lifted(s).expect("the chord is not the minimum");
        // (the planes' least-squares point costs 1.28e-7, the chord 6.9e-7)
        assert!(
            q.eval(p) < cs * 0.25,
            "lifted cost {} against {cs}",
            q.eval(p)
        );
        assert!(p.length() > 1.0, "{p}");
        let side = (p - s) - (p - s).dot(DVec3::Z) * DVec3::Z;
        assert!(side.length() < 0.01 * (p1 - p0).length(), "{p} {s}");
        // a point at the minimum stays
        let c = DVec3::new(1.0, 2.0, 3.0);
        let corner = plane(DVec3::X, c) + plane(DVec3::Y, c) + plane(DVec3::Z, c);
        assert!(corner.lifted(c).is_none());
    }

    #[test]
    fn segment_fallback_beats_endpoints_and_midpoint() {
        // plane z = 0.25: best point on the segment z ∈ [0, 1] is z = 0.25.
        let q = plane(DVec3::Z, DVec3::new(0.0, 0.0, 0.25));
        let (p, c) = q.best_on_segment(DVec3::ZERO, DVec3::Z);
        assert!((p.z - 0.25).abs() < 1e-12 && c < 1e-20);
    }
}
