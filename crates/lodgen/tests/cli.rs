//! The `lodgen` binary as users run it: outputs, tables, reports, errors,
//! determinism. Every glTF written here is also copied to `$LODGEN_TEST_OUT`
//! (when set) for the glTF-Validator and Babylon.js checks of `cargo xtask
//! test`.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use support::{lodgen, obj_text, stderr, stdout};

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Copy outputs for the validator / Babylon checks.
fn publish(files: &[&Path]) {
    for f in files {
        support::publish(f, f.file_name().unwrap().to_str().unwrap());
    }
}

fn write_torus_obj(path: &Path) {
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 48, 24);
    std::fs::write(path, obj_text(&[("torus", &m.positions, &m.triangles)])).unwrap();
}

/// Triangle count of each level of the first mesh in a `--report`.
fn level_triangles(r: &serde_json::Value) -> Vec<u64> {
    r["meshes"][0]["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["triangles"].as_u64().unwrap())
        .collect()
}

fn report(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// `lodgen INPUT --levels LEVELS -o DIR/NAME.glb --report DIR/NAME.json
/// EXTRA…`, which must succeed: the report's first mesh's levels and the
/// written file's bytes.
fn build_with_report(
    input: &Path,
    levels: &str,
    d: &Path,
    name: &str,
    extra: &[&str],
) -> (Vec<serde_json::Value>, Vec<u8>) {
    let rep = d.join(format!("{name}.json"));
    let out = d.join(format!("{name}.glb"));
    let mut args = vec![
        input.to_str().unwrap(),
        "--levels",
        levels,
        "-o",
        out.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = lodgen(&args);
    assert!(o.status.success(), "{name}: {}", stderr(&o));
    let levels = report(&rep)["meshes"][0]["levels"]
        .as_array()
        .unwrap()
        .clone();
    (levels, std::fs::read(&out).unwrap())
}

#[test]
fn builds_three_levels_with_a_table_and_a_report() {
    let d = tmp("three");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let o = lodgen(&[
        input.to_str().unwrap(),
        "--levels",
        "50%,10%,2%",
        "--report",
        d.join("torus.report.json").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = d.join("torus.glb");
    assert!(out.exists(), "default output beside the input");
    let table = stdout(&o);
    assert!(table.contains("hausdorff %"), "{table}");
    let r = report(&d.join("torus.report.json"));
    let levels = r["meshes"][0]["levels"].as_array().unwrap();
    let tris: Vec<u64> = levels
        .iter()
        .map(|l| l["triangles"].as_u64().unwrap())
        .collect();
    assert_eq!(tris, vec![1152, 230, 46]);
    let h: Vec<f64> = levels
        .iter()
        .map(|l| l["hausdorff_percent"].as_f64().unwrap())
        .collect();
    assert!(h[0] <= h[1] && h[1] <= h[2] && h[2] > 0.0, "{h:?}");
    publish(&[&out, &d.join("torus.report.json")]);
}

#[test]
fn output_is_byte_identical_across_runs() {
    let d = tmp("determinism");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let mut outs = Vec::new();
    for name in ["a.glb", "b.glb"] {
        let out = d.join(name);
        let o = lodgen(&[input.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stdout(&o).is_empty(), "--quiet prints nothing");
        outs.push(std::fs::read(out).unwrap());
    }
    assert_eq!(outs[0], outs[1]);
}

#[test]
fn gltf_output_writes_one_bin_per_level() {
    let d = tmp("gltf");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let out = d.join("torus.gltf");
    let o = lodgen(&[
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--levels",
        "40%,5%",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bins: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "bin"))
        .collect();
    assert_eq!(bins.len(), 2, "one .bin per level");
    let (doc, buffers, _) = gltf::import(&out).unwrap();
    assert_eq!(doc.meshes().count(), 2);
    assert_eq!(buffers.len(), 2);
    if let Some(dir) = std::env::var_os("LODGEN_TEST_OUT") {
        let dir = PathBuf::from(dir).join("cli-gltf");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(&out, dir.join("torus.gltf")).unwrap();
        for b in &bins {
            std::fs::copy(b.path(), dir.join(b.file_name())).unwrap();
        }
    }
}

#[test]
fn bad_input_names_file_and_line_and_writes_nothing() {
    let d = tmp("bad");
    let input = d.join("bad.obj");
    std::fs::write(&input, "v 0 0 0\nv 1 0 0\nf 0 1 2\n").unwrap();
    let out = d.join("bad.glb");
    let o = lodgen(&[input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("bad.obj:3"), "{err}");
    assert!(err.starts_with("error: reading"), "{err}");
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(&d).unwrap().count(),
        1,
        "no temporary files left"
    );

    let o = lodgen(&[d.join("missing.obj").to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("missing.obj"));

    let good = d.join("t.obj");
    write_torus_obj(&good);
    let o = lodgen(&[
        good.to_str().unwrap(),
        "-o",
        d.join("no/such/dir/t.glb").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("writing"), "{}", stderr(&o));

    for (flag, value) in [
        ("--levels", "50%,abc"),
        ("--levels", "150%"),
        ("--max-error", "0.5"),
        ("--tau", "-1"),
    ] {
        let o = lodgen(&[good.to_str().unwrap(), &format!("{flag}={value}")]);
        assert!(!o.status.success(), "{flag} {value} accepted");
        assert!(stderr(&o).contains(flag), "{flag} {value}: {}", stderr(&o));
    }
}

/// An output path lodgen cannot write is refused before the input is read
/// (a long build would otherwise be thrown away at its end): here the input
/// is broken too, and the error is about the output.
#[test]
fn a_bad_output_path_is_refused_before_the_work() {
    let d = tmp("output-first");
    let bad = d.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 0 1 2\n").unwrap();
    for (output, says) in [
        (
            d.join("x.obj"),
            "output file name must end in .glb or .gltf",
        ),
        (d.join("no/such/dir/x.glb"), "does not exist"),
    ] {
        let o = lodgen(&[bad.to_str().unwrap(), "-o", output.to_str().unwrap()]);
        assert!(!o.status.success());
        let err = stderr(&o);
        assert!(err.starts_with("error: writing "), "{err}");
        assert!(err.contains(says), "{err}");
        assert!(
            !err.contains("bad.obj:3"),
            "read before the output was checked: {err}"
        );
    }
    // the input under another name: refused, the input left as it was
    // (`-o ./x.glb` for `x.glb` overwrote it)
    let input = d.join("in.obj");
    write_torus_obj(&input);
    let glb = d.join("in.glb");
    assert!(
        lodgen(&[input.to_str().unwrap(), "-o", glb.to_str().unwrap(), "-q"])
            .status
            .success()
    );
    let before = std::fs::read(&glb).unwrap();
    let hard = d.join("hard.glb");
    std::fs::hard_link(&glb, &hard).unwrap();
    // (run in `d`: `in.glb` and `./in.glb` are different paths)
    let mut cases = vec![
        (PathBuf::from("in.glb"), PathBuf::from("./in.glb")),
        (PathBuf::from("in.glb"), glb.clone()),
        (glb.clone(), hard),
    ];
    #[cfg(unix)]
    {
        let link = d.join("link.glb");
        std::os::unix::fs::symlink(&glb, &link).unwrap();
        cases.push((link, glb.clone()));
    }
    for (from, to) in &cases {
        let args = [from.to_str().unwrap(), "-o", to.to_str().unwrap(), "-q"];
        let o = support::lodgen_in(&args, &d);
        assert_eq!(
            o.status.code(),
            Some(1),
            "{} -> {}",
            from.display(),
            to.display()
        );
        assert!(
            stderr(&o).contains("would overwrite the input"),
            "{}",
            stderr(&o)
        );
    }
    assert_eq!(std::fs::read(&glb).unwrap(), before);
    std::fs::remove_dir_all(&d).unwrap();
}

/// A negative number after an option is its value, so the option's own
/// check explains what is wrong (not clap's "unexpected argument '-0'").
#[test]
fn a_negative_value_reaches_its_options_check() {
    let d = tmp("negative");
    let good = d.join("t.obj");
    write_torus_obj(&good);
    for (flag, value, says) in [
        ("--levels", "-0.5", "must be in (0, 1]"),
        ("--max-error", "-1%", "non-negative"),
        ("--tau", "-1", "non-negative"),
        ("--boundary-weight", "-1", "non-negative"),
        ("--samples", "-2", "positive"),
    ] {
        let o = lodgen(&[good.to_str().unwrap(), flag, value, "-q"]);
        assert!(!o.status.success(), "{flag} {value} accepted");
        let err = stderr(&o);
        assert!(
            err.contains(flag) && err.contains(says),
            "{flag} {value}: {err}"
        );
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// Each error names the file and place once: the command's `reading FILE`
/// and the reader's `FILE:LINE: what` make one line, and an I/O error
/// already in its parent's text is not repeated as a cause (batch mode's
/// one-line messages likewise).
/// `--levels 50%, 10%` (a space after the comma) makes `10%` a second
/// input: the error says so, instead of asking for batch mode's --out-dir.
#[test]
fn a_level_cut_off_by_a_space_is_named() {
    let d = tmp("stray-level");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let o = lodgen(&[input.to_str().unwrap(), "--levels", "50%,", "10%"]);
    assert_eq!(o.status.code(), Some(2), "a bad argument");
    let err = stderr(&o);
    assert!(
        err.contains("10%: no such input file; a space inside an option's value?"),
        "{err}"
    );
    // two real inputs without --out-dir still ask for it
    let o = lodgen(&[input.to_str().unwrap(), input.to_str().unwrap()]);
    assert!(stderr(&o).contains("need --out-dir DIR"), "{}", stderr(&o));
}

#[test]
fn errors_say_the_file_and_the_cause_once() {
    let d = tmp("errors-once");
    let bad = d.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 0 1 2\n").unwrap();
    let o = lodgen(&[
        bad.to_str().unwrap(),
        "-o",
        d.join("bad.glb").to_str().unwrap(),
    ]);
    let err = stderr(&o);
    let first = err.lines().next().unwrap_or_default();
    assert!(
        first.starts_with(&format!("error: reading {}:3:3: ", bad.display())),
        "{err}"
    );
    assert_eq!(err.matches("bad.obj").count(), 1, "{err}");

    // an output path that is a directory: the rename fails
    let good = d.join("t.obj");
    write_torus_obj(&good);
    let taken = d.join("taken.glb");
    std::fs::create_dir_all(&taken).unwrap();
    let o = lodgen(&[good.to_str().unwrap(), "-o", taken.to_str().unwrap(), "-q"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.starts_with("error: writing "), "{err}");
    assert_eq!(err.matches("taken.glb").count(), 1, "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");

    // batch mode: the report's and the table's message
    std::fs::create_dir_all(d.join("in")).unwrap();
    std::fs::write(d.join("in/empty.obj"), "").unwrap();
    let o = support::lodgen_in(&["in", "--out-dir", "out", "--report", "r.json", "-q"], &d);
    assert!(!o.status.success());
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("r.json")).unwrap()).unwrap();
    assert_eq!(
        r["files"][0]["error"],
        "reading in/empty.obj: no triangles in the file"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn help_explains_every_flag() {
    let o = lodgen(&["--help"]);
    assert!(o.status.success());
    let h = stdout(&o);
    for flag in [
        "--output",
        "--levels",
        "--max-error",
        "--tau",
        "--boundary",
        "--boundary-weight",
        "--placement",
        "--schedule",
        "--uniform-weights",
        "--quantize",
        "--compress",
        "--report",
        "--samples",
        "--quiet",
        "--verbose",
        "inspect",
        "measure",
    ] {
        assert!(h.contains(flag), "--help lacks {flag}");
    }
    assert!(h.contains("[default: 50%,10%,2%]"));
    // every option says its default (a switch: "Off by default" or what
    // happens without it), but those with nothing to default to
    let exempt = [
        "--help",
        "--version",
        "--out-dir",
        "--report",
        "--quiet",
        "--verbose",
        "--max-error",
        "--strict",
    ];
    let mut entries: Vec<(String, String)> = Vec::new();
    for line in h.lines() {
        let t = line.trim_start();
        let indent = line.len() - t.len();
        if t.starts_with('-') && (2..=6).contains(&indent) {
            let name = t
                .split([' ', ','])
                .find(|w| w.starts_with("--"))
                .unwrap_or(t)
                .to_string();
            entries.push((name, String::new()));
        } else if let Some(e) = entries.last_mut() {
            e.1 += line;
            e.1 += "\n";
        }
    }
    assert!(entries.len() > 30, "{} options in --help", entries.len());
    for (name, text) in &entries {
        if !exempt.contains(&name.as_str()) {
            assert!(
                text.to_lowercase().contains("default"),
                "--help of {name} does not say its default:\n{text}"
            );
        }
    }
}

#[test]
fn max_error_levels_stay_within_their_bounds() {
    let d = tmp("maxerr");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let rep = d.join("r.json");
    let o = lodgen(&[
        input.to_str().unwrap(),
        "--max-error",
        "0.2%,1%,4%",
        "--report",
        rep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = report(&rep);
    let levels = r["meshes"][0]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    for (l, bound) in levels.iter().zip([0.2, 1.0, 4.0]) {
        // searched with lighter sampling; the final measurement may find a
        // slightly larger maximum
        assert!(
            l["hausdorff_percent"].as_f64().unwrap() <= bound * 1.25,
            "{l}"
        );
    }
    let tris: Vec<u64> = levels
        .iter()
        .map(|l| l["triangles"].as_u64().unwrap())
        .collect();
    assert!(tris[0] > tris[1] && tris[1] > tris[2], "{tris:?}");
}

#[test]
fn inspect_and_measure_report_on_outputs() {
    let d = tmp("inspect");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let out = d.join("torus.glb");
    assert!(lodgen(&[input.to_str().unwrap(), "-q"]).status.success());
    let o = lodgen(&["inspect", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for n in ["1152", "230", "46"] {
        assert!(text.contains(n), "inspect lacks {n}: {text}");
    }
    let o = lodgen(&["measure", input.to_str().unwrap(), input.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("symmetric"));
    let o = lodgen(&[
        "measure",
        "--json",
        input.to_str().unwrap(),
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // the finest level (50%) is what the scene draws
    assert!(v["hausdorff_percent"].as_f64().unwrap() > 0.0);
    // where each direction's maximum lies: a point in the torus's box (radii 1 and 0.35)
    for dir in ["a_to_b", "b_to_a"] {
        let at: Vec<f64> = v[dir]["at"]
            .as_array()
            .unwrap_or_else(|| panic!("no {dir}.at in {v}"))
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(at.len(), 3, "{v}");
        assert!(at.iter().all(|x| x.abs() <= 1.4), "{dir}.at {at:?}");
    }
    let o = lodgen(&["measure", input.to_str().unwrap(), out.to_str().unwrap()]);
    assert!(stdout(&o).contains("A -> B maximum at ("), "{}", stdout(&o));
}

/// `lodgen measure` of a glTF whose scene draws no triangles (its one mesh
/// on no node) is an error naming the file, in either place: there is no
/// distance to measure (it printed an infinite one, exit code 0). So is a
/// `--samples` beyond what memory holds.
#[test]
fn measure_refuses_no_triangles_and_too_many_samples() {
    let d = tmp("measure-empty");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let mut doc = support::gltf::Doc::new();
    let pos = doc.floats(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], true);
    let idx = doc.indices(&[[0, 1, 2]]);
    doc.push(
        "meshes",
        serde_json::json!({"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}),
    );
    doc.json["scenes"] = serde_json::json!([{"nodes": []}]);
    let undrawn = d.join("undrawn.gltf");
    std::fs::write(&undrawn, doc.gltf()).unwrap();
    let (a, b) = (input.to_str().unwrap(), undrawn.to_str().unwrap());
    for args in [["measure", a, b], ["measure", b, a]] {
        let o = lodgen(&args);
        assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
        let err = stderr(&o);
        assert!(
            err.contains(&format!("measuring: {b} draws no triangles")),
            "{err}"
        );
        assert!(stdout(&o).is_empty());
    }
    // --samples asking for more samples than memory holds: an error, not
    // an aborted process (it died on a failed allocation), for a build too
    let o = lodgen(&["measure", "--samples", "1e12", a, a]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("lower --samples"), "{}", stderr(&o));
    let out = d.join("t.glb");
    let o = lodgen(&[a, "--samples", "1e12", "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("lower --samples"), "{}", stderr(&o));
    assert!(!out.exists());
    let o = lodgen(&[
        a,
        "--samples",
        "1e12",
        "--measure",
        "off",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// The bunny and cow LOD sets, as a pipeline would make them; the bunny's
/// is what the Babylon.js check loads.
#[test]
fn bunny_and_cow_lod_sets() {
    for name in ["bunny", "cow"] {
        let Some(input) = lodgen::assets::shared_asset(&format!("{name}.obj")) else {
            return;
        };
        let d = tmp(name);
        let out = d.join(format!("{name}.glb"));
        let rep = d.join(format!("{name}.report.json"));
        let o = lodgen(&[
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--levels",
            "50%,10%,2%",
            "--report",
            rep.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let r = report(&rep);
        let levels = r["meshes"][0]["levels"].as_array().unwrap();
        assert_eq!(levels.len(), 3);
        // round trip through the gltf crate: same per-level triangle counts
        let (doc, _, _) = gltf::import(&out).unwrap();
        let mut counts: Vec<u64> = doc
            .meshes()
            .map(|m| {
                m.primitives()
                    .map(|p| p.indices().unwrap().count() as u64 / 3)
                    .sum()
            })
            .collect();
        counts.sort_unstable_by(|a, b| b.cmp(a));
        let expected: Vec<u64> = levels
            .iter()
            .map(|l| l["triangles"].as_u64().unwrap())
            .collect();
        assert_eq!(counts, expected);
        publish(&[&out, &rep]);
    }
}

#[test]
fn both_schedules_build_the_requested_levels() {
    let d = tmp("schedules");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let mut hashes = Vec::new();
    for schedule in ["passes", "greedy"] {
        let rep = d.join(format!("{schedule}.json"));
        let out = d.join(format!("{schedule}.glb"));
        let o = lodgen(&[
            input.to_str().unwrap(),
            "--schedule",
            schedule,
            "--levels",
            "50%,10%",
            "-o",
            out.to_str().unwrap(),
            "--report",
            rep.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{schedule}: {}", stderr(&o));
        let tris = level_triangles(&report(&rep));
        assert_eq!(tris, vec![1152, 230], "{schedule}");
        hashes.push(std::fs::read(&out).unwrap());
    }
    // the two orders contract different pairs
    assert_ne!(hashes[0], hashes[1]);
    let o = lodgen(&[input.to_str().unwrap(), "--schedule", "random"]);
    assert!(!o.status.success());
}

#[test]
fn every_method_builds_levels() {
    let d = tmp("methods");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    for method in ["qem", "edge", "half-edge", "triangle", "qem-curvature"] {
        let rep = d.join(format!("{method}.json"));
        let o = lodgen(&[
            input.to_str().unwrap(),
            "--method",
            method,
            "--levels",
            "50%,20%",
            "-o",
            d.join(format!("{method}.glb")).to_str().unwrap(),
            "--report",
            rep.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{method}: {}", stderr(&o));
        let tris = level_triangles(&report(&rep));
        assert_eq!(tris.len(), 2, "{method}");
        assert!(tris[0] <= 1152 && tris[0] > tris[1], "{method}: {tris:?}");
    }
    let o = lodgen(&[input.to_str().unwrap(), "--method", "nope"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--method"));
}

#[test]
fn a_mesh_that_cannot_reach_its_levels_says_where_it_stopped_and_why() {
    // a tetrahedron cannot lose a face without flattening into a sheet
    let d = tmp("tetra");
    let input = d.join("tetra.obj");
    std::fs::write(
        &input,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n",
    )
    .unwrap();
    let out = d.join("tetra.glb");
    let o = lodgen(&[
        input.to_str().unwrap(),
        "--levels",
        "50%,25%",
        "--min-triangles",
        "1",
        "--keep-topology",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("simplification stopped at 4 triangles")
            && text.contains("no legal contraction is left")
            && text.contains("would flatten a closed part into a double-sided sheet")
            && text.contains("--allow-topology-change reaches it")
            && text.contains("are not written"),
        "{text}"
    );
    // the option it suggests flattens the tetrahedron into two faces: the
    // 50 % level (the only one) is written (fails if the option relaxes
    // nothing)
    // and so does the default, which runs again with joins and flattening
    // allowed when the topology stopped it (fails if it does not)
    let relaxed = d.join("tetra-relaxed.glb");
    for extra in [Some("--allow-topology-change"), None] {
        let mut args = vec![input.to_str().unwrap(), "--levels", "50%"];
        args.extend(["--min-triangles", "1", "-o", relaxed.to_str().unwrap()]);
        args.extend(extra);
        let o = lodgen(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = stdout(&o);
        assert!(
            !text.contains("simplification stopped")
                && text.contains("1 contractions changed the topology")
                && text.contains("1 flattened a closed part")
                && text
                    .lines()
                    .any(|l| l.split_whitespace().take(2).eq(["0", "2"])),
            "{extra:?}: {text}"
        );
    }
    publish(&[&out, &relaxed]);
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    // one thread steps serially; several plan the walk in parallel batches
    let d = tmp("threads");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let mut outs = Vec::new();
    for threads in ["1", "3"] {
        let out = d.join(format!("t{threads}.glb"));
        let o = Command::new(env!("CARGO_BIN_EXE_lodgen"))
            .args([
                input.to_str().unwrap(),
                "--tau",
                "1%",
                "--progressive",
                "-o",
                out.to_str().unwrap(),
                "-q",
            ])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        outs.push(std::fs::read(out).unwrap());
    }
    assert!(outs[0] == outs[1], "1 and 3 threads wrote different files");
}

/// `-v` prints tables in words (phases with their share, refusals, what
/// preparation removed), never a Rust `Debug` dump, and `--report` carries
/// the same data.
/// `--report -` writes the report to standard output in place of the
/// table (a file named `-` before), for a single file and for a batch; `-v`
/// still goes to standard error.
#[test]
fn report_dash_goes_to_standard_output() {
    let d = tmp("report-dash");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let args = [input.to_str().unwrap(), "--report", "-", "-v"];
    let o = support::lodgen_in(&args, &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("stdout is not the JSON report ({e}):\n{}", stdout(&o)));
    assert_eq!(level_triangles(&r), vec![1152, 230, 46]);
    assert!(stderr(&o).contains("time by phase"), "{}", stderr(&o));
    assert!(!d.join("-").exists());
    let o = support::lodgen_in(&["torus.obj", "--out-dir", "out", "--report", "-"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("stdout is not the batch report ({e}):\n{}", stdout(&o)));
    assert_eq!(r["files"][0]["status"], "built", "{r}");
    assert!(!d.join("-").exists());
}

#[test]
fn verbose_prints_tables_and_the_report_carries_them() {
    let d = tmp("verbose");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let rep = d.join("r.json");
    let o = lodgen(&[
        input.to_str().unwrap(),
        "-v",
        "--report",
        rep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    for want in [
        "time by phase",
        "read",
        "contractions",
        "measure",
        "write",
        "total",
        "stopped: reached the target",
        "preparation removed",
    ] {
        assert!(err.contains(want), "-v lacks {want:?}:\n{err}");
    }
    for debug in [
        "Stats {",
        "PhaseTimes",
        "PrepareStats",
        "Rejections {",
        "ms,",
    ] {
        assert!(!err.contains(debug), "-v prints a Debug dump:\n{err}");
    }
    let r = report(&rep);
    for key in [
        "read",
        "simplify",
        "simplify.contractions",
        "measure",
        "write",
    ] {
        assert!(
            r["phases_ms"][key].as_f64().is_some(),
            "phases_ms.{key}: {r}"
        );
    }
    let m = &r["meshes"][0];
    assert_eq!(m["stop_reason"], "reached the target");
    assert!(m["refusals"]["flip"].as_u64().is_some(), "{m}");
    assert_eq!(
        m["prepare"]["input_triangles"].as_u64(),
        m["welded_triangles"].as_u64()
    );
    assert!(m["contractions"].as_u64().unwrap() > 0);
}

/// `--measure off`: errors and coverages from the quadric estimate, marked
/// `≈` in the table, `measured: false` and no RMS in the report; the chain
/// still has rising errors and falling coverages, and the same levels.
#[test]
fn measure_off_estimates_errors_and_keeps_the_chain_valid() {
    let d = tmp("measure-off");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let rep = d.join("r.json");
    let o = lodgen(&[
        input.to_str().unwrap(),
        "--measure",
        "off",
        "--report",
        rep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains('≈'), "{}", stdout(&o));
    let r = report(&rep);
    assert_eq!(r["meshes"][0]["measured"], false);
    let levels = r["meshes"][0]["levels"].as_array().unwrap();
    let h: Vec<f64> = levels
        .iter()
        .map(|l| l["hausdorff_percent"].as_f64().unwrap())
        .collect();
    let c: Vec<f64> = levels
        .iter()
        .map(|l| l["screen_coverage"].as_f64().unwrap())
        .collect();
    assert!(h[0] <= h[1] && h[1] <= h[2] && h[2] > 0.0, "{h:?}");
    assert!(c[0] > c[1] && c[1] > c[2], "{c:?}");
    assert!(levels.iter().all(|l| l["rms_percent"].is_null()));
    assert_eq!(level_triangles(&r), vec![1152, 230, 46]);
}

/// `--measure bounded`: the Hausdorff distance by bounded subdivision is attained at a point
/// of the surface, so it is at least every sampled estimate up to the tolerance (1 % plus
/// 10⁻⁵ of the diagonal) — here never below the default's; RMS within 5 % (fewer samples).
#[test]
fn measure_bounded_is_at_least_the_sampled_estimate() {
    let d = tmp("measure-bounded");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let run = |mode: &str| {
        let rep = d.join(format!("{mode}.json"));
        let o = lodgen(&[
            input.to_str().unwrap(),
            "--measure",
            mode,
            "--report",
            rep.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let r = report(&rep);
        assert_eq!(r["meshes"][0]["measured"], true);
        let levels = r["meshes"][0]["levels"].as_array().unwrap().clone();
        assert_eq!(level_triangles(&r), vec![1152, 230, 46]);
        levels
            .iter()
            .map(|l| {
                let f = |k: &str| l[k].as_f64().unwrap();
                (f("hausdorff_percent"), f("rms_percent"))
            })
            .collect::<Vec<_>>()
    };
    let (sampled, bounded) = (run("on"), run("bounded"));
    for (s, b) in sampled.iter().zip(&bounded) {
        assert!(b.0 >= s.0 / 1.01 - 1e-3, "bounded {b:?} vs sampled {s:?}");
        assert!(
            (b.1 - s.1).abs() <= 0.05 * s.1,
            "bounded {b:?} vs sampled {s:?}"
        );
    }
}

/// `--reach` (on by default) keeps the tips of thin parts: the cow's tail
/// tip is the 50 % level's Hausdorff maximum with `--reach off` (0.56 % of
/// the diagonal) and is kept by default (0.17 %, docs/quality.md). Without
/// a value the factor is `DEFAULT_REACH_FACTOR`, as by default; a factor
/// that is not positive, or a word other than "off", is refused.
#[test]
fn reach_lowers_the_cows_hausdorff_error() {
    let Some(input) = lodgen::assets::shared_asset("cow.obj") else {
        eprintln!("skipped: cow.obj not found (set LODGEN_ASSETS)");
        return;
    };
    let d = tmp("reach");
    let run = |extra: &[&str], name: &str| {
        let (levels, bytes) = build_with_report(&input, "50%", &d, name, extra);
        (levels[0]["hausdorff_percent"].as_f64().unwrap(), bytes)
    };
    let (h_off, _) = run(&["--reach", "off"], "off");
    let (h_on, bytes_on) = run(&[], "on");
    let (_, bytes_flag) = run(&["--reach"], "flag");
    let factor = lodgen_pm::DEFAULT_REACH_FACTOR.to_string();
    let (_, bytes_factor) = run(&["--reach", &factor], "factor");
    assert!(
        h_on < 0.6 * h_off,
        "default {h_on} % against --reach off {h_off} %"
    );
    assert_eq!(
        bytes_on, bytes_flag,
        "--reach without a value is not the default"
    );
    assert_eq!(
        bytes_on, bytes_factor,
        "the default is not --reach {factor}"
    );
    for bad in ["0", "-1", "on"] {
        let o = lodgen(&[input.to_str().unwrap(), "--reach", bad]);
        assert!(!o.status.success(), "--reach {bad} accepted");
        assert!(stderr(&o).contains("--reach"), "{}", stderr(&o));
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// `--reach-faces` reaches the simplifier: the cow's 50 % level differs
/// from the default's; without a value the factor is
/// `DEFAULT_REACH_FACES_FACTOR`; "off" is the default; a factor that is
/// not positive, or a word other than "off", is refused.
#[test]
fn reach_faces_flag_reaches_the_simplifier() {
    let Some(input) = lodgen::assets::shared_asset("cow.obj") else {
        eprintln!("skipped: cow.obj not found (set LODGEN_ASSETS)");
        return;
    };
    let d = tmp("reach-faces");
    let run = |extra: &[&str], name: &str| build_with_report(&input, "50%", &d, name, extra).1;
    let plain = run(&[], "plain");
    let flag = run(&["--reach-faces"], "flag");
    let factor = lodgen_pm::DEFAULT_REACH_FACES_FACTOR.to_string();
    let with_factor = run(&["--reach-faces", &factor], "factor");
    let off = run(&["--reach-faces", "off"], "off");
    assert_ne!(plain, flag, "--reach-faces changed nothing");
    assert_eq!(plain, off, "the default is not --reach-faces off");
    assert_eq!(
        flag, with_factor,
        "--reach-faces is not --reach-faces {factor}"
    );
    for bad in ["0", "-1", "on"] {
        let o = lodgen(&[input.to_str().unwrap(), "--reach-faces", bad]);
        assert!(!o.status.success(), "--reach-faces {bad} accepted");
        assert!(stderr(&o).contains("--reach-faces"), "{}", stderr(&o));
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// `--polish` moves the written levels' vertices towards the original: on
/// the bundled knot each level keeps its triangle count and its measured
/// RMS and Hausdorff errors fall below the unpolished run's (by 12–30 %
/// when written). Fails when the flag does not reach the build (same
/// bytes, same errors) or the polished positions are not the written ones
/// (the report measures what is written).
#[test]
fn polish_lowers_the_written_levels_errors() {
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/knot.obj");
    let d = tmp("polish");
    let run = |extra: &[&str], name: &str| {
        let (levels, bytes) = build_with_report(&input, "10%,2%", &d, name, extra);
        let levels: Vec<(u64, f64, f64)> = levels
            .iter()
            .map(|l| {
                (
                    l["triangles"].as_u64().unwrap(),
                    l["rms_percent"].as_f64().unwrap(),
                    l["hausdorff_percent"].as_f64().unwrap(),
                )
            })
            .collect();
        (levels, bytes)
    };
    let (plain, plain_bytes) = run(&[], "plain");
    let (polished, polished_bytes) = run(&["--polish"], "polished");
    assert_ne!(plain_bytes, polished_bytes, "--polish changed nothing");
    assert_eq!(plain.len(), 2);
    for ((t0, r0, h0), (t1, r1, h1)) in plain.iter().zip(&polished) {
        assert_eq!(t0, t1, "polish changed the triangle count");
        assert!(r1 < &(0.95 * r0), "RMS {r1} % polished vs {r0} %");
        assert!(h1 < h0, "Hausdorff {h1} % polished vs {h0} %");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// `--fix-worst` reaches the build (different bytes, no level's Hausdorff
/// distance raised, one lowered, the counts kept), `--fix-worst=0` is the
/// default run byte for byte, and the flag is refused with `--measure off`
/// (nothing to find the worst spot by) or a round count that is not one,
/// with a message naming it. Fails when the flag is ignored or accepted
/// where it cannot act.
#[test]
fn fix_worst_lowers_the_worst_spot_and_needs_the_measurement() {
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/knot.obj");
    let d = tmp("fix-worst");
    let hausdorff = |levels: &[serde_json::Value]| -> Vec<(u64, f64)> {
        levels
            .iter()
            .map(|l| {
                let t = l["triangles"].as_u64().unwrap();
                (t, l["hausdorff_percent"].as_f64().unwrap())
            })
            .collect()
    };
    let (plain, plain_bytes) = build_with_report(&input, "10%,2%", &d, "plain", &[]);
    let (fixed, fixed_bytes) = build_with_report(&input, "10%,2%", &d, "fixed", &["--fix-worst"]);
    let (_, zero_bytes) = build_with_report(&input, "10%,2%", &d, "zero", &["--fix-worst=0"]);
    assert_ne!(plain_bytes, fixed_bytes, "--fix-worst changed nothing");
    assert_eq!(
        plain_bytes, zero_bytes,
        "--fix-worst=0 is not the default run"
    );
    let (plain, fixed) = (hausdorff(&plain), hausdorff(&fixed));
    for ((t0, h0), (t1, h1)) in plain.iter().zip(&fixed) {
        assert_eq!(t0, t1, "--fix-worst changed a triangle count");
        assert!(h1 <= h0, "Hausdorff {h1} % fixed vs {h0} %");
    }
    assert!(plain.iter().zip(&fixed).any(|(p, f)| f.1 < p.1));
    let i = input.to_str().unwrap();
    let out = d.join("refused.glb");
    let o = out.to_str().unwrap();
    for bad in [
        vec![i, "--fix-worst", "--measure", "off", "-o", o],
        vec![i, "--fix-worst=two", "-o", o],
    ] {
        let r = lodgen(&bad);
        assert!(!r.status.success(), "{bad:?} accepted");
        assert!(stderr(&r).contains("--fix-worst"), "{}", stderr(&r));
        assert!(!out.exists(), "{bad:?} wrote {}", out.display());
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// A flag's bad value is a bad argument (exit 2, as clap's own errors), and
/// a `--report` that cannot be written is refused before the work: nothing
/// written, not an output and then an error. (Fails when the value errors
/// exit 1, or the output is left behind.)
#[test]
fn bad_values_exit_2_and_a_bad_report_path_writes_nothing() {
    let d = tmp("bad-values");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let out = d.join("t.glb");
    let i = input.to_str().unwrap();
    let o_arg = out.to_str().unwrap();
    for bad in [
        &["--levels", "abc"][..],
        &["--max-error", "x"],
        &["--tau", "-1"],
        &["--samples", "0"],
        &["--jobs", "0"],
    ] {
        let mut args = vec![i, "-o", o_arg];
        args.extend_from_slice(bad);
        let o = lodgen(&args);
        assert_eq!(o.status.code(), Some(2), "{bad:?}: {}", stderr(&o));
        assert!(stderr(&o).starts_with("error: "), "{bad:?}: {}", stderr(&o));
        assert!(!out.exists());
    }
    // an output that is no glTF file is a bad argument too (it exited 1)
    let obj_out = d.join("t.obj");
    let o = lodgen(&[i, "-o", obj_out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("must end in .glb or .gltf"),
        "{}",
        stderr(&o)
    );
    assert!(!obj_out.exists());
    let report = d.join("missing-dir/r.json");
    let o = lodgen(&[i, "-o", o_arg, "--report", report.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("does not exist"), "{}", stderr(&o));
    assert!(!out.exists(), "the output was written");
    let _ = std::fs::remove_dir_all(&d);
}

/// `--report` naming the input or the output is refused before the work: the report replaced
/// a scan with its JSON, or the `.glb` it reports on, and the run exited 0. The input and the
/// other names of the output (`./`, the absolute path) stay as they were.
#[test]
fn a_report_never_overwrites_the_input_or_the_output() {
    let d = tmp("report-targets");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let before = std::fs::read(&input).unwrap();
    let out = d.join("t.glb");
    let i = input.to_str().unwrap();
    let o_arg = out.to_str().unwrap();
    let dotted = d.join(".").join("t.glb");
    for (report, what) in [
        (i, "input"),
        (o_arg, "output"),
        (dotted.to_str().unwrap(), "output"),
    ] {
        let o = lodgen(&[i, "-o", o_arg, "--report", report, "-q"]);
        assert_eq!(o.status.code(), Some(1), "{report}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains(&format!("would overwrite the {what}")),
            "{report}: {e}"
        );
        assert_eq!(std::fs::read(&input).unwrap(), before, "the input changed");
        assert!(!out.exists(), "{report}: the output was written");
    }
    // batch: a report among the inputs
    let out_dir = d.join("out");
    let o = lodgen(&[
        i,
        "--out-dir",
        out_dir.to_str().unwrap(),
        "--report",
        i,
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("would overwrite the input"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(&input).unwrap(), before, "the input changed");
    let _ = std::fs::remove_dir_all(&d);
}

/// Ratios are of the welded, cleaned mesh: with every face written twice
/// (the duplicates dropped), `2%` is 2 % of the torus's own triangles, the
/// count the 50 % and 10 % levels are taken of too. (Fails when the run
/// stops at 2 % of the raw count, twice the level's.)
#[test]
fn ratios_are_of_the_cleaned_mesh() {
    let d = tmp("duplicated-faces");
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 48, 24);
    let twice: Vec<[u32; 3]> = m.triangles.iter().chain(&m.triangles).copied().collect();
    let input = d.join("twice.obj");
    std::fs::write(&input, obj_text(&[("twice", &m.positions, &twice)])).unwrap();
    let r = d.join("r.json");
    let o = lodgen(&[
        input.to_str().unwrap(),
        "-o",
        d.join("t.glb").to_str().unwrap(),
        "--report",
        r.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let counts = level_triangles(&report(&r));
    let n = m.triangles.len() as u64;
    assert_eq!(counts.len(), 3, "{counts:?}");
    assert!(counts[0] <= n / 2 && counts[1] <= n / 10, "{counts:?}");
    assert!(counts[2] <= n / 50, "{counts:?} (2 % of {n} is {})", n / 50);
    let _ = std::fs::remove_dir_all(&d);
}

/// `lodgen view` streams one chain: on a file of several (a scene of two
/// meshes with `--progressive`) it says which it shows and that the others
/// are not shown. (Fails when it shows the first silently.)
#[test]
fn view_says_when_it_shows_one_of_several_streams() {
    let d = tmp("view-streams");
    let a = lodgen_pm::shapes::torus(1.0, 0.35, 24, 12);
    let b = lodgen_pm::shapes::torus(2.0, 0.5, 24, 12);
    let input = d.join("two.obj");
    let text = obj_text(&[
        ("a", &a.positions, &a.triangles),
        ("b", &b.positions, &b.triangles),
    ]);
    std::fs::write(&input, text).unwrap();
    let out = d.join("two.glb");
    let o = lodgen(&[
        input.to_str().unwrap(),
        "--progressive",
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = lodgen(&["view", out.to_str().unwrap(), "--print-levels"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("carries 2 streams"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&d);
}

/// lodgen on its own output: the input's coarser levels give way to the
/// levels lodgen makes of the finest, with a warning each, instead of each
/// old level getting a chain of its own beside the new one. (Fails when the
/// old levels are read as meshes.)
#[test]
fn an_lod_file_is_made_again_from_its_finest_level() {
    let d = tmp("relod");
    let input = d.join("torus.obj");
    write_torus_obj(&input);
    let a = d.join("a.glb");
    let b = d.join("b.glb");
    let o = lodgen(&[input.to_str().unwrap(), "-o", a.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = d.join("r.json");
    let o = lodgen(&[
        a.to_str().unwrap(),
        "-o",
        b.to_str().unwrap(),
        "--report",
        r.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(
        err.matches("MSFT_lod chain in the input: left out").count(),
        2,
        "{err}"
    );
    let rep = report(&r);
    assert_eq!(rep["meshes"].as_array().unwrap().len(), 1, "{rep}");
    assert_eq!(level_triangles(&rep).len(), 3, "{rep}");
    let _ = std::fs::remove_dir_all(&d);
}

/// A scan in UTM coordinates (a torus of radius 1 at x 512,345.678, y 5,412,345.678) as a
/// binary double PLY and as an OBJ: read moved to its first vertex (rounded), written with
/// that offset in its nodes' translation, so every vertex is where the file put it (to
/// 10⁻⁴), none merged, and `lodgen measure` finds the written full level on the input (also
/// through `--quantize`'s node transforms). Read straight into `f32`, whose step there is
/// 0.5, the torus fell apart: its vertices merged, the run took minutes.
#[test]
fn a_scan_far_from_the_origin_keeps_its_detail() {
    let d = tmp("far-scan");
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 48, 24);
    let at = [512_345.678, 5_412_345.678, 312.345];
    let far: Vec<[f64; 3]> = m
        .positions
        .iter()
        .map(|p| std::array::from_fn(|k| f64::from(p[k]) + at[k]))
        .collect();
    let mut ply = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\n\
         property double y\nproperty double z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        far.len(),
        m.triangles.len()
    )
    .into_bytes();
    for p in &far {
        p.iter().for_each(|x| ply.extend(x.to_le_bytes()));
    }
    for t in &m.triangles {
        ply.push(3);
        t.iter().for_each(|&v| ply.extend((v as i32).to_le_bytes()));
    }
    let mut obj = String::new();
    for p in &far {
        obj += &format!("v {:.9} {:.9} {:.9}\n", p[0], p[1], p[2]);
    }
    for t in &m.triangles {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    let (ply_path, obj_path) = (d.join("scan.ply"), d.join("scan.obj"));
    std::fs::write(&ply_path, ply).unwrap();
    std::fs::write(&obj_path, obj).unwrap();
    for input in [&ply_path, &obj_path] {
        for quantize in [false, true] {
            let out = d.join("out.glb");
            let mut args = vec![input.to_str().unwrap(), "--levels", "100%,10%", "-q"];
            args.extend(["-o", out.to_str().unwrap()]);
            if quantize {
                args.push("--quantize");
            }
            let o = lodgen(&args);
            assert!(o.status.success(), "{}", stderr(&o));
            let scene = lodgen::io::read_scene(&out).unwrap();
            let (written, _) = lodgen::cli::world_triangles(&scene);
            assert_eq!(written.len(), far.len(), "{input:?}: vertices merged");
            let tolerance = if quantize { 1e-3 } else { 1e-4 };
            for w in &written {
                let nearest = far
                    .iter()
                    .map(|p| (0..3).map(|k| (p[k] - w[k]).powi(2)).sum::<f64>().sqrt())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    nearest < tolerance,
                    "{input:?}: {w:?} is {nearest} from the input"
                );
            }
            let report = lodgen::cli::measure_report(input, &out, 2.0, true).unwrap();
            let r: serde_json::Value = serde_json::from_str(&report).unwrap();
            let h = r["hausdorff_percent"].as_f64().unwrap();
            assert!(h < 0.01, "{input:?} quantize {quantize}: {h} %");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}
