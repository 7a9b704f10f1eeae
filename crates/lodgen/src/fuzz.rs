//! What the fuzzer (`cargo xtask fuzz`) runs, shared with the replay test
//! of `tests/fuzz-regressions/`: valid seed files of every input format
//! (and a GLB written with `--progressive`, made at run time by the build
//! command's own entry point, so it follows the current stream format), and
//! one case = read a (mutated) file, and when it reads, `lodgen measure` it
//! against itself, build its LODs, write them and inspect the result; a GLB
//! case also goes through `lodgen inspect` and, when it has a
//! `LODGEN_progressive` stream, through the viewer's decode and replay
//! (`view --print-levels`). Errors are the expected outcome of most
//! mutations; only a panic or a hang is a defect, and the callers check for
//! those (`catch_unwind`, a timeout per case).

mod scene;

use std::path::Path;

use clap::Parser;

use crate::gltf_out::{write_lods, Compression, WriteOptions};
use crate::io::read_scene;
use crate::lod::{build_lods, BuildOptions, LevelRequest};
use lodgen_pm::levels::LevelSpec;

/// A valid input file: its extension (which picks the reader) and bytes.
pub struct Seed {
    /// File extension without the dot: `obj`, `ply`, `smf`, `gltf`, `glb`.
    pub ext: &'static str,
    /// What the seed is, for messages.
    pub name: &'static str,
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// A part worth mutating on its own, the file's structure kept: the
    /// `LODGEN_progressive` stream's bytes in the progressive seed.
    pub focus: Option<std::ops::Range<usize>>,
}

/// A small torus (96 triangles) in every input format: OBJ with normals and
/// UVs and two objects, ASCII and binary PLY, SMF, and GLB as lodgen writes
/// it plain and quantized + meshopt-compressed (written into `dir`); and a
/// glTF scene with morph targets, a skin, an animation, a camera, a light
/// and material extensions (`scene.rs`).
pub fn seeds(dir: &Path) -> Result<Vec<Seed>, String> {
    let m = lodgen_pm::shapes::torus(1.0, 0.4, 8, 6);
    let (p, t) = (&m.positions, &m.triangles);
    let mut obj = String::from("o torus\n");
    for v in p {
        obj += &format!(
            "v {} {} {}\nvt {} {}\nvn 0 0 1\n",
            v[0], v[1], v[2], v[0], v[1]
        );
    }
    for f in t {
        let [a, b, c] = f.map(|i| i + 1);
        obj += &format!("f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\n");
    }
    obj += "o quad\nv 5 0 0\nv 6 0 0\nv 6 1 0\nv 5 1 0\nf -4 -3 -2 -1\n";
    let mut smf = String::new();
    for v in p {
        smf += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for f in t {
        smf += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
             property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
            p.len(),
            t.len()
        )
    };
    let mut ascii = header("ascii");
    for v in p {
        ascii += &format!("{} {} {}\n", v[0], v[1], v[2]);
    }
    for f in t {
        ascii += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    let mut binary = header("binary_little_endian").into_bytes();
    for v in p {
        for c in v {
            binary.extend_from_slice(&c.to_le_bytes());
        }
    }
    for f in t {
        binary.push(3);
        for i in f {
            binary.extend_from_slice(&(*i as i32).to_le_bytes());
        }
    }
    let mut seeds = vec![
        Seed {
            ext: "obj",
            name: "obj",
            bytes: obj.into_bytes(),
            focus: None,
        },
        Seed {
            ext: "smf",
            name: "smf",
            bytes: smf.into_bytes(),
            focus: None,
        },
        Seed {
            ext: "ply",
            name: "ply-ascii",
            bytes: ascii.into_bytes(),
            focus: None,
        },
        Seed {
            ext: "ply",
            name: "ply-binary",
            bytes: binary,
            focus: None,
        },
    ];
    // GLB seeds: the OBJ through lodgen itself
    let obj_path = dir.join("seed.obj");
    std::fs::write(&obj_path, &seeds[0].bytes).map_err(|e| e.to_string())?;
    let scene = read_scene(&obj_path).map_err(|e| e.to_string())?;
    let builds = build_lods(&scene, &small_options(), &mut |_| {}).map_err(|e| e.to_string())?;
    let lods: Vec<_> = builds.into_iter().map(|b| b.lod).collect();
    for (name, opts) in [
        ("glb", WriteOptions::default()),
        (
            "glb-quantized-meshopt",
            WriteOptions {
                quantize: true,
                compression: Compression::Meshopt,
            },
        ),
    ] {
        let path = dir.join(format!("{name}.glb"));
        write_lods(&path, &scene, &lods, &opts).map_err(|e| e.to_string())?;
        let bytes = std::fs::read(&path).map_err(|e| e.to_string())?;
        seeds.push(Seed {
            ext: "glb",
            name,
            bytes,
            focus: None,
        });
    }
    seeds.push(Seed {
        ext: "gltf",
        name: "gltf-scene",
        bytes: scene::scene_gltf(),
        focus: None,
    });
    let (bytes, focus) = progressive_seed(&obj_path, dir)?;
    seeds.push(Seed {
        ext: "glb",
        name: "glb-progressive",
        bytes,
        focus: Some(focus),
    });
    Ok(seeds)
}

/// The command line's build arguments, for [`progressive_seed`].
#[derive(Parser)]
struct Command {
    #[command(flatten)]
    build: crate::cli::BuildArgs,
}

/// `lodgen seed.obj --progressive --levels 50%,10%` through
/// [`crate::cli::build_file`]: whatever the stream format is today. Returns
/// the GLB and where its stream is.
fn progressive_seed(obj: &Path, dir: &Path) -> Result<(Vec<u8>, std::ops::Range<usize>), String> {
    let out = dir.join("glb-progressive.glb");
    let args = Command::try_parse_from(["lodgen", "--progressive", "--levels", "50%,10%", "-q"])
        .map_err(|e| e.to_string())?
        .build;
    crate::cli::build_file(obj, &out, &args, &mut |_| {}).map_err(|e| format!("{e:#}"))?;
    let bytes = std::fs::read(&out).map_err(|e| e.to_string())?;
    let found = crate::progressive::read_glb(&bytes)
        .map_err(|e| e.to_string())?
        .ok_or("no LODGEN_progressive in the progressive seed")?
        .0;
    // the BIN chunk's data starts after the header, the JSON chunk and its
    // own chunk header
    let json_len = bytes
        .get(12..16)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        .ok_or("short GLB")?;
    let start = 12 + 8 + json_len + 8 + found.range.1;
    Ok((bytes, start..start + found.range.2))
}

/// Two levels and light sampling: a case must stay cheap.
fn small_options() -> BuildOptions {
    let mut o = BuildOptions {
        levels: LevelRequest::Specs(vec![LevelSpec::Ratio(0.5), LevelSpec::Ratio(0.1)]),
        ..BuildOptions::default()
    };
    o.measure = o.measure.with_samples_per_triangle(0.5);
    o
}

/// Inputs with more triangles than this are read but not simplified (a
/// mutation can turn a count into millions; the case must stay quick).
const MAX_BUILD_TRIANGLES: usize = 20_000;

/// One case: write `bytes` to `dir/case.<ext>`, read it, and when it reads,
/// build two levels, write them (plain, then quantized and compressed) and
/// inspect the output. Returns what happened, in words: errors on the input
/// are fine. `Err` is a defect other than a panic: lodgen's own output does
/// not read back or inspect.
pub fn run_case(dir: &Path, ext: &str, bytes: &[u8]) -> Result<String, String> {
    let input = dir.join(format!("case.{ext}"));
    if let Err(e) = std::fs::write(&input, bytes) {
        return Ok(format!("could not write the case: {e}"));
    }
    let mut stream = "";
    if ext == "glb" {
        // the input itself through `lodgen inspect` and the stream decoder
        // (errors are the usual outcome; the case goes on either way)
        let _ = crate::inspect::inspect(&input).map(|r| r.to_string());
        if let Ok(Some(_)) = crate::progressive::read_file(&input) {
            stream = match crate::view::print_levels(&input) {
                Ok(_) => "stream replayed, ",
                Err(_) => "stream error, ",
            };
        }
    }
    read_measure_build(dir, &input).map(|what| format!("{stream}{what}"))
}

/// The rest of [`run_case`]: read, measure, build, write, inspect, read back.
fn read_measure_build(dir: &Path, input: &Path) -> Result<String, String> {
    let scene = match read_scene(input) {
        Ok(s) => s,
        Err(e) => return Ok(format!("read error: {e}")),
    };
    let triangles = scene.triangle_count();
    if triangles > MAX_BUILD_TRIANGLES {
        return Ok(format!("read {triangles} triangles (not simplified)"));
    }
    if let Err(e) = crate::cli::measure_report(input, input, 0.5, true) {
        return Ok(format!("measure error: {e:#}"));
    }
    let builds = match build_lods(&scene, &small_options(), &mut |_| {}) {
        Ok(b) => b,
        Err(e) => return Ok(format!("build error: {e}")),
    };
    let lods: Vec<_> = builds.into_iter().map(|b| b.lod).collect();
    let out = dir.join("out.glb");
    for opts in [
        WriteOptions::default(),
        WriteOptions {
            quantize: true,
            compression: Compression::Meshopt,
        },
    ] {
        if let Err(e) = write_lods(&out, &scene, &lods, &opts) {
            return Ok(format!("write error: {e}"));
        }
        if let Err(e) = crate::inspect::inspect(&out) {
            return Err(format!("lodgen's own output does not inspect: {e}"));
        }
        if let Err(e) = read_scene(&out) {
            return Err(format!("lodgen's own output does not read back: {e}"));
        }
    }
    Ok("built".into())
}
