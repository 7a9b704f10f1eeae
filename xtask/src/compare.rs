//! `cargo xtask compare`: every simplification method of lodgen-pm (QEM, the
//! QEM–curvature hybrid and the three curvature-adaptive collapse operators
//! of Ceballos, Hernández & Prieto) plus `meshopt::simplify`, on bunny, cow
//! and fandisk at 50 %, 10 % and 2 % of their triangles. Writes
//! `docs/compare.md` (table), `docs/compare.png` (error against triangle
//! count) and `docs/renders/*.png` (the bunny at 10 % per method).
//!
//! Meshes are read from `$LODGEN_ASSETS`, else `<workspace>/../shared/assets`
//! (or `shared/assets` beside a further ancestor).
//! Errors are measured with `lodgen_pm::metric` against the welded input,
//! in percent of its bounding-box diagonal. Options: `--meshes a,b` to run a
//! subset; `--no-render` to skip pictures.

use crate::render::{render, write_png, View};
use anyhow::{bail, Context, Result};
use lodgen_pm::adaptive::Reclassify;
use lodgen_pm::metric::{measure, MeasureOptions, MeshRef};
use lodgen_pm::{
    prepare, simplify_method, AdaptiveOptions, AdaptiveReport, AdaptiveStop, Mesh, Method,
};
use lodgen_pm::{SimplifyOptions, StopReason};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

const MESHES: [&str; 3] = ["bunny", "cow", "fandisk"];
const RATIOS: [f64; 3] = [0.5, 0.1, 0.02];
/// The level the side-by-side pictures show.
const RENDER_RATIO: f64 = 0.1;
const RENDER_SIZE: usize = 256;
/// The bunny seen from its front-left, slightly from above.
const RENDER_YAW: f64 = -25.0;
const RENDER_PITCH: f64 = 12.0;
/// meshopt's `target_error` is relative to the mesh extent: 1.0 never binds,
/// so the triangle count alone stops it, as for the other methods.
const MESHOPT_NO_ERROR_BOUND: f32 = 1.0;
const PLOT_WIDTH: u32 = 1500;
const PLOT_HEIGHT: u32 = 960;
/// Errors are drawn on a log axis; a 0 (a flat part simplified exactly) is
/// drawn at this floor (percent of the diagonal).
const PLOT_ERROR_FLOOR: f64 = 1e-4;
const DEFAULT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

#[derive(Clone, Copy)]
enum Kind {
    Lodgen(Method, AdaptiveOptions),
    Meshopt,
}

#[derive(Clone, Copy)]
struct Variant {
    label: &'static str,
    kind: Kind,
    colour: (u8, u8, u8),
}

fn variants() -> Vec<Variant> {
    let every = AdaptiveOptions::DEFAULT.with_reclassify(Reclassify::EverySweep);
    let d = AdaptiveOptions::DEFAULT;
    vec![
        Variant {
            label: "qem",
            kind: Kind::Lodgen(Method::Qem, d),
            colour: (31, 119, 180),
        },
        Variant {
            label: "qem-curvature",
            kind: Kind::Lodgen(Method::QemCurvature, d),
            colour: (23, 190, 207),
        },
        Variant {
            label: "qem-curvature/w=1",
            kind: Kind::Lodgen(Method::QemCurvature, d.with_hybrid_weight(1.0)),
            colour: (120, 200, 230),
        },
        Variant {
            label: "qem-curvature/w=16",
            kind: Kind::Lodgen(Method::QemCurvature, d.with_hybrid_weight(16.0)),
            colour: (0, 100, 110),
        },
        Variant {
            label: "edge",
            kind: Kind::Lodgen(Method::Edge, d),
            colour: (214, 39, 40),
        },
        Variant {
            label: "half-edge",
            kind: Kind::Lodgen(Method::HalfEdge, d),
            colour: (255, 127, 14),
        },
        Variant {
            label: "triangle",
            kind: Kind::Lodgen(Method::Triangle, d),
            colour: (44, 160, 44),
        },
        Variant {
            label: "edge/every-sweep",
            kind: Kind::Lodgen(Method::Edge, every),
            colour: (227, 119, 194),
        },
        Variant {
            label: "half-edge/every-sweep",
            kind: Kind::Lodgen(Method::HalfEdge, every),
            colour: (188, 189, 34),
        },
        Variant {
            label: "triangle/every-sweep",
            kind: Kind::Lodgen(Method::Triangle, every),
            colour: (148, 103, 189),
        },
        Variant {
            label: "meshopt",
            kind: Kind::Meshopt,
            colour: (60, 60, 60),
        },
    ]
}

struct Row {
    mesh: &'static str,
    ratio: f64,
    variant: usize,
    target: usize,
    triangles: usize,
    hausdorff: f64,
    in_to_out: f64,
    out_to_in: f64,
    rms: f64,
    millis: f64,
    /// Why an adaptive method stopped before the target, else empty.
    note: String,
    /// Legality rejections / rollbacks (lodgen methods).
    prevented: usize,
    repaired: usize,
}

/// All primitives of a file as one triangle list.
fn load(path: &Path) -> Result<(Vec<[f32; 3]>, Vec<u32>)> {
    let scene =
        lodgen::io::read_scene(path).with_context(|| format!("reading {}", path.display()))?;
    let m = lodgen::cli::merged_mesh(&scene);
    let indices = m.indices();
    Ok((m.positions, indices))
}

/// meshopt's simplifier on the welded mesh, compacted.
fn meshopt_simplify(mesh: &Mesh, target: usize) -> Mesh {
    let bytes = meshopt::typed_to_bytes(&mesh.positions);
    let indices = mesh.indices();
    let out = match meshopt::VertexDataAdapter::new(bytes, 12, 0) {
        Ok(adapter) => meshopt::simplify(
            &indices,
            &adapter,
            target * 3,
            MESHOPT_NO_ERROR_BOUND,
            meshopt::SimplifyOptions::None,
            None,
        ),
        Err(_) => indices,
    };
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    let triangles = out
        .chunks_exact(3)
        .map(|c| {
            [c[0], c[1], c[2]].map(|v| {
                if remap[v as usize] == u32::MAX {
                    remap[v as usize] = positions.len() as u32;
                    positions.push(mesh.positions[v as usize]);
                }
                remap[v as usize]
            })
        })
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

fn stop_note(r: &AdaptiveReport) -> String {
    let locked = format!(
        "{} of {} interior vertices left are high-curvature (locked)",
        r.last_high, r.last_interior
    );
    match r.stop {
        AdaptiveStop::Target | AdaptiveStop::Qem(StopReason::Target) => String::new(),
        AdaptiveStop::Locked => format!(
            "stopped after {} sweeps: no removable edge or triangle left; {locked}",
            r.sweeps
        ),
        AdaptiveStop::Illegal => format!(
            "stopped after {} sweeps: {locked}; none of the {} candidate triangles around the \
             others has a legal collapse (link/flip) or one free of Algorithm 5 defects",
            r.sweeps, r.last_candidates
        ),
        AdaptiveStop::Qem(r) => format!("stopped: {r:?}"),
    }
}

pub fn run(args: &[String]) -> Result<()> {
    if crate::rerun_in_release("compare", args)? {
        return Ok(());
    }
    let mut meshes: Vec<&'static str> = MESHES.to_vec();
    let mut pictures = true;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--meshes" => {
                let list = it
                    .next()
                    .context("--meshes needs a list, e.g. cow,fandisk")?;
                meshes = MESHES
                    .into_iter()
                    .filter(|m| list.split(',').any(|x| x == *m))
                    .collect();
            }
            "--no-render" => pictures = false,
            other => bail!("unknown option {other:?} (expected --meshes a,b or --no-render)"),
        }
    }
    let assets = crate::shared_assets()?;
    let docs = crate::workspace_root().join("docs");
    std::fs::create_dir_all(docs.join("renders")).context("creating docs/renders")?;
    let vars = variants();
    let mut rows = Vec::new();
    let mut renders: Vec<(String, String)> = Vec::new();
    for &name in &meshes {
        let path = assets.join(format!("{name}.obj"));
        let (positions, indices) = load(&path)?;
        let prepared = prepare(&positions, &indices)
            .with_context(|| format!("preparing {}", path.display()))?;
        let orig = &prepared.mesh;
        let n = orig.triangles.len();
        eprintln!("{name}: {n} triangles");
        let view = View::fit(&orig.positions, RENDER_YAW, RENDER_PITCH, RENDER_SIZE);
        if pictures && name == "bunny" {
            let file = "bunny-original.png".to_string();
            let img = render(&orig.positions, &orig.triangles, &view);
            write_png(
                &docs.join("renders").join(&file),
                RENDER_SIZE,
                RENDER_SIZE,
                &img,
            )?;
            renders.push((format!("original ({n})"), file));
        }
        for &ratio in &RATIOS {
            let target = (ratio * n as f64).floor() as usize;
            for (vi, v) in vars.iter().enumerate() {
                let t0 = Instant::now();
                let (result, note, prevented, repaired) = match v.kind {
                    Kind::Meshopt => (meshopt_simplify(orig, target), String::new(), 0, 0),
                    Kind::Lodgen(method, adaptive) => {
                        let opts = SimplifyOptions::DEFAULT.with_target_triangles(target);
                        let out = simplify_method(&positions, &indices, method, &opts, &adaptive)
                            .with_context(|| format!("{name}: {}", v.label))?;
                        let r = out.report;
                        (
                            out.simplified.pm.base,
                            stop_note(&r),
                            r.prevented.total(),
                            r.repaired.total(),
                        )
                    }
                };
                let millis = t0.elapsed().as_secs_f64() * 1e3;
                let err = measure(
                    MeshRef::new(&orig.positions, &orig.triangles),
                    MeshRef::new(&result.positions, &result.triangles),
                    &MeasureOptions::default(),
                )
                .map_err(|e| anyhow::anyhow!("{name}: {}: measuring: {e}", v.label))?;
                let pct = |d: f64| err.percent(d);
                eprintln!(
                    "  {:>4}% {:<22} {:>6} tris  H {:.3}%  rms {:.4}%  {:.0} ms {}",
                    ratio * 100.0,
                    v.label,
                    result.triangles.len(),
                    err.hausdorff_percent(),
                    err.rms_percent(),
                    millis,
                    note
                );
                if pictures && name == "bunny" && ratio == RENDER_RATIO {
                    let file = format!("bunny-10-{}.png", v.label.replace('/', "-"));
                    let img = render(&result.positions, &result.triangles, &view);
                    write_png(
                        &docs.join("renders").join(&file),
                        RENDER_SIZE,
                        RENDER_SIZE,
                        &img,
                    )?;
                    renders.push((format!("{} ({})", v.label, result.triangles.len()), file));
                }
                rows.push(Row {
                    mesh: name,
                    ratio,
                    variant: vi,
                    target,
                    triangles: result.triangles.len(),
                    hausdorff: err.hausdorff_percent(),
                    in_to_out: pct(err.a_to_b.max),
                    out_to_in: pct(err.b_to_a.max),
                    rms: err.rms_percent(),
                    millis,
                    note,
                    prevented,
                    repaired,
                });
            }
        }
    }
    plot(&docs.join("compare.png"), &meshes, &vars, &rows)?;
    let md = report(&meshes, &vars, &rows, &renders);
    std::fs::write(docs.join("compare.md"), md).context("writing docs/compare.md")?;
    eprintln!("wrote docs/compare.md, docs/compare.png, docs/renders/");
    Ok(())
}

fn report(meshes: &[&str], vars: &[Variant], rows: &[Row], renders: &[(String, String)]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Method comparison\n\n\
         Generated by `cargo xtask compare` (release build; run it again to refresh — times \
         depend on the machine). Every method of `lodgen_pm::adaptive::Method` plus \
         `meshopt::simplify` (meshoptimizer, no error bound, default options) at 50 %, 10 % and \
         2 % of the welded input's triangles. Errors from `lodgen_pm::metric` against the welded \
         input, in % of its bounding-box diagonal: **H** symmetric Hausdorff, **in→out** / \
         **out→in** one-sided maxima (input samples to the result, result samples to the input), \
         **RMS** the larger one-sided RMS. Time is the whole call (preparation included for \
         lodgen's methods, not for meshopt, which runs on the already welded mesh).\n\n\
         Methods: `qem` GH97 pair contraction; `qem-curvature` the same with pair costs × \
         (1 + w·θ/θ_max), θ the average normal deviation over the 3-ring, w = 4 unless the label says otherwise; `edge`, `half-edge`, \
         `triangle` the paper's operators on low-curvature vertices (θ ≤ mean + 2σ of the input, \
         threshold fixed, θ re-measured every sweep); `…/every-sweep` the same with the threshold \
         recomputed from each sweep's θ (the paper's Step 4 taken literally). \
         **rej/rb**: operations refused by the legality rules / rolled back for an Algorithm 5 \
         defect.\n"
    );
    let _ = writeln!(s, "![error against triangle count](compare.png)\n");
    summary(&mut s, meshes, vars, rows);
    mesh_tables(&mut s, meshes, vars, rows);
    if !renders.is_empty() {
        render_table(&mut s, renders);
    }
    s
}

/// The summary: the hybrid's verdict per weight, the best method per mesh
/// and ratio, where a method stopped early.
fn summary(s: &mut String, meshes: &[&str], vars: &[Variant], rows: &[Row]) {
    // hybrid verdict, per weight
    let _ = writeln!(s, "## Summary\n");
    for h_label in ["qem-curvature/w=1", "qem-curvature", "qem-curvature/w=16"] {
        let (mut better, mut better_h, mut total) = (0, 0, 0);
        for m in meshes {
            for &r in &RATIOS {
                let find = |label: &str| {
                    rows.iter()
                        .find(|x| x.mesh == *m && x.ratio == r && vars[x.variant].label == label)
                };
                if let (Some(q), Some(h)) = (find("qem"), find(h_label)) {
                    total += 1;
                    better += usize::from(h.rms < q.rms);
                    better_h += usize::from(h.hausdorff < q.hausdorff);
                }
            }
        }
        let _ = writeln!(
            s,
            "- Does the curvature weighting help QEM? `{h_label}` has a lower RMS error than `qem` \
             in {better} of {total} cases and a lower Hausdorff distance in {better_h} of {total} \
             (same triangle targets; `qem-curvature` is w = 4, the default)."
        );
    }
    let _ = writeln!(s);
    for m in meshes {
        for &r in &RATIOS {
            let at: Vec<&Row> = rows
                .iter()
                .filter(|x| x.mesh == *m && x.ratio == r && x.note.is_empty())
                .collect();
            if let Some(best) = at.iter().min_by(|a, b| a.rms.total_cmp(&b.rms)) {
                let _ = writeln!(
                    s,
                    "- {m} at {}: lowest RMS among methods that reached the target: `{}` ({:.4} %); \
                     lowest Hausdorff: `{}`.",
                    pct_label(r),
                    vars[best.variant].label,
                    best.rms,
                    at.iter()
                        .min_by(|a, b| a.hausdorff.total_cmp(&b.hausdorff))
                        .map_or("-", |x| vars[x.variant].label)
                );
            }
        }
    }
    let early: Vec<&Row> = rows.iter().filter(|x| !x.note.is_empty()).collect();
    if !early.is_empty() {
        let _ = writeln!(s, "\n### Where a method stopped early\n");
        for x in early {
            let _ = writeln!(
                s,
                "- {} at {} with `{}`: {} triangles instead of {} — {}.",
                x.mesh,
                pct_label(x.ratio),
                vars[x.variant].label,
                x.triangles,
                x.target,
                x.note
            );
        }
    }
}

/// One Markdown table row: `| a | b | … |`.
fn table_row<S: AsRef<str>>(s: &mut String, cells: impl IntoIterator<Item = S>) {
    s.push('|');
    for c in cells {
        let _ = write!(s, " {} |", c.as_ref());
    }
    s.push('\n');
}

/// Per mesh, every variant at every ratio.
fn mesh_tables(s: &mut String, meshes: &[&str], vars: &[Variant], rows: &[Row]) {
    let header = [
        "target",
        "method",
        "triangles",
        "H %",
        "in→out %",
        "out→in %",
        "RMS %",
        "time ms",
        "rej/rb",
        "note",
    ];
    for m in meshes {
        let _ = writeln!(s, "\n## {m}\n");
        table_row(s, header);
        let _ = writeln!(s, "|---|---|---:|---:|---:|---:|---:|---:|---:|---|");
        for x in rows.iter().filter(|x| x.mesh == *m) {
            let note = if x.note.is_empty() {
                ""
            } else {
                "**stopped early**"
            };
            table_row(
                s,
                [
                    format!("{} ({})", pct_label(x.ratio), x.target),
                    format!("`{}`", vars[x.variant].label),
                    x.triangles.to_string(),
                    format!("{:.3}", x.hausdorff),
                    format!("{:.3}", x.in_to_out),
                    format!("{:.3}", x.out_to_in),
                    format!("{:.4}", x.rms),
                    format!("{:.0}", x.millis),
                    format!("{}/{}", x.prevented, x.repaired),
                    note.to_string(),
                ],
            );
        }
    }
}

/// The renders, five to a row: labels, then images.
fn render_table(s: &mut String, renders: &[(String, String)]) {
    let _ = writeln!(
        s,
        "\n## The bunny at 10 %\n\nFlat-shaded, same camera, {RENDER_SIZE}×{RENDER_SIZE} \
         (software rasterizer in `xtask/src/render.rs`; back faces red).\n"
    );
    for chunk in renders.chunks(5) {
        table_row(s, chunk.iter().map(|r| r.0.as_str()));
        let _ = writeln!(s, "|{}", "---|".repeat(chunk.len()));
        table_row(
            s,
            chunk.iter().map(|r| format!("![{}](renders/{})", r.0, r.1)),
        );
        s.push('\n');
    }
}

fn pct_label(r: f64) -> String {
    format!("{} %", r * 100.0)
}

fn plot(path: &Path, meshes: &[&str], vars: &[Variant], rows: &[Row]) -> Result<()> {
    use plotters::prelude::*;
    let font_path = std::env::var_os("LODGEN_FONT")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(DEFAULT_FONT));
    let font = std::fs::read(&font_path).with_context(|| {
        format!(
            "reading the plot font {} (set LODGEN_FONT to a .ttf file)",
            font_path.display()
        )
    })?;
    let font: &'static [u8] = Box::leak(font.into_boxed_slice());
    plotters::style::register_font("sans-serif", FontStyle::Normal, font)
        .map_err(|_| anyhow::anyhow!("{} is not a usable font", font_path.display()))?;
    let (w, h) = (PLOT_WIDTH, PLOT_HEIGHT);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
        let panels = root.split_evenly((2, meshes.len().max(1)));
        for (row, metric) in ["RMS", "Hausdorff"].iter().enumerate() {
            for (col, m) in meshes.iter().enumerate() {
                let area = &panels[row * meshes.len() + col];
                let of = |x: &Row| {
                    let e = if *metric == "RMS" { x.rms } else { x.hausdorff };
                    e.max(PLOT_ERROR_FLOOR)
                };
                let pts: Vec<&Row> = rows.iter().filter(|x| x.mesh == *m).collect();
                if pts.is_empty() {
                    continue;
                }
                let xmin = pts.iter().map(|x| x.triangles).min().unwrap_or(1).max(1) as f64;
                let xmax = pts.iter().map(|x| x.triangles).max().unwrap_or(2) as f64;
                let ymin = pts.iter().map(|x| of(x)).fold(f64::INFINITY, f64::min);
                let ymax = pts.iter().map(|x| of(x)).fold(0.0, f64::max);
                let mut chart = ChartBuilder::on(area)
                    .caption(format!("{m}: {metric} (% of diagonal)"), ("sans-serif", 20))
                    .margin(10)
                    .x_label_area_size(36)
                    .y_label_area_size(56)
                    .build_cartesian_2d(
                        (xmin * 0.8..xmax * 1.25).log_scale(),
                        (ymin * 0.7..ymax * 1.4).log_scale(),
                    )
                    .map_err(|e| anyhow::anyhow!("{e}"))?;
                chart
                    .configure_mesh()
                    .x_desc("triangles")
                    .x_labels(6)
                    .y_labels(6)
                    .label_style(("sans-serif", 13))
                    .draw()
                    .map_err(|e| anyhow::anyhow!("{e}"))?;
                for (vi, v) in vars.iter().enumerate() {
                    let mut series: Vec<(f64, f64)> = pts
                        .iter()
                        .filter(|x| x.variant == vi)
                        .map(|x| (x.triangles.max(1) as f64, of(x)))
                        .collect();
                    series.sort_by(|a, b| a.0.total_cmp(&b.0));
                    let c = RGBColor(v.colour.0, v.colour.1, v.colour.2);
                    let drawn = chart
                        .draw_series(LineSeries::new(series.clone(), c.stroke_width(2)))
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                    if row == 0 && col == 0 {
                        drawn.label(v.label).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(3))
                        });
                    }
                    chart
                        .draw_series(
                            series
                                .iter()
                                .map(|&(x, y)| Circle::new((x, y), 3, c.filled())),
                        )
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                }
                if row == 0 && col == 0 {
                    chart
                        .configure_series_labels()
                        .background_style(WHITE.mix(0.85))
                        .border_style(BLACK)
                        .label_font(("sans-serif", 12))
                        .position(SeriesLabelPosition::UpperRight)
                        .draw()
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                }
            }
        }
        root.present().map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    write_png(path, w as usize, h as usize, &buf)
}
