//! `cargo xtask quality --write-levels DIR`: the meshes a run measured, as
//! OBJ files, so that a cell can be looked at with `lodgen measure` (which
//! prints where each direction's maximum lies) or given to a peer by hand.

use anyhow::{Context, Result};
use lodgen_pm::Mesh;
use std::fmt::Write as _;
use std::path::Path;

/// Writes `DIR/MESH.obj` (the welded input every tool gets) and, per level,
/// `DIR/MESH-P.obj` (lodgen's level, P = the level's percentage) and
/// `DIR/MESH-P-meshopt.obj` (meshoptimizer's at the same count): `levels`
/// are (percentage, lodgen's level, meshoptimizer's level).
pub(super) fn write_levels(
    dir: &Path,
    name: &str,
    input: &Mesh,
    levels: &[(u32, &Mesh, Mesh)],
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    write_obj(&dir.join(format!("{name}.obj")), input)?;
    for (percent, lodgen, meshopt) in levels {
        write_obj(&dir.join(format!("{name}-{percent}.obj")), lodgen)?;
        write_obj(&dir.join(format!("{name}-{percent}-meshopt.obj")), meshopt)?;
    }
    Ok(())
}

/// `m` as OBJ: every position (unused ones too: the level keeps the
/// input's numbering), then the triangles; floats in their shortest exact
/// form, so the file reads back to the same bits.
fn write_obj(path: &Path, m: &Mesh) -> Result<()> {
    let mut s = String::with_capacity(32 * (m.positions.len() + m.triangles.len()));
    for p in &m.positions {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    for t in &m.triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, s).with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A written level reads back (through lodgen's OBJ reader) to the
    /// same positions and triangles.
    #[test]
    fn written_levels_read_back() {
        let dir = std::env::temp_dir().join(format!("xtask-levels-{}", std::process::id()));
        let input = lodgen_pm::shapes::icosphere(2);
        let level = Mesh {
            positions: input.positions.clone(),
            triangles: input.triangles[..40].to_vec(),
        };
        let meshopt = Mesh {
            positions: input.positions.clone(),
            triangles: input.triangles[40..60].to_vec(),
        };
        let written = write_levels(&dir, "ball", &input, &[(10, &level, meshopt)]);
        let read = |f: &str| -> Result<Mesh> {
            let scene = lodgen::io::read_scene(&dir.join(f))?;
            Ok(lodgen::cli::merged_mesh(&scene))
        };
        let back = written.and_then(|()| Ok((read("ball.obj")?, read("ball-10.obj")?)));
        let has_meshopt = dir.join("ball-10-meshopt.obj").exists();
        let _ = std::fs::remove_dir_all(&dir);
        let (a, b) = back.expect("levels written and read back");
        assert!(has_meshopt);
        // (the reader may drop or renumber positions: compare corners)
        let corners = |m: &Mesh| -> Vec<[f32; 3]> {
            m.triangles
                .iter()
                .flatten()
                .map(|&v| m.positions[v as usize])
                .collect()
        };
        assert_eq!(corners(&a), corners(&input));
        assert_eq!(corners(&b), corners(&level));
    }
}
