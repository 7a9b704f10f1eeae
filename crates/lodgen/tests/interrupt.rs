//! Ctrl-C (SIGINT) or SIGTERM while `lodgen` writes its output: the
//! temporary files (`.NAME.PID.lodgen-tmp`) and any output whose main file
//! is not in place are removed, one line says so, and the exit code is
//! 128 + the signal (130 for SIGINT).
//!
//! No timing luck: the child makes one of its own temporary names a FIFO
//! before it starts (its PID is known then), and the test holds the FIFO's
//! reading end. The child's write into it blocks once the pipe is full, so
//! the test sends the signal only after it has read the first bytes (the
//! write has begun) while the rest cannot have been written (the file is
//! larger than the pipe).
#![cfg(unix)]

mod support;

use std::fs::File;
use std::io::Read;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::OpenOptionsExt;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// An OBJ of 81,920 triangles in `dir` (its finest level's buffer is far
/// larger than a pipe's 64 KiB).
fn input(dir: &Path, name: &str) -> PathBuf {
    let m = lodgen_pm::shapes::icosphere(6);
    let path = dir.join(name);
    std::fs::write(
        &path,
        support::obj_text(&[("", &m.positions, &m.triangles)]),
    )
    .unwrap();
    path
}

/// `lodgen ARGS` in `cwd`, whose temporary file for `out` (a path in
/// `out_dir`) is a FIFO made in the child before `exec`; returns the child
/// and the FIFO's path once the child has begun writing into it.
fn spawn_blocked(
    args: &[&str],
    cwd: &Path,
    out_dir: &Path,
    out: &str,
    terminal: Option<&Path>,
) -> (std::process::Child, PathBuf, File) {
    // ".{out}.{pid}.lodgen-tmp", the name built in the child without
    // allocating (only async-signal-safe calls between fork and exec)
    let head: Vec<u8> = [out_dir.as_os_str().as_bytes(), b"/.", out.as_bytes(), b"."].concat();
    let tail: &[u8] = b".lodgen-tmp\0";
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lodgen"));
    cmd.args(args).current_dir(cwd).stdin(Stdio::null());
    match terminal {
        // (standard output and error on that terminal)
        Some(t) => {
            let open = || {
                std::fs::OpenOptions::new()
                    .write(true)
                    .custom_flags(libc::O_NOCTTY)
                    .open(t)
                    .unwrap()
            };
            cmd.stdout(open()).stderr(open())
        }
        None => cmd.stdout(Stdio::piped()).stderr(Stdio::piped()),
    };
    // SAFETY: the closure writes into a stack buffer and calls getpid and
    // mkfifo, both async-signal-safe; it allocates nothing.
    unsafe {
        cmd.pre_exec(move || {
            let mut buf = [0u8; 4096];
            let mut n = 0;
            for &b in &head {
                buf[n] = b;
                n += 1;
            }
            let mut pid = libc::getpid() as u32;
            let mut digits = [0u8; 10];
            let mut d = 0;
            loop {
                digits[d] = b'0' + (pid % 10) as u8;
                d += 1;
                pid /= 10;
                if pid == 0 {
                    break;
                }
            }
            while d > 0 {
                d -= 1;
                buf[n] = digits[d];
                n += 1;
            }
            for &b in tail {
                buf[n] = b;
                n += 1;
            }
            if libc::mkfifo(buf.as_ptr().cast(), 0o600) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let child = cmd.spawn().unwrap();
    let fifo = out_dir.join(format!(".{out}.{}.lodgen-tmp", child.id()));
    // (non-blocking open: there is no writer yet)
    let mut reader = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(&fifo)
        .unwrap();
    // wait until the child writes (it then blocks once the pipe is full)
    let mut byte = [0u8; 1];
    loop {
        match reader.read(&mut byte) {
            Ok(1) => break,
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => panic!("reading the FIFO: {e}"),
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    (child, fifo, reader)
}

/// Sends `signal` and returns the exit code and standard error.
fn interrupt(child: std::process::Child, signal: libc::c_int) -> (Option<i32>, String) {
    // SAFETY: kill with the PID of a child not yet waited for.
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, signal) }, 0);
    let out = child.wait_with_output().unwrap();
    (out.status.code(), support::stderr(&out))
}

/// Names of the files in `dir` (not directories), sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = walkdir::WalkDir::new(dir)
        .into_iter()
        .filter_map(Result::ok)
        .filter(|e| !e.file_type().is_dir())
        .map(|e| e.path().strip_prefix(dir).unwrap().display().to_string())
        .collect();
    names.sort();
    names
}

/// A `.gltf` output (a main file and one `.bin` per level): interrupted
/// while its finest level's buffer is written, the main file's and the
/// coarser levels' temporary files are removed as well: nothing is left.
#[test]
fn sigint_during_the_write_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("in");
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&src).unwrap();
    let mesh = input(&src, "ico.obj");
    let target = out.join("ico.gltf");
    let args = [
        mesh.to_str().unwrap(),
        "-o",
        target.to_str().unwrap(),
        "--levels",
        "100%,10%,2%",
    ];
    // the finest level's buffer is the last temporary file written
    let (child, fifo, _reader) = spawn_blocked(&args, dir.path(), &out, "ico.lod0.bin", None);
    let (code, err) = interrupt(child, libc::SIGINT);
    assert_eq!(code, Some(130), "{err}");
    assert!(
        err.contains("lodgen: interrupted (SIGINT); removed 4 unfinished output files"),
        "{err}"
    );
    assert_eq!(err.matches("interrupted").count(), 1, "{err}");
    assert!(!fifo.exists());
    assert_eq!(files(&out), Vec::<String>::new());
}

/// Batch mode (`--out-dir`, one file at a time): SIGTERM while the second
/// output is written leaves the first, complete, output and nothing of
/// the second, and the manifest knows the first: a re-run skips it.
#[test]
fn sigterm_in_a_batch_keeps_finished_outputs_only() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("in");
    let out = dir.path().join("out");
    std::fs::create_dir_all(&src).unwrap();
    std::fs::create_dir_all(&out).unwrap();
    input(&src, "a.obj");
    input(&src, "b.obj");
    let args = [
        "in",
        "--out-dir",
        "out",
        "--jobs",
        "1",
        "--levels",
        "50%,10%",
    ];
    let (child, _fifo, _reader) = spawn_blocked(&args, dir.path(), &out, "b.glb", None);
    let (code, err) = interrupt(child, libc::SIGTERM);
    assert_eq!(code, Some(143), "{err}");
    assert!(
        err.contains("lodgen: interrupted (SIGTERM); removed 1 unfinished output file"),
        "{err}"
    );
    assert_eq!(
        files(&out),
        vec![".lodgen-manifest.json".to_string(), "a.glb".to_string()]
    );
    let a = std::fs::read(out.join("a.glb")).unwrap();
    assert_eq!(&a[..4], b"glTF");
    assert_eq!(
        u32::from_le_bytes([a[8], a[9], a[10], a[11]]) as usize,
        a.len()
    );
    // the manifest recorded the finished file as it ended: the batch run
    // again builds only the other one (it rebuilt both)
    let o = support::lodgen_in(&args, dir.path());
    assert!(o.status.success(), "{}", support::stderr(&o));
    let table = support::stdout(&o);
    let status = |name: &str| {
        table
            .lines()
            .find(|l| l.contains(name))
            .and_then(|l| l.split_whitespace().last())
            .unwrap_or_default()
            .to_string()
    };
    assert_eq!(
        (status("a.obj"), status("b.obj")),
        ("unchanged".into(), "built".into()),
        "{table}"
    );
}

/// A pseudo-terminal: the master's descriptor and the slave's path.
fn pty() -> (File, PathBuf) {
    use std::os::unix::io::FromRawFd;
    // SAFETY: posix_openpt returns a new descriptor (checked), which the
    // File owns from then on; grantpt/unlockpt/ptsname take that
    // descriptor; ptsname's static buffer is copied out at once.
    unsafe {
        let fd = libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY);
        assert!(fd >= 0);
        let master = File::from_raw_fd(fd);
        assert_eq!(libc::grantpt(fd), 0);
        assert_eq!(libc::unlockpt(fd), 0);
        let name = libc::ptsname(fd);
        assert!(!name.is_null());
        let slave = std::ffi::CStr::from_ptr(name)
            .to_string_lossy()
            .into_owned();
        (master, PathBuf::from(slave))
    }
}

/// Ctrl-C while the progress line is drawn on a terminal (the spinner
/// ticks while the output's write is blocked): the line is cleared, the
/// message printed, and nothing is drawn after it (the message holds
/// standard error until the process ends).
#[test]
fn nothing_is_drawn_after_the_interrupt_message_on_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = input(dir.path(), "ico.obj");
    let target = dir.path().join("ico.glb");
    let (mut master, slave) = pty();
    // (read all along: a full terminal buffer would block the child's output)
    let reader = std::thread::spawn(move || {
        let mut seen = Vec::new();
        let mut buf = [0u8; 4096];
        // until EOF, or EIO once no slave is open (Linux)
        while let Ok(n) = master.read(&mut buf) {
            if n == 0 {
                break;
            }
            seen.extend_from_slice(&buf[..n]);
        }
        seen
    });
    let args = [mesh.to_str().unwrap(), "-o", target.to_str().unwrap()];
    let (child, _fifo, _r) = spawn_blocked(&args, dir.path(), dir.path(), "ico.glb", Some(&slave));
    // a few spinner ticks (120 ms) while the write is blocked
    std::thread::sleep(std::time::Duration::from_millis(500));
    let (code, _) = interrupt(child, libc::SIGINT);
    let seen = reader.join().unwrap();
    let text = String::from_utf8_lossy(&seen);
    assert_eq!(code, Some(130), "{text:?}");
    assert!(text.contains("writing"), "{text:?}");
    assert!(
        text.ends_with(
            "\r\x1b[2Klodgen: interrupted (SIGINT); removed 1 unfinished output file\r\n"
        ),
        "{text:?}"
    );
    assert!(!target.exists());
}
