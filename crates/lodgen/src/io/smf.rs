//! SMF reader (Garland's "Simple Model Format" used by QSlim and the
//! original quadric-error-metric models).
//!
//! Read: `v x y z` (vertex), `f a b c ...` (1-based vertex indices, polygons
//! fan-triangulated; SMF has no relative indices) and `#` comments. Every
//! other command is ignored without error: attribute data (`n`, `c`, `r`,
//! `bind`), transforms and scoping (`begin`, `end`, `t`, `trans`, `scale`,
//! `rot`, `tex`), and settings (`set`, `inc`, `dec`). The result is one mesh
//! named after the file stem with one primitive; unreferenced vertices are
//! dropped (numbering by first use).

use std::path::Path;

use super::common::{check_not_empty, compact, file_stem, lines, parse_coords};
use super::error::{ErrorKind, Location, ReadError};
use crate::scene::{Origin, Primitive, Scene, SourceMesh};

/// Reads an SMF file from its bytes; `path` names it in errors.
pub fn read_smf(src: &[u8], path: &Path) -> Result<Scene, ReadError> {
    let text = String::from_utf8_lossy(src);
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    let mut face: Vec<u32> = Vec::new();
    for (line_no, line) in lines(&text) {
        let mut tokens = line.split_ascii_whitespace();
        match tokens.next() {
            Some("v") => {
                positions.push(parse_coords(
                    &mut tokens,
                    path,
                    line_no,
                    "vertex coordinate",
                )?);
            }
            Some("f") => {
                face.clear();
                for token in tokens.take_while(|t| !t.starts_with('#')) {
                    let err = |kind| ReadError::new(path, Location::Line(line_no), kind);
                    let index: i64 = token.parse().map_err(|_| {
                        err(ErrorKind::Syntax {
                            expected: "a vertex index".to_owned(),
                            found: token.to_owned(),
                        })
                    })?;
                    if index < 1 || index > positions.len() as i64 {
                        return Err(err(ErrorKind::IndexOutOfRange {
                            what: "face",
                            target: "vertex",
                            index,
                            count: positions.len(),
                        }));
                    }
                    face.push((index - 1) as u32);
                }
                if face.len() < 3 {
                    return Err(ReadError::new(
                        path,
                        Location::Line(line_no),
                        ErrorKind::Invalid(format!(
                            "face has {} corners, needs at least 3",
                            face.len()
                        )),
                    ));
                }
                for i in 1..face.len() - 1 {
                    indices.extend_from_slice(&[face[0], face[i], face[i + 1]]);
                }
            }
            _ => {}
        }
    }
    let primitive = compact(Primitive {
        material: None,
        positions,
        normals: None,
        texcoords: None,
        indices,
        ..Primitive::default()
    });
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: file_stem(path),
            primitives: vec![primitive],
        }],
        materials: Vec::new(),
        origin: Origin::Flat,
        warnings: Vec::new(),
    };
    check_not_empty(&scene, path)?;
    Ok(scene)
}
