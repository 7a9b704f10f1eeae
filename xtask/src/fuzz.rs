//! `cargo xtask fuzz [--cases N] [--seed S]`: structure-aware mutations of
//! valid files of every input format (`lodgen::fuzz::seeds`: OBJ, ASCII and
//! binary PLY, SMF, GLB plain, quantized + meshopt-compressed, and with a
//! `LODGEN_progressive` stream written at run time, and a glTF scene with
//! morph targets, a skin, animations, a camera, a light and material
//! extensions), each run in-process
//! through `lodgen::fuzz::run_case` (inspect and stream decode + replay of
//! GLB input, read, measure, build, write, inspect, read back) with a
//! timeout. Cases and shrinking come from proptest's
//! runner with a fixed seed, so a run is reproducible. A panic, a hang or a
//! defect `run_case` reports is shrunk to a small case, stored under
//! `tests/fuzz-regressions/` (replayed by `cargo test` forever, see
//! crates/lodgen/tests/fuzz_regressions.rs), and the task fails.

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner};

use crate::workspace_root;

/// Longest a case may take before it counts as a hang.
const CASE_TIMEOUT: Duration = Duration::from_secs(20);

/// Values a number in a text file is replaced with: the edges readers trip on.
const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1e309",
    "-1e309",
    "nan",
    "inf",
    "4294967295",
    "4294967296",
    "2147483648",
    "99999999999999999999",
    "0x10",
    "",
    "1.5",
    "-0",
];

/// One edit of a seed file.
#[derive(Clone, Debug)]
enum Mutation {
    /// Flip one bit (position taken modulo the length).
    Flip { at: usize, bit: u8 },
    /// Keep only a prefix (length modulo the length + 1).
    Truncate { len: usize },
    /// Copy a slice of the file to another place (duplicated chunks, lines).
    Duplicate { from: usize, len: usize, to: usize },
    /// Delete a slice.
    Delete { from: usize, len: usize },
    /// Overwrite 4 bytes with an extreme little-endian u32 (binary counts).
    Word { at: usize, value: u32 },
    /// Replace the number starting at or after a position by an edge value.
    Number { at: usize, which: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        any::<usize>().prop_map(|len| Mutation::Truncate { len }),
        (any::<usize>(), 1usize..64, any::<usize>())
            .prop_map(|(from, len, to)| Mutation::Duplicate { from, len, to }),
        (any::<usize>(), 1usize..64).prop_map(|(from, len)| Mutation::Delete { from, len }),
        (
            any::<usize>(),
            prop_oneof![
                Just(0u32),
                Just(u32::MAX),
                Just(0x7fff_ffff),
                Just(0x8000_0000),
                any::<u32>()
            ]
        )
            .prop_map(|(at, value)| Mutation::Word { at, value }),
        (any::<usize>(), 0..NUMBERS.len()).prop_map(|(at, which)| Mutation::Number { at, which }),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    let n = bytes.len();
    match *m {
        Mutation::Flip { at, bit } if n > 0 => bytes[at % n] ^= 1 << bit,
        Mutation::Truncate { len } => bytes.truncate(len % (n + 1)),
        Mutation::Duplicate { from, len, to } if n > 0 => {
            let from = from % n;
            let chunk = bytes[from..(from + len).min(n)].to_vec();
            let to = to % (n + 1);
            bytes.splice(to..to, chunk);
        }
        Mutation::Delete { from, len } if n > 0 => {
            let from = from % n;
            bytes.drain(from..(from + len).min(n));
        }
        Mutation::Word { at, value } if n >= 4 => {
            let at = at % (n - 3);
            bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
        }
        Mutation::Number { at, which } if n > 0 => {
            let is_num = |b: u8| b.is_ascii_digit() || b == b'.' || b == b'-' || b == b'e';
            let Some(start) = (at % n..n).find(|&i| is_num(bytes[i])) else {
                return;
            };
            let end = (start..n).find(|&i| !is_num(bytes[i])).unwrap_or(n);
            bytes.splice(start..end, NUMBERS[which].bytes());
        }
        _ => {}
    }
}

/// The seed's bytes with the mutations applied: to the whole file, or with
/// `focused` to the seed's focus only (kept at its length: cut bytes are
/// zero-filled, added ones dropped), so the container stays readable.
fn mutated(seed: &lodgen::fuzz::Seed, muts: &[Mutation], focused: bool) -> Vec<u8> {
    let mut bytes = seed.bytes.clone();
    match seed.focus.clone().filter(|_| focused) {
        Some(range) => {
            let mut part = bytes[range.clone()].to_vec();
            for m in muts {
                apply(&mut part, m);
            }
            part.resize(range.len(), 0);
            bytes[range].copy_from_slice(&part);
        }
        None => muts.iter().for_each(|m| apply(&mut bytes, m)),
    }
    bytes
}

/// What a case did, or the defect it found.
fn run_with_timeout(dir: &Path, ext: &'static str, bytes: Vec<u8>) -> Result<String, String> {
    let (tx, rx) = mpsc::channel();
    let dir = dir.to_path_buf();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(|| lodgen::fuzz::run_case(&dir, ext, &bytes));
        let _ = tx.send(r);
    });
    match rx.recv_timeout(CASE_TIMEOUT) {
        Ok(Ok(r)) => r,
        Ok(Err(panic)) => Err(format!(
            "panic: {}",
            panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("(no message)")
        )),
        Err(_) => Err(format!("no answer within {CASE_TIMEOUT:?} (a hang)")),
    }
}

/// Where failing cases are kept, replayed by `cargo test`.
pub fn regressions_dir() -> PathBuf {
    workspace_root().join("tests").join("fuzz-regressions")
}

pub fn run(args: &[String]) -> Result<()> {
    let mut cases = 2000u32;
    let mut seed = 1u64;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .with_context(|| format!("{name} needs a value"))
                .cloned()
        };
        match a.as_str() {
            "--cases" => cases = value("--cases")?.parse().context("--cases N")?,
            "--seed" => seed = value("--seed")?.parse().context("--seed S")?,
            other => {
                bail!("unknown argument {other} (usage: cargo xtask fuzz [--cases N] [--seed S])")
            }
        }
    }
    let work = tempfile::tempdir()?;
    let seeds = lodgen::fuzz::seeds(work.path()).map_err(anyhow::Error::msg)?;
    // panics are expected to be caught and reported once, not printed per case
    std::panic::set_hook(Box::new(|_| {}));
    let mut rng_seed = [0u8; 32];
    rng_seed[..8].copy_from_slice(&seed.to_le_bytes());
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases,
            failure_persistence: None,
            max_shrink_iters: 2000,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &rng_seed),
    );
    // focused: the mutations go to the seed's focus (the progressive
    // stream) only, the file around it intact
    let strategy = (
        0..seeds.len(),
        prop::collection::vec(mutation(), 1..6),
        any::<bool>(),
    );
    let t0 = Instant::now();
    let outcomes = std::cell::RefCell::new(std::collections::BTreeMap::<String, usize>::new());
    let result = runner.run(&strategy, |(s, muts, focused)| {
        let seed = &seeds[s];
        let bytes = mutated(seed, &muts, focused);
        match run_with_timeout(work.path(), seed.ext, bytes) {
            Ok(what) => {
                let kind = what.split(':').next().unwrap_or("").to_string();
                *outcomes
                    .borrow_mut()
                    .entry(format!("{}: {kind}", seed.name))
                    .or_default() += 1;
                Ok(())
            }
            Err(defect) => Err(TestCaseError::fail(defect)),
        }
    });
    let _ = std::panic::take_hook();
    println!(
        "fuzz: {cases} cases, seed {seed}, {:.1} s",
        t0.elapsed().as_secs_f64()
    );
    for (k, n) in outcomes.borrow().iter() {
        println!("  {n:>6}  {k}");
    }
    match result {
        Ok(()) => {
            println!("fuzz: no panic, hang or defect");
            Ok(())
        }
        Err(TestError::Fail(why, (s, muts, focused))) => {
            let seed_file = &seeds[s];
            let bytes = mutated(seed_file, &muts, focused);
            let dir = regressions_dir();
            std::fs::create_dir_all(&dir)?;
            let name = format!(
                "{}-{:016x}.{}",
                seed_file.name,
                fnv1a(&bytes),
                seed_file.ext
            );
            std::fs::write(dir.join(&name), &bytes)?;
            bail!(
                "fuzz found a defect ({why}) from seed {} with {muts:?}; the case is stored as \
                 tests/fuzz-regressions/{name} (commit it: cargo test replays it)",
                seed_file.name
            )
        }
        Err(TestError::Abort(why)) => bail!("fuzz aborted: {why}"),
    }
}

/// FNV-1a, for stable file names.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}
