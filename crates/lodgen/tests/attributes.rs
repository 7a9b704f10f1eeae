//! Authored attributes survive simplification: skin weights stay valid,
//! spot's UV charts are never bridged, and every glTF vertex attribute makes
//! the round trip through the writer and the reader.

use lodgen::gltf_out::{write_lods, WriteOptions};
use lodgen::io::read_scene;
use lodgen::lod::{build_one, BuildOptions, LevelRequest};
use lodgen::scene::{LodLevel, LodMesh, Origin, Primitive, Scene, SourceMesh};
use lodgen_pm::levels::LevelSpec;
use std::collections::{BTreeMap, BTreeSet};

fn build(mesh: &SourceMesh, ratios: &[f64]) -> LodMesh {
    let opts = BuildOptions {
        levels: LevelRequest::Specs(ratios.iter().map(|&r| LevelSpec::Ratio(r)).collect()),
        ..BuildOptions::default()
    };
    build_one(0, mesh, &opts, &mut |_| {}).unwrap().lod
}

/// A 48×3 strip along x bent upwards, skinned to 6 joints with linear
/// blends; every fifth vertex's weights are given unnormalised (sum 2).
fn skinned_strip() -> SourceMesh {
    let (nx, ny) = (48u32, 3u32);
    let mut p = Primitive::default();
    let (mut joints, mut weights) = (Vec::new(), Vec::new());
    for j in 0..=ny {
        for i in 0..=nx {
            let x = i as f32 / nx as f32;
            p.positions
                .push([x * 6.0, j as f32 / ny as f32, 0.5 * (x * 3.0).sin()]);
            let s = (x * 5.0).min(4.999);
            let (b, f) = (s.floor() as u16, s.fract());
            joints.push([b, b + 1, 0, 0]);
            let scale = if (i + j) % 5 == 0 { 2.0 } else { 1.0 };
            weights.push([(1.0 - f) * scale, f * scale, 0.0, 0.0]);
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            let a = j * (nx + 1) + i;
            let w = nx + 1;
            p.indices
                .extend_from_slice(&[a, a + 1, a + w + 1, a, a + w + 1, a + w]);
        }
    }
    p.joints = Some(joints);
    p.weights = Some(weights);
    SourceMesh {
        name: "strip".into(),
        primitives: vec![p],
    }
}

#[test]
fn skinned_strip_keeps_valid_joints_and_weights() {
    let src = skinned_strip();
    let input = &src.primitives[0];
    let pairs: BTreeSet<[u16; 4]> = input.joints.as_ref().unwrap().iter().copied().collect();
    let lod = build(&src, &[0.5, 0.1, 0.02]);
    assert_eq!(lod.levels.len(), 3);
    for (l, level) in lod.levels.iter().enumerate() {
        let p = &level.primitives[0];
        let (j, w) = (p.joints.as_ref().unwrap(), p.weights.as_ref().unwrap());
        assert_eq!(j.len(), p.positions.len());
        assert_eq!(w.len(), p.positions.len());
        for (v, (jv, wv)) in j.iter().zip(w).enumerate() {
            let sum: f32 = wv.iter().sum();
            assert!(
                (sum - 1.0).abs() < 1e-5,
                "level {l} vertex {v}: weights sum {sum}"
            );
            assert!(wv.iter().all(|&x| x >= 0.0));
            // joints come from one source vertex: never a blend of two
            assert!(pairs.contains(jv), "level {l} vertex {v}: joints {jv:?}");
        }
    }
}

/// The chart (UV-connected triangle component) of each input triangle.
fn uv_charts(p: &Primitive) -> Vec<u32> {
    let n = p.positions.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for t in p.indices.chunks_exact(3) {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, t[0]), find(&mut parent, t[k]));
            parent[a.max(b) as usize] = a.min(b);
        }
    }
    p.indices
        .chunks_exact(3)
        .map(|t| find(&mut parent, t[0]))
        .collect()
}

/// Squared distance in UV space from `q` to the triangle `t`.
fn uv_distance2(q: [f32; 2], t: [[f32; 2]; 3]) -> f32 {
    let cross = |a: [f32; 2], b: [f32; 2], c: [f32; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let s = [0, 1, 2].map(|k| cross(t[k], t[(k + 1) % 3], q));
    if s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0) {
        return 0.0;
    }
    (0..3)
        .map(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let ab = [b[0] - a[0], b[1] - a[1]];
            let l2 = (ab[0] * ab[0] + ab[1] * ab[1]).max(f32::MIN_POSITIVE);
            let u = (((q[0] - a[0]) * ab[0] + (q[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0);
            let d = [a[0] + u * ab[0] - q[0], a[1] + u * ab[1] - q[1]];
            d[0] * d[0] + d[1] * d[1]
        })
        .fold(f32::INFINITY, f32::min)
}

#[test]
fn spot_at_ten_percent_keeps_its_seams() {
    let Some(path) = lodgen::assets::shared_asset("spot.obj") else {
        return;
    };
    let scene = read_scene(&path).unwrap();
    let src = &scene.meshes[0];
    let input = &src.primitives[0];
    let charts = uv_charts(input);
    let chart_count = charts.iter().collect::<BTreeSet<_>>().len();
    assert!(chart_count > 1, "spot has several UV charts");
    let lod = build(src, &[0.1]);
    let level = &lod.levels[0];
    assert!(level.triangle_count() <= input.triangle_count() / 10 + 1);
    // a level UV belongs to the chart of the input UV triangle it lies in
    // (fitted UVs are not input UVs, but stay in their chart's island)
    let in_uv = input.texcoords.as_ref().unwrap();
    let uv_tris: Vec<[[f32; 2]; 3]> = input
        .indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| in_uv[t[k] as usize]))
        .collect();
    let chart_of = |q: [f32; 2]| {
        let (mut best, mut chart) = (f32::INFINITY, u32::MAX);
        for (t, tri) in uv_tris.iter().enumerate() {
            let d = uv_distance2(q, *tri);
            if d < best {
                (best, chart) = (d, charts[t]);
            }
        }
        chart
    };
    let mut spanning = 0;
    for p in &level.primitives {
        let uv = p.texcoords.as_ref().unwrap();
        let chart: Vec<u32> = uv.iter().map(|&q| chart_of(q)).collect();
        for t in p.indices.chunks_exact(3) {
            let c = [0, 1, 2].map(|k| chart[t[k] as usize]);
            if c[0] != c[1] || c[1] != c[2] {
                spanning += 1;
            }
        }
    }
    assert_eq!(spanning, 0, "triangles spanning two UV charts");
}

/// The skinned strip with a second influence set (JOINTS_1 / WEIGHTS_1,
/// eight influences per vertex, the sum of both sets 1.25 × the first
/// one's) and a second colour set.
fn eight_influence_strip() -> SourceMesh {
    let mut src = skinned_strip();
    let p = &mut src.primitives[0];
    let j0 = p.joints.clone().unwrap();
    let w0 = p.weights.clone().unwrap();
    p.extra_joints = vec![j0.iter().map(|j| [(j[0] + 2) % 6, 7, 8, 0]).collect()];
    p.extra_weights = vec![w0
        .iter()
        .map(|w| {
            let s: f32 = w.iter().sum();
            [0.15 * s, 0.1 * s, 0.0, 0.0]
        })
        .collect()];
    p.extra_colors = vec![p
        .positions
        .iter()
        .map(|q| [q[0] / 6.0, q[1], 0.5, 1.0])
        .collect()];
    src
}

#[test]
fn every_set_of_joints_weights_and_colours_stays_valid() {
    let src = eight_influence_strip();
    let input = &src.primitives[0];
    let eight = |p: &Primitive, v: usize| {
        let mut j = p.joints.as_ref().unwrap()[v].to_vec();
        j.extend(p.extra_joints[0][v]);
        j
    };
    let tuples: BTreeSet<Vec<u16>> = (0..input.positions.len())
        .map(|v| eight(input, v))
        .collect();
    let lod = build(&src, &[0.5, 0.1, 0.02]);
    assert_eq!(lod.levels.len(), 3);
    for (l, level) in lod.levels.iter().enumerate() {
        let p = &level.primitives[0];
        let n = p.positions.len();
        assert_eq!(p.extra_joints.len(), 1);
        assert_eq!(p.extra_weights.len(), 1);
        assert_eq!(p.extra_colors.len(), 1);
        assert_eq!(p.extra_joints[0].len(), n);
        assert_eq!(p.extra_weights[0].len(), n);
        assert_eq!(p.extra_colors[0].len(), n);
        for v in 0..n {
            let (w0, w1) = (p.weights.as_ref().unwrap()[v], p.extra_weights[0][v]);
            let sum: f32 = w0.iter().chain(&w1).sum();
            assert!(
                (sum - 1.0).abs() < 1e-5,
                "level {l} vertex {v}: weights of both sets sum to {sum}"
            );
            assert!(w1[0] > 0.0, "level {l} vertex {v}: second set lost");
            // all eight joints from one source vertex
            assert!(tuples.contains(&eight(p, v)), "level {l} vertex {v}");
            let c = p.extra_colors[0][v];
            assert!(c.iter().all(|x| (0.0..=1.0).contains(x)), "{c:?}");
        }
    }
}

#[test]
fn every_vertex_attribute_round_trips_through_gltf() {
    let mut p = eight_influence_strip().primitives.remove(0);
    let n = p.positions.len();
    for v in 0..n {
        let w = p.weights.as_mut().unwrap();
        let s: f32 = w[v].iter().chain(&p.extra_weights[0][v]).sum();
        w[v] = w[v].map(|x| x / s);
        p.extra_weights[0][v] = p.extra_weights[0][v].map(|x| x / s);
    }
    p.normals = Some(vec![[0.0, 0.0, 1.0]; n]);
    p.texcoords = Some((0..n).map(|i| [i as f32 / n as f32, 0.25]).collect());
    p.tangents = Some(vec![[1.0, 0.0, 0.0, -1.0]; n]);
    p.extra_texcoords = vec![(0..n).map(|i| [0.5, i as f32 / n as f32]).collect()];
    p.colors = Some(
        (0..n)
            .map(|i| [i as f32 / n as f32, 0.5, 0.25, 1.0])
            .collect(),
    );
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: "strip".into(),
            primitives: vec![p.clone()],
        }],
        materials: Vec::new(),
        origin: Origin::Flat,
        warnings: Vec::new(),
    };
    let lod = LodMesh {
        source: 0,
        name: "strip".into(),
        levels: vec![LodLevel {
            primitives: vec![p.clone()],
            ..LodLevel::default()
        }],
    };
    let dir = std::env::temp_dir().join(format!("lodgen-attrs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("strip.glb");
    write_lods(&path, &scene, &[lod], &WriteOptions::default()).unwrap();
    let back = read_scene(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let q = &back.meshes[0].primitives[0];
    // the writer reorders vertices: compare per-vertex records as sets
    let key = |p: &Primitive, v: usize| {
        let mut k: Vec<u32> = p.positions[v].map(f32::to_bits).to_vec();
        k.extend(p.texcoords.as_ref().unwrap()[v].map(f32::to_bits));
        k.extend(p.tangents.as_ref().unwrap()[v].map(f32::to_bits));
        k.extend(p.extra_texcoords[0][v].map(f32::to_bits));
        k.extend(p.colors.as_ref().unwrap()[v].map(f32::to_bits));
        k.extend(p.joints.as_ref().unwrap()[v].map(u32::from));
        k.extend(p.weights.as_ref().unwrap()[v].map(f32::to_bits));
        k.extend(p.extra_colors[0][v].map(f32::to_bits));
        k.extend(p.extra_joints[0][v].map(u32::from));
        k.extend(p.extra_weights[0][v].map(f32::to_bits));
        k
    };
    let a: BTreeSet<Vec<u32>> = (0..n).map(|v| key(&p, v)).collect();
    let b: BTreeSet<Vec<u32>> = (0..q.positions.len()).map(|v| key(q, v)).collect();
    assert_eq!(q.extra_texcoords.len(), 1);
    assert_eq!(q.extra_colors.len(), 1);
    assert_eq!(q.extra_joints.len(), 1);
    assert_eq!(q.extra_weights.len(), 1);
    assert_eq!(a, b);
}

#[test]
fn attribute_weights_parse_and_refuse_bad_input() {
    use lodgen::cli::parse_attribute_weights;
    let w = parse_attribute_weights("normal=0.25, uv=2").unwrap();
    assert_eq!((w.normal, w.uv), (0.25, 2.0));
    assert_eq!(w.color, lodgen::lod::AttributeWeights::DEFAULT.color);
    for bad in ["normal", "uv=-1", "uv=x", "bone=1", "uv=inf"] {
        assert!(parse_attribute_weights(bad).is_err(), "{bad}");
    }
}

/// A 40×40 bumpy height field on [0, 1]² with its exact normals and
/// UVs = (x, y).
fn bumpy_field() -> SourceMesh {
    let g = lodgen_pm::shapes::grid(40, 40, |x, y| 0.08 * (7.0 * x).sin() * (5.0 * y).cos());
    let normals = g
        .positions
        .iter()
        .map(|p| {
            let (x, y) = (f64::from(p[0]), f64::from(p[1]));
            let dx = 0.08 * 7.0 * (7.0 * x).cos() * (5.0 * y).cos();
            let dy = -0.08 * 5.0 * (7.0 * x).sin() * (5.0 * y).sin();
            let l = (dx * dx + dy * dy + 1.0).sqrt();
            [(-dx / l) as f32, (-dy / l) as f32, (1.0 / l) as f32]
        })
        .collect();
    let texcoords = g.positions.iter().map(|p| [p[0], p[1]]).collect();
    SourceMesh {
        name: "bumps".into(),
        primitives: vec![Primitive {
            normals: Some(normals),
            texcoords: Some(texcoords),
            indices: g.triangles.iter().flatten().copied().collect(),
            positions: g.positions,
            ..Primitive::default()
        }],
    }
}

/// RMS normal angle (degrees) and RMS UV distance between the input's
/// interpolated attributes at points sampled on it and the level's at the
/// nearest point of the level (what `cargo xtask attributes` measures).
fn attribute_error(input: &Primitive, level: &[Primitive]) -> (f64, f64) {
    use lodgen_pm::metric::bvh::TriangleBvh;
    use lodgen_pm::metric::MeshRef;
    let (mut pos, mut nrm, mut uv, mut tris) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for p in level {
        let off = pos.len() as u32;
        pos.extend_from_slice(&p.positions);
        nrm.extend_from_slice(p.normals.as_ref().unwrap());
        uv.extend_from_slice(p.texcoords.as_ref().unwrap());
        tris.extend(
            p.indices
                .chunks_exact(3)
                .map(|t| [t[0] + off, t[1] + off, t[2] + off]),
        );
    }
    let bvh = TriangleBvh::new(MeshRef::new(&pos, &tris)).unwrap();
    let f = |p: [f32; 3]| p.map(f64::from);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let lerp3 = |w: [f64; 3], v: [[f32; 3]; 3]| {
        [0, 1, 2].map(|c| (0..3).map(|k| w[k] * f64::from(v[k][c])).sum::<f64>())
    };
    let lerp2 = |w: [f64; 3], v: [[f32; 2]; 3]| {
        [0, 1].map(|c| (0..3).map(|k| w[k] * f64::from(v[k][c])).sum::<f64>())
    };
    let (in_n, in_uv) = (
        input.normals.as_ref().unwrap(),
        input.texcoords.as_ref().unwrap(),
    );
    let (mut angle2, mut uv2, mut count) = (0.0, 0.0, 0.0);
    for t in input.indices.chunks_exact(3) {
        for w in [
            [1.0 / 3.0; 3],
            [4.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0],
            [1.0 / 6.0, 1.0 / 6.0, 4.0 / 6.0],
        ] {
            let corners = [0, 1, 2].map(|k| t[k] as usize);
            let p = lerp3(w, corners.map(|v| input.positions[v]));
            let (na, ua) = (
                lerp3(w, corners.map(|v| in_n[v])),
                lerp2(w, corners.map(|v| in_uv[v])),
            );
            let (_, lt, q) = bvh.closest_point(p).unwrap();
            let c = tris[lt as usize].map(|v| v as usize);
            let [a, b, d] = c.map(|v| f(pos[v]));
            let (v0, v1, v2) = (sub(b, a), sub(d, a), sub(q, a));
            let (d00, d01, d11, d20, d21) = (
                dot(v0, v0),
                dot(v0, v1),
                dot(v1, v1),
                dot(v2, v0),
                dot(v2, v1),
            );
            let den = d00 * d11 - d01 * d01;
            let (y, z) = ((d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den);
            let wb = [1.0 - y - z, y, z];
            let (nb, ub) = (lerp3(wb, c.map(|v| nrm[v])), lerp2(wb, c.map(|v| uv[v])));
            let cos = dot(na, nb) / (dot(na, na) * dot(nb, nb)).sqrt();
            angle2 += cos.clamp(-1.0, 1.0).acos().to_degrees().powi(2);
            uv2 += (ua[0] - ub[0]).powi(2) + (ua[1] - ub[1]).powi(2);
            count += 1.0;
        }
    }
    ((angle2 / count).sqrt(), (uv2 / count).sqrt())
}

#[test]
fn level_attributes_are_fitted_to_the_surface() {
    let src = bumpy_field();
    let lod = build(&src, &[0.1]);
    let (normal, uv) = attribute_error(&src.primitives[0], &lod.levels[0].primitives);
    // measured: 0.57° and 0.0002 fitted; each corner keeping its source
    // vertex's values (the positions being quadric-optimal) gave 3.2° and
    // 0.024
    assert!(normal < 1.5, "normal error {normal}°");
    assert!(uv < 0.005, "uv error {uv}");
}

#[test]
fn full_refinement_keeps_the_input_attributes_exactly() {
    let src = bumpy_field();
    let lod = build(&src, &[1.0, 0.1]);
    let input = &src.primitives[0];
    let key = |p: &Primitive, v: usize| {
        let mut k: Vec<u32> = p.positions[v].map(f32::to_bits).to_vec();
        k.extend(p.normals.as_ref().unwrap()[v].map(f32::to_bits));
        k.extend(p.texcoords.as_ref().unwrap()[v].map(f32::to_bits));
        k
    };
    let full = &lod.levels[0].primitives[0];
    assert_eq!(full.triangle_count(), input.triangle_count());
    let a: BTreeSet<Vec<u32>> = (0..input.positions.len()).map(|v| key(input, v)).collect();
    let b: BTreeSet<Vec<u32>> = (0..full.positions.len()).map(|v| key(full, v)).collect();
    assert_eq!(a, b);
}

/// A 6×6-per-face cube with hard normals: every face its own vertices,
/// all with the face's normal, and UVs = the face's own 2D coordinates.
fn hard_cube() -> SourceMesh {
    let n = 6;
    let cube = lodgen_pm::shapes::cube([-1.0; 3], [1.0; 3], n);
    let per_face = (2 * n * n) as usize;
    let mut p = Primitive::default();
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for (f, tris) in cube.triangles.chunks(per_face).enumerate() {
        let q = tris[0].map(|v| cube.positions[v as usize]);
        let axis = (0..3)
            .find(|&a| q[0][a] == q[1][a] && q[1][a] == q[2][a])
            .unwrap();
        let mut normal = [0.0; 3];
        normal[axis] = q[0][axis].signum();
        let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut local = BTreeMap::new();
        for t in tris {
            for &v in t {
                let id = *local.entry(v).or_insert_with(|| {
                    let x = cube.positions[v as usize];
                    p.positions.push(x);
                    normals.push(normal);
                    uvs.push([0.5 + 0.5 * x[u], (f as f32 + 0.5 + 0.5 * x[w]) / 6.0]);
                    p.positions.len() as u32 - 1
                });
                p.indices.push(id);
            }
        }
    }
    p.normals = Some(normals);
    p.texcoords = Some(uvs);
    SourceMesh {
        name: "cube".into(),
        primitives: vec![p],
    }
}

#[test]
fn cube_with_hard_normals_stays_flat_shaded_with_exact_normals() {
    let src = hard_cube();
    let lod = build(&src, &[0.5, 0.1, 0.02]);
    for (l, level) in lod.levels.iter().enumerate() {
        let p = &level.primitives[0];
        let normals = p.normals.as_ref().unwrap();
        let mut faces = BTreeSet::new();
        for t in p.indices.chunks_exact(3) {
            let c = [0, 1, 2].map(|k| t[k] as usize);
            // every corner has the face's own axis normal, bit for bit
            let n = normals[c[0]];
            assert!(
                c.iter().all(|&v| normals[v] == n),
                "level {l}: corners of one triangle differ: {:?}",
                c.map(|v| normals[v])
            );
            let axis = (0..3).find(|&a| n[a] != 0.0).unwrap();
            assert_eq!(n[axis].abs(), 1.0, "level {l}: normal {n:?}");
            assert!(c.iter().all(|&v| p.positions[v][axis] == n[axis]));
            faces.insert(n.map(f32::to_bits));
        }
        assert_eq!(faces.len(), 6, "level {l}: six flat faces");
    }
    // the coarsest level: two triangles per face
    assert_eq!(lod.levels[2].triangle_count(), 12);
}

/// A 16×16 grid with a UV seam along x = 0.5: the right half's UVs are
/// shifted by 2 (another chart).
fn seamed_textured_grid() -> SourceMesh {
    let g = lodgen_pm::shapes::grid(16, 16, |x, y| 0.05 * (3.0 * x).sin() * (2.0 * y).cos());
    let mut p = Primitive::default();
    let mut uvs = Vec::new();
    let mut ids = BTreeMap::new();
    for t in &g.triangles {
        let right = t.iter().map(|&v| g.positions[v as usize][0]).sum::<f32>() > 1.5;
        for &v in t {
            let id = *ids.entry((right, v)).or_insert_with(|| {
                let x = g.positions[v as usize];
                p.positions.push(x);
                uvs.push([x[0] + if right { 2.0 } else { 0.0 }, x[1]]);
                p.positions.len() as u32 - 1
            });
            p.indices.push(id);
        }
    }
    p.texcoords = Some(uvs);
    SourceMesh {
        name: "seamed".into(),
        primitives: vec![p],
    }
}

#[test]
fn textured_grid_keeps_its_uv_seam_at_every_level() {
    let src = seamed_textured_grid();
    let input_uv: BTreeSet<[u32; 2]> = src.primitives[0]
        .texcoords
        .as_ref()
        .unwrap()
        .iter()
        .map(|t| t.map(f32::to_bits))
        .collect();
    let lod = build(&src, &[0.5, 0.25, 0.1, 0.05]);
    for (l, level) in lod.levels.iter().enumerate() {
        let p = &level.primitives[0];
        let uv = p.texcoords.as_ref().unwrap();
        for t in p.indices.chunks_exact(3) {
            let c = [0, 1, 2].map(|k| t[k] as usize);
            // one chart per triangle: all corners left (u < 1.5) or right
            let right = c.map(|v| uv[v][0] > 1.5);
            assert!(
                right.iter().all(|&r| r == right[0]),
                "level {l}: spans the seam"
            );
            for v in c {
                let x = p.positions[v];
                // geometry on its side of the seam line
                assert!(
                    if right[0] { x[0] >= 0.5 } else { x[0] <= 0.5 },
                    "level {l}"
                );
                // seam vertices keep their input UVs exactly on both sides
                if x[0] == 0.5 {
                    assert!(
                        input_uv.contains(&uv[v].map(f32::to_bits)),
                        "level {l}: {:?}",
                        uv[v]
                    );
                }
            }
        }
    }
}

/// A flat 24×24 grid whose only attribute is a second UV set (`TEXCOORD_1`,
/// e.g. a lightmap) that bends: every collapse is free geometrically, so
/// any cost comes from pricing that set.
fn flat_grid_with_lightmap_uvs() -> SourceMesh {
    let n = 24u32;
    let mut p = Primitive::default();
    let mut uv1 = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            p.positions.push([x, y, 0.0]);
            // a lightmap chart with one sharp local distortion
            let bump = (-((x - 0.3).powi(2) + (y - 0.6).powi(2)) / 0.01).exp();
            uv1.push([x + 0.2 * bump, y - 0.2 * bump]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let (a, w) = (j * (n + 1) + i, n + 1);
            p.indices
                .extend_from_slice(&[a, a + 1, a + w + 1, a, a + w + 1, a + w]);
        }
    }
    p.extra_texcoords = vec![uv1];
    SourceMesh {
        name: "lightmapped".into(),
        primitives: vec![p],
    }
}

/// RMS distance between the input's `TEXCOORD_1` at its vertices and the
/// level's, interpolated at the same (x, y) (the grid stays flat at z = 0).
fn lightmap_error(input: &Primitive, level: &Primitive) -> f64 {
    let uv = level.extra_texcoords[0].as_slice();
    let mut sum = 0.0;
    for (p, want) in input.positions.iter().zip(&input.extra_texcoords[0]) {
        let got = level
            .indices
            .chunks_exact(3)
            .find_map(|t| {
                let [a, b, c] = [0, 1, 2].map(|k| level.positions[t[k] as usize]);
                let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
                let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (p[1] - a[1])) / det;
                let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
                let l = [1.0 - l1 - l2, l1, l2];
                l.iter().all(|&x| x >= -1e-5).then(|| {
                    [0, 1].map(|c| (0..3).map(|k| l[k] * uv[t[k] as usize][c]).sum::<f32>())
                })
            })
            .expect("the level covers the grid");
        sum += f64::from((got[0] - want[0]).powi(2) + (got[1] - want[1]).powi(2));
    }
    (sum / input.positions.len() as f64).sqrt()
}

#[test]
fn every_uv_set_is_priced_under_the_uv_weight() {
    let src = flat_grid_with_lightmap_uvs();
    let error = |uv: f32| {
        let opts = BuildOptions {
            levels: LevelRequest::Specs(vec![LevelSpec::Ratio(0.1)]),
            attribute_weights: lodgen::lod::AttributeWeights {
                uv,
                ..lodgen::lod::AttributeWeights::DEFAULT
            },
            ..BuildOptions::default()
        };
        let lod = build_one(0, &src, &opts, &mut |_| {}).unwrap().lod;
        lightmap_error(&src.primitives[0], &lod.levels[0].primitives[0])
    };
    let (priced, free) = (error(1.0), error(0.0));
    eprintln!("TEXCOORD_1 RMS error at 10 %: {priced:.5} priced, {free:.5} with uv = 0");
    // a flat grid gives geometry no say: only pricing TEXCOORD_1 keeps
    // vertices where the lightmap bends
    assert!(priced < 0.5 * free, "priced {priced} vs unpriced {free}");
}

/// The stream's attribute table: every set some primitive has, by its glTF
/// name, the input's values exactly, padding where a primitive lacks a set
/// (white for colours, zeros otherwise), the primitive as the group.
#[test]
fn stream_attributes_carry_every_set_of_every_primitive() {
    let mut src = eight_influence_strip();
    let bare = Primitive {
        positions: src.primitives[0].positions.clone(),
        indices: src.primitives[0].indices.clone(),
        ..Primitive::default()
    };
    src.primitives.push(bare);
    let a = lodgen::lod::stream_attributes(&src);
    let names: Vec<&str> = a.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        ["COLOR_1", "JOINTS_0", "WEIGHTS_0", "JOINTS_1", "WEIGHTS_1"]
    );
    let p = &src.primitives[0];
    let n = p.positions.len();
    assert_eq!(a.count, 2 * n);
    for v in 0..n {
        let mut want: Vec<f32> = p.extra_colors[0][v].to_vec();
        want.extend(p.joints.as_ref().unwrap()[v].map(f32::from));
        want.extend(p.weights.as_ref().unwrap()[v]);
        want.extend(p.extra_joints[0][v].map(f32::from));
        want.extend(p.extra_weights[0][v]);
        assert_eq!(a.wedge(v as u32), want.as_slice(), "vertex {v}");
        assert_eq!(a.group(v as u32), 0);
        let pad = a.wedge((n + v) as u32);
        assert_eq!(&pad[..4], &[1.0; 4]);
        assert!(pad[4..].iter().all(|&x| x == 0.0));
        assert_eq!(a.group((n + v) as u32), 1);
    }
}
