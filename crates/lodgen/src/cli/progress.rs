//! The progress line on a terminal (stderr): the phase (reading, welding,
//! simplifying with the share of the target reached, measuring level by
//! level, writing) and, once it can be estimated, the time left in the
//! phase; in batch mode, how many files are done and which are being
//! built. Nothing is shown on a pipe or with `-q` (the caller decides).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use lodgen_pm::{Meter, Stage};

use crate::lod::Progress;

/// The spinner and what its poller reads.
pub(super) struct Spinner {
    bar: ProgressBar,
    /// The simplification's progress, read by [`Spinner::poll`].
    pub(super) meter: Arc<Meter>,
    /// The mesh being built, and of how many (for the poller's line).
    mesh: AtomicUsize,
    meshes: AtomicUsize,
    /// Set when the build is over: the poller returns.
    pub(super) done: AtomicBool,
    /// Start of the measuring phase (levels take similar times).
    measure_start: Mutex<Instant>,
}

impl Spinner {
    pub(super) fn new() -> Spinner {
        let bar = ProgressBar::new_spinner();
        if let Ok(style) = ProgressStyle::with_template("{spinner} {elapsed:>3} {msg}") {
            bar.set_style(style);
        }
        bar.enable_steady_tick(Duration::from_millis(120));
        Spinner {
            bar,
            meter: Arc::new(Meter::default()),
            mesh: AtomicUsize::new(0),
            meshes: AtomicUsize::new(1),
            done: AtomicBool::new(false),
            measure_start: Mutex::new(Instant::now()),
        }
    }

    /// The line for a build event.
    pub(super) fn on_progress(&self, p: Progress, input: &Path, output: &Path) {
        let msg = match p {
            Progress::Reading => format!("reading {}", input.display()),
            Progress::Writing => format!("writing {}", output.display()),
            Progress::Simplifying { mesh, of } => {
                self.mesh.store(mesh, Relaxed);
                self.meshes.store(of, Relaxed);
                format!("mesh {}/{of}: preparing", mesh + 1)
            }
            Progress::Measuring { mesh, level, of } => {
                let mut start = self.measure_start.lock().unwrap_or_else(|e| e.into_inner());
                if level == 0 {
                    *start = Instant::now();
                }
                let eta = left(start.elapsed(), level as f64 / of as f64);
                format!("mesh {}: measuring level {}/{of}{eta}", mesh + 1, level + 1)
            }
        };
        self.bar.set_message(msg);
    }

    /// Until `done`: the simplification's stage and share of its target,
    /// read from the meter every 100 ms (the core never prints).
    pub(super) fn poll(&self) {
        let mut contracting_since: Option<Instant> = None;
        while !self.done.load(Relaxed) {
            std::thread::sleep(Duration::from_millis(100));
            let stage = self.meter.stage();
            let mesh = format!(
                "mesh {}/{}",
                self.mesh.load(Relaxed) + 1,
                self.meshes.load(Relaxed)
            );
            let msg = match stage {
                Stage::Idle => {
                    contracting_since = None;
                    continue;
                }
                Stage::Preparing => format!("{mesh}: welding, quadrics, pairs"),
                Stage::Contracting => {
                    let since = *contracting_since.get_or_insert_with(Instant::now);
                    let f = self.meter.fraction().unwrap_or(0.0);
                    format!(
                        "{mesh}: simplifying, {:.0} % of the target{}",
                        100.0 * f,
                        left(since.elapsed(), f)
                    )
                }
                Stage::Finishing => format!("{mesh}: simplifying, writing the vertex-split log"),
                Stage::Clustering => format!(
                    "{mesh}: simplifying, {:.0} % of the target, cutting the mesh into clusters",
                    100.0 * self.meter.fraction().unwrap_or(0.0)
                ),
            };
            // (the stage may have ended meanwhile: the main thread's line wins)
            if self.meter.stage() == stage && !self.done.load(Relaxed) {
                self.bar.set_message(msg);
            }
        }
    }

    pub(super) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Batch mode's line on a terminal: how many files are done and which are
/// being built, each finished file's line printed above it.
pub struct BatchProgress {
    bar: ProgressBar,
    total: usize,
    /// Files done, and the files being built.
    state: Mutex<(usize, Vec<PathBuf>)>,
}

impl BatchProgress {
    pub fn new(total: usize) -> BatchProgress {
        let bar = ProgressBar::new_spinner();
        if let Ok(style) = ProgressStyle::with_template("{spinner} {elapsed:>3} {msg}") {
            bar.set_style(style);
        }
        bar.enable_steady_tick(Duration::from_millis(120));
        bar.set_message(batch_line(0, total, &[]));
        BatchProgress {
            bar,
            total,
            state: Mutex::new((0, Vec::new())),
        }
    }

    /// A file's build begins.
    pub fn start(&self, input: &Path) {
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        state.1.push(input.to_path_buf());
        self.bar
            .set_message(batch_line(state.0, self.total, &state.1));
    }

    /// A file is done: `line` goes above the progress line.
    pub fn done(&self, input: &Path, line: &str) {
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        state.1.retain(|p| p != input);
        state.0 += 1;
        self.bar.println(line);
        self.bar
            .set_message(batch_line(state.0, self.total, &state.1));
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// `"3 of 22 files done; building a.obj, b.obj"`.
fn batch_line(done: usize, total: usize, building: &[PathBuf]) -> String {
    let mut line = format!("{done} of {total} files done");
    if !building.is_empty() {
        let names: Vec<String> = building.iter().map(|p| p.display().to_string()).collect();
        line += &format!("; building {}", names.join(", "));
    }
    line
}

/// `", about N s left"` once a share `done` of a phase took `elapsed`
/// (nothing before 5 % or one second: too early to say).
fn left(elapsed: Duration, done: f64) -> String {
    let t = elapsed.as_secs_f64();
    if done < 0.05 || t < 1.0 || done >= 1.0 {
        return String::new();
    }
    format!(", about {:.0} s left", t * (1.0 - done) / done)
}

#[cfg(test)]
mod tests {
    use super::{batch_line, left};
    use std::path::PathBuf;
    use std::time::Duration;

    #[test]
    fn the_batch_line_names_the_files_being_built() {
        assert_eq!(batch_line(0, 22, &[]), "0 of 22 files done");
        let building = [
            PathBuf::from("in/a b.obj"),
            PathBuf::from("big/bunny-1m.obj"),
        ];
        assert_eq!(
            batch_line(3, 22, &building),
            "3 of 22 files done; building in/a b.obj, big/bunny-1m.obj"
        );
    }

    #[test]
    fn time_left_is_proportional_and_silent_early() {
        assert_eq!(left(Duration::from_secs(10), 0.25), ", about 30 s left");
        assert_eq!(left(Duration::from_secs(10), 0.01), "");
        assert_eq!(left(Duration::from_millis(500), 0.5), "");
        assert_eq!(left(Duration::from_secs(10), 1.0), "");
    }
}
