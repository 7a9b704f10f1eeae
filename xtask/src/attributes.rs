//! `cargo xtask attributes [--mesh NAME]`: attribute fidelity of lodgen
//! against meshoptimizer's `simplify_with_attributes` on a shared mesh
//! (default spot.obj: UVs, smooth normals computed on the welded positions
//! since the file has none; beetle.obj: the file's normals, hard edges
//! included) at 50 %, 10 % and 2 %, at the same triangle count.
//!
//! Errors are sampled on the original surface (area-weighted, seeded): at
//! each sample, the nearest point of the simplified mesh; UV error is the UV
//! distance between the two points' interpolated UVs, normal error the angle
//! between their interpolated normals. Geometric error (symmetric
//! Hausdorff / RMS, % of the bbox diagonal) from `lodgen_pm::metric`.
//! A benchmark, not a test: it prints a table.

use anyhow::{Context, Result};
use lodgen::lod::{build_one, BuildOptions, LevelRequest};
use lodgen::scene::{Primitive, SourceMesh};
use lodgen_pm::attrfit::barycentric;
use lodgen_pm::levels::LevelSpec;
use lodgen_pm::metric::bvh::TriangleBvh;
use lodgen_pm::metric::{measure, MeasureOptions, MeshRef};

/// Samples on the original surface: enough for the mean to settle to ~1 %.
const SAMPLES: usize = 50_000;
/// meshoptimizer's customary weights (normal 0.5, uv 1; its own scale).
const MESHOPT_WEIGHTS: [f32; 5] = [0.5, 0.5, 0.5, 1.0, 1.0];

/// A triangle soup with UVs and normals per vertex.
struct Surface {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

/// An error naming the first option `run` does not know.
fn check_options(args: &[String]) -> Result<()> {
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        match a.as_str() {
            "--half-edge" | "--reach-off" => {}
            "--mesh" => {
                rest.next();
            }
            a if a.starts_with("--attribute-weights=") => {}
            other => anyhow::bail!(
                "unknown attributes option {other:?} (expected --mesh NAME, --half-edge, \
                 --reach-off or --attribute-weights=LIST)"
            ),
        }
    }
    Ok(())
}

pub fn run(args: &[String]) -> Result<()> {
    check_options(args)?;
    // `--attribute-weights=LIST`: lodgen's weights (default: its defaults)
    let weights = match args
        .iter()
        .find_map(|a| a.strip_prefix("--attribute-weights="))
    {
        Some(list) => lodgen::cli::parse_attribute_weights(list)?,
        None => lodgen::lod::AttributeWeights::DEFAULT,
    };
    // `--half-edge`: lodgen keeps input positions too, like meshopt
    let placement = if args.iter().any(|a| a == "--half-edge") {
        lodgen_pm::Placement::HalfEdge
    } else {
        lodgen_pm::Placement::Optimal
    };
    // `--reach-off`: lodgen without `SimplifyOptions::reach` (on by default)
    let reach = if args.iter().any(|a| a == "--reach-off") {
        None
    } else {
        lodgen_pm::SimplifyOptions::DEFAULT.reach
    };
    let name = match args.iter().position(|a| a == "--mesh") {
        Some(i) => args
            .get(i + 1)
            .context("--mesh needs a name, e.g. beetle")?,
        None => "spot",
    };
    let path = crate::shared_assets()?.join(format!("{name}.obj"));
    let scene =
        lodgen::io::read_scene(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut prim = scene
        .meshes
        .first()
        .and_then(|m| m.primitives.first())
        .with_context(|| format!("{} has no triangles", path.display()))?
        .clone();
    if prim.normals.is_none() {
        prim.normals = Some(smooth_normals(&prim));
    }
    let source = SourceMesh {
        name: name.into(),
        primitives: vec![prim.clone()],
    };
    let original = surface_of(&prim);
    println!(
        "{name}.obj: {} triangles; {SAMPLES} samples; errors: UV distance (mean / rms), normal angle in degrees (mean / rms), geometry % of bbox diagonal (Hausdorff / rms)",
        original.triangles.len()
    );
    println!(
        "lodgen attribute weights: normal {}, uv {}; meshopt weights {MESHOPT_WEIGHTS:?} (normal xyz, uv)",
        weights.normal, weights.uv
    );
    println!(
        "{:>6} {:>8} {:>7} {:>15} {:>15} {:>17}",
        "level", "tool", "tris", "uv mean/rms", "normal° mean/rms", "geom H/rms %"
    );
    for ratio in [0.5, 0.1, 0.02] {
        let opts = BuildOptions {
            levels: LevelRequest::Specs(vec![LevelSpec::Ratio(ratio)]),
            simplify: lodgen_pm::SimplifyOptions::DEFAULT
                .with_placement(placement)
                .with_reach(reach),
            attribute_weights: weights,
            ..BuildOptions::default()
        };
        let build = build_one(0, &source, &opts, &mut |_| {})?;
        let level = &build.lod.levels[0];
        let ours = merge(&level.primitives);
        let tris = ours.triangles.len();

        let vertices =
            meshopt::VertexDataAdapter::new(meshopt::typed_to_bytes(&prim.positions), 12, 0)?;
        let attrs: Vec<f32> = (0..prim.positions.len())
            .flat_map(|v| {
                let n = prim.normals.as_ref().map_or([0.0; 3], |a| a[v]);
                let t = prim.texcoords.as_ref().map_or([0.0; 2], |a| a[v]);
                [n[0], n[1], n[2], t[0], t[1]]
            })
            .collect();
        let idx = meshopt::simplify_with_attributes_and_locks(
            &prim.indices,
            &vertices,
            &attrs,
            &MESHOPT_WEIGHTS,
            5 * 4,
            &vec![false; prim.positions.len()],
            3 * tris,
            1.0,
            meshopt::SimplifyOptions::None,
            None,
        );
        let theirs = Surface {
            triangles: idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            ..surface_of(&prim)
        };
        for (name, s) in [("lodgen", &ours), ("meshopt", &theirs)] {
            let (uv, normal) = attribute_errors(&original, s)?;
            let g = measure(
                MeshRef::new(&original.positions, &original.triangles),
                MeshRef::new(&s.positions, &s.triangles),
                &MeasureOptions::DEFAULT,
            )?;
            println!(
                "{:>5}% {:>8} {:>7} {:>7.4}/{:<7.4} {:>7.2}/{:<7.2} {:>8.3}/{:<8.3}",
                ratio * 100.0,
                name,
                s.triangles.len(),
                uv.0,
                uv.1,
                normal.0,
                normal.1,
                g.hausdorff_percent(),
                g.rms_percent()
            );
        }
    }
    Ok(())
}

/// Area-weighted vertex normals on welded positions (continuous across UV
/// seams), given to every vertex at that position.
fn smooth_normals(p: &Primitive) -> Vec<[f32; 3]> {
    let key = |v: usize| p.positions[v].map(f32::to_bits);
    let mut sum: std::collections::BTreeMap<[u32; 3], [f64; 3]> = Default::default();
    for t in p.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| p.positions[t[k] as usize].map(f64::from));
        let n = cross(sub(b, a), sub(c, a));
        for &v in t {
            let s = sum.entry(key(v as usize)).or_insert([0.0; 3]);
            for k in 0..3 {
                s[k] += n[k];
            }
        }
    }
    (0..p.positions.len())
        .map(|v| {
            let n = sum.get(&key(v)).copied().unwrap_or([0.0, 0.0, 1.0]);
            let l = dot(n, n).sqrt().max(f64::MIN_POSITIVE);
            n.map(|x| (x / l) as f32)
        })
        .collect()
}

fn surface_of(p: &Primitive) -> Surface {
    Surface {
        positions: p.positions.clone(),
        uvs: p
            .texcoords
            .clone()
            .unwrap_or_else(|| vec![[0.0; 2]; p.positions.len()]),
        normals: p
            .normals
            .clone()
            .unwrap_or_else(|| vec![[0.0, 0.0, 1.0]; p.positions.len()]),
        triangles: p
            .indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
    }
}

fn merge(prims: &[Primitive]) -> Surface {
    let mut s = Surface {
        positions: Vec::new(),
        uvs: Vec::new(),
        normals: Vec::new(),
        triangles: Vec::new(),
    };
    for p in prims {
        let off = s.positions.len() as u32;
        let q = surface_of(p);
        s.positions.extend(q.positions);
        s.uvs.extend(q.uvs);
        s.normals.extend(q.normals);
        s.triangles
            .extend(q.triangles.iter().map(|t| t.map(|v| v + off)));
    }
    s
}

/// ((uv mean, uv rms), (normal° mean, normal° rms)) of `b` against `a`.
fn attribute_errors(a: &Surface, b: &Surface) -> Result<((f64, f64), (f64, f64))> {
    let bvh = TriangleBvh::new(MeshRef::new(&b.positions, &b.triangles))?;
    let p3 = |s: &Surface, t: [u32; 3]| t.map(|v| s.positions[v as usize].map(f64::from));
    let mut cumulative = Vec::with_capacity(a.triangles.len());
    let mut total = 0.0;
    for &t in &a.triangles {
        let [x, y, z] = p3(a, t);
        total += dot(cross(sub(y, x), sub(z, x)), cross(sub(y, x), sub(z, x))).sqrt();
        cumulative.push(total);
    }
    let mut rng = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut uv, mut uv2, mut an, mut an2) = (0.0, 0.0, 0.0, 0.0);
    for _ in 0..SAMPLES {
        let t = cumulative
            .partition_point(|&c| c < next() * total)
            .min(a.triangles.len() - 1);
        let (r1, r2) = (next().sqrt(), next());
        let w = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
        let tri = a.triangles[t];
        let pa = p3(a, tri);
        let p = [0, 1, 2].map(|k| w[0] * pa[0][k] + w[1] * pa[1][k] + w[2] * pa[2][k]);
        let (uv_a, n_a) = interpolate(a, tri, w);
        let (_, tb, q) = bvh.closest_point(p).context("empty simplified mesh")?;
        let tri_b = b.triangles[tb as usize];
        let (uv_b, n_b) = interpolate(b, tri_b, barycentric(p3(b, tri_b), q));
        let d = ((uv_a[0] - uv_b[0]).powi(2) + (uv_a[1] - uv_b[1]).powi(2)).sqrt();
        let cos = dot(n_a, n_b)
            / (dot(n_a, n_a) * dot(n_b, n_b))
                .sqrt()
                .max(f64::MIN_POSITIVE);
        let angle = cos.clamp(-1.0, 1.0).acos().to_degrees();
        uv += d;
        uv2 += d * d;
        an += angle;
        an2 += angle * angle;
    }
    let n = SAMPLES as f64;
    Ok(((uv / n, (uv2 / n).sqrt()), (an / n, (an2 / n).sqrt())))
}

fn interpolate(s: &Surface, t: [u32; 3], w: [f64; 3]) -> ([f64; 2], [f64; 3]) {
    let mut uv = [0.0; 2];
    let mut n = [0.0; 3];
    for (k, &v) in t.iter().enumerate() {
        let v = v as usize;
        for (c, x) in uv.iter_mut().enumerate() {
            *x += w[k] * f64::from(s.uvs[v][c]);
        }
        for (c, x) in n.iter_mut().enumerate() {
            *x += w[k] * f64::from(s.normals[v][c]);
        }
    }
    (uv, n)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
