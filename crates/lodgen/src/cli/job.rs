//! The build job: read → LODs → write (→ `LODGEN_progressive`) for one
//! file, timed, without printing. [`BuiltFile`] is what it made.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};

use crate::gltf_out;
use crate::io;
use crate::lod::{self, MeshBuild, Progress};
use crate::scene::Scene;

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
}

/// Read → LODs → write (→ LODGEN_progressive) for one file, without
/// printing: what `lodgen INPUT` and each file of a batch run.
pub fn build_file(
    input: &Path,
    output: &Path,
    args: &BuildArgs,
    on_progress: &mut dyn FnMut(Progress),
) -> Result<BuiltFile> {
    let opts = args.build_options()?;
    if output == input {
        bail!("the output {} would overwrite the input", output.display());
    }
    on_progress(Progress::Reading);
    let t_read = Instant::now();
    let scene = io::read_scene(input).with_context(|| format!("reading {}", input.display()))?;
    let read = t_read.elapsed();
    let t_build = Instant::now();
    let builds = lod::build_lods(&scene, &opts, on_progress)
        .with_context(|| format!("simplifying {}", input.display()))?;
    let build = t_build.elapsed();
    on_progress(Progress::Writing);
    let t_write = Instant::now();
    let lods: Vec<_> = builds.iter().map(|b| b.lod.clone()).collect();
    let summary = gltf_out::write_lods(output, &scene, &lods, &args.write_options())
        .with_context(|| format!("writing {}", output.display()))?;
    // --- LODGEN_progressive (issue 6): append each mesh's split stream ---
    if args.progressive {
        let chains = builds
            .iter()
            .map(|b| crate::progressive::ChainStream::from_build(b, &scene.meshes[b.lod.source]))
            .collect::<Result<Vec<_>, _>>()
            .context("encoding the vertex-split stream")?;
        crate::progressive::embed(output, &chains)
            .with_context(|| format!("adding LODGEN_progressive to {}", output.display()))?;
    }
    // --- end LODGEN_progressive ---
    let write = t_write.elapsed();
    let level_bytes: Vec<Vec<u64>> = summary
        .meshes
        .iter()
        .map(|m| m.level_bytes.clone())
        .collect();
    Ok(BuiltFile {
        output: output.to_path_buf(),
        scene,
        builds,
        level_bytes,
        times: FileTimes { read, build, write },
    })
}
