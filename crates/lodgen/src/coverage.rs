//! `MSFT_screencoverage` values from measured level errors.
//!
//! This module owns the screen-coverage model only: a pure function from each
//! level's measured symmetric Hausdorff error to the switching thresholds that
//! the glTF writer stores in `extras.MSFT_screencoverage`.
//!
//! # What the values mean to clients
//!
//! The `MSFT_lod` specification gives one value per level, finest first:
//! level 0 is drawn while the object's screen coverage is at least `s[0]`,
//! level `k` while it lies in `[s[k], s[k-1])`, and nothing below the last value
//! (the last level's value is the cull threshold). So a chain of `n` levels has
//! `n` values; the final one is the cull value.
//!
//! "Screen coverage" is taken as Babylon.js defines it (`Mesh.getLOD` with
//! `useLODScreenCoverage`): the area of the object's bounding sphere projected
//! onto the screen divided by the screen area,
//! `c = π (r·n/d)² / (w_n·h_n)` with `r` the bounding-sphere radius (half the
//! bounding-box diagonal `D`), `d` the distance, and `w_n × h_n` the near-plane
//! rectangle.
//!
//! # The model
//!
//! Reference viewport: `H = 1080` lines, 16:9, so `N = 1920 × 1080` pixels.
//! A world length `L` at distance `d` spans `L / p` pixels with
//! `p = 2 d tan(fov/2) / H`. Expressed in pixels, the bounding disc has radius
//! `r/p` and `c = π (r/p)² / N`.
//!
//! Level `k`'s error is `e_k = h_k · D = 2 h_k r` (`h_k` = measured Hausdorff
//! distance as a fraction of `D`). It projects to at most one pixel while
//! `e_k ≤ p`, i.e. `r/p ≤ 1/(2 h_k)`, i.e. while
//!
//! ```text
//! c ≤ C(h_k) = π / (4 · N · h_k²)
//! ```
//!
//! independent of the object's size and the field of view. Level `k+1` may
//! therefore replace level `k` once the coverage falls to `C(h_{k+1})`:
//!
//! ```text
//! s[k]   = C(h_{k+1})      for k < n-1   (switch from level k to level k+1)
//! s[n-1] = C(1)            (cull: drawing nothing is an error of the whole
//!                           diagonal, h = 1, i.e. the object is < 1 px across)
//! ```
//!
//! Values are clamped to `[0, 1]` and made non-increasing (a coarser level
//! that measures better than a finer one takes over no later than the finer
//! one's own switch point). `h = 0` gives `C = ∞`, clamped to 1.
//!
//! Worked example (tested below): `h = [0, 0.001, 0.01]` gives
//! `s = [π/8.2944 ≈ 0.3788, π/829.44 ≈ 3.788e-3, π/8 294 400 ≈ 3.788e-7]`.

use crate::scene::LodMesh;

/// Reference viewport height in pixels (lines).
pub const REFERENCE_LINES: f64 = 1080.0;
/// Reference viewport width in pixels (16:9 at [`REFERENCE_LINES`]).
pub const REFERENCE_COLUMNS: f64 = 1920.0;

/// Largest screen coverage at which an error of `h` (fraction of the bounding
/// box diagonal) stays within one pixel: `π / (4 · N · h²)` with `N` the
/// reference pixel count. Returns `f64::INFINITY` for `h <= 0`.
pub fn coverage_for_error(h: f64) -> f64 {
    if h.is_nan() || h <= 0.0 {
        return f64::INFINITY;
    }
    std::f64::consts::PI / (4.0 * REFERENCE_COLUMNS * REFERENCE_LINES * h * h)
}

/// `MSFT_screencoverage` values for a chain whose level `k` has measured
/// symmetric Hausdorff error `level_errors[k]` (fraction of the original's
/// bounding-box diagonal, finest level first). One value per level, the last
/// being the cull threshold; see the module documentation for the formula.
pub fn screen_coverages(level_errors: &[f64]) -> Vec<f64> {
    let n = level_errors.len();
    let mut out = Vec::with_capacity(n);
    let mut previous = 1.0_f64;
    for k in 0..n {
        let h = if k + 1 < n { level_errors[k + 1] } else { 1.0 };
        let value = coverage_for_error(h).clamp(0.0, 1.0).min(previous);
        out.push(value);
        previous = value;
    }
    debug_assert!(out.windows(2).all(|w| w[0] >= w[1]));
    out
}

/// Sets every level's [`LodLevel::screen_coverage`](crate::scene::LodLevel)
/// from its measured `hausdorff` with [`screen_coverages`].
pub fn assign_screen_coverages(lod: &mut LodMesh) {
    let errors: Vec<f64> = lod.levels.iter().map(|l| l.hausdorff).collect();
    for (level, value) in lod.levels.iter_mut().zip(screen_coverages(&errors)) {
        level.screen_coverage = value;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
    }

    #[test]
    fn hand_computed_three_levels() {
        // N = 1920*1080 = 2 073 600; 4N = 8 294 400.
        // s0 = pi / (8 294 400 * 1e-6) = pi / 8.2944 = 0.378 760 688 4
        // s1 = pi / (8 294 400 * 1e-4) = pi / 829.44 = 0.003 787 606 9
        // s2 = pi / 8 294 400 (cull) = 3.787 606 9e-7
        let s = screen_coverages(&[0.0, 0.001, 0.01]);
        assert_eq!(s.len(), 3);
        assert!(close(s[0], 0.378_760_688_366_8), "{}", s[0]);
        assert!(close(s[0], std::f64::consts::PI / 8.2944));
        assert!(close(s[1], std::f64::consts::PI / 829.44));
        assert!(close(s[2], std::f64::consts::PI / 8_294_400.0));
    }

    #[test]
    fn one_percent_error_is_one_pixel_at_the_threshold() {
        // At coverage C(h) the disc radius in pixels is sqrt(c N / pi); the
        // error 2 h r must then be exactly one pixel.
        for h in [0.02, 0.005, 0.0003] {
            let c = coverage_for_error(h);
            let r_px = (c * REFERENCE_COLUMNS * REFERENCE_LINES / std::f64::consts::PI).sqrt();
            assert!(
                (2.0 * h * r_px - 1.0).abs() < 1e-9,
                "h={h}: {}",
                2.0 * h * r_px
            );
        }
    }

    #[test]
    fn tiny_errors_clamp_to_one_and_single_level_is_cull_only() {
        let s = screen_coverages(&[0.0, 1e-6, 0.05]);
        assert_eq!(s[0], 1.0);
        assert!(close(s[1], std::f64::consts::PI / (8_294_400.0 * 0.0025)));
        let single = screen_coverages(&[0.0]);
        assert_eq!(single.len(), 1);
        assert!(close(single[0], std::f64::consts::PI / 8_294_400.0));
        assert!(screen_coverages(&[]).is_empty());
    }

    #[test]
    fn non_monotone_errors_still_give_non_increasing_values() {
        let s = screen_coverages(&[0.0, 0.01, 0.002, 0.02]);
        assert!(s.windows(2).all(|w| w[0] >= w[1]), "{s:?}");
        assert_eq!(s[1], s[0]);
    }
}
