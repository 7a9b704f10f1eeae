//! Reader speed against the disk and parse floors (issue 14):
//! `read_timing MESH ROUNDS` reads MESH ROUNDS times and prints one line per
//! round: the floor (the file's bytes read into memory, then a scan for line
//! ends), then `lodgen::io::read_scene` — wall and CPU milliseconds of the
//! process (every thread), and the triangles read.
//!
//! `read_timing MESH --to-ply OUT` writes MESH (every mesh merged, positions
//! and triangles) as binary little-endian PLY: `float x y z`, faces as
//! `list uchar int vertex_indices`, the layout scanners write.

use std::io::Write;
use std::time::Instant;

use anyhow::{bail, Context, Result};

fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes the struct it is given.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut ru) };
    let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
    t(ru.ru_utime) + t(ru.ru_stime)
}

fn to_ply(input: &str, output: &str) -> Result<()> {
    let scene =
        lodgen::io::read_scene(input.as_ref()).with_context(|| format!("reading {input}"))?;
    let m = lodgen::cli::merged_mesh(&scene);
    let mut w = std::io::BufWriter::new(std::fs::File::create(output)?);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        m.positions.len(),
        m.triangles.len()
    )?;
    for p in &m.positions {
        for x in p {
            w.write_all(&x.to_le_bytes())?;
        }
    }
    for t in &m.triangles {
        w.write_all(&[3])?;
        for i in t {
            w.write_all(&(*i as i32).to_le_bytes())?;
        }
    }
    w.flush()?;
    Ok(())
}

fn main() -> Result<()> {
    let a: Vec<String> = std::env::args().collect();
    match a.as_slice() {
        [_, input, flag, output] if flag == "--to-ply" => to_ply(input, output),
        [_, path, rounds] => {
            for _ in 0..rounds.parse::<usize>()? {
                let (t, c) = (Instant::now(), cpu_seconds());
                let bytes = std::fs::read(path)?;
                let lines = bytes.iter().filter(|&&b| b == b'\n').count();
                let floor = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
                drop(bytes);
                let (t, c) = (Instant::now(), cpu_seconds());
                let scene = lodgen::io::read_scene(path.as_ref())?;
                let read = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
                let triangles = scene.triangle_count();
                drop(scene);
                println!(
                    "floor {:.1} ms wall {:.1} ms CPU ({lines} lines)  read {:.1} ms wall {:.1} ms CPU ({triangles} triangles)",
                    floor.0 * 1e3,
                    floor.1 * 1e3,
                    read.0 * 1e3,
                    read.1 * 1e3
                );
            }
            Ok(())
        }
        _ => bail!("usage: read_timing MESH ROUNDS | read_timing MESH --to-ply OUT"),
    }
}
