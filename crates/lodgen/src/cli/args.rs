//! The arguments of the main job (clap): [`BuildArgs`], the mode enums,
//! level-list / error-list / weight / τ parsing, and their translation into
//! [`BuildOptions`] and [`WriteOptions`].

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use lodgen_pm::levels::LevelSpec;
use lodgen_pm::metric::MeasureOptions;
use lodgen_pm::{
    Boundary, Placement, Schedule, SimplifyOptions, Tau, TopologyChange, DEFAULT_BOUNDARY_WEIGHT,
};

use crate::gltf_out::{Compression, WriteOptions};
use crate::lod::{self, AttributeWeights, BuildOptions, LevelRequest};

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
        conflicts_with = "max_error",
        allow_hyphen_values = true
    )]
    pub levels: String,

    /// Build levels by measured error instead: for each bound (in % of the
    /// bounding-box diagonal, e.g. "0.1%,0.5%,2%") a level whose measured
    /// symmetric Hausdorff distance stays within it while the level one
    /// collapse coarser exceeds it, found by binary search over the
    /// collapse sequence. The error rises in steps (one collapse can move it
    /// from well under the bound to over it), so the level's error may sit
    /// far below the bound; where the error is not monotone a coarser level
    /// may also be within the bound and not be found.
    #[arg(long, value_name = "LIST", allow_hyphen_values = true)]
    pub max_error: Option<String>,

    /// Pair threshold τ: vertices closer than this may merge even without
    /// an edge (joins separate parts). In mesh units ("0.01") or in % of the
    /// bounding-box diagonal ("0.5%"). 0 = edge collapses only.
    #[arg(
        long,
        value_name = "DIST",
        default_value = "0",
        allow_hyphen_values = true
    )]
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
    #[arg(
        long,
        value_name = "W",
        default_value_t = DEFAULT_BOUNDARY_WEIGHT,
        allow_negative_numbers = true
    )]
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

    /// Keep the tips of thin parts (a tail, a horn, a spout): each pass
    /// (schedule "passes") also puts off a contraction that moves the
    /// surface farther than FACTOR × the pass's spread bound. On by default
    /// with FACTOR 1.1, the factor measured best over the quality table
    /// (docs/quality.md: Hausdorff against the best other simplifier per
    /// cell 1.14× → 0.92× in geometric mean, for 2–5 % more CPU over a
    /// whole run); "off" turns it off.
    #[arg(
        long,
        value_name = "FACTOR|off",
        num_args = 0..=1,
        allow_negative_numbers = true,
        default_value = "1.1",
        default_missing_value = "1.1"
    )]
    pub reach: String,

    /// With reach on, also defer a contraction one of whose new faces
    /// leaves the old surface farther than FACTOR × the reach distance (the
    /// midpoints of its new edges; reach tests vertices only), while a
    /// tenth of the input's triangles live. Off by default; with no value,
    /// 1.2. Lowers the Hausdorff distance of most 50 % and 10 % levels
    /// (bunny 10 % 0.25 → 0.16 %, positions only), raises the bunny's 2 %
    /// level (0.52 → 0.70 %), 3–6 % more CPU (docs/quality.md, "The new
    /// faces' reach, cheaper").
    #[arg(
        long,
        value_name = "FACTOR|off",
        num_args = 0..=1,
        allow_negative_numbers = true,
        default_value = "off",
        default_missing_value = "1.2"
    )]
    pub reach_faces: String,

    /// Reach every requested triangle count, at any price to the
    /// surface's topology and features: when no contraction that keeps
    /// them is left (the table's note says where a mesh stopped, and why),
    /// go on with the refused kinds, one more each time the run is stuck
    /// again — joins that make the surface non-manifold or pinch two
    /// borders together, closed parts flattened into double-sided sheets,
    /// seams and hard edges leaving their lines, faces turning over —
    /// cheapest first. Without it (the default), a run that the topology
    /// stops above the coarsest level runs again allowing joins and
    /// flattening only (docs/quality.md, "Reaching the count").
    #[arg(long, conflicts_with = "keep_topology")]
    pub allow_topology_change: bool,

    /// Never change the surface's topology: a mesh whose topology holds its
    /// triangles (non-manifold edges, many border loops) stops above the
    /// coarsest level instead of running again with joins and flattening
    /// allowed (the default).
    #[arg(long)]
    pub keep_topology: bool,

    /// Polish each written level: after simplification, move its vertices
    /// towards the original surface (one round of least-squares moves
    /// against the original's vertices and points on the level's faces,
    /// paired through the simplification's own clusters; borders held on
    /// their lines, no face turned over). Lowers the levels' RMS error by
    /// up to 31 % and most Hausdorff errors on the quality table
    /// (docs/quality.md, "The polish from the clusters"), for about 1.7x
    /// the CPU time of a bunny's run. The written levels
    /// and their reported errors are the polished ones; the progressive
    /// mesh (`--progressive`) keeps the simplifier's positions. Off by
    /// default.
    #[arg(long)]
    pub polish: bool,

    /// Fix each written level's worst spot, in up to ROUNDS rounds (6 when
    /// no value is given: `--fix-worst` or `--fix-worst=3`). A round moves
    /// the three corners of the level's face at its maximum distance (the
    /// four of two faces when it lies on their edge) to lower the largest
    /// distance around them, measures the level again and keeps the move
    /// only if the Hausdorff distance fell and the RMS stayed within 2 %;
    /// when that gains nothing, other spots about as far as the maximum
    /// (a symmetric mesh's equal spots) are fixed together, and the fix
    /// stops at the first round that gains nothing. Each round costs one
    /// more measurement of each level and a local search, the levels fixed
    /// side by side (the bunny's run: 0.33 s without, 1.36 s with six
    /// rounds); on the quality table six rounds lower the geometric mean of
    /// lodgen's Hausdorff distance over the best peer's from 0.895 to 0.745,
    /// and with `--polish` every cell but one is at or under the best peer
    /// (docs/quality.md, "Session 31"). The written
    /// levels and their
    /// reported errors are the fixed ones; the progressive mesh
    /// (`--progressive`) keeps the simplifier's positions. Needs the
    /// measurement (not with `--measure off`). Off by default.
    #[arg(long, value_name = "ROUNDS", num_args = 0..=1, require_equals = true, default_missing_value = "6")]
    pub fix_worst: Option<u32>,

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
    #[arg(long, value_name = "W", default_value_t = lodgen_pm::AdaptiveOptions::DEFAULT.hybrid_weight, allow_negative_numbers = true)]
    pub curvature_weight: f64,

    /// Weight every face plane equally instead of by triangle area. Off by
    /// default.
    #[arg(long)]
    pub uniform_weights: bool,

    /// Write quantized vertex data (KHR_mesh_quantization): 16-bit
    /// positions, 8-bit normals, 16-bit UVs. Off by default (32-bit floats).
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
    /// file's report with its status, error and time); `-`: to standard
    /// output, instead of the table.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,

    /// Area samples per triangle of the larger mesh for the error
    /// measurement, up to 2,048 triangles; above that the count grows with
    /// the square root (N·√(2,048·t)). Every vertex, the centroids and edge
    /// midpoints of a coarse level and a search from the farthest points
    /// add to the maximum.
    #[arg(long, value_name = "N", default_value_t = MeasureOptions::DEFAULT.samples_per_triangle, allow_negative_numbers = true)]
    pub samples: f64,

    /// Measure each level's error against the input (`on`: Metro-style sampling,
    /// whose Hausdorff figure is a lower estimate), find the Hausdorff
    /// distance by bounded subdivision (`bounded`: certified within 1 % plus
    /// 10⁻⁵ of the diagonal; slower: the bunny run takes 4.5× the CPU), or skip it for
    /// speed (`off`): errors and screen coverages then come from the
    /// simplifier's own estimate (the quadric error of the contractions
    /// still in a level), marked `≈` in the table; RMS is not known.
    #[arg(long, value_enum, value_name = "on|bounded|off", default_value = "on")]
    pub measure: MeasureMode,

    /// Floor per mesh, in triangles: no level has fewer (nor fewer than 1),
    /// so a mesh with at most this many (a quad, a card, a decal) is written
    /// unsimplified. A mesh too small for its requested levels keeps its
    /// coarsest allowed mesh for them; levels that coincide are written
    /// once, so its chain is shorter, and the table says so in a note.
    #[arg(long, value_name = "N", default_value_t = lod::DEFAULT_MIN_TRIANGLES)]
    pub min_triangles: usize,

    /// Fail instead of warning: a part of the input that would be left out
    /// or written differently (a glTF primitive that cannot be read, points
    /// or lines, a mesh that cannot be simplified and would be written
    /// unsimplified, an animation or skin that cannot be carried) is an
    /// error, and nothing is written. Without it such a file is written,
    /// every warning is printed, and the exit code is 3.
    #[arg(long)]
    pub strict: bool,

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
    Bounded,
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
        } else if item.bytes().all(|b| b.is_ascii_digit()) {
            // a count beyond any mesh (as any count above the mesh's: the
            // whole mesh), not a fraction
            LevelSpec::Triangles(usize::MAX)
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

/// Parse the value of `flag` (`--reach`, `--reach-faces`): "off", or the
/// factor (positive, finite).
pub fn parse_factor(flag: &str, s: &str) -> Result<Option<f64>> {
    let s = s.trim();
    if s == "off" {
        return Ok(None);
    }
    let f: f64 = s
        .parse()
        .with_context(|| format!("{flag}: {s:?} is neither a factor nor \"off\""))?;
    if !(f > 0.0 && f.is_finite()) {
        bail!("{flag}: the factor {s:?} must be positive and finite");
    }
    Ok(Some(f))
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
    /// Every value checked before any work: the options ([`Self::build_options`])
    /// and the batch flags. An error here is a bad argument (exit code 2).
    pub fn check(&self) -> Result<()> {
        // a second "input" that is no file is most often an option's value
        // cut in two by a space (`--levels 50%, 10%`): named first, as the
        // option's own value (`50%,`) is then wrong too
        if self.batch.out_dir.is_none() {
            let stray = self.inputs.iter().skip(1).find(|i| {
                let text = i.to_string_lossy();
                !i.exists()
                    && !text.contains(['*', '?', '['])
                    && text.starts_with(|c: char| c.is_ascii_digit())
            });
            if let Some(stray) = stray {
                bail!(
                    "{}: no such input file; a space inside an option's value? (write `--levels \
                     50%,10%`, not `--levels 50%, 10%`)",
                    stray.display()
                );
            }
        }
        self.build_options()?;
        if self.batch.jobs == 0 {
            bail!("--jobs must be at least 1");
        }
        // (`-o x.obj`: a bad argument, refused before anything is read)
        if let Some(output) = &self.output {
            crate::gltf_out::check_output_path(output)
                .with_context(|| format!("writing {}", output.display()))?;
        }
        Ok(())
    }

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
            })
            .with_reach(parse_factor("--reach", &self.reach)?)
            .with_reach_faces(parse_factor("--reach-faces", &self.reach_faces)?)
            .with_topology_change(if self.allow_topology_change {
                TopologyChange::All
            } else if self.keep_topology {
                TopologyChange::Never
            } else {
                TopologyChange::WhenShort
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
            measure: if self.measure == MeasureMode::Bounded {
                MeasureOptions::BOUNDED
            } else {
                MeasureOptions::DEFAULT.with_samples_per_triangle(self.samples)
            },
            measured: self.measure != MeasureMode::Off,
            attribute_weights: parse_attribute_weights(&self.attribute_weights)?,
            min_triangles: self.min_triangles,
            meter: None,
            keep_progressive: true,
            keep_input: true,
            polish: self.polish.then_some(lodgen_pm::PolishOptions::CLUSTERS),
            fix_worst: self.fix_worst_options()?,
            level_ready: None,
        })
    }

    /// `--fix-worst`'s options (`None`: off, or 0 rounds).
    fn fix_worst_options(&self) -> Result<Option<lodgen_pm::polish::WorstOptions>> {
        match self.fix_worst {
            Some(r) if r > 0 && self.measure == MeasureMode::Off => bail!(
                "--fix-worst measures each level to find its worst spot: it cannot be used with --measure off"
            ),
            Some(r) if r > 0 => Ok(Some(lodgen_pm::polish::WorstOptions {
                rounds: r,
                ..lodgen_pm::polish::WorstOptions::DEFAULT
            })),
            _ => Ok(None),
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A count too large for the machine is a count (the whole mesh, as any
    /// count above it), not a fraction out of range; the other forms as
    /// documented. (Fails when `2^64` is called a fraction.)
    #[test]
    fn level_forms() {
        let l = parse_levels("50%, 0.1,20000,18446744073709551616").unwrap();
        assert_eq!(
            l,
            [
                LevelSpec::Ratio(0.5),
                LevelSpec::Ratio(0.1),
                LevelSpec::Triangles(20000),
                LevelSpec::Triangles(usize::MAX)
            ]
        );
        let e = parse_levels("1.5").unwrap_err().to_string();
        assert!(e.contains("fraction \"1.5\" must be in (0, 1]"), "{e}");
        assert!(parse_levels("0").is_err() && parse_levels("50%,").is_err());
    }
}
