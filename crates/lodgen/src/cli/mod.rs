//! The command line's building blocks, in the library so tests and the
//! xtask drive exactly what users run: argument types (clap), level-list
//! parsing, the build job (read → LODs → write → table / JSON report) and
//! `measure`.
//!
//! Owns user-facing text (tables, progress, error context). The algorithms
//! are in `lod` and the core; formats in `io` and `gltf_out`.
//!
//! # Files
//! `args` (clap arguments → options) → `job` (`build_file`: read → LODs →
//! write, timed) → `output` (tables, `--report`), `progress` (the progress
//! line: build events and the simplification's `Meter`, polled); `measure`
//! (`lodgen measure`), `golden` (golden summaries), `errors` (an error's
//! cause chain without repeats, as every front end shows it).

mod args;
mod errors;
mod golden;
pub(crate) mod job;
mod measure;
mod output;
mod progress;

pub use args::{
    default_output, parse_attribute_weights, parse_levels, parse_max_errors, parse_tau,
    BoundaryMode, BuildArgs, CompressMode, MeasureMode, PlacementMode, ScheduleMode,
};
pub use errors::{error_line, error_parts};
pub use golden::golden_summary;
pub use job::{build_file, build_file_metered, BuiltFile, FileTimes};
pub use measure::{
    check_sample_count, measure_files, measure_report, merged_mesh, world_triangles,
    MAX_AREA_SAMPLES,
};
pub use output::{
    build, check_parent_dir, check_report_path, check_report_targets, report_to_stdout, stop_note,
    table, write_atomically, write_report,
};
pub use progress::BatchProgress;
