//! The readers on the real meshes of `../shared/assets` (see its README for
//! the measured counts asserted here). The assets are never copied into
//! the repository: the directory comes from `LODGEN_ASSETS`, else
//! `<workspace>/../shared/assets`; when missing the tests print a notice and
//! pass, unless `CI=true`.

use std::path::PathBuf;

use lodgen::io::read_scene;
use lodgen::scene::{Origin, Scene};

fn asset(name: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("LODGEN_ASSETS")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets")
        });
    let path = dir.join(name);
    if path.is_file() {
        return Some(path);
    }
    if std::env::var("CI").as_deref() == Ok("true") {
        panic!("test asset {} is missing", path.display());
    }
    eprintln!(
        "notice: {} not found, skipping (set LODGEN_ASSETS)",
        path.display()
    );
    None
}

fn read(name: &str) -> Option<Scene> {
    let path = asset(name)?;
    Some(read_scene(&path).unwrap_or_else(|e| panic!("{e}")))
}

/// (vertices, triangles) over all primitives.
fn counts(s: &Scene) -> (usize, usize) {
    let prims = s.meshes.iter().flat_map(|m| &m.primitives);
    prims.fold((0, 0), |(v, t), p| {
        (v + p.positions.len(), t + p.triangle_count())
    })
}

#[test]
fn bunny_keeps_only_referenced_vertices() {
    let Some(path) = asset("bunny.obj") else {
        return;
    };
    // Timing is reported, not asserted (shared machines); see the report
    // for the release figure: `cargo test --release -p lodgen --test
    // io_assets bunny -- --nocapture`.
    let start = std::time::Instant::now();
    let s = read_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    eprintln!(
        "bunny.obj read in {:.1} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.meshes[0].name, "bunny");
    assert_eq!(s.meshes[0].primitives.len(), 1);
    assert_eq!(counts(&s), (34_834, 69_451));
    let p = &s.meshes[0].primitives[0];
    assert!(p.normals.is_none() && p.texcoords.is_none());
    assert!(matches!(s.origin, Origin::Flat));
}

#[test]
fn spot_splits_corners_at_uv_seams() {
    let Some(s) = read("spot.obj") else { return };
    let (vertices, triangles) = counts(&s);
    assert_eq!(triangles, 5_856);
    // One vertex per distinct `v/vt` corner: 3,225, counted independently
    // with `grep '^f' spot.obj | tr ' ' '\n' | grep / | sort -u | wc -l`.
    assert_eq!(vertices, 3_225, "UV seams must split vertices");
    let p = &s.meshes[0].primitives[0];
    let uv = p.texcoords.as_ref().expect("spot has UVs");
    // The file's UVs lie in [-0.053, 1.001]; v is flipped (1 - v).
    assert!(uv
        .iter()
        .all(|t| (-0.06..=1.0).contains(&t[0]) && (-0.01..=0.9).contains(&t[1])));
    assert!(p.normals.is_none());
}

#[test]
fn beetle_has_normals_and_a_missing_mtllib_is_a_warning() {
    let Some(s) = read("beetle.obj") else { return };
    let (vertices, triangles) = counts(&s);
    assert_eq!(triangles, 2_053);
    // One vertex per distinct `v//vn` corner (1,254, counted as for spot).
    assert_eq!(vertices, 1_254);
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.meshes[0].name, "VWBUG");
    assert_eq!(s.materials.len(), 1);
    assert_eq!(s.materials[0].name, "None");
    for p in s.meshes.iter().flat_map(|m| &m.primitives) {
        let n = p.normals.as_ref().expect("beetle has normals");
        assert_eq!(n.len(), p.positions.len());
    }
    assert!(s.materials.iter().all(|m| m.base_color.is_none()));
    let w: Vec<String> = s.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].starts_with("mtllib VWBugMesh002.mtl:"), "{w:?}");
}

#[test]
fn teapot_cow_fandisk_rocker_arm() {
    for (name, vertices, triangles) in [
        ("teapot.obj", 3_644, 6_320),
        ("cow.obj", 2_903, 5_804),
        ("fandisk.obj", 6_475, 12_946),
        ("rocker-arm.obj", 10_044, 20_088),
    ] {
        let Some(s) = read(name) else { return };
        assert_eq!(counts(&s), (vertices, triangles), "{name}");
    }
}
