//! The viewer page in headless Chromium (`tests/js/viewer.mjs`): serves the
//! bunny (or, without the shared asset, a noisy torus knot) through the
//! in-memory pipeline, writes the expected per-level triangle counts and
//! index hashes, and runs the script, which checks the page against them and
//! writes `target/test-out/viewer-*.png`; then the same for spot.obj, whose
//! stream carries its UVs, with the per-level hashes of every corner's
//! attribute values (`target/test-out/viewer-spot/`).
//!
//! `LODGEN_VIEW_FILE=path` serves that file instead (e.g. a `.glb` written
//! with `--progressive`).
//!
//! Needs `node`, Chromium (`/usr/bin/chromium` or `LODGEN_CHROMIUM`) and
//! `tests/js/node_modules/playwright-core`. Without them the test says so and
//! passes, unless `LODGEN_BROWSER_TEST=1` (as in `.ci/run`) makes their
//! absence a failure.

mod support;

use lodgen::view::{ViewData, ViewServer};
use lodgen_pm::shapes::torus_knot;
use support::{browser, root};

#[test]
fn viewer_page_matches_levels_in_headless_chromium() {
    if !browser::ready("viewer browser test", &["playwright-core"]) {
        return;
    }
    let bunny = lodgen::assets::shared_assets_dir().join("bunny.obj");
    // LODGEN_VIEW_FILE: any file `lodgen view` accepts (e.g. a `.glb`
    // written with --progressive) instead of the bunny
    let data = if let Some(file) = std::env::var_os("LODGEN_VIEW_FILE") {
        ViewData::load(std::path::Path::new(&file)).unwrap()
    } else if lodgen::assets::shared_asset("bunny.obj").is_some() {
        ViewData::load(&bunny).unwrap()
    } else {
        let m = torus_knot(2, 3, 300, 24, 0.02);
        ViewData::from_mesh("torus knot".into(), &m.positions, &m.indices()).unwrap()
    };
    run_viewer(data, &root().join("target/test-out"));

    // a textured mesh: the stream carries its UVs (wedges), the page must
    // show every corner's streamed values at each level (attribute hash)
    if let Some(spot) = lodgen::assets::shared_asset("spot.obj") {
        let data = ViewData::load(&spot).unwrap();
        let summary = data.level_summary().unwrap();
        assert_eq!(summary["channels"], serde_json::json!(["TEXCOORD_0"]));
        run_viewer(data, &root().join("target/test-out/viewer-spot"));
    }
}

/// Serve `data`, run tests/js/viewer.mjs against it, screenshots into `out`.
fn run_viewer(data: ViewData, out: &std::path::Path) {
    std::fs::create_dir_all(out).unwrap();
    // stale screenshots must not satisfy the count below
    for e in std::fs::read_dir(out).unwrap().filter_map(Result::ok) {
        let n = e.file_name().to_string_lossy().into_owned();
        if n.starts_with("viewer-L") && n.ends_with(".png") {
            std::fs::remove_file(e.path()).unwrap();
        }
    }
    let expect = out.join("viewer-expect.json");
    std::fs::write(&expect, data.level_summary().unwrap().to_string()).unwrap();

    let server = ViewServer::bind(data, 0).unwrap();
    let url = server.url();
    let stop = server.stopper();
    let thread = std::thread::spawn(move || server.run());
    let run = std::panic::catch_unwind(|| {
        browser::run_script(
            "viewer.mjs",
            &[
                "--url",
                &url,
                "--expect",
                expect.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        )
    });
    stop.stop();
    thread.join().unwrap();
    if let Err(panic) = run {
        std::panic::resume_unwind(panic);
    }
    let shots = std::fs::read_dir(out)
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| {
            let n = e.file_name().to_string_lossy().into_owned();
            n.starts_with("viewer-L") && n.ends_with(".png")
        })
        .count();
    assert!(
        shots >= 3,
        "expected three screenshots in {}",
        out.display()
    );
}
