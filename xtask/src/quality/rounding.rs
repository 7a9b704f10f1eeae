//! The input file's stored precision, and the table's tie rule: a cell
//! where lodgen's and the best peer's errors (Hausdorff and RMS) are all
//! below the rounding of the input's coordinates compares noise, not the
//! simplifiers (fandisk 50 %: docs/quality.md, "Session 24").
//!
//! The precision of an OBJ is read from the text of its `v` lines: every
//! coordinate is a decimal number the writer rounded, so the input surface
//! is only known to within half a unit of its last stored digit. Two
//! writers occur in the shared assets. A fixed-point one (`%.6f`: bunny,
//! cow, teapot, beetle) writes every coordinate with the same number `D`
//! of decimals, trailing zeros kept: the step is `10^-D` everywhere. A
//! `%g`-like one (fandisk, spot, rocker-arm) writes `S` significant digits
//! and strips trailing zeros (and sometimes uses an exponent): a coordinate
//! `x` has the step `10^(floor(log10 |x|) − S + 1)`, and `S` is the most
//! frequent count of significant digits over the coordinates (stripped
//! zeros make some counts smaller, and a few longer ones — fandisk's
//! `16.104799`, a single-precision value printed in full — are noise of
//! the writer, not precision). The file's rounding is the largest
//! half-step over all its coordinates (x, y and z alike): the most one
//! stored coordinate can be off from the surface that was written.

use std::collections::BTreeMap;

/// One coordinate's text: written decimals (trailing zeros kept), the
/// count of significant digits (trailing zeros stripped) and the decimal
/// exponent of its leading digit (None: the value is zero).
struct Token {
    /// Written with an exponent (`1e-06`).
    exponent_form: bool,
    decimals: i32,
    significant: i32,
    exponent: Option<i32>,
}

fn token(text: &str) -> Option<Token> {
    let t = text.trim_start_matches(['-', '+']);
    let exp_form = t.contains(['e', 'E']);
    let (mantissa, exp) = match t.find(['e', 'E']) {
        Some(i) => (&t[..i], t[i + 1..].parse::<i32>().ok()?),
        None => (t, 0),
    };
    let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
    if int.is_empty() && frac.is_empty()
        || !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit())
    {
        return None;
    }
    let digits: String = format!("{int}{frac}");
    let lead = digits.bytes().position(|b| b != b'0');
    let decimals = frac.len() as i32 - exp;
    let Some(lead) = lead else {
        return Some(Token {
            exponent_form: exp_form,
            decimals,
            significant: 0,
            exponent: None,
        });
    };
    let trimmed = digits[lead..].trim_end_matches('0');
    Some(Token {
        exponent_form: exp_form,
        decimals,
        significant: trimmed.len() as i32,
        // the leading digit's place: int.len() − 1 − lead, shifted by the exponent
        exponent: Some(int.len() as i32 - 1 - lead as i32 + exp),
    })
}

/// The largest half-step of the coordinates of the `v` lines of an OBJ
/// file's `text`, in the file's units (None: no parsable vertex).
pub(super) fn obj_half_step(text: &str) -> Option<f64> {
    let tokens: Vec<Token> = text
        .lines()
        .filter_map(|l| {
            let mut words = l.split_whitespace();
            (words.next() == Some("v")).then_some(words)
        })
        .flat_map(|words| words.take(3))
        .filter_map(token)
        .collect();
    let first = tokens.first()?;
    let fixed = tokens
        .iter()
        .all(|t| !t.exponent_form && t.decimals == first.decimals);
    let step = if fixed {
        10f64.powi(-first.decimals)
    } else {
        let mut counts: BTreeMap<i32, usize> = BTreeMap::new();
        for t in tokens.iter().filter(|t| t.exponent.is_some()) {
            *counts.entry(t.significant).or_default() += 1;
        }
        // the most frequent count; on a tie, the larger one
        let s = counts
            .iter()
            .max_by_key(|&(s, n)| (*n, *s))
            .map_or(1, |(s, _)| *s);
        let e = tokens.iter().filter_map(|t| t.exponent).max()?;
        10f64.powi(e - s + 1)
    };
    Some(step / 2.0)
}

/// The tie rule: lodgen's Hausdorff and RMS and the best peer's (`best`:
/// Hausdorff, RMS) are all below the input's `rounding` (the same unit).
pub(super) fn under_rounding(lodgen: (f64, f64), best: (f64, f64), rounding: f64) -> bool {
    [lodgen.0, lodgen.1, best.0, best.1]
        .iter()
        .all(|&e| e < rounding)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Option<f64>, b: f64) -> bool {
        a.is_some_and(|a| (a - b).abs() <= 1e-12 * b)
    }

    #[test]
    fn fixed_point_files_step_by_their_decimals() {
        let obj = "# c\nv -0.037830 0.127940 0.004475\nv 12.500000 -3.000000 0.000000\nf 1 2 2\n";
        assert!(close(obj_half_step(obj), 5e-7));
        let obj = "v 1.50 2.25 -0.75\nv 10.00 0.00 3.10\n";
        assert!(close(obj_half_step(obj), 5e-3));
    }

    #[test]
    fn significant_digit_files_step_by_their_largest_coordinate() {
        // fandisk's lines: six significant digits, trailing zeros stripped,
        // exponents, and a single-precision value printed in full
        let obj = "v 1e-06 15.3644 -1.47466\nv 0.094235 15.3735 -1.37664\n\
                   v 0 15.43 -0.393752\nv 0.180379 16.104799 -1.37917\n\
                   v 4.25823 17.85 2.68026\n";
        // 17.85 has its leading digit at 10^1: step 10^(1 − 6 + 1)
        assert!(close(obj_half_step(obj), 5e-5));
        // the same values below 10: one digit finer
        let obj = "v 1e-06 5.3644 -1.47466\nv 0.094235 5.3735 -1.37664\nv 0 5.43 -0.393752\n";
        assert!(close(obj_half_step(obj), 5e-6));
        // an exponent form shifts the leading digit: 1.23457e+03 is 1234.57
        let obj = "v 1.23457e+03 1.5 2.25\nv 0.5 0.25 0.125\nv 3.14159 2.71828 1.41421\n";
        assert!(close(obj_half_step(obj), 5e-3));
    }

    #[test]
    fn files_without_vertices_have_no_precision() {
        assert!(obj_half_step("# nothing\nf 1 2 3\n").is_none());
        assert!(obj_half_step("v x y z\n").is_none());
    }

    #[test]
    fn a_tie_needs_all_four_errors_under_the_rounding() {
        // fandisk 50 %: lodgen 0.000501 / 0.0000324 %, Open3D 0.000448 /
        // 0.0000294 %, the file's ±5e-5 on a 7.6156 diagonal 0.000657 %
        let r = 100.0 * 5e-5 / 7.6156;
        assert!(under_rounding(
            (0.000501, 0.0000324),
            (0.000448, 0.0000294),
            r
        ));
        assert!(!under_rounding(
            (0.0007, 0.0000324),
            (0.000448, 0.0000294),
            r
        ));
        assert!(!under_rounding(
            (0.000501, 0.0000324),
            (0.0007, 0.0000294),
            r
        ));
        assert!(!under_rounding(
            (0.000501, 0.0007),
            (0.000448, 0.0000294),
            r
        ));
        assert!(!under_rounding(
            (0.000501, 0.0000324),
            (0.000448, 0.0007),
            r
        ));
        // an error exactly at the rounding is not under it
        assert!(!under_rounding((r, 0.0000324), (0.000448, 0.0000294), r));
    }
}
