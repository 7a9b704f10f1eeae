//! `cargo xtask stream-bench [--quick] [--runs N] [--bytes] [--mesh NAME] [--timeline]`: time to first pixel and
//! to full detail of a progressive file against the plain compressed full
//! mesh, over a throttled local line (10 Mbit/s, 50 ms latency, set in the
//! server), in headless Chromium with three.js (`tests/js/stream-bench.mjs`).
//!
//! Per mesh (the bunny, spot and the 1.1M-triangle subdivided bunny;
//! `--quick`: the bunny only; `--mesh NAME`: that one) it writes, with the release `lodgen`:
//! * plain: `lodgen X --levels 100% --quantize --compress meshopt`, loaded by
//!   GLTFLoader + MeshoptDecoder until drawn;
//! * progressive: `lodgen X --levels 100%,50%,10%,2% --progressive
//!   --quantize --compress meshopt`, loaded by lodgen's three.js loader (the
//!   coarsest level drawn = first pixel; the finest applied and drawn = full
//!   detail),
//!
//! and prints the table the README's Streaming section quotes, with the
//! stream's bytes against the plain file's and each time's floor (one
//! latency + the bytes needed at the line rate), and the best ratios those
//! floors allow (first pixel or full detail floor over the plain floor).
//!
//! Each mesh runs plain and progressive alternately, `--runs N` pairs
//! (default: the bunny 9, spot 21, bunny-1m 3: a small file's load is
//! ~100 ms, where the machine's load moves single runs by 50 %); the table
//! gives medians with their spread (min – max) and the median of the pairs'
//! own full/plain ratios. `--timeline` prints each run's loader timeline
//! and where the progressive full-detail time goes past its floor (line
//! lag, the last chunk's decode and apply, the final draw; main-thread
//! totals). `--bytes` writes the files and prints the stream's bytes per
//! column kind instead (no browser). `--decode worker|main|both`: where the
//! loader decodes the stream (its Web Worker, the default, or the page's
//! main thread; `both`: each run loads the progressive file both ways, a
//! table row each). `--cold`: the page loaded anew before each progressive
//! load (the decoder's JIT cold, as in a page's one load).

use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;

fn lodgen(exe: &Path, input: &Path, output: &Path, args: &[&str]) -> Result<()> {
    let status = Command::new(exe)
        .arg(input)
        .arg("-o")
        .arg(output)
        .args(args)
        .arg("--quiet")
        .status()
        .with_context(|| format!("running {}", exe.display()))?;
    anyhow::ensure!(status.success(), "lodgen {} failed", input.display());
    Ok(())
}

/// Bytes of the `LODGEN_progressive` stream in a written GLB, and the
/// bytes before it in the file (the JSON and, as lodgen writes it, the
/// coarsest level: what a client needs for its first pixel).
fn stream_bytes(path: &Path) -> Result<(usize, usize)> {
    let bytes = std::fs::read(path)?;
    let (root, bin) = lodgen::progressive::parse_glb(&bytes)?;
    let found = lodgen::progressive::find(&root)?.context("no LODGEN_progressive")?;
    let (_, off, len) = found.range;
    Ok((len, bytes.len() - bin.len() + off))
}

/// Prints where the stream's bytes go, per column kind (`--bytes`).
fn print_columns(id: &str, path: &Path, plain: usize) -> Result<()> {
    let bytes = std::fs::read(path)?;
    let (root, bin) = lodgen::progressive::parse_glb(&bytes)?;
    let found = lodgen::progressive::find(&root)?.context("no LODGEN_progressive")?;
    let (_, off, len) = found.range;
    let stream = &bin[off..off + len];
    let h = lodgen_pm::stream::decode_header(stream)?;
    let stats = lodgen_pm::stream::column_stats(stream)?;
    println!(
        "\n{id}: stream {len} B = {:.3}× the plain file ({plain} B); {} splits, {:.2} B/split; file bytes before the stream {}",
        len as f64 / plain as f64,
        h.split_count,
        len as f64 / h.split_count.max(1) as f64,
        bytes.len() - bin.len() + off,
    );
    println!(
        "{:<20} {:>10} {:>10} {:>7} {:>9}",
        "column", "values", "bytes", "share", "B/split"
    );
    for s in stats {
        println!(
            "{:<20} {:>10} {:>10} {:>6.1}% {:>9.3}",
            s.name,
            s.count,
            s.bytes,
            100.0 * s.bytes as f64 / len as f64,
            s.bytes as f64 / h.split_count.max(1) as f64
        );
    }
    Ok(())
}

/// The bench's throttled line: rate and latency per response.
#[derive(Clone, Copy)]
struct Line {
    mbit: f64,
    latency_ms: f64,
}

impl Line {
    /// The time (ms) `bytes` take on the line, one latency included.
    fn ms(self, bytes: usize) -> f64 {
        self.latency_ms + bytes as f64 * 8.0 / (self.mbit * 1e6) * 1e3
    }
}

/// The example line: 10 Mbit/s, 50 ms latency per response.
const DEFAULT_LINE: Line = Line {
    mbit: 10.0,
    latency_ms: 50.0,
};

const USAGE: &str = "usage: cargo xtask stream-bench [--quick] [--bytes] [--mesh bunny|spot|bunny-1m] [--runs N]
       [--timeline] [--decode worker|main|both] [--cold] [--mbit RATE] [--latency-ms MS]
  --quick        the bunny only
  --bytes        print the stream's columns and sizes, no browser
  --mesh NAME    one mesh (default: bunny, spot, bunny-1m)
  --runs N       pairs of alternating plain/progressive loads (default: bunny 9, spot 21, bunny-1m 3)
  --timeline     where the full-detail time goes past its floor
  --decode MODE  the loader's stream decoder: worker (default), main, or both alternating
  --cold         the page loaded anew before each progressive load (decoder JIT cold)
  --mbit RATE    the line's rate in Mbit/s (default 10)
  --latency-ms MS  latency per response in ms (default 50)";

/// Pairs of runs per mesh unless `--runs` says otherwise: enough that the
/// median of a ~100 ms load holds still on a loaded 2-core machine.
fn default_runs(mesh: &str) -> usize {
    match mesh {
        "spot" => 21,
        "bunny" => 9,
        _ => 3,
    }
}

struct Args {
    quick: bool,
    bytes_only: bool,
    runs: Option<usize>,
    mesh: Option<String>,
    timeline: bool,
    line: Line,
    /// stream-bench.mjs's `--decode` and `--cold`, passed on
    pass: Vec<String>,
}

/// The value after `flag`, a positive number.
fn positive(flag: &str, v: Option<&String>) -> Result<f64> {
    let x: f64 = v
        .with_context(|| format!("{flag} needs a number"))?
        .parse()
        .with_context(|| format!("{flag} needs a number"))?;
    anyhow::ensure!(x.is_finite() && x > 0.0, "{flag} needs a positive number");
    Ok(x)
}

/// `--quick`, `--bytes`, `--runs N`, `--mesh NAME`, `--timeline`,
/// `--decode MODE`, `--cold`, `--mbit RATE`, `--latency-ms MS` (see `USAGE`).
fn parse_args(args: &[String]) -> Result<Option<Args>> {
    let (mut quick, mut bytes_only, mut runs, mut timeline) = (false, false, None, false);
    let mut line = DEFAULT_LINE;
    let mut mesh = None;
    let mut pass = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--bytes" => bytes_only = true,
            "--timeline" => timeline = true,
            "--cold" => pass.push(a.clone()),
            "-h" | "--help" => return Ok(None),
            "--mbit" => line.mbit = positive(a, it.next())?,
            "--latency-ms" => line.latency_ms = positive(a, it.next())?,
            "--decode" => {
                let m = it.next().context("--decode needs worker, main or both")?;
                anyhow::ensure!(
                    ["worker", "main", "both"].contains(&m.as_str()),
                    "stream-bench: --decode {m:?} (worker, main or both)"
                );
                pass.extend([a.clone(), m.clone()]);
            }
            "--runs" => {
                let n: usize = it.next().context("--runs needs a number")?.parse()?;
                anyhow::ensure!(n > 0, "--runs needs at least 1");
                runs = Some(n);
            }
            "--mesh" => {
                let m = it.next().context("--mesh needs bunny, spot or bunny-1m")?;
                anyhow::ensure!(
                    ["bunny", "spot", "bunny-1m"].contains(&m.as_str()),
                    "stream-bench: unknown mesh {m:?} (bunny, spot or bunny-1m)"
                );
                mesh = Some(m.clone());
            }
            other => bail!("stream-bench: unknown argument {other:?}\n{USAGE}"),
        }
    }
    Ok(Some(Args {
        quick,
        bytes_only,
        runs,
        mesh,
        timeline,
        line,
        pass,
    }))
}

pub fn run(args: &[String]) -> Result<()> {
    let Args {
        quick,
        bytes_only,
        runs,
        mesh,
        timeline,
        line,
        pass,
    } = match parse_args(args)? {
        Some(a) => a,
        None => {
            println!("{USAGE}");
            return Ok(());
        }
    };
    let root = crate::workspace_root();
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .args(["build", "--release", "--quiet", "-p", "lodgen"])
        .current_dir(&root)
        .status()?;
    anyhow::ensure!(status.success(), "building lodgen failed");
    let exe = root.join("target/release/lodgen");
    let js = root.join("tests/js");
    anyhow::ensure!(
        bytes_only || js.join("node_modules/three").is_dir(),
        "tests/js/node_modules is missing: cd tests/js && npm ci"
    );
    let dir = root.join("target/stream-bench");
    std::fs::create_dir_all(&dir)?;
    let meshes: Vec<&str> = match (&mesh, quick) {
        (Some(m), _) => vec![m.as_str()],
        (None, true) => vec!["bunny"],
        (None, false) => vec!["bunny", "spot", "bunny-1m"],
    };
    let mut rows = Vec::new();
    for id in &meshes {
        let input = match *id {
            "spot" => crate::shared_assets()?.join("spot.obj"),
            _ => crate::e2e::mesh_file(id)?,
        };
        let plain = dir.join(format!("{id}-plain.glb"));
        let prog = dir.join(format!("{id}-progressive.glb"));
        let q = ["--quantize", "--compress", "meshopt"];
        lodgen(
            &exe,
            &input,
            &plain,
            &[&["--levels", "100%"][..], &q].concat(),
        )?;
        let levels = ["--levels", "100%,50%,10%,2%", "--progressive"];
        lodgen(&exe, &input, &prog, &[&levels[..], &q].concat())?;
        if bytes_only {
            print_columns(id, &prog, std::fs::metadata(&plain)?.len() as usize)?;
            continue;
        }
        let json = dir.join(format!("{id}.json"));
        let n = runs.unwrap_or_else(|| default_runs(id));
        let status = Command::new("node")
            .arg(js.join("stream-bench.mjs"))
            .arg("--progressive")
            .arg(&prog)
            .arg("--plain")
            .arg(&plain)
            .args(["--name", id, "--runs", &n.to_string()])
            .args(timeline.then_some("--timeline"))
            .args(&pass)
            .args([
                "--mbit",
                &line.mbit.to_string(),
                "--latency-ms",
                &line.latency_ms.to_string(),
            ])
            .arg("--json")
            .arg(&json)
            .current_dir(&root)
            .status()?;
        anyhow::ensure!(status.success(), "stream-bench.mjs failed on {id}");
        let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json)?)?;
        let plain_bytes = std::fs::metadata(&plain)?.len() as usize;
        let (stream, before) = stream_bytes(&prog)?;
        let floors = [
            line.ms(plain_bytes),
            line.ms(before),
            line.ms(before + stream),
        ];
        let ratio = stream as f64 / plain_bytes as f64;
        // `--decode both`: a row per decoder
        match r["decoders"].as_object().filter(|d| d.len() > 1) {
            Some(d) => {
                for (mode, v) in d {
                    rows.push((format!("{id} [{mode}]"), v.clone(), ratio, floors));
                }
            }
            None => rows.push((id.to_string(), r, ratio, floors)),
        }
    }
    if bytes_only {
        return Ok(());
    }
    print_table(&rows, timeline, line);
    Ok(())
}

/// `median (min – max)` of a stats object of stream-bench.mjs, `d` decimals.
fn spread(v: &serde_json::Value, d: usize) -> String {
    let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    format!("{:.d$} ({:.d$}–{:.d$})", f("median"), f("min"), f("max"))
}

type Row = (String, serde_json::Value, f64, [f64; 3]);

fn print_table(rows: &[Row], timeline: bool, line: Line) {
    let Line { mbit, latency_ms } = line;
    println!("\nthrottled line: {mbit} Mbit/s, {latency_ms} ms latency per response; three.js in headless Chromium; plain and progressive alternately, N pairs");
    println!(
        "ms: median (min–max) over the runs; ratios: median (min–max) of each pair's own ratio"
    );
    println!("floors: one latency + the bytes needed at the line rate (plain: the file; first pixel: JSON + coarsest level; full: + stream), no parsing or drawing");
    println!("(floor ratios: the best first/pl and full/pl these bytes allow, floor over the plain floor; first/pl <= 0.1 needs a plain file of at least 9 latencies of bytes)");
    println!(
        "{:<9} {:>3} {:>20} {:>6} {:>8} {:>16} {:>6} {:>20} {:>6} {:>17} {:>7} {:>17} {:>7}",
        "mesh",
        "N",
        "plain ms",
        "floor",
        "str/pl",
        "first px ms",
        "floor",
        "full ms",
        "floor",
        "first/pl",
        "(floor)",
        "full/pl",
        "(floor)"
    );
    for (id, r, ratio, [plain, first, full]) in rows {
        println!(
            "{:<9} {:>3} {:>20} {:>6.0} {:>7.2}× {:>16} {:>6.0} {:>20} {:>6.0} {:>17} {:>6.2}× {:>17} {:>6.2}×",
            id,
            r["runs"].as_u64().unwrap_or(0),
            spread(&r["plain"], 0),
            plain,
            ratio,
            spread(&r["firstPixel"], 0),
            first,
            spread(&r["fullDetail"], 0),
            full,
            spread(&r["firstRatio"], 2),
            first / plain,
            spread(&r["fullRatio"], 2),
            full / plain,
        );
    }
    if !timeline {
        return;
    }
    println!("\nwhere the time goes (medians, ms): plain past its floor (loaded, then its draw); progressive full detail past its floor:");
    println!("line lag (the stream's last byte after its floor), then decoding the last chunk, applying it (+ normals), the final draw;");
    println!("main-thread totals of the whole progressive load: coarse level parse, decode, apply, normals, draws (count, ms)");
    println!(
        "{:<9} {:>8} {:>6} | {:>8} {:>7} {:>7} {:>7} | {:>6} {:>7} {:>6} {:>8} {:>12}",
        "mesh",
        "pl late",
        "pl drw",
        "line lag",
        "decode",
        "apply",
        "draw",
        "parse",
        "decode",
        "apply",
        "normals",
        "draws"
    );
    for (id, r, _, _) in rows {
        let p = |k: &str| r["parts"][k].as_f64().unwrap_or(f64::NAN);
        let q = |k: &str| r["plainParts"][k].as_f64().unwrap_or(f64::NAN);
        println!(
            "{:<9} {:>8.0} {:>6.0} | {:>8.0} {:>7.0} {:>7.0} {:>7.0} | {:>6.0} {:>7.0} {:>6.0} {:>8.0} {:>4.0} {:>7.0}",
            id,
            q("lag"),
            q("draw"),
            p("lag"),
            p("tailDecode"),
            p("tailApply"),
            p("finalDraw"),
            p("parse"),
            p("decode"),
            p("apply"),
            p("normals"),
            p("draws"),
            p("drawMs"),
        );
    }
}
