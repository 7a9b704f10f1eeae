//! `--max-error`: the search's rule as `--help` and the README state it.
//! The level found measures within the bound and the level one split
//! coarser measures above it (the measured error rises in steps as the
//! mesh coarsens: the next collapse is the one that crosses the bound).

mod support;

use serde_json::Value;
use std::fmt::Write as _;

/// A bumpy torus knot (a few thousand triangles) as OBJ text.
fn knot_obj() -> String {
    let m = lodgen_pm::shapes::torus_knot(2, 3, 96, 12, 0.02);
    let mut s = String::new();
    for p in &m.positions {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    for t in &m.triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// The report's levels: (splits, triangles, hausdorff %) each.
fn levels(dir: &std::path::Path, input: &str, args: &[&str]) -> Vec<(u64, u64, f64)> {
    let out = dir.join("out.glb");
    let mut all = vec![input, "-o", out.to_str().unwrap(), "-q", "--report", "-"];
    all.extend_from_slice(args);
    let o = support::lodgen(&all);
    assert!(o.status.success(), "{}", support::stderr(&o));
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    r["meshes"][0]["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| {
            (
                l["splits"].as_u64().unwrap(),
                l["triangles"].as_u64().unwrap(),
                l["hausdorff_percent"].as_f64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn each_level_is_within_its_bound_and_one_split_coarser_is_not() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("knot.obj");
    std::fs::write(&input, knot_obj()).unwrap();
    let input = input.to_str().unwrap();
    let bounds = [0.2, 1.0, 3.0];
    let found = levels(dir.path(), input, &["--max-error", "0.2%,1%,3%"]);
    assert_eq!(found.len(), bounds.len(), "{found:?}");
    for (&(splits, triangles, error), bound) in found.iter().zip(bounds) {
        assert!(error <= bound, "{error} % over {bound} %: {found:?}");
        assert!(splits > 0, "{found:?}");
        // the largest split count with fewer triangles: one split coarser
        // (with a 1-triangle level: the same run to the floor, the same
        // sequence; a run stopped at the level would start the sequence there)
        let fewer = format!("{},1", triangles - 1);
        let next = levels(dir.path(), input, &["--levels", &fewer]);
        assert_eq!(next[0].0, splits - 1, "{next:?} after {found:?}");
        assert!(
            next[0].2 > bound,
            "one split coarser than the {bound} % level measures {} %",
            next[0].2
        );
    }
}
