//! Every input under `tests/fuzz-regressions/` (stored by `cargo xtask fuzz`
//! when it found a defect) goes through the fuzzer's case again: no panic,
//! and lodgen's own output reads back. The fuzzer's seeds go through it too,
//! and must read and build.

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
    assert_eq!(seeds.len(), 7);
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
