//! Small meshes generated in code, for tests, examples and benchmarks:
//! grids, boxes, tetrahedra, icospheres, tori and a noisy torus knot. Pure
//! functions, deterministic.
//!
//! ```
//! let m = lodgen_pm::shapes::icosphere(1);
//! assert_eq!(m.triangles.len(), 80);
//! ```

use crate::mesh::Mesh;
use std::f64::consts::TAU;

/// An `nx × ny` grid of quads (two triangles each) in the z = 0 plane,
/// spanning `[0, 1]²`, with heights `z(x, y)`.
pub fn grid(nx: u32, ny: u32, z: impl Fn(f64, f64) -> f64) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (f64::from(i) / f64::from(nx), f64::from(j) / f64::from(ny));
            positions.push([x as f32, y as f32, z(x, y) as f32]);
        }
    }
    let mut triangles = Vec::new();
    let w = nx + 1;
    for j in 0..ny {
        for i in 0..nx {
            let a = j * w + i;
            triangles.push([a, a + 1, a + w + 1]);
            triangles.push([a, a + w + 1, a + w]);
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// An axis-aligned box from `min` to `max`, each face an `n × n` grid,
/// outward-facing, welded.
pub fn cube(min: [f32; 3], max: [f32; 3], n: u32) -> Mesh {
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut triangles = Vec::new();
    // (normal axis, side, u axis, v axis) chosen so u × v points outward
    let faces = [
        (0, 1, 1, 2),
        (0, 0, 2, 1),
        (1, 1, 2, 0),
        (1, 0, 0, 2),
        (2, 1, 0, 1),
        (2, 0, 1, 0),
    ];
    let mut index_of = std::collections::BTreeMap::new();
    for (axis, side, ua, va) in faces {
        let mut ids = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let mut g = [0u32; 3];
                g[axis] = if side == 1 { n } else { 0 };
                g[ua] = i;
                g[va] = j;
                let id = *index_of.entry(g).or_insert_with(|| {
                    positions.push([0, 1, 2].map(|k| {
                        let t = g[k] as f32 / n as f32;
                        min[k] + (max[k] - min[k]) * t
                    }));
                    positions.len() as u32 - 1
                });
                ids.push(id);
            }
        }
        let w = n + 1;
        for j in 0..n {
            for i in 0..n {
                let a = ids[(j * w + i) as usize];
                let b = ids[(j * w + i + 1) as usize];
                let c = ids[((j + 1) * w + i + 1) as usize];
                let d = ids[((j + 1) * w + i) as usize];
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// A regular tetrahedron, outward-facing.
pub fn tetrahedron() -> Mesh {
    Mesh {
        positions: vec![
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ],
        triangles: vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
    }
}

/// An icosphere of radius 1 after `subdivisions` 4-to-1 splits
/// (20 · 4^s triangles).
pub fn icosphere(subdivisions: u32) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::BTreeMap::new();
        let mut next = Vec::with_capacity(tris.len() * 4);
        let mut midpoint = |a: u32, b: u32, p: &mut Vec<[f64; 3]>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (x, y) = (p[a as usize], p[b as usize]);
                p.push([0, 1, 2].map(|k| (x[k] + y[k]) / 2.0));
                p.len() as u32 - 1
            })
        };
        for &[a, b, c] in &tris {
            let ab = midpoint(a, b, &mut p);
            let bc = midpoint(b, c, &mut p);
            let ca = midpoint(c, a, &mut p);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    Mesh {
        positions: p
            .iter()
            .map(|v| {
                let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                v.map(|c| (c / l) as f32)
            })
            .collect(),
        triangles: tris,
    }
}

/// A tube of radius `r` swept along a closed curve `c(t)`, t ∈ [0, 1),
/// with `n` rings of `m` vertices; optional deterministic radial noise.
fn tube(c: impl Fn(f64) -> [f64; 3], r: f64, n: u32, m: u32, noise: f64) -> Mesh {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let norm = |a: [f64; 3]| {
        let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        a.map(|x| x / l)
    };
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = move || {
        // splitmix64
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut positions = Vec::new();
    for i in 0..n {
        let t = f64::from(i) / f64::from(n);
        let p = c(t);
        let tangent = norm(sub(c(t + 1e-4), c(t - 1e-4)));
        let up = if tangent[2].abs() < 0.9 {
            [0.0, 0.0, 1.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let u = norm(cross(tangent, up));
        let v = cross(tangent, u);
        for j in 0..m {
            let a = TAU * f64::from(j) / f64::from(m);
            let rr = r * (1.0 + noise * (rnd() - 0.5));
            positions
                .push([0, 1, 2].map(|k| (p[k] + rr * (a.cos() * u[k] + a.sin() * v[k])) as f32));
        }
    }
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let a = i * m + j;
            let b = i * m + (j + 1) % m;
            let c2 = ((i + 1) % n) * m + (j + 1) % m;
            let d = ((i + 1) % n) * m + j;
            triangles.push([a, b, c2]);
            triangles.push([a, c2, d]);
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// A torus with major radius `big_r`, minor radius `r`, `n × m` quads.
pub fn torus(big_r: f64, r: f64, n: u32, m: u32) -> Mesh {
    tube(
        |t| [big_r * (TAU * t).cos(), big_r * (TAU * t).sin(), 0.0],
        r,
        n,
        m,
        0.0,
    )
}

/// A (p, q) torus knot tube with relative radial noise `noise` (e.g. 0.05):
/// the project's bundled example mesh. `2 · n · m` triangles.
pub fn torus_knot(p: u32, q: u32, n: u32, m: u32, noise: f64) -> Mesh {
    let (p, q) = (f64::from(p), f64::from(q));
    tube(
        move |t| {
            let a = TAU * t;
            let r = 2.0 + (q * a).cos();
            [r * (p * a).cos(), r * (p * a).sin(), -(q * a).sin()]
        },
        0.4,
        n,
        m,
        noise,
    )
}

/// 4-to-1 midpoint subdivision (shared edge midpoints, so the result stays
/// welded and manifold): the benchmark's ~1M-triangle bunny is the bunny
/// subdivided twice.
pub fn subdivide(m: &Mesh) -> Mesh {
    let mut positions = m.positions.clone();
    let mut mid: std::collections::BTreeMap<(u32, u32), u32> = Default::default();
    let mut triangles = Vec::with_capacity(m.triangles.len() * 4);
    let mut midpoint = |a: u32, b: u32, positions: &mut Vec<[f32; 3]>| {
        *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (p, q) = (positions[a as usize], positions[b as usize]);
            positions.push([0, 1, 2].map(|k| 0.5 * (p[k] + q[k])));
            positions.len() as u32 - 1
        })
    };
    for &[a, b, c] in &m.triangles {
        let ab = midpoint(a, b, &mut positions);
        let bc = midpoint(b, c, &mut positions);
        let ca = midpoint(c, a, &mut positions);
        triangles.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    Mesh {
        positions,
        triangles,
    }
}
