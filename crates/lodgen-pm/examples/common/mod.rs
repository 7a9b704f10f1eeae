//! What the examples share: a minimal OBJ reader (`v` and `f` lines only,
//! polygons fanned), enough for the shared test meshes, and their first two
//! arguments. Examples panic on a bad file; the product's reader is
//! `lodgen::io`.

use lodgen_pm::shapes::subdivide;
use lodgen_pm::Mesh;

/// The mesh the first two arguments name: an OBJ file (default: the shared
/// bunny) subdivided by midpoints that many times (default 0).
#[allow(dead_code)] // (not every example takes these arguments)
pub fn mesh_from_args(args: &[String]) -> Mesh {
    let path = args
        .get(1)
        .map_or("../shared/assets/bunny.obj", String::as_str);
    let subdivisions: usize = args.get(2).map_or(0, |s| s.parse().unwrap());
    let mut m = load_obj(path);
    for _ in 0..subdivisions {
        m = subdivide(&m);
    }
    m
}

pub fn load_obj(path: &str) -> Mesh {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let c: Vec<f32> = w.take(3).map(|s| s.parse().unwrap()).collect();
                positions.push([c[0], c[1], c[2]]);
            }
            Some("f") => {
                let c: Vec<u32> = w
                    .map(|s| s.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for k in 1..c.len() - 1 {
                    triangles.push([c[0], c[k], c[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// CPU time of the calling thread in ms (Linux; NaN elsewhere), so figures
/// survive a loaded machine.
#[allow(dead_code)] // (not every example times itself)
pub fn thread_cpu_ms() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-6)
}
