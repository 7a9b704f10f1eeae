//! `lodgen measure`: the distance between the meshes two files draw.

use std::path::Path;

use anyhow::{bail, Context, Result};
use lodgen_pm::metric::{self, MeasureOptions, MeshRef};
use serde_json::json;

use crate::io;
use crate::scene::{Origin, Scene};

/// Every mesh the file's default scene draws (for glTF: the meshes on nodes
/// reachable from the scene, so coarser MSFT_lod levels are left out), merged
/// into one triangle list. Node transforms are not applied.
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
        Origin::Flat => (0..scene.meshes.len()).collect(),
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
    let read = |p: &Path| -> Result<lodgen_pm::Mesh> {
        let scene = io::read_scene(p).with_context(|| format!("reading {}", p.display()))?;
        Ok(merged_mesh(&scene))
    };
    let (ma, mb) = (read(a)?, read(b)?);
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
                "a_to_b": {"hausdorff": r.a_to_b.max, "at": r.a_to_b.at, "mean": r.a_to_b.mean, "rms": r.a_to_b.rms, "samples": r.a_to_b.samples},
                "b_to_a": {"hausdorff": r.b_to_a.max, "at": r.b_to_a.at, "mean": r.b_to_a.mean, "rms": r.b_to_a.rms, "samples": r.b_to_a.samples},
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
            if let Some([x, y, z]) = d.at {
                writeln!(
                    out,
                    "{name} maximum at ({x:.6}, {y:.6}, {z:.6}), a point of {mesh}"
                )?;
            }
        }
    }
    Ok(out)
}
