//! The `lodgen` command: read a mesh, build its LOD chain in one
//! simplification pass, measure every level, write glTF with `MSFT_lod`.
//! Also `inspect`, `measure` and `view`.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use lodgen::cli::{self, BuildArgs};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

/// Turn a triangle mesh into a chain of levels of detail (glTF 2.0 with
/// MSFT_lod) and a progressive mesh, by Garland–Heckbert quadric pair
/// contraction that records every contraction as a vertex split.
///
/// Exit codes: 0 written; 1 error (nothing written); 2 bad arguments;
/// 3 written, with warnings (a part of the input left out or written
/// unsimplified, each printed as `warning: FILE: PLACE: what`; --strict
/// makes them errors); 130 interrupted (Ctrl-C; 143 SIGTERM, 129 SIGHUP):
/// unfinished outputs removed.
///
/// Examples:
///   lodgen bunny.obj --levels 50%,10%,2% -o bunny.glb
///   lodgen scan.ply --max-error 0.1%,0.5%,2% --report scan.json
///   lodgen inspect bunny.glb
///   lodgen measure bunny.obj bunny.glb
///   lodgen bunny.obj --progressive -o bunny.glb && lodgen view bunny.glb
#[derive(Parser, Debug)]
#[command(name = "lodgen", version, verbatim_doc_comment)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    build: BuildArgs,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Print the LOD structure of a glTF file: chains, levels, triangle and
    /// vertex counts, screen coverage.
    Inspect {
        /// A .glb or .gltf file.
        file: PathBuf,
    },
    /// Print the distance between two meshes (any readable format; the
    /// meshes each file's scene draws are merged, node transforms not
    /// applied): one-sided and symmetric Hausdorff, mean and RMS, absolute
    /// and in % of A's bounding-box diagonal. For a LOD file, its finest
    /// level is used.
    Measure(MeasureArgs),
    /// Serve a WebGL2 viewer on 127.0.0.1 that shows the coarsest level and
    /// streams the vertex-split log (LODGEN_progressive) to refine it, with a
    /// level slider, a triangle counter, orbit controls and a mode that
    /// switches MSFT_lod levels by screen coverage. FILE is a lodgen output
    /// written with --progressive, or any readable mesh (simplified in
    /// memory first).
    View {
        /// A .glb/.gltf with LODGEN_progressive, or any mesh lodgen reads.
        file: PathBuf,
        /// TCP port on 127.0.0.1 (0 = any free port).
        #[arg(long, default_value_t = 8080)]
        port: u16,
        /// Print the per-level record counts and triangle counts, then exit.
        #[arg(long)]
        print_levels: bool,
    },
}

#[derive(Args, Debug)]
struct MeasureArgs {
    /// The reference mesh (A).
    a: PathBuf,
    /// The mesh compared with it (B).
    b: PathBuf,
    /// Area samples per triangle of the larger mesh, up to 2,048 triangles,
    /// then N·√(2,048·t) (plus every vertex and a max-seeking search).
    #[arg(long, default_value_t = 2.0, value_name = "N")]
    samples: f64,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    quiet_on_closed_pipe();
    // (before any thread: Ctrl-C removes unfinished outputs, exit 130)
    lodgen::interrupt::install();
    let cli = Cli::parse();
    // (after parsing, which starts no thread: the setting depends on the input's size)
    tune_allocator(&cli);
    let result = match cli.command {
        Some(Command::Inspect { file }) => lodgen::inspect::inspect(&file)
            .with_context(|| format!("inspecting {}", file.display()))
            .map(|r| print!("{r}"))
            .map(|()| 0),
        Some(Command::Measure(m)) => cli::measure_files(&m.a, &m.b, m.samples, m.json).map(|()| 0),
        Some(Command::View {
            file,
            port,
            print_levels,
        }) => if print_levels {
            lodgen::view::print_levels(&file).map(|s| println!("{s}"))
        } else {
            lodgen::view::serve(&file, port)
        }
        .with_context(|| format!("viewing {}", file.display()))
        .map(|()| 0),
        None => {
            // (a bad value is a bad argument, as clap's own errors are)
            if let Err(e) = cli.build.check() {
                print_error(&e);
                return ExitCode::from(2);
            }
            run_build(cli.build)
        }
    };
    match result {
        Ok(0) => ExitCode::SUCCESS,
        // written, with warnings
        Ok(_) => ExitCode::from(3),
        Err(e) => {
            print_error(&e);
            ExitCode::FAILURE
        }
    }
}

/// `error: …` and its causes, one a line, on stderr.
fn print_error(e: &anyhow::Error) {
    let parts = cli::error_parts(e);
    let mut parts = parts.iter();
    eprintln!("error: {}", parts.next().map_or("", |p| p.as_str()));
    for cause in parts {
        eprintln!("  caused by: {cause}");
    }
}

/// The build; returns the number of warnings.
fn run_build(args: BuildArgs) -> Result<usize> {
    // (before the work, which a report that cannot be written would throw away)
    cli::check_report_path(&args)?;
    if lodgen::batch::is_batch(&args) {
        return lodgen::batch::run(&args);
    }
    let Some(input) = args.inputs.first().cloned() else {
        bail!("no input mesh given (try `lodgen --help`)");
    };
    let show_progress = !args.quiet && std::io::stderr().is_terminal();
    cli::build(&input, &args, show_progress)
}

/// `lodgen … | head` must end quietly when the reader goes away, as every
/// Unix tool does, not panic in `println!` ("failed printing to stdout").
/// Outputs are written before the table is printed, so nothing is cut short.
fn quiet_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE, before any
    // thread is started; no handler runs Rust code.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// One input file up to this size (the bunny's OBJ, 69,451 triangles, is
/// 2.4 MB) is built with freed blocks kept for reuse (see [`tune_allocator`]).
const SMALL_INPUT_BYTES: u64 = 8 << 20;

/// glibc's malloc serves blocks of 128 KiB and more by `mmap` and gives
/// them back on `free`, but after freeing one it raises that threshold to
/// the freed block's size (up to 32 MiB): the simplifier's and the
/// measurement's large arrays freed between phases then stay resident in
/// the heap, and the next phase's peak stacks on them. A fixed threshold
/// keeps returning them (bunny-1m: peak 396 -> 352 MB, same bytes).
///
/// A build of one small file does the opposite: every block returned is a
/// block the next phase maps again, and the kernel faults and zeroes its
/// pages anew (the bunny's run spent ~8 % of its CPU there). Up to
/// [`SMALL_INPUT_BYTES`] of input, blocks up to 32 MiB come from the heap
/// and the heap keeps up to 64 MiB of free memory: CPU −7 to −9 % (one
/// thread), peak 22.7 → ~30 MB (docs/performance.md).
fn tune_allocator(cli: &Cli) {
    let small = cli.command.is_none()
        && !lodgen::batch::is_batch(&cli.build)
        && cli.build.inputs.first().is_some_and(|p| {
            std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.len() <= SMALL_INPUT_BYTES)
        });
    if small {
        keep_freed_blocks();
    } else {
        return_large_blocks();
    }
}

/// For a small build: blocks below 32 MiB from the heap, up to 64 MiB of
/// free heap kept (glibc; elsewhere nothing).
fn keep_freed_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; called before any
    // thread is started.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 64 << 20);
    }
}

/// For any other run: the fixed 128 KiB threshold (the reason above).
fn return_large_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets an allocator parameter; called before any
    // thread is started.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 << 10);
    }
}
