//! `cargo xtask quality`: lodgen's geometric error against the other
//! simplifiers, mesh by mesh and level by level (issue 19's table).
//!
//! Every tool gets the same positions-only input — the welded, cleaned mesh
//! `lodgen_pm::prepare` makes of each OBJ in `$LODGEN_ASSETS` (plus the
//! bunny subdivided twice by midpoints, 1.1 M triangles, as `cargo xtask
//! bench` makes it) — and the same triangle count: lodgen runs once to the
//! smallest level and cuts 50 %, 10 % and 2 % from its vertex-split log, as
//! `lodgen` does; each peer is then asked for exactly the count lodgen's
//! level has. Peers: meshoptimizer through the `meshopt` crate, in process;
//! MeshLab (`pymeshlab`, `meshing_decimation_quadric_edge_collapse`),
//! Open3D (`simplify_quadric_decimation`), pyfqmr and fast-simplification
//! through their PyPI packages, all with their default settings, in a venv
//! this task makes under `target/quality-venv` (a peer whose package does
//! not install or import is skipped with a notice). Every output is
//! measured by `lodgen_pm::metric` against the welded input: symmetric,
//! `SAMPLES` area samples per direction plus every vertex, in percent of
//! the bounding-box diagonal.
//!
//! Writes `docs/quality.md` (the table; the file's hand-written part after
//! [`HAND_WRITTEN`] is kept) and `docs/quality.png` (error against triangle
//! count, one panel per mesh). A full run records the peers' cells with the
//! triangle count each was asked for (`target/quality-peers.tsv`) and re-runs
//! the Python peers only for the cells whose count changed since (`--fresh`
//! re-runs them all). `--quick`: lodgen and
//! meshopt only, no big mesh, nothing written (the loop for trying a change
//! of the simplifier); when the last full run recorded the peers' cells
//! (`target/quality-peers.tsv`), only lodgen is run and measured and its
//! ratios are against the recorded best peer. `--meshes a,b` runs a subset;
//! `--no-peers` skips the Python tools; `--greedy` runs lodgen with
//! `Schedule::Greedy` instead of its default pass schedule; `--reach-off` with
//! `SimplifyOptions::reach` off (it is on by default); `--reach-faces` with
//! `SimplifyOptions::reach_faces` at `DEFAULT_REACH_FACES_FACTOR` (off by
//! default); `--polish`
//! polishes lodgen's levels as `lodgen --polish` does
//! (`lodgen_pm::polish_clusters`, `PolishOptions::CLUSTERS`) before they are
//! measured, `--polish-exact` with `lodgen_pm::polish` (the hierarchies'
//! closest points, default options); `--worst R`, `--worst-cli R`, `--worst-bounded R`: `quality/worst.rs`. `--write-levels DIR` writes the welded
//! input and lodgen's and meshoptimizer's levels of each mesh as OBJ files
//! to `DIR` (`quality/levels.rs`), for `lodgen measure`, which says where a
//! cell's maximum lies.
//!
//! A cell where lodgen's and the best peer's Hausdorff and RMS are all
//! under the rounding of the input file's coordinates (its stored digits,
//! `quality/rounding.rs`) is marked a tie, not a loss: the gap there is
//! the input's noise (fandisk 50 %).

use anyhow::{bail, Context, Result};
use lodgen_pm::metric::{MeasureOptions, MeshRef, Reference};
use lodgen_pm::shapes::subdivide;
use lodgen_pm::{prepare, simplify, Mesh, SimplifyOptions};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

mod levels;
mod peers;
mod plot;
mod rounding;
mod worst;

use peers::{peer_python, python_peers, PEERS};

const MESHES: [&str; 8] = [
    "bunny",
    "cow",
    "fandisk",
    "rocker-arm",
    "teapot",
    "spot",
    "beetle",
    "bunny-1m",
];
const RATIOS: [f64; 3] = [0.5, 0.1, 0.02];
/// Area samples per direction (the Metro-style setting).
const SAMPLES: usize = 1_000_000;
/// meshopt's `target_error` is relative to the mesh extent: 1.0 never binds.
const MESHOPT_NO_ERROR_BOUND: f32 = 1.0;
/// The peers' cells of the last full runs: one line per cell, `mesh ratio
/// peer triangles hausdorff rms asked`, tab-separated (peer: index in
/// `Row::peers`, 0 = meshopt; asked: the triangle count the peer was asked
/// for, lodgen's; older files lack it).
const RECORDED: &str = "target/quality-peers.tsv";
/// The line of docs/quality.md after which the text is hand-written: a full
/// run rewrites what is above it and keeps the rest.
const HAND_WRITTEN: &str = "<!-- Hand-written below: `cargo xtask quality` keeps what follows. -->";
const PLOT_PANEL: (u32, u32) = (420, 330);
const DEFAULT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// One measured output.
#[derive(Clone, Copy, Debug)]
struct Cell {
    triangles: usize,
    hausdorff: f64,
    rms: f64,
}

/// One mesh at one level: lodgen, then every peer (None: skipped / failed).
struct Row {
    mesh: &'static str,
    ratio: f64,
    lodgen: Cell,
    peers: Vec<Option<Cell>>,
    /// The triangle count the peers were asked for: lodgen's, unless a quick
    /// run compares with cells recorded at another count.
    asked: usize,
    /// The rounding of the input file's coordinates in % of the diagonal
    /// (`quality/rounding.rs`; None: not known).
    rounding: Option<f64>,
}

struct Args {
    meshes: Vec<&'static str>,
    quick: bool,
    python: bool,
    greedy: bool,
    reach_off: bool,
    /// `SimplifyOptions::reach_faces` at its suggested factor.
    reach_faces: bool,
    polish: Option<Polish>,
    fresh: bool,
    /// `--write-levels DIR`: the input and the levels as OBJ files.
    write_levels: Option<PathBuf>,
    /// `--worst R` (rounds; 0: off) / `--worst-cli R` / `--worst-bounded R`
    /// (`quality/worst.rs`).
    worst: (u32, worst::Judge),
}

/// How `--polish` pairs the surfaces.
#[derive(Clone, Copy, PartialEq)]
enum Polish {
    /// From the simplification's clusters (`lodgen_pm::polish_clusters`).
    Clusters,
    /// Closest points through the hierarchies (`lodgen_pm::polish`).
    Exact,
}

fn parse(args: &[String]) -> Result<Args> {
    let mut out = Args {
        meshes: MESHES.to_vec(),
        quick: false,
        python: true,
        greedy: false,
        reach_off: false,
        reach_faces: false,
        polish: None,
        fresh: false,
        write_levels: None,
        worst: (0, worst::Judge::Table),
    };
    let mut it = args.iter();
    let mut chosen = false;
    while let Some(a) = it.next() {
        match a.as_str() {
            "--meshes" => {
                let list = it.next().context("--meshes needs a list, e.g. cow,spot")?;
                out.meshes = MESHES
                    .into_iter()
                    .filter(|m| list.split(',').any(|x| x == *m))
                    .collect();
                chosen = true;
            }
            "--quick" => out.quick = true,
            "--no-peers" => out.python = false,
            "--greedy" => out.greedy = true,
            "--reach-off" => out.reach_off = true,
            "--reach-faces" => out.reach_faces = true,
            "--polish" => out.polish = Some(Polish::Clusters),
            "--polish-exact" => out.polish = Some(Polish::Exact),
            "--fresh" => out.fresh = true,
            "--worst" | "--worst-cli" | "--worst-bounded" => {
                let r = it.next().context("--worst needs a round count")?;
                let judge = match a.as_str() {
                    "--worst-cli" => worst::Judge::Command,
                    "--worst-bounded" => worst::Judge::Bounded,
                    _ => worst::Judge::Table,
                };
                out.worst = (r.parse().context("--worst R")?, judge);
            }
            "--write-levels" => {
                let dir = it.next().context("--write-levels needs a directory")?;
                out.write_levels = Some(PathBuf::from(dir));
            }
            other => bail!(
                "unknown option {other:?} (expected --meshes a,b, --quick, --no-peers, --greedy, \
                 --reach-off, --reach-faces, --polish, --polish-exact, --worst R, --worst-cli R, --worst-bounded R, --fresh, \
                 --write-levels DIR)"
            ),
        }
    }
    if out.quick {
        out.python = false;
        if !chosen {
            out.meshes.retain(|m| *m != "bunny-1m");
        }
    }
    Ok(out)
}

/// The OBJ file mesh `name` is made from.
fn source(assets: &Path, name: &str) -> PathBuf {
    let file = if name == "bunny-1m" { "bunny" } else { name };
    assets.join(format!("{file}.obj"))
}

/// The rounding of mesh `name`'s file (`quality/rounding.rs`) in % of
/// the `reference`'s diagonal (None: not known). (Midpoint subdivision
/// keeps the bound: a midpoint of rounded points is off by at most their
/// largest rounding.)
fn input_rounding(assets: &Path, name: &str, reference: &Reference) -> Result<Option<f64>> {
    let path = source(assets, name);
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    Ok(rounding::obj_half_step(&text)
        .filter(|_| reference.diagonal() > 0.0)
        .map(|h| 100.0 * h / reference.diagonal()))
}

/// The welded, cleaned input mesh `name`.
fn input(assets: &Path, name: &str) -> Result<Mesh> {
    let path = source(assets, name);
    let scene =
        lodgen::io::read_scene(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut m = lodgen::cli::merged_mesh(&scene);
    if name == "bunny-1m" {
        m = subdivide(&subdivide(&m));
    }
    let p = prepare(&m.positions, &m.indices())
        .with_context(|| format!("preparing {}", path.display()))?;
    Ok(p.mesh)
}

/// lodgen's levels: one run to the smallest ratio, levels cut from the log.
fn lodgen_levels(m: &Mesh, args: &Args) -> Result<Vec<Mesh>> {
    let n = m.triangles.len();
    let mut opts = SimplifyOptions::DEFAULT.with_target_ratio(RATIOS[RATIOS.len() - 1]);
    if args.reach_off {
        opts = opts.with_reach(None);
    }
    if args.reach_faces {
        opts = opts.with_reach_faces(Some(lodgen_pm::DEFAULT_REACH_FACES_FACTOR));
    }
    if args.greedy {
        opts = opts.with_schedule(lodgen_pm::Schedule::Greedy);
    }
    let out = simplify(&m.positions, &m.indices(), &opts)?;
    let mut c = out.pm.cursor();
    let full = out.pm.mesh_at_splits(out.pm.len());
    let original = (args.polish == Some(Polish::Clusters))
        .then(|| lodgen_pm::polish::Original::new(MeshRef::new(&full.positions, &full.triangles)));
    let reference = match args.polish {
        Some(Polish::Exact) => Some(Reference::new(MeshRef::new(&m.positions, &m.triangles))?),
        _ => None,
    };
    Ok(RATIOS
        .iter()
        .map(|r| {
            let k = out.pm.splits_for_triangles((r * n as f64).floor() as usize);
            c.seek(k);
            let mut level = c.mesh().clone();
            match (&original, &reference) {
                (Some(original), _) => {
                    let rep = out.pm.representatives(k);
                    let popts = lodgen_pm::PolishOptions::CLUSTERS;
                    lodgen_pm::polish_clusters(original, &mut level, &rep, &popts);
                }
                (None, Some(reference)) => {
                    lodgen_pm::polish(
                        MeshRef::new(&m.positions, &m.triangles),
                        reference.bvh(),
                        &mut level,
                        &lodgen_pm::PolishOptions::DEFAULT,
                    );
                }
                _ => {}
            }
            level
        })
        .collect())
}

fn meshopt_level(m: &Mesh, target: usize) -> Result<Mesh> {
    let adapter = meshopt::VertexDataAdapter::new(meshopt::typed_to_bytes(&m.positions), 12, 0)?;
    let idx = meshopt::simplify(
        &m.indices(),
        &adapter,
        target * 3,
        MESHOPT_NO_ERROR_BOUND,
        meshopt::SimplifyOptions::None,
        None,
    );
    Ok(Mesh {
        positions: m.positions.clone(),
        triangles: idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    })
}

/// `--write-levels DIR`: the input `m`, lodgen's `levels` and
/// meshoptimizer's at their counts as OBJ files (`quality/levels.rs`).
fn write_levels(dir: &Path, name: &str, m: &Mesh, levels: &[Mesh]) -> Result<()> {
    let all = RATIOS
        .iter()
        .zip(levels)
        .map(|(r, l)| {
            let percent = (r * 100.0).round() as u32;
            Ok((percent, l, meshopt_level(m, l.triangles.len())?))
        })
        .collect::<Result<Vec<_>>>()?;
    levels::write_levels(dir, name, m, &all)
}

fn measure_cell(reference: &Reference, m: &Mesh, opts: &MeasureOptions) -> Result<Cell> {
    let e = reference.measure(MeshRef::new(&m.positions, &m.triangles), opts)?;
    Ok(Cell {
        triangles: m.triangles.len(),
        hausdorff: e.hausdorff_percent(),
        rms: e.rms_percent(),
    })
}

pub fn run(args: &[String]) -> Result<()> {
    if crate::rerun_in_release("quality", args)? {
        return Ok(());
    }
    let args = parse(args)?;
    let assets = crate::shared_assets()?;
    let samples = SAMPLES;
    let mopts = MeasureOptions::DEFAULT
        .with_samples_per_triangle(0.0)
        .with_min_samples(samples);
    let python = if args.python { peer_python()? } else { None };
    let recorded = if args.fresh {
        Vec::new()
    } else {
        read_recorded()?
    };
    let mut rows = Vec::new();
    let mut rerun = 0;
    for &name in &args.meshes {
        let m = input(&assets, name)?;
        let reference = Reference::new(MeshRef::new(&m.positions, &m.triangles))?;
        let rounding = input_rounding(&assets, name, &reference)?;
        let mut levels = lodgen_levels(&m, &args)?;
        worst::fix_levels(&reference, &m, &mut levels, name, &mopts, args.worst)?;
        if let Some(dir) = &args.write_levels {
            write_levels(dir, name, &m, &levels)?;
        }
        let counts: Vec<usize> = levels.iter().map(|l| l.triangles.len()).collect();
        // levels whose recorded peers' cells may stand (all of them in a
        // quick run, which only says when a count moved)
        let reuse: Vec<bool> = (0..counts.len())
            .map(|k| python.is_none() || recorded_at(&recorded, name, RATIOS[k], counts[k]))
            .collect();
        let mut peers: Vec<Vec<Option<Mesh>>> = vec![vec![None; counts.len()]; PEERS.len()];
        if let Some((py, usable)) = &python {
            let stale: Vec<usize> = (0..counts.len()).filter(|&k| !reuse[k]).collect();
            if !stale.is_empty() {
                let asked: Vec<usize> = stale.iter().map(|&k| counts[k]).collect();
                let ran = python_peers(py, usable, &m, &asked)?;
                for (i, per_count) in ran.into_iter().enumerate() {
                    for (mesh, &k) in per_count.into_iter().zip(&stale) {
                        peers[i][k] = mesh;
                    }
                }
                rerun += stale.len();
            }
        }
        for (k, level) in levels.iter().enumerate() {
            let lodgen = measure_cell(&reference, level, &mopts)?;
            let asked = recorded
                .iter()
                .filter(|_| reuse[k] && python.is_none())
                .find(|r| r.mesh == name && r.ratio == RATIOS[k])
                .and_then(|r| r.asked)
                .unwrap_or(counts[k]);
            if asked.abs_diff(counts[k]) * 100 > counts[k] {
                eprintln!(
                    "quality: notice: {name} {}: the peers were recorded at {asked} triangles, \
                     lodgen has {} (a full run records the peers again)",
                    RATIOS[k], counts[k]
                );
            }
            let recorded_cell = |i: usize| {
                if !reuse[k] {
                    return None;
                }
                recorded
                    .iter()
                    .find(|r| r.mesh == name && r.ratio == RATIOS[k] && r.peer == i)
                    .map(|r| r.cell)
            };
            let meshopt = match recorded_cell(0).filter(|_| python.is_none()) {
                Some(c) => c,
                None => measure_cell(&reference, &meshopt_level(&m, counts[k])?, &mopts)?,
            };
            let mut cells = vec![Some(meshopt)];
            for (i, p) in peers.iter().enumerate() {
                cells.push(match &p[k] {
                    Some(mesh) => Some(measure_cell(&reference, mesh, &mopts)?),
                    None => recorded_cell(i + 1),
                });
            }
            let row = Row {
                mesh: name,
                ratio: RATIOS[k],
                lodgen,
                peers: cells,
                asked,
                rounding,
            };
            println!("{}", line(&row));
            rows.push(row);
        }
    }
    let (gh, gr, n) = geo_means(&rows);
    println!(
        "lodgen / best peer, geometric mean over {n} of {} cells: Hausdorff {gh:.3}, RMS {gr:.3}",
        rows.len()
    );
    if n < rows.len() {
        println!(
            "({} cells left out: their peers were recorded more than 1 % away from the \
             triangle count lodgen's level has now; a full run records them again)",
            rows.len() - n
        );
    }
    if !args.quick {
        write_docs(&args.meshes, &rows, samples, rerun)?;
        if python.is_some() {
            write_recorded(&rows)?;
        }
        eprintln!("wrote docs/quality.md, docs/quality.png");
    }
    Ok(())
}

/// docs/quality.png and docs/quality.md (its hand-written part kept);
/// `rerun`: the cells the Python peers ran for.
fn write_docs(meshes: &[&str], rows: &[Row], samples: usize, rerun: usize) -> Result<()> {
    let docs = crate::workspace_root().join("docs");
    plot::plot(&docs.join("quality.png"), meshes, rows)?;
    let md = docs.join("quality.md");
    let old = std::fs::read_to_string(&md).unwrap_or_default();
    let hand = old.find(HAND_WRITTEN).map_or("", |i| &old[i..]);
    let note = format!(
        "This table: `cargo xtask quality {}`; the Python peers ran for {rerun} of the {} \
         cells, the others are the cells recorded at the same triangle count by earlier \
         runs (`--fresh` runs them all).",
        std::env::args().skip(2).collect::<Vec<_>>().join(" "),
        rows.len()
    );
    std::fs::write(&md, report(rows, samples, &note, hand))
        .with_context(|| format!("writing {}", md.display()))
}

/// A recorded peer's cell.
struct RecordedCell {
    mesh: String,
    ratio: f64,
    /// Index in `Row::peers`.
    peer: usize,
    cell: Cell,
    /// The triangle count the peer was asked for (lodgen's), when recorded.
    asked: Option<usize>,
}

/// Whether the cells recorded for `mesh` at `ratio` were asked for `count`
/// triangles (for cells recorded without it: whether meshopt's is within
/// 1 % of `count`).
fn recorded_at(recorded: &[RecordedCell], mesh: &str, ratio: f64, count: usize) -> bool {
    let mut cells = recorded
        .iter()
        .filter(|r| r.mesh == mesh && r.ratio == ratio)
        .peekable();
    cells.peek().is_some()
        && cells.all(|r| match r.asked {
            Some(a) => a == count,
            None => r.peer != 0 || r.cell.triangles.abs_diff(count) * 100 <= count,
        })
}

/// Records the peers' cells of a full run for `--quick` (replacing
/// the recorded cells of the meshes it ran, keeping the others).
fn write_recorded(rows: &[Row]) -> Result<()> {
    let mut s = String::new();
    for r in read_recorded()? {
        if rows.iter().all(|row| row.mesh != r.mesh) {
            let c = r.cell;
            let _ = write!(
                s,
                "{}\t{}\t{}\t{}\t{}\t{}",
                r.mesh, r.ratio, r.peer, c.triangles, c.hausdorff, c.rms
            );
            let _ = match r.asked {
                Some(a) => writeln!(s, "\t{a}"),
                None => writeln!(s),
            };
        }
    }
    for row in rows {
        for (i, c) in row.peers.iter().enumerate() {
            if let Some(c) = c {
                let _ = writeln!(
                    s,
                    "{}\t{}\t{i}\t{}\t{}\t{}\t{}",
                    row.mesh, row.ratio, c.triangles, c.hausdorff, c.rms, row.lodgen.triangles
                );
            }
        }
    }
    let path = crate::workspace_root().join(RECORDED);
    std::fs::write(&path, s).with_context(|| format!("writing {}", path.display()))
}

/// The cells [`write_recorded`] wrote (none when there is no file).
fn read_recorded() -> Result<Vec<RecordedCell>> {
    let path = crate::workspace_root().join(RECORDED);
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(Vec::new());
    };
    eprintln!(
        "quality: the peers' cells are the ones recorded in {} (lodgen's alone are measured)",
        path.display()
    );
    text.lines()
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            let bad = || format!("{}: bad line {l:?}", path.display());
            anyhow::ensure!(f.len() == 6 || f.len() == 7, bad());
            let num = |i: usize| f[i].parse::<f64>().with_context(bad);
            Ok(RecordedCell {
                mesh: f[0].to_string(),
                ratio: num(1)?,
                peer: f[2].parse().with_context(bad)?,
                cell: Cell {
                    triangles: f[3].parse().with_context(bad)?,
                    hausdorff: num(4)?,
                    rms: num(5)?,
                },
                asked: f.get(6).map(|a| a.parse()).transpose().with_context(bad)?,
            })
        })
        .collect()
}

/// Peer labels, in `Row::peers` order.
fn peer_labels() -> Vec<&'static str> {
    std::iter::once("meshopt")
        .chain(PEERS.iter().map(|p| p.0))
        .collect()
}

/// An error value and the tool that reached it.
type Best = (f64, &'static str);

/// Whether a peer's cell stopped short of the count it was asked for (more
/// than 1 % over): it is shown but not compared (pyfqmr stops at 472
/// triangles on beetle, for instance, where lodgen's level has 96).
fn over_count(c: &Cell, row: &Row) -> bool {
    c.triangles * 100 > row.asked * 101
}

/// The best peer's Hausdorff and RMS (each over the peers that ran and met
/// the count), with the tools' labels.
fn best(row: &Row) -> Option<(Best, Best)> {
    let labels = peer_labels();
    let mut h: Option<(f64, &str)> = None;
    let mut r: Option<(f64, &str)> = None;
    for (c, l) in row.peers.iter().zip(labels) {
        if let Some(c) = c.filter(|c| !over_count(c, row)) {
            if h.is_none_or(|b| c.hausdorff < b.0) {
                h = Some((c.hausdorff, l));
            }
            if r.is_none_or(|b| c.rms < b.0) {
                r = Some((c.rms, l));
            }
        }
    }
    Some((h?, r?))
}

fn line(row: &Row) -> String {
    let mut s = format!(
        "{:<10} {:>3}% {:>7} tris  lodgen H {:.4} R {:.5}",
        row.mesh,
        row.ratio * 100.0,
        row.lodgen.triangles,
        row.lodgen.hausdorff,
        row.lodgen.rms
    );
    for (c, l) in row.peers.iter().zip(peer_labels()) {
        if let Some(c) = c {
            let _ = write!(s, " | {l} H {:.4} R {:.5}", c.hausdorff, c.rms);
        }
    }
    if let Some(((h, _), (r, _))) = best(row) {
        let _ = write!(
            s,
            " | ratio H {:.2} R {:.2}",
            row.lodgen.hausdorff / h,
            row.lodgen.rms / r
        );
    }
    if let Some(x) = tie(row) {
        let _ = write!(s, " (a tie: under the input's rounding, ±{})", percent(x));
    }
    s
}

/// The input's rounding (% of the diagonal) when lodgen's and the best
/// peer's Hausdorff and RMS are all under it: the cell is a tie.
fn tie(row: &Row) -> Option<f64> {
    let ((h, _), (r, _)) = best(row)?;
    let lodgen = (row.lodgen.hausdorff, row.lodgen.rms);
    row.rounding
        .filter(|&x| rounding::under_rounding(lodgen, (h, r), x))
}

/// A percentage to two significant digits (`0.00066 %`).
fn percent(x: f64) -> String {
    let decimals = if x > 0.0 {
        (1 - x.log10().floor() as i32).max(0) as usize
    } else {
        0
    };
    format!("{x:.decimals$} %")
}

/// Geometric means of lodgen / best peer over the rows (Hausdorff, RMS).
fn geo_means(rows: &[Row]) -> (f64, f64, usize) {
    let (mut lh, mut lr, mut n) = (0.0, 0.0, 0usize);
    // (a level a triangle or two off the recorded count still compares)
    let near = |r: &&Row| r.asked.abs_diff(r.lodgen.triangles) * 100 <= r.lodgen.triangles;
    for row in rows.iter().filter(near) {
        if let Some(((h, _), (r, _))) = best(row) {
            if h > 0.0 && r > 0.0 && row.lodgen.hausdorff > 0.0 && row.lodgen.rms > 0.0 {
                lh += (row.lodgen.hausdorff / h).ln();
                lr += (row.lodgen.rms / r).ln();
                n += 1;
            }
        }
    }
    if n == 0 {
        return (f64::NAN, f64::NAN, 0);
    }
    ((lh / n as f64).exp(), (lr / n as f64).exp(), n)
}

/// docs/quality.md: the generated text with `note` (how this table was
/// made), then `hand` (the file's hand-written part, from [`HAND_WRITTEN`]).
fn report(rows: &[Row], samples: usize, note: &str, hand: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Quality against other simplifiers\n\n\
         Generated by `cargo xtask quality` (xtask/src/quality.rs). Positions-only input: the \
         welded, cleaned mesh of each OBJ in the shared assets, and `bunny-1m` (the bunny \
         subdivided twice by midpoints, as `cargo xtask bench` makes it). lodgen runs once to \
         2 % with its defaults and its levels are cut from the vertex-split log; every peer is \
         asked for exactly the triangle count of lodgen's level, with its default settings: \
         meshoptimizer (`meshopt` crate, `simplify`, no error bound), MeshLab \
         (`pymeshlab`, `meshing_decimation_quadric_edge_collapse`), Open3D \
         (`simplify_quadric_decimation`), pyfqmr, fast-simplification. Errors: \
         `lodgen_pm::metric`, symmetric, {samples} area samples per direction plus every \
         vertex, in % of the bounding-box diagonal. H = Hausdorff, R = RMS; **bold**: lodgen \
         worse than the best peer; ratio = lodgen / best peer. A peer that stopped more than \
         1 % above the count is shown in parentheses with its count and not compared. A ratio \
         marked *tie* is a cell where lodgen's and the best peer's H and R are all under the \
         rounding of the input file's coordinates (±: half the step of its last stored digit, \
         the largest over the coordinates, in % of the diagonal; `quality/rounding.rs`): \
         there the gap is the input's noise, not a loss (not bold; it still counts in the \
         geometric means).\n\n{note}\n"
    );
    let labels = peer_labels();
    let _ = write!(s, "| mesh | level | tris | lodgen H / R |");
    for l in &labels {
        let _ = write!(s, " {l} H / R |");
    }
    let _ = writeln!(s, " best H | best R | ratio H / R |");
    let _ = write!(s, "|---|---|---|---|");
    for _ in &labels {
        let _ = write!(s, "---|");
    }
    let _ = writeln!(s, "---|---|---|");
    for row in rows {
        let b = best(row);
        let (bh, br) = match tie(row) {
            Some(_) => (f64::INFINITY, f64::INFINITY),
            None => b.map_or((f64::INFINITY, f64::INFINITY), |x| (x.0 .0, x.1 .0)),
        };
        let bold = |v: f64, lim: f64, t: String| if v > lim { format!("**{t}**") } else { t };
        let _ = write!(
            s,
            "| {} | {} % | {} | {} / {} |",
            row.mesh,
            row.ratio * 100.0,
            row.lodgen.triangles,
            bold(
                row.lodgen.hausdorff,
                bh,
                format!("{:.4}", row.lodgen.hausdorff)
            ),
            bold(row.lodgen.rms, br, format!("{:.5}", row.lodgen.rms)),
        );
        for c in &row.peers {
            match c {
                Some(c) if over_count(c, row) => {
                    let _ = write!(
                        s,
                        " ({:.4} / {:.5} at {} tris) |",
                        c.hausdorff, c.rms, c.triangles
                    );
                }
                Some(c) => {
                    let _ = write!(s, " {:.4} / {:.5} |", c.hausdorff, c.rms);
                }
                None => {
                    let _ = write!(s, " – |");
                }
            }
        }
        match b {
            Some(((h, hl), (r, rl))) => {
                let ratio = format!(
                    "{:.2} / {:.2}",
                    row.lodgen.hausdorff / h,
                    row.lodgen.rms / r
                );
                let ratio = match tie(row) {
                    Some(x) => format!(
                        "*tie*: under the input's rounding (±{}) ({ratio})",
                        percent(x)
                    ),
                    None => ratio,
                };
                let _ = writeln!(s, " {h:.4} ({hl}) | {r:.5} ({rl}) | {ratio} |");
            }
            None => {
                let _ = writeln!(s, " – | – | – |");
            }
        }
    }
    let (gh, gr, _) = geo_means(rows);
    let _ = writeln!(
        s,
        "\nGeometric mean of lodgen / best peer over the cells: Hausdorff {gh:.3}, RMS {gr:.3}.\n\n\
         ![error against triangle count](quality.png)\n"
    );
    if hand.is_empty() {
        let _ = writeln!(s, "{HAND_WRITTEN}");
    } else {
        s.push_str(hand);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(triangles: usize, hausdorff: f64, rms: f64) -> Cell {
        Cell {
            triangles,
            hausdorff,
            rms,
        }
    }

    /// fandisk 50 %: lodgen over Open3D, all four errors under ±0.00066 %.
    fn fandisk(rounding: Option<f64>) -> Row {
        let mut peers = vec![Some(cell(6472, 0.0322, 0.0019)); PEERS.len() + 1];
        peers[2] = Some(cell(6472, 0.000448, 0.0000294));
        Row {
            mesh: "fandisk",
            ratio: 0.5,
            lodgen: cell(6472, 0.000501, 0.0000324),
            peers,
            asked: 6472,
            rounding,
        }
    }

    #[test]
    fn a_cell_under_the_inputs_rounding_is_a_tie_not_a_loss() {
        let row = fandisk(Some(0.00066));
        assert_eq!(tie(&row), Some(0.00066));
        let md = report(&[row], 1000, "", "");
        assert!(!md.contains("**0.0005**") && !md.contains("**0.00003**"));
        assert!(md.contains("*tie*: under the input's rounding (±0.00066 %) (1.12 / 1.10)"));
        assert!(line(&fandisk(Some(0.00066))).contains("a tie"));
        // a rounding under lodgen's Hausdorff, or none known: a loss
        for rounding in [Some(0.0005), None] {
            let row = fandisk(rounding);
            assert_eq!(tie(&row), None);
            let md = report(&[row], 1000, "", "");
            assert!(md.contains("**0.0005** / **0.00003**") && !md.contains("*tie*: under"));
        }
    }
}
