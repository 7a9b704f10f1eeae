//! The command line's building blocks, in the library so tests and the
//! xtask drive exactly what users run: argument types (clap), level-list
//! parsing, the build job (read → LODs → write → table / JSON report) and
//! `measure`.
//!
//! Owns user-facing text (tables, progress, error context). The algorithms
//! are in `lod` and the core; formats in `io` and `gltf_out`.

use crate::gltf_out::{self, Compression, WriteOptions};
use crate::io;
use crate::lod::{self, AttributeWeights, BuildOptions, LevelRequest, MeshBuild, Progress};
use crate::scene::{Origin, Scene};
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use lodgen_pm::levels::LevelSpec;
use lodgen_pm::metric::{self, MeasureOptions, MeshRef};
use lodgen_pm::{Boundary, Placement, Schedule, SimplifyOptions, Tau, DEFAULT_BOUNDARY_WEIGHT};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of the main job (`lodgen INPUT ...`).
#[derive(Args, Debug, Clone)]
pub struct BuildArgs {
    /// Input mesh: .obj, .ply (ascii or binary), .smf, .gltf or .glb.
    /// Several inputs, directories (walked recursively) or quoted glob
    /// patterns ("assets/**/*.obj") build a batch into --out-dir.
    #[arg(value_name = "INPUT")]
    pub inputs: Vec<PathBuf>,

    #[command(flatten)]
    pub batch: crate::batch::BatchFlags,

    /// Output file, .glb or .gltf (.gltf writes one .bin per level beside
    /// it). Default: the input's name with .glb, beside the input
    /// (INPUT.lod.glb when the input is itself a .glb).
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,

    /// Levels to build, finest first or in any order, comma-separated:
    /// ratios of the input's triangles ("50%", or a fraction like 0.5) or
    /// absolute triangle counts ("20000"). All levels come from one
    /// simplification pass.
    #[arg(
        long,
        value_name = "LIST",
        default_value = "50%,10%,2%",
        conflicts_with = "max_error"
    )]
    pub levels: String,

    /// Build levels by measured error instead: for each bound (in % of the
    /// bounding-box diagonal, e.g. "0.1%,0.5%,2%") the coarsest level whose
    /// measured symmetric Hausdorff distance stays within it.
    #[arg(long, value_name = "LIST")]
    pub max_error: Option<String>,

    /// Pair threshold τ: vertices closer than this may merge even without
    /// an edge (joins separate parts). In mesh units ("0.01") or in % of the
    /// bounding-box diagonal ("0.5%"). 0 = edge collapses only.
    #[arg(long, value_name = "DIST", default_value = "0")]
    pub tau: String,

    /// How open borders are kept: "weighted" adds constraint planes (border
    /// vertices may merge along the border), "locked" never touches them.
    #[arg(long, value_enum, default_value_t = BoundaryMode::Weighted)]
    pub boundary: BoundaryMode,

    /// Weights of attributes in the cost (Hoppe 1999 attribute quadrics),
    /// e.g. "normal=0.5,uv=1,color=0.5" (unnamed ones keep their default).
    /// 1 makes an attribute difference of 1 cost like a displacement by the
    /// bounding-box diagonal; 0 leaves an attribute out. "uv" weighs every
    /// TEXCOORD_n set, "color" every COLOR_n set. Seams, hard edges
    /// and material borders are kept whatever the weights. The defaults
    /// measured best on spot.obj (`cargo xtask attributes`, ARCHITECTURE.md).
    #[arg(
        long,
        value_name = "LIST",
        default_value = "normal=0.05,uv=0.5,color=0.5"
    )]
    pub attribute_weights: String,

    /// Weight of the border constraint planes relative to the face planes
    /// (with --boundary weighted; scaled by edge length²).
    #[arg(long, value_name = "W", default_value_t = DEFAULT_BOUNDARY_WEIGHT)]
    pub boundary_weight: f64,

    /// Where a merged pair's vertex goes: "optimal" solves the quadric,
    /// "half-edge" keeps one of the two (every level then reuses input
    /// positions).
    #[arg(long, value_enum, default_value_t = PlacementMode::Optimal)]
    pub placement: PlacementMode,

    /// Order of the contractions (method qem): "passes" costs every pair,
    /// then contracts the cheapest first, each vertex at most once per pass
    /// (meshoptimizer's schedule, the fast one); "greedy" is
    /// Garland–Heckbert to the letter, one heap, always the cheapest pair
    /// next (about twice as slow, same error on the meshes measured).
    #[arg(long, value_enum, default_value_t = ScheduleMode::Passes)]
    pub schedule: ScheduleMode,

    /// Simplification method: "qem" (Garland–Heckbert pair contraction),
    /// the curvature-adaptive operators of seed 001 — "edge" (full edge
    /// collapse to the midpoint), "half-edge", "triangle" (three vertices to
    /// the centroid) — which only touch low-curvature, non-border vertices
    /// and may stop before the target, or "qem-curvature" (QEM with costs
    /// scaled by 1 + w·θ/θmax). See docs/compare.md for how they compare.
    #[arg(long, default_value = "qem", value_parser = ["qem", "edge", "half-edge", "triangle", "qem-curvature"])]
    pub method: String,

    /// Curvature classification of the adaptive methods: "sigma" (a vertex
    /// is high-curvature when θ > mean + 2σ), "median" (the lower half is
    /// removable), or a fraction such as 0.7 (that share is removable).
    #[arg(long, value_name = "RULE", default_value = "sigma")]
    pub curvature_threshold: String,

    /// Depth k of the k-ring umbrella over which the region normal is
    /// averaged (adaptive methods).
    #[arg(long, value_name = "K", default_value_t = lodgen_pm::AdaptiveOptions::DEFAULT.k_ring)]
    pub k_ring: usize,

    /// Weight w of the curvature term in --method qem-curvature.
    #[arg(long, value_name = "W", default_value_t = lodgen_pm::AdaptiveOptions::DEFAULT.hybrid_weight)]
    pub curvature_weight: f64,

    /// Weight every face plane equally instead of by triangle area.
    #[arg(long)]
    pub uniform_weights: bool,

    /// Write quantized vertex data (KHR_mesh_quantization): 16-bit
    /// positions, 8-bit normals, 16-bit UVs.
    #[arg(long)]
    pub quantize: bool,

    /// Geometry compression: "none", or "meshopt" (EXT_meshopt_compression,
    /// with an uncompressed fallback buffer).
    #[arg(long, value_enum, default_value_t = CompressMode::None)]
    pub compress: CompressMode,

    /// Also store the vertex-split stream (glTF extension LODGEN_progressive,
    /// docs/LODGEN_progressive.md) on each mesh's coarsest level, for
    /// viewers that refine while downloading (`lodgen view`). Off by default.
    #[arg(long)]
    pub progressive: bool,

    /// Also write the table as JSON to this file (in batch mode: every
    /// file's report with its status, error and time).
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,

    /// Area samples per triangle for the error measurement (plus every
    /// vertex).
    #[arg(long, value_name = "N", default_value_t = MeasureOptions::DEFAULT.samples_per_triangle)]
    pub samples: f64,

    /// Measure each level's error against the input (`on`), or skip it for
    /// speed (`off`): errors and screen coverages then come from the
    /// simplifier's own estimate (the quadric error of the contractions
    /// still in a level), marked `≈` in the table; RMS is not known.
    #[arg(long, value_enum, value_name = "on|off", default_value = "on")]
    pub measure: MeasureMode,

    /// Floor per mesh, in triangles: no level has fewer (nor fewer than 1),
    /// so a mesh with at most this many (a quad, a card, a decal) is written
    /// unsimplified. A mesh too small for its requested levels keeps its
    /// coarsest allowed mesh for them; levels that coincide are written
    /// once, so its chain is shorter, and the table says so in a note.
    #[arg(long, value_name = "N", default_value_t = lod::DEFAULT_MIN_TRIANGLES)]
    pub min_triangles: usize,

    /// No table, no progress bar; errors only.
    #[arg(short, long)]
    pub quiet: bool,

    /// Also print simplification statistics: collapses, rejections by
    /// reason, time per phase.
    #[arg(short, long)]
    pub verbose: bool,
}

/// `--measure`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeasureMode {
    On,
    Off,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundaryMode {
    Weighted,
    Locked,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlacementMode {
    Optimal,
    HalfEdge,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScheduleMode {
    Passes,
    Greedy,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompressMode {
    None,
    Meshopt,
}

/// Parse `--levels`: "50%", "0.5" (ratios) or "20000" (triangle counts).
pub fn parse_levels(list: &str) -> Result<Vec<LevelSpec>> {
    let mut out = Vec::new();
    for item in list.split(',').map(str::trim) {
        if item.is_empty() {
            bail!("--levels {list:?}: empty entry");
        }
        let spec = if let Some(p) = item.strip_suffix('%') {
            let v: f64 = p
                .trim()
                .parse()
                .with_context(|| format!("--levels: {item:?} is not a percentage"))?;
            if !(v > 0.0 && v <= 100.0) {
                bail!("--levels: {item:?} must be in (0%, 100%]");
            }
            LevelSpec::Ratio(v / 100.0)
        } else if let Ok(n) = item.parse::<usize>() {
            if n == 0 {
                bail!("--levels: a level needs at least one triangle");
            }
            LevelSpec::Triangles(n)
        } else {
            let v: f64 = item.parse().with_context(|| {
                format!(
                    "--levels: {item:?} is neither a percentage, a fraction nor a triangle count"
                )
            })?;
            if !(v > 0.0 && v <= 1.0) {
                bail!("--levels: the fraction {item:?} must be in (0, 1]");
            }
            LevelSpec::Ratio(v)
        };
        out.push(spec);
    }
    Ok(out)
}

/// Parse `--max-error`: percentages of the bounding-box diagonal, returned
/// as fractions.
pub fn parse_max_errors(list: &str) -> Result<Vec<f64>> {
    list.split(',')
        .map(str::trim)
        .map(|item| {
            let p = item.strip_suffix('%').with_context(|| {
                format!("--max-error: {item:?} must be a percentage of the bounding-box diagonal, e.g. 0.5%")
            })?;
            let v: f64 = p
                .trim()
                .parse()
                .with_context(|| format!("--max-error: {item:?} is not a number"))?;
            if !(v >= 0.0 && v.is_finite()) {
                bail!("--max-error: {item:?} must be a finite, non-negative percentage");
            }
            Ok(v / 100.0)
        })
        .collect()
}

/// Parse `--attribute-weights`: `name=weight` items (`normal`, `uv`,
/// `color`), comma-separated; names left out keep their default.
pub fn parse_attribute_weights(list: &str) -> Result<AttributeWeights> {
    let mut w = AttributeWeights::DEFAULT;
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (name, value) = item.split_once('=').with_context(|| {
            format!("--attribute-weights: {item:?} must be name=weight, e.g. normal=0.5")
        })?;
        let v: f32 = value
            .trim()
            .parse()
            .with_context(|| format!("--attribute-weights: {value:?} is not a number"))?;
        if !(v >= 0.0 && v.is_finite()) {
            bail!("--attribute-weights: {item:?} must be finite and non-negative");
        }
        match name.trim() {
            "normal" => w.normal = v,
            "uv" => w.uv = v,
            "color" => w.color = v,
            other => bail!("--attribute-weights: unknown attribute {other:?} (normal, uv, color)"),
        }
    }
    Ok(w)
}

/// Parse `--tau`: mesh units, or "%" of the bounding-box diagonal.
pub fn parse_tau(s: &str) -> Result<Tau> {
    let s = s.trim();
    let (v, pct) = match s.strip_suffix('%') {
        Some(p) => (p.trim(), true),
        None => (s, false),
    };
    let v: f64 = v
        .parse()
        .with_context(|| format!("--tau: {s:?} is not a distance"))?;
    if !(v >= 0.0 && v.is_finite()) {
        bail!("--tau: {s:?} must be finite and non-negative");
    }
    Ok(if pct {
        Tau::DiagonalFraction(v / 100.0)
    } else {
        Tau::Absolute(v)
    })
}

impl BuildArgs {
    /// The library options these arguments mean.
    pub fn build_options(&self) -> Result<BuildOptions> {
        let levels = match &self.max_error {
            Some(list) => LevelRequest::MaxErrors(parse_max_errors(list)?),
            None => LevelRequest::Specs(parse_levels(&self.levels)?),
        };
        if !(self.boundary_weight >= 0.0 && self.boundary_weight.is_finite()) {
            bail!("--boundary-weight must be finite and non-negative");
        }
        if !(self.samples > 0.0 && self.samples.is_finite()) {
            bail!("--samples must be positive");
        }
        let simplify = SimplifyOptions::DEFAULT
            .with_tau(parse_tau(&self.tau)?)
            .with_area_weighted(!self.uniform_weights)
            .with_boundary(match self.boundary {
                BoundaryMode::Weighted => Boundary::Weighted(self.boundary_weight),
                BoundaryMode::Locked => Boundary::Locked,
            })
            .with_placement(match self.placement {
                PlacementMode::Optimal => Placement::Optimal,
                PlacementMode::HalfEdge => Placement::HalfEdge,
            })
            .with_schedule(match self.schedule {
                ScheduleMode::Passes => SimplifyOptions::DEFAULT.schedule,
                ScheduleMode::Greedy => Schedule::Greedy,
            });
        let method: lodgen_pm::Method = self
            .method
            .parse()
            .map_err(|e| anyhow::anyhow!("--method {:?}: {e:?}", self.method))?;
        let threshold = match self.curvature_threshold.trim() {
            "sigma" => lodgen_pm::Threshold::Sigma(lodgen_pm::adaptive::DEFAULT_SIGMA),
            "median" => lodgen_pm::Threshold::Median,
            other => {
                let f: f64 = other.parse().with_context(|| {
                    format!("--curvature-threshold: {other:?} is not sigma, median or a fraction")
                })?;
                if !(f > 0.0 && f < 1.0) {
                    bail!("--curvature-threshold: the fraction {other:?} must be in (0, 1)");
                }
                lodgen_pm::Threshold::Fraction(f)
            }
        };
        if self.k_ring == 0 {
            bail!("--k-ring must be at least 1");
        }
        if !(self.curvature_weight >= 0.0 && self.curvature_weight.is_finite()) {
            bail!("--curvature-weight must be finite and non-negative");
        }
        let adaptive = lodgen_pm::AdaptiveOptions::DEFAULT
            .with_threshold(threshold)
            .with_k_ring(self.k_ring)
            .with_hybrid_weight(self.curvature_weight);
        Ok(BuildOptions {
            levels,
            simplify,
            method,
            adaptive,
            measure: MeasureOptions::DEFAULT.with_samples_per_triangle(self.samples),
            measured: self.measure == MeasureMode::On,
            attribute_weights: parse_attribute_weights(&self.attribute_weights)?,
            min_triangles: self.min_triangles,
        })
    }

    pub fn write_options(&self) -> WriteOptions {
        WriteOptions {
            quantize: self.quantize,
            compression: match self.compress {
                CompressMode::None => Compression::None,
                CompressMode::Meshopt => Compression::Meshopt,
            },
        }
    }
}

/// The default output path for `input`.
pub fn default_output(input: &Path) -> PathBuf {
    let stem = input.file_stem().map_or_else(
        || std::ffi::OsString::from("out"),
        std::ffi::OsStr::to_os_string,
    );
    let mut name = stem.clone();
    name.push(".glb");
    let candidate = input.with_file_name(&name);
    if candidate == input {
        let mut name = stem;
        name.push(".lod.glb");
        input.with_file_name(name)
    } else {
        candidate
    }
}

/// What one build job made: the scene read, its LOD builds and the bytes of
/// each level as written.
pub struct BuiltFile {
    pub output: PathBuf,
    pub scene: Scene,
    pub builds: Vec<MeshBuild>,
    pub level_bytes: Vec<Vec<u64>>,
    /// Wall time of reading, building (all meshes) and writing.
    pub times: crate::summary::FileTimes,
}

impl BuiltFile {
    /// The JSON `--report` of this file.
    pub fn report_json(&self, input: &Path) -> serde_json::Value {
        let mut report = report_json(
            input,
            &self.output,
            &self.scene,
            &self.builds,
            &self.level_bytes,
        );
        crate::summary::extend_report(&mut report, self);
        report
    }
}

/// Read → LODs → write (→ LODGEN_progressive) for one file, without
/// printing: what `lodgen INPUT` and each file of a batch run.
pub fn build_file(
    input: &Path,
    output: &Path,
    args: &BuildArgs,
    on_progress: &mut dyn FnMut(Progress),
) -> Result<BuiltFile> {
    let opts = args.build_options()?;
    if output == input {
        bail!("the output {} would overwrite the input", output.display());
    }
    on_progress(Progress::Reading);
    let t_read = Instant::now();
    let scene = io::read_scene(input).with_context(|| format!("reading {}", input.display()))?;
    let read = t_read.elapsed();
    let t_build = Instant::now();
    let builds = lod::build_lods(&scene, &opts, on_progress)
        .with_context(|| format!("simplifying {}", input.display()))?;
    let build = t_build.elapsed();
    on_progress(Progress::Writing);
    let t_write = Instant::now();
    let lods: Vec<_> = builds.iter().map(|b| b.lod.clone()).collect();
    let summary = gltf_out::write_lods(output, &scene, &lods, &args.write_options())
        .with_context(|| format!("writing {}", output.display()))?;
    // --- LODGEN_progressive (issue 6): append each mesh's split stream ---
    if args.progressive {
        let chains = builds
            .iter()
            .map(|b| crate::progressive::ChainStream::from_build(b, &scene.meshes[b.lod.source]))
            .collect::<Result<Vec<_>, _>>()
            .context("encoding the vertex-split stream")?;
        crate::progressive::embed(output, &chains)
            .with_context(|| format!("adding LODGEN_progressive to {}", output.display()))?;
    }
    // --- end LODGEN_progressive ---
    let write = t_write.elapsed();
    let level_bytes: Vec<Vec<u64>> = summary
        .meshes
        .iter()
        .map(|m| m.level_bytes.clone())
        .collect();
    Ok(BuiltFile {
        output: output.to_path_buf(),
        scene,
        builds,
        level_bytes,
        times: crate::summary::FileTimes { read, build, write },
    })
}

/// The main job. Prints the table (unless quiet) and writes the report.
pub fn build(input: &Path, args: &BuildArgs, show_progress: bool) -> Result<()> {
    let output = args.output.clone().unwrap_or_else(|| default_output(input));
    let t0 = Instant::now();
    let bar = show_progress.then(|| {
        let b = indicatif::ProgressBar::new_spinner();
        if let Ok(style) = indicatif::ProgressStyle::with_template("{spinner} {elapsed:>3} {msg}") {
            b.set_style(style);
        }
        b.enable_steady_tick(std::time::Duration::from_millis(120));
        b
    });
    // Phase start, for the measuring ETA (levels take similar times).
    let mut phase_start = Instant::now();
    let mut on_progress = |p: Progress| {
        let Some(b) = &bar else { return };
        let msg = match p {
            Progress::Reading => format!("reading {}", input.display()),
            Progress::Writing => format!("writing {}", output.display()),
            Progress::Simplifying { mesh, of } => format!("simplifying mesh {}/{of}", mesh + 1),
            Progress::Measuring { mesh, level, of } => {
                if level == 0 {
                    phase_start = Instant::now();
                }
                let eta = if level > 0 {
                    let per = phase_start.elapsed().as_secs_f64() / level as f64;
                    format!(", about {:.0} s left", per * (of - level) as f64)
                } else {
                    String::new()
                };
                format!("mesh {}: measuring level {}/{of}{eta}", mesh + 1, level + 1)
            }
        };
        b.set_message(msg);
    };
    let built = build_file(input, &output, args, &mut on_progress)?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let elapsed = t0.elapsed();
    let BuiltFile {
        builds,
        level_bytes,
        ..
    } = &built;
    if !args.quiet {
        print!("{}", table(builds, level_bytes));
        if args.verbose {
            eprint!("{}", crate::summary::verbose(&built, elapsed));
        }
        println!(
            "wrote {} in {:.2} s",
            output.display(),
            elapsed.as_secs_f64()
        );
    }
    if let Some(path) = &args.report {
        let json = built.report_json(input);
        write_atomically(path, serde_json::to_string_pretty(&json)?.as_bytes())
            .with_context(|| format!("writing the report {}", path.display()))?;
    }
    Ok(())
}

/// Why a simplification stopped short of its target, in words: where it
/// stopped, and the refusals that stopped it, most frequent first.
pub fn stop_note(stop: lodgen_pm::StopReason, stats: &lodgen_pm::Stats) -> String {
    let r = &stats.rejected;
    let mut why: Vec<(usize, &str)> = vec![
        (
            r.feature,
            "would move a seam, hard edge or material border off its line",
        ),
        (r.link, "would make the surface non-manifold"),
        (r.flip, "would flip a face"),
        (
            r.duplicate,
            "would flatten a closed part into a double-sided sheet",
        ),
        (r.degenerate, "would leave a sliver"),
        (r.boundary_pinch, "would pinch two borders together"),
        (
            r.locked,
            "would join two locked vertices (non-manifold input, or --boundary locked)",
        ),
        (r.error, "would exceed --max-error"),
    ];
    why.retain(|w| w.0 > 0);
    why.sort_by_key(|w| std::cmp::Reverse(w.0));
    let reasons: Vec<String> = why.iter().map(|(n, w)| format!("{n} {w}")).collect();
    let head = match stop {
        lodgen_pm::StopReason::MaxError => "every remaining contraction exceeds the error bound",
        _ => "no legal contraction is left",
    };
    format!(
        "simplification stopped at {} triangles, before the coarsest requested level: {head}{}; \
         coarser levels would repeat this one and are not written",
        stats.output_triangles,
        if reasons.is_empty() {
            String::new()
        } else {
            format!(" (of the candidates refused, {})", reasons.join(", "))
        }
    )
}

/// The per-mesh table printed on stdout.
pub fn table(builds: &[MeshBuild], bytes: &[Vec<u64>]) -> String {
    let mut s = String::new();
    for (i, b) in builds.iter().enumerate() {
        let st = &b.simplified;
        s += &format!(
            "{} ({} triangles, {} vertices after welding)\n",
            if b.lod.name.is_empty() {
                format!("mesh {i}")
            } else {
                b.lod.name.clone()
            },
            st.stats.input_triangles,
            st.stats.input_vertices
        );
        if st.stop != lodgen_pm::StopReason::Target {
            s += &format!("  note: {}\n", stop_note(st.stop, &st.stats));
        }
        for n in &b.notes {
            s += &format!("  note: {n}\n");
        }
        s += "  level  triangles  vertices  hausdorff %  rms %     coverage    bytes\n";
        for (k, (l, e)) in b.lod.levels.iter().zip(&b.errors).enumerate() {
            let verts: usize = l.primitives.iter().map(|p| p.positions.len()).sum();
            // --measure off: the quadric's estimate, marked ≈; RMS unknown
            let (h, rms) = if b.measured {
                (
                    format!("{:.4}", e.hausdorff_percent()),
                    format!("{:.4}", e.rms_percent()),
                )
            } else {
                (format!("≈{:.4}", e.hausdorff_percent()), "—".to_string())
            };
            s += &format!(
                "  {k:>5}  {:>9}  {:>8}  {h:>11}  {rms:>8}  {:>10.3e}  {:>8}\n",
                l.triangle_count(),
                verts,
                l.screen_coverage,
                bytes.get(i).and_then(|b| b.get(k)).copied().unwrap_or(0),
            );
        }
    }
    s
}

fn report_json(
    input: &Path,
    output: &Path,
    scene: &Scene,
    builds: &[MeshBuild],
    bytes: &[Vec<u64>],
) -> serde_json::Value {
    json!({
        "input": input.display().to_string(),
        "output": output.display().to_string(),
        "meshes": builds.iter().enumerate().map(|(i, b)| json!({
            "name": b.lod.name,
            "source_mesh": b.lod.source,
            "input_triangles": scene.meshes[b.lod.source].primitives.iter().map(|p| p.triangle_count()).sum::<usize>(),
            "welded_triangles": b.simplified.stats.input_triangles,
            "measured": b.measured,
            "stop": format!("{:?}", b.simplified.stop),
            "notes": b.notes,
            "levels": b.lod.levels.iter().zip(&b.errors).zip(&b.level_splits).enumerate().map(|(k, ((l, e), s))| json!({
                "triangles": l.triangle_count(),
                "vertices": l.primitives.iter().map(|p| p.positions.len()).sum::<usize>(),
                "splits": s,
                "hausdorff_percent": e.hausdorff_percent(),
                "rms_percent": e.rms_percent(),
                "mean_percent": e.mean_percent(),
                "original_to_level_percent": e.percent(e.a_to_b.max),
                "level_to_original_percent": e.percent(e.b_to_a.max),
                "screen_coverage": l.screen_coverage,
                "bytes": bytes.get(i).and_then(|b| b.get(k)).copied().unwrap_or(0),
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

/// Write `bytes` to a temporary file beside `path`, then rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        })
}

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
    let r = metric::measure(
        MeshRef::new(&ma.positions, &ma.triangles),
        MeshRef::new(&mb.positions, &mb.triangles),
        &MeasureOptions::DEFAULT.with_samples_per_triangle(samples),
    )
    .context("measuring")?;
    if as_json {
        writeln!(
            out,
            "{}",
            serde_json::to_string_pretty(&json!({
                "a": a.display().to_string(), "b": b.display().to_string(),
                "diagonal": r.diagonal,
                "a_to_b": {"hausdorff": r.a_to_b.max, "mean": r.a_to_b.mean, "rms": r.a_to_b.rms, "samples": r.a_to_b.samples},
                "b_to_a": {"hausdorff": r.b_to_a.max, "mean": r.b_to_a.mean, "rms": r.b_to_a.rms, "samples": r.b_to_a.samples},
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
    }
    Ok(out)
}

/// FNV-1a, 64 bit: a small, stable hash for golden summaries.
fn fnv1a(hash: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *hash ^= u64::from(b);
        *hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

/// The golden summary of LOD builds (`assets/golden/*.txt`): per level the
/// triangle and vertex counts, measured errors, and a hash of the index data
/// and of the positions quantized to 2⁻¹⁶ of the bounding-box diagonal.
pub fn golden_summary(title: &str, builds: &[MeshBuild]) -> String {
    let mut s = format!(
        "# lodgen golden summary: {title}\n# regenerate with `cargo xtask golden` and commit\n"
    );
    for b in builds {
        let full = b.simplified.pm.mesh_at_splits(b.simplified.pm.len());
        let (lo, _) = full.bounds().unwrap_or(([0.0; 3], [0.0; 3]));
        let diag = full.diagonal().max(f64::MIN_POSITIVE);
        s += &format!(
            "mesh {:?} welded_triangles {} welded_vertices {}\n",
            b.lod.name, b.simplified.stats.input_triangles, b.simplified.stats.input_vertices
        );
        for (k, (l, e)) in b.lod.levels.iter().zip(&b.errors).enumerate() {
            let mut h = 0xcbf2_9ce4_8422_2325u64;
            for p in &l.primitives {
                for i in &p.indices {
                    fnv1a(&mut h, &i.to_le_bytes());
                }
                for v in &p.positions {
                    for c in 0..3 {
                        let q =
                            ((f64::from(v[c]) - f64::from(lo[c])) / diag * 65536.0).round() as i64;
                        fnv1a(&mut h, &q.to_le_bytes());
                    }
                }
            }
            s += &format!(
                "level {k} triangles {} vertices {} hausdorff_percent {:.6} rms_percent {:.6} hash {h:016x}\n",
                l.triangle_count(),
                l.primitives.iter().map(|p| p.positions.len()).sum::<usize>(),
                e.hausdorff_percent(),
                e.rms_percent(),
            );
        }
    }
    s
}
