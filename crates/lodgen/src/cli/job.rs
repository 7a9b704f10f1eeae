//! The build job: read → LODs → write (→ `LODGEN_progressive`) for one
//! file, timed, without printing. [`BuiltFile`] is what it made.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use lodgen_pm::Meter;

use crate::gltf_out;
use crate::io;
use crate::lod::{self, LevelHook, MeshBuild, Progress};
use crate::scene::{LodMesh, Scene, Warning};

use super::args::BuildArgs;

/// Wall time of one file's phases outside the meshes' builds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FileTimes {
    /// Parsing the input file.
    pub read: Duration,
    /// Every mesh's build ([`crate::lod::BuildTimes`] splits it).
    pub build: Duration,
    /// Writing the glTF (and the progressive stream when asked).
    pub write: Duration,
}

/// What one build job made: the scene read, its LOD builds and the bytes of
/// each level as written.
pub struct BuiltFile {
    pub output: PathBuf,
    pub scene: Scene,
    pub builds: Vec<MeshBuild>,
    pub level_bytes: Vec<Vec<u64>>,
    /// Wall time of reading, building (all meshes) and writing.
    pub times: FileTimes,
    /// What was left out or written unsimplified, each naming the mesh /
    /// primitive / animation (reader, builder and writer together).
    pub warnings: Vec<Warning>,
}

/// Read → LODs → write (→ LODGEN_progressive) for one file, without
/// printing: what `lodgen INPUT` and each file of a batch run.
pub fn build_file(
    input: &Path,
    output: &Path,
    args: &BuildArgs,
    on_progress: &mut dyn FnMut(Progress),
) -> Result<BuiltFile> {
    build_file_metered(input, output, args, on_progress, None)
}

/// [`build_file`], each QEM simplification reporting to `meter`
/// ([`crate::lod::BuildOptions::meter`]) for a progress display.
pub fn build_file_metered(
    input: &Path,
    output: &Path,
    args: &BuildArgs,
    on_progress: &mut dyn FnMut(Progress),
    meter: Option<Arc<Meter>>,
) -> Result<BuiltFile> {
    let mut opts = args.build_options()?;
    opts.meter = meter;
    // the progressive mesh is written with --progressive only; else it is
    // freed before the error measurement (peak memory)
    opts.keep_progressive = args.progressive;
    // likewise each simplified mesh's input positions and indices, which
    // nothing but the stream reads once the levels are extracted
    opts.keep_input = args.progressive;
    if same_file(input, output) {
        bail!("the output {} would overwrite the input", output.display());
    }
    // (before the work, which a bad output path would throw away)
    gltf_out::check_output_path(output).with_context(|| format!("writing {}", output.display()))?;
    super::check_parent_dir(output, "the output")?;
    on_progress(Progress::Reading);
    let t_read = Instant::now();
    let read_opts = io::ReadOptions {
        strict: args.strict,
    };
    let mut scene = io::read_scene_with(input, &read_opts)
        .with_context(|| format!("reading {}", input.display()))?;
    let read = t_read.elapsed();
    if opts.measured {
        // (each level is measured against its mesh's input)
        for mesh in &scene.meshes {
            let t = mesh.primitives.iter().map(|p| p.indices.len() / 3).sum();
            super::check_sample_count(&opts.measure, t, t)?;
        }
    }
    let mut warnings = scene.warnings.clone();
    // each level's buffers prepared while the build measures the next
    // (`lod::LevelHook`): the write then only assembles them
    let ready = Arc::new(gltf_out::PreparedLevels::for_scene(&scene));
    let store = Arc::clone(&ready);
    opts.level_ready = Some(LevelHook(Arc::new(move |mesh, level, primitives| {
        store.prepare(mesh, level, primitives)
    })));
    let t_build = Instant::now();
    let (builds, lods) = build_isolated(&mut scene, &opts, args.strict, &mut warnings, on_progress)
        .with_context(|| format!("simplifying {}", input.display()))?;
    let build = t_build.elapsed();
    drop(opts);
    // (a mesh written unsimplified may have had levels prepared)
    let built: std::collections::BTreeSet<usize> = builds.iter().map(|b| b.lod.source).collect();
    ready.retain_meshes(|m| built.contains(&m));
    if args.progressive {
        progressive_warnings(input, &scene, &builds, args.strict, &mut warnings)?;
    }
    on_progress(Progress::Writing);
    let t_write = Instant::now();
    let wopts = args.write_options();
    // --- LODGEN_progressive (issue 6): each mesh's split stream, added to
    // the file before it is written (a failure leaves the output as it was)
    let chains = if args.progressive {
        builds
            .iter()
            .map(|b| crate::progressive::ChainStream::from_build(b, &scene.meshes[b.lod.source]))
            .collect::<Result<Vec<_>, _>>()
            .context("encoding the vertex-split stream")?
    } else {
        Vec::new()
    };
    let embed = |path: &Path, bytes: Vec<u8>| {
        crate::progressive::embed_bytes(path, &bytes, &chains)
            .map_err(|e| format!("adding LODGEN_progressive: {}", error_chain(&e)))
    };
    let add: Option<gltf_out::Addition<'_>> = args.progressive.then_some(&embed as _);
    let summary = gltf_out::write_lods_added(
        output,
        &scene,
        &lods,
        &wopts,
        args.strict,
        Some(&ready),
        add,
    )
    .with_context(|| format!("writing {}", output.display()))?;
    warnings.extend(summary.warnings.iter().cloned());
    // --- end LODGEN_progressive ---
    let write = t_write.elapsed();
    // the simplified chains' bytes (the written chains are in source order)
    let level_bytes: Vec<Vec<u64>> = builds
        .iter()
        .filter_map(|b| lods.iter().position(|l| l.source == b.lod.source))
        .filter_map(|j| summary.meshes.get(j).map(|m| m.level_bytes.clone()))
        .collect();
    Ok(BuiltFile {
        output: output.to_path_buf(),
        scene,
        builds,
        level_bytes,
        times: FileTimes { read, build, write },
        warnings,
    })
}

/// `e` and its sources, joined by ": ".
fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// Whether `a` and `b` name one file: the same path, the same file after
/// symbolic links and `.` / `..` are resolved (`./x.glb`, an absolute path,
/// a link), or (Unix) the same inode (a hard link).
fn same_file(a: &Path, b: &Path) -> bool {
    if a == b {
        return true;
    }
    if let (Ok(x), Ok(y)) = (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        if x == y {
            return true;
        }
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    false
}

/// Whether `a` and `b` name one file, existing or not: [`same_file`], or the same name in
/// one directory (after links and `.` / `..` are resolved) for a file not yet written.
pub(crate) fn same_place(a: &Path, b: &Path) -> bool {
    if same_file(a, b) {
        return true;
    }
    let dir = |p: &Path| {
        let d = p.parent().filter(|d| !d.as_os_str().is_empty());
        std::fs::canonicalize(d.unwrap_or(Path::new("."))).ok()
    };
    a.file_name() == b.file_name() && dir(a).is_some() && dir(a) == dir(b)
}

/// The builds and every chain to write: with `strict` the first mesh that
/// fails fails the file; else it is kept unsimplified, with a warning.
fn build_isolated(
    scene: &mut Scene,
    opts: &lod::BuildOptions,
    strict: bool,
    warnings: &mut Vec<Warning>,
    on_progress: &mut dyn FnMut(Progress),
) -> Result<(Vec<MeshBuild>, Vec<LodMesh>), lod::BuildError> {
    if strict {
        let builds = lod::build_lods(scene, opts, on_progress)?;
        let lods = builds.iter().map(|b| b.lod.clone()).collect();
        return Ok((builds, lods));
    }
    let built = lod::build_lods_isolated(scene, opts, on_progress)?;
    warnings.extend(built.warnings.iter().cloned());
    let lods = built.lods();
    Ok((built.builds, lods))
}

/// Morph targets are in every MSFT_lod level but not in the stream: a
/// warning per such mesh (an error with `strict`).
fn progressive_warnings(
    input: &Path,
    scene: &Scene,
    builds: &[MeshBuild],
    strict: bool,
    warnings: &mut Vec<Warning>,
) -> Result<()> {
    for b in builds {
        let mesh = &scene.meshes[b.lod.source];
        if mesh.primitives.iter().any(|p| !p.targets.is_empty()) {
            let w = Warning::new(
                format!("meshes[{}] (mesh `{}`)", b.lod.source, mesh.name),
                "its morph targets are in every MSFT_lod level but not in the \
                 LODGEN_progressive stream",
            );
            if strict {
                bail!("{}: {w} (--strict)", input.display());
            }
            warnings.push(w);
        }
    }
    Ok(())
}
