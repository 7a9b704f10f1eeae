//! Golden LOD summaries of the bunny and the cow (`assets/golden/*.txt`,
//! written by `cargo xtask golden`): counts and hashes must match exactly,
//! measured errors within `ERROR_TOLERANCE`.

use lodgen::lod::{build_lods, BuildOptions, LevelRequest};

/// Absolute tolerance on errors, in % of the diagonal: sampling is
/// deterministic, so only floating-point differences across platforms are
/// allowed for.
const ERROR_TOLERANCE: f64 = 1e-4;

fn compare(name: &str) {
    let Some(input) = lodgen::assets::shared_asset(&format!("{name}.obj")) else {
        return;
    };
    let golden_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/golden")
        .join(format!("{name}.txt"));
    let golden = std::fs::read_to_string(&golden_path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; run `cargo xtask golden` and commit",
            golden_path.display()
        )
    });
    let scene = lodgen::io::read_scene(&input).unwrap();
    let opts = BuildOptions {
        levels: LevelRequest::Specs(lodgen::cli::parse_levels("50%,10%,2%").unwrap()),
        ..BuildOptions::default()
    };
    let builds = build_lods(&scene, &opts, &mut |_| {}).unwrap();
    let fresh = lodgen::cli::golden_summary(
        &format!("{name}.obj at 50%,10%,2%, default options"),
        &builds,
    );
    let (g, f): (Vec<&str>, Vec<&str>) = (golden.lines().collect(), fresh.lines().collect());
    assert_eq!(
        g.len(),
        f.len(),
        "{name}: line count differs; run `cargo xtask golden` and commit"
    );
    for (gl, fl) in g.iter().zip(&f) {
        let (gw, fw): (Vec<&str>, Vec<&str>) = (
            gl.split_whitespace().collect(),
            fl.split_whitespace().collect(),
        );
        assert_eq!(
            gw.len(),
            fw.len(),
            "{name}: `{gl}` vs `{fl}`; run `cargo xtask golden` and commit"
        );
        for (i, (a, b)) in gw.iter().zip(&fw).enumerate() {
            let is_error = i > 0 && gw[i - 1].ends_with("_percent");
            if is_error {
                let (x, y): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
                assert!(
                    (x - y).abs() <= ERROR_TOLERANCE,
                    "{name}: {} was {a}, now {b}; run `cargo xtask golden` and commit",
                    gw[i - 1]
                );
            } else {
                assert_eq!(
                    a, b,
                    "{name}: `{gl}` became `{fl}`; run `cargo xtask golden` and commit"
                );
            }
        }
    }
}

#[test]
fn bunny_matches_its_golden_summary() {
    compare("bunny");
}

#[test]
fn cow_matches_its_golden_summary() {
    compare("cow");
}
