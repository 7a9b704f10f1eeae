//! Every input under `tests/fuzz-regressions/` (stored by `cargo xtask fuzz`
//! when it found a defect) goes through the fuzzer's case again: no panic,
//! and lodgen's own output reads back. The fuzzer's seeds go through it too,
//! and must read and build.

mod support;

use std::path::Path;

fn case(dir: &Path, ext: &str, bytes: &[u8]) -> Result<String, String> {
    std::panic::catch_unwind(|| lodgen::fuzz::run_case(dir, ext, bytes))
        .unwrap_or_else(|_| Err("panic".into()))
}

#[test]
fn stored_fuzz_cases_do_not_fail_again() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fuzz-regressions");
    let work = tempfile::tempdir().unwrap();
    let mut entries: Vec<_> = std::fs::read_dir(&root)
        .expect("tests/fuzz-regressions exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e != "md"))
        .collect();
    entries.sort();
    for path in entries {
        let ext = path.extension().unwrap().to_str().unwrap().to_owned();
        let bytes = std::fs::read(&path).unwrap();
        if let Err(defect) = case(work.path(), &ext, &bytes) {
            panic!("{}: {defect}", path.display());
        }
    }
}

#[test]
fn every_fuzz_seed_reads_builds_and_writes() {
    let work = tempfile::tempdir().unwrap();
    let seeds = lodgen::fuzz::seeds(work.path()).unwrap();
    assert_eq!(seeds.len(), 8);
    // the progressive seed has a stream the viewer's decoder replays
    let progressive = seeds.iter().find(|s| s.name == "glb-progressive").unwrap();
    let path = work.path().join("p.glb");
    std::fs::write(&path, &progressive.bytes).unwrap();
    assert!(lodgen::progressive::read_file(&path).unwrap().is_some());
    let levels = lodgen::view::print_levels(&path).unwrap();
    assert!(levels.contains("\"splits\""), "{levels}");
    for s in seeds {
        let expected = match s.name {
            "glb-progressive" => "stream replayed, built",
            _ => "built",
        };
        assert_eq!(
            case(work.path(), s.ext, &s.bytes).as_deref(),
            Ok(expected),
            "seed {}",
            s.name
        );
    }
}

/// The glTF scene seed is valid glTF and lodgen writes it with nothing
/// left out (so mutations start from a file that exercises the carry-over
/// of skins, morph targets, animations, cameras, lights and extensions).
#[test]
fn the_scene_seed_is_valid_and_written_without_warnings() {
    let work = tempfile::tempdir().unwrap();
    let seeds = lodgen::fuzz::seeds(work.path()).unwrap();
    let seed = seeds.iter().find(|s| s.name == "gltf-scene").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scene.gltf");
    std::fs::write(&input, &seed.bytes).unwrap();
    let out = dir.path().join("scene.glb");
    let run = support::lodgen(&[input.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]);
    let stderr = support::stderr(&run);
    assert_eq!(run.status.code(), Some(0), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    let json = support::gltf::glb_json(&out);
    for key in ["skins", "animations", "cameras", "extensions", "textures"] {
        assert!(json.get(key).is_some(), "{key} carried");
    }
    assert_eq!(
        json["animations"][0]["channels"].as_array().unwrap().len(),
        3
    );
    if let Some(log) = support::validate(dir.path()) {
        assert!(
            log.contains("scene.gltf: 0 errors") && log.contains("scene.glb: 0 errors"),
            "{log}"
        );
    }
}
