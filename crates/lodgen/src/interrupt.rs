//! Unfinished outputs and what an interrupt does with them.
//!
//! Every file an output is written to first (a temporary name beside the
//! output, renamed when complete) is created through [`create`], which
//! records it, and leaves the record through [`rename`] or [`discard`].
//! The `lodgen` command calls [`install`] first: SIGINT, SIGTERM and SIGHUP
//! are then taken by a thread of their own, which removes every recorded
//! file, prints one line and ends the process with `128 + signal` (130 for
//! Ctrl-C). The record's lock is held while a file is created or renamed
//! and while the handler removes them, so no file is created after the
//! handler's sweep, nor renamed into place from under it. The library
//! (and the Python module, which leaves signals to Python) records the
//! same files without installing anything.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// The files being written now: temporary files, and side files of an
/// output already renamed into place before its main file.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> MutexGuard<'static, Vec<PathBuf>> {
    // (a panic while holding the lock leaves the list as valid as before)
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Creates (or truncates) `path`, recorded as unfinished.
pub fn create(path: &Path) -> std::io::Result<File> {
    let mut list = pending();
    let file = File::create(path)?;
    list.push(path.to_path_buf());
    Ok(file)
}

/// Renames the unfinished file `from` to `to`. With `keep`, `to` stays
/// recorded as unfinished (a side file whose main file is not in place
/// yet: [`discard`] it or [`finished`] it after the main file).
pub fn rename(from: &Path, to: &Path, keep: bool) -> std::io::Result<()> {
    let mut list = pending();
    std::fs::rename(from, to)?;
    list.retain(|p| p != from);
    if keep {
        list.push(to.to_path_buf());
    }
    Ok(())
}

/// Removes the unfinished files `paths` (errors ignored: a file not
/// created yet) and their records.
pub fn discard(paths: &[PathBuf]) {
    let mut list = pending();
    for p in paths {
        let _ = std::fs::remove_file(p);
    }
    list.retain(|p| !paths.contains(p));
}

/// The files `paths` are complete: no longer recorded.
pub fn finished(paths: &[PathBuf]) {
    pending().retain(|p| !paths.contains(p));
}

/// Writes `parts` to `path` through the temporary file `PATH.tmp`, renamed
/// when complete (removed on error or interrupt).
pub fn write_atomically(path: &Path, parts: &[&[u8]]) -> std::io::Result<()> {
    use std::io::Write;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let written = create(&tmp).and_then(|mut f| {
        for part in parts {
            f.write_all(part)?;
        }
        Ok(())
    });
    written
        .and_then(|()| rename(&tmp, path, false))
        .inspect_err(|_| discard(std::slice::from_ref(&tmp)))
}

/// Takes SIGINT, SIGTERM and SIGHUP on a thread of its own (see the
/// module's documentation). Call it before any other thread starts: the
/// signals are blocked in the calling thread, whose mask every thread
/// started after inherits. Does nothing elsewhere than on Unix.
pub fn install() {
    #[cfg(unix)]
    unix::install();
}

/// The handler's line: which signal, and what was removed.
fn message(signal: &str, removed: usize) -> String {
    match removed {
        0 => format!("lodgen: interrupted ({signal})"),
        1 => format!("lodgen: interrupted ({signal}); removed 1 unfinished output file"),
        n => format!("lodgen: interrupted ({signal}); removed {n} unfinished output files"),
    }
}

/// Removes every recorded file, holding the record's lock from then on
/// (the process ends with it held); returns how many existed.
fn sweep() -> (MutexGuard<'static, Vec<PathBuf>>, usize) {
    let list = pending();
    let removed = list
        .iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count();
    (list, removed)
}

#[cfg(unix)]
mod unix {
    use std::io::{IsTerminal, Write};

    /// The signals taken.
    const SIGNALS: [(libc::c_int, &str); 3] = [
        (libc::SIGINT, "SIGINT"),
        (libc::SIGTERM, "SIGTERM"),
        (libc::SIGHUP, "SIGHUP"),
    ];

    pub(super) fn install() {
        // SAFETY: `set` is a local sigset_t initialised by sigemptyset
        // before use; the calls only change this thread's signal mask.
        let set = unsafe {
            let mut set: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut set);
            for (s, _) in SIGNALS {
                libc::sigaddset(&mut set, s);
            }
            if libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) != 0 {
                return;
            }
            set
        };
        let started = std::thread::Builder::new()
            .name("lodgen-signals".into())
            .spawn(move || wait(set));
        if started.is_err() {
            // no thread to take them: the default action again
            // SAFETY: as above, on this thread's mask only.
            unsafe {
                libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
            }
        }
    }

    fn wait(set: libc::sigset_t) {
        let mut signal: libc::c_int = 0;
        // SAFETY: `set` is initialised; `signal` is a valid out pointer.
        while unsafe { libc::sigwait(&set, &mut signal) } != 0 {}
        // a second Ctrl-C while the files are removed ends the process at
        // once (the default action, on this thread, the only one taking it)
        // SAFETY: as in `install`, on this thread's mask only.
        unsafe {
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        }
        let (_held, removed) = super::sweep();
        let name = SIGNALS
            .iter()
            .find(|(s, _)| *s == signal)
            .map_or("a signal", |(_, n)| n);
        let mut err = std::io::stderr().lock();
        // (clear the progress line first)
        let clear = if err.is_terminal() { "\r\x1b[2K" } else { "" };
        let _ = writeln!(err, "{clear}{}", super::message(name, removed));
        let _ = err.flush();
        std::process::exit(128 + signal);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_line_says_what_was_removed() {
        assert_eq!(message("SIGINT", 0), "lodgen: interrupted (SIGINT)");
        assert_eq!(
            message("SIGTERM", 1),
            "lodgen: interrupted (SIGTERM); removed 1 unfinished output file"
        );
        assert_eq!(
            message("SIGINT", 3),
            "lodgen: interrupted (SIGINT); removed 3 unfinished output files"
        );
    }

    #[test]
    fn records_follow_create_rename_and_discard() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b, c) = (
            dir.path().join("a"),
            dir.path().join("b"),
            dir.path().join("c"),
        );
        let recorded = |p: &Path| pending().contains(&p.to_path_buf());
        drop(create(&a).unwrap());
        drop(create(&b).unwrap());
        assert!(recorded(&a) && recorded(&b));
        rename(&a, &c, true).unwrap();
        assert!(!recorded(&a) && recorded(&c) && c.exists());
        finished(std::slice::from_ref(&c));
        assert!(!recorded(&c) && c.exists());
        discard(std::slice::from_ref(&b));
        assert!(!recorded(&b) && !b.exists());
        // a file that cannot be created is not recorded
        let bad = dir.path().join("no/such/dir/x");
        assert!(create(&bad).is_err());
        assert!(!recorded(&bad));
        write_atomically(&a, &[b"ab", b"cd"]).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"abcd");
        assert!(!dir.path().join("a.tmp").exists() && !recorded(&dir.path().join("a.tmp")));
    }
}
