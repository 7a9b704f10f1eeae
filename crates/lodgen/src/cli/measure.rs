//! `lodgen measure`: the distance between the meshes two files draw.

use std::path::Path;

use anyhow::{bail, Context, Result};
use lodgen_pm::metric::{self, MeasureOptions, MeshRef};
use serde_json::json;

use crate::io;
use crate::scene::{Origin, Scene};

/// Every mesh the file's default scene draws (for glTF: the meshes on nodes
/// reachable from the scene, so coarser MSFT_lod levels are left out), merged
/// into one triangle list. Node transforms are not applied (`world_triangles` applies them).
pub fn merged_mesh(scene: &Scene) -> lodgen_pm::Mesh {
    let meshes: Vec<usize> = match &scene.origin {
        Origin::Gltf { document, .. } => {
            let mut out = Vec::new();
            let scene_index = document.scene.map_or(0, |s| s.value());
            let mut stack: Vec<usize> = document
                .scenes
                .get(scene_index)
                .map(|s| s.nodes.iter().map(|n| n.value()).collect())
                .unwrap_or_default();
            while let Some(n) = stack.pop() {
                if let Some(node) = document.nodes.get(n) {
                    if let Some(m) = node.mesh {
                        out.push(m.value());
                    }
                    stack.extend(node.children.iter().flatten().map(|c| c.value()));
                }
            }
            out.sort_unstable();
            out.dedup();
            out
        }
        Origin::Flat | Origin::Moved { .. } => (0..scene.meshes.len()).collect(),
    };
    let mut m = lodgen_pm::Mesh::default();
    for p in meshes
        .iter()
        .filter_map(|&i| scene.meshes.get(i))
        .flat_map(|m| &m.primitives)
    {
        let off = m.positions.len() as u32;
        m.positions.extend_from_slice(&p.positions);
        m.triangles.extend(
            p.indices
                .chunks_exact(3)
                .map(|c| [c[0] + off, c[1] + off, c[2] + off]),
        );
    }
    m
}

/// Positions in `f64` and triangles: [`world_triangles`].
pub type WorldTriangles = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// Every triangle the file's default scene draws, in the file's own coordinates, in `f64`:
/// glTF nodes' world transforms applied (read from the JSON as written, so a translation of
/// 5·10⁶ keeps its digits), a mesh drawn by two nodes twice, coarser `MSFT_lod` levels left
/// out; a far read's offset ([`Origin::Moved`]) added back.
pub fn world_triangles(scene: &Scene) -> WorldTriangles {
    use glam::{DMat4, DQuat, DVec3};
    let mut instances: Vec<(usize, DMat4)> = Vec::new();
    match &scene.origin {
        Origin::Gltf { document, json, .. } => {
            let nodes = json.get("nodes").and_then(|n| n.as_array());
            let num = |v: Option<&serde_json::Value>, k: usize, or: f64| {
                v.and_then(|a| a.get(k))
                    .and_then(|x| x.as_f64())
                    .unwrap_or(or)
            };
            let local = |n: usize| {
                let node = nodes.and_then(|ns| ns.get(n));
                let field = |name: &str| node.and_then(|x| x.get(name));
                if let Some(m) = field("matrix") {
                    return DMat4::from_cols_array(&std::array::from_fn(|k| {
                        num(Some(m), k, f64::from(u8::from(k % 5 == 0)))
                    }));
                }
                let (t, r, s) = (field("translation"), field("rotation"), field("scale"));
                let t = DVec3::new(num(t, 0, 0.0), num(t, 1, 0.0), num(t, 2, 0.0));
                let q = DQuat::from_xyzw(
                    num(r, 0, 0.0),
                    num(r, 1, 0.0),
                    num(r, 2, 0.0),
                    num(r, 3, 1.0),
                );
                let q = if q.length_squared() > 0.0 {
                    q.normalize()
                } else {
                    DQuat::IDENTITY
                };
                let s = DVec3::new(num(s, 0, 1.0), num(s, 1, 1.0), num(s, 2, 1.0));
                DMat4::from_scale_rotation_translation(s, q, t)
            };
            let scene_index = document.scene.map_or(0, |s| s.value());
            let roots: Vec<usize> = document
                .scenes
                .get(scene_index)
                .map(|s| s.nodes.iter().rev().map(|n| n.value()).collect())
                .unwrap_or_default();
            // depth first, each node once (a broken hierarchy does not loop)
            let mut seen = vec![false; document.nodes.len()];
            let mut stack: Vec<(usize, DMat4)> =
                roots.into_iter().map(|n| (n, DMat4::IDENTITY)).collect();
            while let Some((n, parent)) = stack.pop() {
                let Some(node) = document
                    .nodes
                    .get(n)
                    .filter(|_| !std::mem::replace(&mut seen[n], true))
                else {
                    continue;
                };
                let world = parent * local(n);
                if let Some(m) = node.mesh {
                    instances.push((m.value(), world));
                }
                for c in node.children.iter().flatten().rev() {
                    stack.push((c.value(), world));
                }
            }
        }
        Origin::Flat => instances.extend((0..scene.meshes.len()).map(|m| (m, DMat4::IDENTITY))),
        Origin::Moved { offset } => {
            let t = DMat4::from_translation(DVec3::from_array(*offset));
            instances.extend((0..scene.meshes.len()).map(|m| (m, t)));
        }
    }
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for (mesh, world) in instances {
        let Some(mesh) = scene.meshes.get(mesh) else {
            continue;
        };
        for p in &mesh.primitives {
            let off = positions.len() as u32;
            positions.extend(p.positions.iter().map(|&x| {
                world
                    .transform_point3(DVec3::from_array(x.map(f64::from)))
                    .to_array()
            }));
            triangles.extend(
                p.indices
                    .chunks_exact(3)
                    .map(|c| [c[0] + off, c[1] + off, c[2] + off]),
            );
        }
    }
    (positions, triangles)
}

/// At most this many area samples per direction (`--samples` beyond it
/// would ask for more memory than any machine has and abort the process).
pub const MAX_AREA_SAMPLES: usize = 1 << 27;

/// An error when `opts` would draw more than [`MAX_AREA_SAMPLES`] area
/// samples for meshes of `tris_a` and `tris_b` triangles.
pub fn check_sample_count(opts: &MeasureOptions, tris_a: usize, tris_b: usize) -> Result<()> {
    let n = opts.area_sample_count(tris_a, tris_b);
    if n > MAX_AREA_SAMPLES {
        bail!(
            "--samples {}: {n} area samples per direction for {} triangles, more than the {} \
             lodgen draws at most; lower --samples",
            opts.samples_per_triangle,
            tris_a.max(tris_b),
            MAX_AREA_SAMPLES
        );
    }
    Ok(())
}

/// `lodgen measure A B`: prints [`measure_report`].
pub fn measure_files(a: &Path, b: &Path, samples: f64, as_json: bool) -> Result<()> {
    print!("{}", measure_report(a, b, samples, as_json)?);
    Ok(())
}

/// What `lodgen measure A B` prints: a table, or JSON with `as_json`.
pub fn measure_report(a: &Path, b: &Path, samples: f64, as_json: bool) -> Result<String> {
    use std::fmt::Write as _;
    let mut out = String::new();
    if !(samples > 0.0 && samples.is_finite()) {
        bail!("--samples must be positive");
    }
    let read = |p: &Path| -> Result<WorldTriangles> {
        let scene = io::read_scene(p).with_context(|| format!("reading {}", p.display()))?;
        Ok(world_triangles(&scene))
    };
    let (wa, wb) = (read(a)?, read(b)?);
    // both in f32 about A's first vertex when it is far from the origin (a scan in UTM
    // coordinates, and its LODs with the offset in their nodes' translation)
    let frame = io::far_offset(wa.0.first().copied().unwrap_or_default()).unwrap_or([0.0; 3]);
    let in_frame = |(ps, triangles): WorldTriangles| lodgen_pm::Mesh {
        positions: ps
            .iter()
            .map(|p| std::array::from_fn(|k| (p[k] - frame[k]) as f32))
            .collect(),
        triangles,
    };
    let (ma, mb) = (in_frame(wa), in_frame(wb));
    let at =
        |p: Option<[f64; 3]>| p.map(|p| -> [f64; 3] { std::array::from_fn(|k| p[k] + frame[k]) });
    // (a scene can hold meshes none of its nodes draw: no distance to
    // measure, rather than an infinite one)
    for (p, m) in [(a, &ma), (b, &mb)] {
        if m.triangles.is_empty() {
            bail!("measuring: {} draws no triangles", p.display());
        }
    }
    let opts = MeasureOptions::DEFAULT.with_samples_per_triangle(samples);
    check_sample_count(&opts, ma.triangles.len(), mb.triangles.len())?;
    let r = metric::measure(
        MeshRef::new(&ma.positions, &ma.triangles),
        MeshRef::new(&mb.positions, &mb.triangles),
        &opts,
    )
    .context("measuring")?;
    if as_json {
        writeln!(
            out,
            "{}",
            serde_json::to_string_pretty(&json!({
                "a": a.display().to_string(), "b": b.display().to_string(),
                "diagonal": r.diagonal,
                "a_to_b": {"hausdorff": r.a_to_b.max, "at": at(r.a_to_b.at), "mean": r.a_to_b.mean, "rms": r.a_to_b.rms, "samples": r.a_to_b.samples},
                "b_to_a": {"hausdorff": r.b_to_a.max, "at": at(r.b_to_a.at), "mean": r.b_to_a.mean, "rms": r.b_to_a.rms, "samples": r.b_to_a.samples},
                "hausdorff_percent": r.hausdorff_percent(), "rms_percent": r.rms_percent(), "mean_percent": r.mean_percent(),
            }))?
        )?;
    } else {
        writeln!(
            out,
            "A = {} ({} triangles), B = {} ({} triangles)",
            a.display(),
            ma.triangles.len(),
            b.display(),
            mb.triangles.len()
        )?;
        writeln!(out, "bounding-box diagonal of A: {:.6}", r.diagonal)?;
        writeln!(
            out,
            "direction   hausdorff (% diag)       mean (% diag)            rms (% diag)"
        )?;
        for (name, d) in [("A -> B", r.a_to_b), ("B -> A", r.b_to_a)] {
            writeln!(
                out,
                "{name:<10}  {:<12.6e} ({:>7.4}%)  {:<12.6e} ({:>7.4}%)  {:<12.6e} ({:>7.4}%)",
                d.max,
                r.percent(d.max),
                d.mean,
                r.percent(d.mean),
                d.rms,
                r.percent(d.rms)
            )?;
        }
        writeln!(
            out,
            "symmetric   {:<12.6e} ({:>7.4}%)  {:<12.6e} ({:>7.4}%)  {:<12.6e} ({:>7.4}%)",
            r.hausdorff(),
            r.hausdorff_percent(),
            r.mean(),
            r.mean_percent(),
            r.rms(),
            r.rms_percent()
        )?;
        for (name, mesh, d) in [("A -> B", "A", r.a_to_b), ("B -> A", "B", r.b_to_a)] {
            if let Some([x, y, z]) = at(d.at) {
                writeln!(
                    out,
                    "{name} maximum at ({x:.6}, {y:.6}, {z:.6}), a point of {mesh}"
                )?;
            }
        }
    }
    Ok(out)
}
