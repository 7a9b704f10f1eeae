//! Options of the metric: which method finds the maximum, how many area samples estimate the
//! mean and RMS, the tolerance of the bounded maximum. Plain data; used by
//! [`measure`](mod@super::measure).

/// How the maximum distance (the Hausdorff figure) is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Method {
    /// Bounded subdivision: the maximum over the whole sampled surface within
    /// [`MeasureOptions::tolerance`] — the reported value is attained by a point of the
    /// surface (never above the true maximum) and the true maximum is at most
    /// `value × (1 + tolerance) + absolute_tolerance × diagonal`
    /// ([`Distance::max_bound`](super::Distance::max_bound) holds the bound).
    /// Mean and RMS come from a budget of stratified area samples: see
    /// [`MeasureOptions::BOUNDED`].
    Bounded,
    /// Metro sampling (the default): the maximum over the area samples and the vertices (a
    /// lower estimate: a maximum over samples only creeps up with density), mean and RMS over
    /// the area samples. See [`MeasureOptions::METRO`].
    Sampled,
}

/// Options of the metric.
///
/// Two methods ([`Method`]). [`MeasureOptions::DEFAULT`] samples, in each direction:
///
/// - area samples for the mean and RMS (and the maximum): 2 per triangle of the larger mesh up
///   to 2,048 triangles, then √(8,192 · t) (t: triangles of the larger mesh), at least 30,000
///   (64 per triangle under 469 triangles); 30,000 per direction for the bunny (69,451
///   triangles) instead of the 138,902 of [`MeasureOptions::METRO`], 190,821 for a 4.4 M-triangle
///   mesh instead of 2.16 M;
/// - for the maximum only, every vertex, and, when the sampled mesh has at most a quarter of the
///   other's triangles (a level measured back to its original), every triangle's centroid and
///   every edge's midpoint: the maxima of such a mesh sit inside its large triangles, or along
///   an edge where two of them meet at a crease (the bunny's 10 % level: 0.2463 % halfway
///   along an edge whose corners are within 0.05 %, which the samples and centroids put at
///   0.2162 %);
/// - for the maximum only, a max-seeking search from the 16 farthest of those points (at most
///   one per triangle or vertex): a pattern search over the point's triangle, climbing to the
///   local maximum (at most 96 points each).
///
/// Every point is measured exactly. Measured against 64 area samples per triangle and the
/// certified maximum of [`MeasureOptions::BOUNDED`]: over 8 seeds, the mean and RMS of the
/// 50 / 10 / 2 % levels of bunny, cow and fandisk scatter 0.2–0.9 % (one standard deviation)
/// around the dense figures, the farthest 1.8 % off (docs/performance.md, eighth round), and each
/// one-sided maximum is at least METRO's (the 10 % level's back direction 6.16 instead of 4.12
/// ×10⁻⁴, the certified maximum 6.15–6.24), for 0.4× of METRO's CPU time.
///
/// [`MeasureOptions::METRO`] is the earlier default, bit for bit: 2 area samples per triangle
/// of the larger mesh (√-growth only above 2¹⁸ triangles) plus every vertex, no centroids, no
/// search. Why 2: the samples are then about half the finer mesh's mean edge length apart (an
/// equilateral triangle of edge e holding 2 samples gives a spacing of √(0.433e²/2) ≈ 0.47e).
///
/// [`MeasureOptions::BOUNDED`] finds the maximum by bounded subdivision, certified within 1 %
/// (plus 10⁻⁵ of the diagonal), and estimates mean and RMS from the same area samples as the
/// default.
///
/// What sampling can miss (both sampled methods): a spike or pit narrower than the sample
/// spacing, away from the vertices and from the farthest samples (the bounded method misses
/// nothing beyond its tolerance). Set `full_rate_triangles` to `usize::MAX` for 2 samples per
/// triangle at any size.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct MeasureOptions {
    /// How the maximum is found.
    ///
    /// Default value: [`Method::Sampled`].
    pub method: Method,
    /// Area samples per direction, per triangle of the mesh with more triangles (up to
    /// [`Self::full_rate_triangles`]). Negative or NaN counts as 0.
    ///
    /// Default value: 2.0.
    pub samples_per_triangle: f64,
    /// Lower bound on the area samples per direction, so that tiny meshes (a 12-triangle cube)
    /// are still sampled densely.
    ///
    /// Default value: 30,000 (METRO: 10,000).
    pub min_samples: usize,
    /// Cap on that lower bound, per triangle of the larger mesh: a 12-triangle card is sampled
    /// 768 times per direction, not 30,000. 64 samples per triangle put the spacing at an
    /// eighth of the triangle's size; without the cap a scene of many small meshes (a game
    /// level: 947 of 1,000 meshes under 157 triangles) spent ~60 % of its run measuring them.
    /// [`MeasureOptions::with_min_samples`] removes it (an explicit bound is taken as given).
    ///
    /// Default value: 64.0.
    pub min_samples_per_triangle: f64,
    /// Triangle count (of the larger mesh) up to which area samples are
    /// `samples_per_triangle` per triangle; above it they grow with the square root of the
    /// count.
    ///
    /// Default value: 2,048 (METRO: 262,144).
    pub full_rate_triangles: usize,
    /// Sampled method: also measure from every vertex the sampled mesh's triangles use (counted
    /// in the maximum only, see [`Distance`](super::Distance)). The bounded method always
    /// measures the corners it needs.
    ///
    /// Default value: true.
    pub vertex_samples: bool,
    /// Sampled method: how many of the farthest points found (at most one per triangle or vertex,
    /// at most 16) start a max-seeking search over their triangle; with 0, neither the search nor
    /// the centroids and edge midpoints of a coarse mesh are measured.
    ///
    /// Default value: 16 (METRO: 0).
    pub seek_candidates: usize,
    /// Sampled method: points each max-seeking search may measure, at most.
    ///
    /// Default value: 96.
    pub seek_budget: usize,
    /// Bounded only: relative tolerance of the maximum (see [`Method::Bounded`]).
    ///
    /// Default value: 0.01 (1 %).
    pub tolerance: f64,
    /// Bounded only: absolute tolerance of the maximum, as a fraction of the original's
    /// bounding-box diagonal, so that a level (almost) equal to the original does not need
    /// its surface resolved to rounding level.
    ///
    /// Default value: 10⁻⁵ (0.001 % of the diagonal).
    pub absolute_tolerance: f64,
    /// Seed of the sample positions. Results are a pure function of the meshes and the options.
    ///
    /// Default value: `0x6c6f_6467_656e` ("lodgen").
    pub seed: u64,
}

impl MeasureOptions {
    /// Budgeted area samples, every vertex, centroids and edge midpoints of a coarse mesh and
    /// the max-seeking
    /// search (see the type's documentation).
    pub const DEFAULT: MeasureOptions = MeasureOptions {
        method: Method::Sampled,
        samples_per_triangle: 2.0,
        min_samples: 30_000,
        min_samples_per_triangle: 64.0,
        full_rate_triangles: 1 << 11,
        vertex_samples: true,
        seek_candidates: 16,
        seek_budget: 96,
        tolerance: 0.01,
        absolute_tolerance: 1e-5,
        seed: 0x6c6f_6467_656e,
    };

    /// Plain Metro sampling (the default until 2026-11-26), bit for bit: 2 area samples per
    /// triangle of the larger mesh and every vertex.
    pub const METRO: MeasureOptions = MeasureOptions {
        method: Method::Sampled,
        samples_per_triangle: 2.0,
        min_samples: 10_000,
        full_rate_triangles: 1 << 18,
        seek_candidates: 0,
        ..Self::DEFAULT
    };

    /// The bounded maximum, with the default's area samples for mean and RMS (opt-in).
    pub const BOUNDED: MeasureOptions = MeasureOptions {
        method: Method::Bounded,
        ..Self::DEFAULT
    };

    /// Switches to [`Method::Sampled`] (with the default's rate rule when coming from the
    /// bounded method) at `samples_per_triangle` area samples per triangle.
    pub fn with_samples_per_triangle(mut self, samples_per_triangle: f64) -> Self {
        self = self.sampled();
        self.samples_per_triangle = samples_per_triangle;
        self
    }

    /// Switches to [`Method::Sampled`] (with the default's rate rule when coming from the
    /// bounded method) with at least `min_samples` area samples per direction, whatever the meshes'
    /// size (the per-triangle cap, [`MeasureOptions::min_samples_per_triangle`], is lifted).
    pub fn with_min_samples(mut self, min_samples: usize) -> Self {
        self = self.sampled();
        self.min_samples = min_samples;
        self.min_samples_per_triangle = f64::INFINITY;
        self
    }

    /// The default's method and rate rule, unless already sampling.
    fn sampled(self) -> Self {
        if self.method == Method::Sampled {
            return self;
        }
        MeasureOptions {
            method: Method::Sampled,
            samples_per_triangle: Self::DEFAULT.samples_per_triangle,
            full_rate_triangles: Self::DEFAULT.full_rate_triangles,
            ..self
        }
    }

    pub fn with_method(mut self, method: Method) -> Self {
        self.method = method;
        self
    }

    pub fn with_min_samples_per_triangle(mut self, min_samples_per_triangle: f64) -> Self {
        self.min_samples_per_triangle = min_samples_per_triangle;
        self
    }

    pub fn with_full_rate_triangles(mut self, full_rate_triangles: usize) -> Self {
        self.full_rate_triangles = full_rate_triangles;
        self
    }

    /// The max-seeking search: `candidates` searches (at most 16; 0: none) of at most `budget`
    /// points each.
    pub fn with_seek(mut self, candidates: usize, budget: usize) -> Self {
        self.seek_candidates = candidates;
        self.seek_budget = budget;
        self
    }

    pub fn with_vertex_samples(mut self, vertex_samples: bool) -> Self {
        self.vertex_samples = vertex_samples;
        self
    }

    /// Relative tolerance of the bounded maximum (NaN or negative counts as 0).
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }

    /// Absolute tolerance of the bounded maximum, a fraction of the diagonal (NaN or negative
    /// counts as 0).
    pub fn with_absolute_tolerance(mut self, absolute_tolerance: f64) -> Self {
        self.absolute_tolerance = absolute_tolerance;
        self
    }

    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Area samples per direction for meshes of `tris_a` and `tris_b` triangles: with
    /// `t = max(tris_a, tris_b)` and `k = full_rate_triangles`,
    /// `samples_per_triangle × (t if t ≤ k, else √(k·t))`, at least
    /// `min(min_samples, min_samples_per_triangle × t)`.
    pub fn area_sample_count(&self, tris_a: usize, tris_b: usize) -> usize {
        let per = if self.samples_per_triangle > 0.0 {
            self.samples_per_triangle
        } else {
            0.0
        };
        let t = tris_a.max(tris_b) as f64;
        let k = self.full_rate_triangles as f64;
        let effective = if t <= k { t } else { (k * t).sqrt() };
        // `as` saturates for huge values.
        let n = (per * effective).ceil() as usize;
        let floor = if self.min_samples_per_triangle >= 0.0 {
            // `as` saturates (infinity: no cap)
            (self.min_samples_per_triangle * t).ceil() as usize
        } else {
            0
        };
        n.max(self.min_samples.min(floor))
    }
}

impl Default for MeasureOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}
