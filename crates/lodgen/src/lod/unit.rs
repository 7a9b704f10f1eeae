//! Attribute values made valid again: unit normals, tangents orthogonal to
//! them, skin weights summing to 1; already valid values keep their bits.

/// `n` made unit; already unit vectors keep their bits (so full refinement
/// gives back the input exactly).
pub(super) fn normalize3(n: [f32; 3]) -> [f32; 3] {
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if (l - 1.0).abs() <= UNIT_EPS {
        n
    } else if l > 0.0 && l.is_finite() {
        n.map(|x| x / l)
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// Tolerance below which a length, a dot product or a weight sum counts as
/// already normalised (and the input's bits are kept).
const UNIT_EPS: f32 = 4.0 * f32::EPSILON;

/// Gram–Schmidt: the tangent's xyz made unit and orthogonal to the normal,
/// its handedness `w` kept as ±1.
pub(super) fn orthogonal_tangent(t: [f32; 4], normal: Option<[f32; 3]>) -> [f32; 4] {
    let mut x = [t[0], t[1], t[2]];
    let d = normal.map_or(0.0, |n| x[0] * n[0] + x[1] * n[1] + x[2] * n[2]);
    let l = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    if d.abs() <= UNIT_EPS && (l - 1.0).abs() <= UNIT_EPS && t[3].abs() == 1.0 {
        return t;
    }
    if let Some(n) = normal {
        x = [x[0] - d * n[0], x[1] - d * n[1], x[2] - d * n[2]];
    }
    let l = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    let x = if l > 1e-12 {
        x.map(|c| c / l)
    } else {
        [1.0, 0.0, 0.0]
    };
    [x[0], x[1], x[2], if t[3] < 0.0 { -1.0 } else { 1.0 }]
}

/// Skin weights of one vertex (every WEIGHTS_n set) made non-negative and
/// summing to 1 over all sets (all on the first joint when they sum to 0).
pub(super) fn normalize_weights(sets: &mut [[f32; 4]]) {
    for w in sets.iter_mut() {
        *w = w.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 });
    }
    let s: f32 = sets.iter().flatten().sum();
    if (s - 1.0).abs() <= UNIT_EPS {
        return;
    }
    for (i, w) in sets.iter_mut().enumerate() {
        *w = if s > 0.0 {
            w.map(|x| x / s)
        } else if i == 0 {
            [1.0, 0.0, 0.0, 0.0]
        } else {
            [0.0; 4]
        };
    }
}
