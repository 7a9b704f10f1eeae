//! `cargo xtask draco [DIR]`: an optional Draco round trip of every LOD level.
//!
//! For each `.glb` under DIR (default `target/test-out`, recursively) and each
//! mesh in it (the writer puts each LOD level in its own mesh), the mesh's
//! triangles (positions only, all triangle primitives in one OBJ) are written
//! as OBJ, encoded with Debian's `draco_encoder -cl 7` (package `draco`),
//! decoded again with `draco_decoder` to PLY, and the compressed size and the
//! decoded vertex/face counts printed. Fails when the decoded face count
//! differs from the level's triangle count. When the Draco tools are not on
//! PATH it says so and exits 0.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{anyhow, bail, Context, Result};

use crate::test::files_under;
use crate::workspace_root;

const ENCODER: &str = "draco_encoder";
const DECODER: &str = "draco_decoder";

/// glTF extensions whose data the `gltf` crate cannot decode into plain f32 positions.
const UNDECODABLE: [&str; 2] = ["EXT_meshopt_compression", "KHR_draco_mesh_compression"];

fn find_on_path(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(program))
        .find(|p| p.is_file())
}

/// One LOD level as a triangle soup over indexed positions.
struct Level {
    name: String,
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    notes: Vec<String>,
}

/// Whether no triangle of `level` has three distinct corner positions.
fn all_degenerate(level: &Level) -> bool {
    level.triangles.iter().all(|t| {
        let [a, b, c] = t.map(|i| level.positions.get(i as usize).map(|p| p.map(f32::to_bits)));
        a == b || b == c || a == c
    })
}

/// Every mesh of a GLB, read with the `gltf` crate.
fn read_levels(glb: &Path) -> Result<Result<Vec<Level>, String>> {
    let bytes = fs::read(glb).with_context(|| format!("reading {}", glb.display()))?;
    // Look at extensionsRequired before validating: the gltf crate refuses a
    // file that requires an extension it does not know.
    let unchecked = gltf::Gltf::from_slice_without_validation(&bytes)
        .with_context(|| format!("parsing {}", glb.display()))?;
    let required: Vec<&str> = unchecked.document.extensions_required().collect();
    if let Some(ext) = required.iter().find(|e| UNDECODABLE.contains(e)) {
        return Ok(Err(format!(
            "requires {ext}, which the gltf crate cannot decode"
        )));
    }
    // Our own outputs are validated by the Khronos validator; here the crate's
    // validation would only refuse extensions it does not know
    // (KHR_mesh_quantization), which the level reader below handles.
    let gltf = unchecked;
    let base = glb.parent();
    let buffers = gltf::import_buffers(&gltf.document, base, gltf.blob.clone())
        .with_context(|| format!("loading the buffers of {}", glb.display()))?;
    let mut levels = Vec::new();
    for mesh in gltf.document.meshes() {
        let mut level = Level {
            name: mesh
                .name()
                .map_or_else(|| format!("mesh{}", mesh.index()), str::to_string),
            positions: Vec::new(),
            triangles: Vec::new(),
            notes: Vec::new(),
        };
        for prim in mesh.primitives() {
            let pi = prim.index();
            if prim.mode() != gltf::mesh::Mode::Triangles {
                level
                    .notes
                    .push(format!("primitive {pi} skipped: mode {:?}", prim.mode()));
                continue;
            }
            let Some(acc) = prim.get(&gltf::Semantic::Positions) else {
                level
                    .notes
                    .push(format!("primitive {pi} skipped: no POSITION"));
                continue;
            };
            if acc.data_type() != gltf::accessor::DataType::F32
                || acc.dimensions() != gltf::accessor::Dimensions::Vec3
            {
                level.notes.push(format!(
                    "primitive {pi} skipped: POSITION is {:?} {:?} (quantized)",
                    acc.dimensions(),
                    acc.data_type()
                ));
                continue;
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
            let positions: Vec<[f32; 3]> = reader
                .read_positions()
                .ok_or_else(|| {
                    anyhow!(
                        "{}: mesh {}: primitive {pi}: unreadable POSITION",
                        glb.display(),
                        level.name
                    )
                })?
                .collect();
            let base_vertex = u32::try_from(level.positions.len())?;
            let count = u32::try_from(positions.len())?;
            let indices: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..count).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                bail!(
                    "{}: mesh {}: primitive {pi}: {} indices",
                    glb.display(),
                    level.name,
                    indices.len()
                );
            }
            if let Some(bad) = indices.iter().find(|&&i| i >= count) {
                bail!(
                    "{}: mesh {}: primitive {pi}: index {bad} >= {count}",
                    glb.display(),
                    level.name
                );
            }
            level.positions.extend(positions);
            level.triangles.extend(
                indices
                    .chunks_exact(3)
                    .map(|t| [t[0] + base_vertex, t[1] + base_vertex, t[2] + base_vertex]),
            );
        }
        levels.push(level);
    }
    Ok(Ok(levels))
}

fn write_obj(level: &Level, path: &Path) -> Result<()> {
    let mut s = String::with_capacity(level.positions.len() * 40 + level.triangles.len() * 30);
    for p in &level.positions {
        writeln!(s, "v {} {} {}", p[0], p[1], p[2])?;
    }
    for t in &level.triangles {
        writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    fs::write(path, s).with_context(|| format!("writing {}", path.display()))
}

/// Vertex and face counts from a PLY header.
fn ply_counts(path: &Path) -> Result<(u64, u64)> {
    let bytes = fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| anyhow!("{}: no PLY header", path.display()))?;
    let header = String::from_utf8_lossy(&bytes[..end]);
    let (mut vertices, mut faces) = (None, None);
    for line in header.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        if let ["element", kind, n] = words[..] {
            let n: u64 = n
                .parse()
                .with_context(|| format!("{}: bad line `{line}`", path.display()))?;
            match kind {
                "vertex" => vertices = Some(n),
                "face" => faces = Some(n),
                _ => {}
            }
        }
    }
    Ok((vertices.unwrap_or(0), faces.unwrap_or(0)))
}

fn tool(program: &Path, args: &[&std::ffi::OsStr]) -> Result<()> {
    let out = Command::new(program)
        .args(args)
        .output()
        .with_context(|| format!("running {}", program.display()))?;
    if !out.status.success() {
        bail!(
            "{} failed ({}):\n{}{}",
            program.display(),
            out.status,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(())
}

pub fn run(args: &[String]) -> Result<()> {
    let root = workspace_root();
    let dir = match args {
        [] => root.join("target").join("test-out"),
        [d] => PathBuf::from(d),
        _ => bail!("usage: cargo xtask draco [DIR]"),
    };
    let (Some(encoder), Some(decoder)) = (find_on_path(ENCODER), find_on_path(DECODER)) else {
        println!("draco: skipped: {ENCODER}/{DECODER} not on PATH (Debian package `draco`: apt-get install draco)");
        return Ok(());
    };
    let glbs = files_under(&dir, &|n| n.ends_with(".glb"))?;
    if glbs.is_empty() {
        println!("draco: skipped: no .glb under {}", dir.display());
        return Ok(());
    }
    let tmp = root.join("target").join("xtask-draco");
    if tmp.exists() {
        fs::remove_dir_all(&tmp)?;
    }
    fs::create_dir_all(&tmp)?;
    println!(
        "draco: {} -cl 7 / {} on {} file(s) under {} (positions only)",
        encoder.display(),
        decoder.display(),
        glbs.len(),
        dir.display()
    );

    let (mut checked, mut failures, mut skipped) = (0usize, Vec::new(), 0usize);
    for glb in &glbs {
        let rel = glb.strip_prefix(&dir).unwrap_or(glb).display().to_string();
        let levels = match read_levels(glb)? {
            Ok(levels) => levels,
            Err(why) => {
                println!("{rel}: skipped: {why}");
                skipped += 1;
                continue;
            }
        };
        for (i, level) in levels.iter().enumerate() {
            for note in &level.notes {
                println!("{rel} mesh {i} '{}': {note}", level.name);
            }
            // a mesh lodgen wrote unsimplified because every triangle is
            // degenerate is refused by draco_encoder: nothing to round-trip
            let skip = if level.triangles.is_empty() {
                Some("no triangles to encode")
            } else {
                all_degenerate(level).then_some("every triangle is degenerate")
            };
            if let Some(why) = skip {
                println!("{rel} mesh {i} '{}': skipped: {why}", level.name);
                skipped += 1;
                continue;
            }
            let obj = tmp.join(format!("level{i}.obj"));
            let drc = tmp.join(format!("level{i}.drc"));
            let ply = tmp.join(format!("level{i}.ply"));
            write_obj(level, &obj)?;
            tool(
                &encoder,
                &[
                    "-i".as_ref(),
                    obj.as_os_str(),
                    "-o".as_ref(),
                    drc.as_os_str(),
                    "-cl".as_ref(),
                    "7".as_ref(),
                ],
            )?;
            tool(
                &decoder,
                &[
                    "-i".as_ref(),
                    drc.as_os_str(),
                    "-o".as_ref(),
                    ply.as_os_str(),
                ],
            )?;
            let compressed = fs::metadata(&drc)?.len();
            let (dv, df) = ply_counts(&ply)?;
            let raw = level.positions.len() * 12 + level.triangles.len() * 12;
            let faces = level.triangles.len() as u64;
            let ok = df == faces;
            println!(
                "{rel} mesh {i} '{}': {} vertices, {faces} triangles, raw {raw} B -> draco {compressed} B ({:.1}x) -> decoded {dv} vertices, {df} faces: {}",
                level.name,
                level.positions.len(),
                raw as f64 / compressed.max(1) as f64,
                if ok { "ok" } else { "FACE COUNT CHANGED" }
            );
            checked += 1;
            if !ok {
                failures.push(format!(
                    "{rel} mesh {i} '{}': {faces} triangles in, {df} faces out",
                    level.name
                ));
            }
        }
    }
    fs::remove_dir_all(&tmp)?;
    println!(
        "draco: {} passed, {} failed, {skipped} skipped",
        checked - failures.len(),
        failures.len()
    );
    if !failures.is_empty() {
        bail!(
            "Draco round trip changed the face count:\n  {}",
            failures.join("\n  ")
        );
    }
    Ok(())
}
