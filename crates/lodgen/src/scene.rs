//! The neutral in-memory form shared by the readers (`io`), the LOD builder
//! (`lod`) and the glTF writer (`gltf_out`). Readers produce a [`Scene`];
//! the builder turns every [`SourceMesh`] into a [`LodMesh`]; the writer
//! serializes `Scene` + `Vec<LodMesh>`.
//!
//! This module owns data only: no I/O, no simplification.

use std::path::PathBuf;

/// Everything read from one input file.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// Meshes in file order. For glTF input, `meshes[i]` is glTF mesh `i`.
    pub meshes: Vec<SourceMesh>,
    /// Materials by index; primitives refer to them by index.
    pub materials: Vec<Material>,
    /// Where the scene came from; the glTF writer uses it to keep the
    /// input's node hierarchy, transforms, materials and textures.
    pub origin: Origin,
    /// What the reader left out or could not read, each naming its place
    /// (a primitive it could not read, points and lines): nothing is
    /// dropped without one. `--strict` turns them into an error.
    pub warnings: Vec<Warning>,
}

impl Scene {
    /// Triangles of every primitive of every mesh.
    pub fn triangle_count(&self) -> usize {
        self.meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .map(|p| p.triangle_count())
            .sum()
    }
}

/// Something left out or written differently from the input, and where:
/// `at` names the place (`meshes[2].primitives[0] (mesh "door")`, a level,
/// an animation), `message` what happened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    pub at: String,
    pub message: String,
}

impl Warning {
    pub fn new(at: impl Into<String>, message: impl Into<String>) -> Self {
        Warning {
            at: at.into(),
            message: message.into(),
        }
    }
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.at, self.message)
    }
}

/// The input file a [`Scene`] was read from.
#[derive(Debug, Clone, Default)]
pub enum Origin {
    /// OBJ, PLY, SMF or a mesh generated in code: one node per mesh.
    #[default]
    Flat,
    /// As [`Origin::Flat`], read far from the origin (a scan in UTM or earth-centred
    /// coordinates): every position was moved by `−offset` before it became `f32`, where
    /// `f32` keeps the mesh's own detail (at 5·10⁶ m it steps by 0.5 m); the writer puts
    /// `offset` back as each node's translation (`f64` in the JSON). See
    /// [`crate::io::FAR_COORDINATE`].
    Moved {
        /// The file's coordinates of the positions' origin.
        offset: [f64; 3],
    },
    /// glTF / GLB: the parsed document and its binary buffers, so the writer
    /// can copy nodes, transforms, materials, images and samplers.
    Gltf {
        /// Path of the input file (for resolving relative image URIs).
        path: PathBuf,
        /// The input document, as parsed JSON root (buffer views: after
        /// `EXT_meshopt_compression` views were decoded into `buffers`).
        document: Box<gltf_json::Root>,
        /// The input's JSON as written, which the writer copies from
        /// (names, extras, extensions and numbers untouched).
        json: Box<serde_json::Value>,
        /// The contents of every buffer, in buffer order.
        buffers: Vec<Vec<u8>>,
    },
}

/// A named material (OBJ `usemtl`, glTF material).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Material {
    pub name: String,
    /// Base colour factor, RGBA, linear. `None` when the source has none.
    pub base_color: Option<[f32; 4]>,
}

/// One mesh: a name and its primitives (one per material).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SourceMesh {
    pub name: String,
    pub primitives: Vec<Primitive>,
}

/// An indexed triangle list with optional per-vertex attributes. Every
/// attribute vector, when present, has `positions.len()` entries.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Primitive {
    /// Index into [`Scene::materials`].
    pub material: Option<usize>,
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    /// `TEXCOORD_0`.
    pub texcoords: Option<Vec<[f32; 2]>>,
    /// `TANGENT`: xyz unit, w = ±1 (bitangent sign).
    pub tangents: Option<Vec<[f32; 4]>>,
    /// `TEXCOORD_1`, `TEXCOORD_2`, …: `extra_texcoords[i]` is set `i + 1`.
    pub extra_texcoords: Vec<Vec<[f32; 2]>>,
    /// `COLOR_0`, linear RGBA (RGB sources get alpha 1).
    pub colors: Option<Vec<[f32; 4]>>,
    /// `JOINTS_0`: four joint indices per vertex.
    pub joints: Option<Vec<[u16; 4]>>,
    /// `WEIGHTS_0`: the weights of `joints`; with `extra_weights`, all sets
    /// together sum to 1.
    pub weights: Option<Vec<[f32; 4]>>,
    /// `COLOR_1`, `COLOR_2`, …: `extra_colors[i]` is set `i + 1`.
    pub extra_colors: Vec<Vec<[f32; 4]>>,
    /// `JOINTS_1`, `JOINTS_2`, …: `extra_joints[i]` is set `i + 1` (more
    /// than four influences per vertex).
    pub extra_joints: Vec<Vec<[u16; 4]>>,
    /// `WEIGHTS_1`, `WEIGHTS_2`, …: the weights of `extra_joints[i]`.
    pub extra_weights: Vec<Vec<[f32; 4]>>,
    /// glTF morph targets, in order: per-vertex displacements, each present
    /// channel with `positions.len()` entries.
    pub targets: Vec<MorphTarget>,
    /// Triangle list: `indices.len() % 3 == 0`, every index `< positions.len()`.
    pub indices: Vec<u32>,
}

/// One morph target of a [`Primitive`]: displacements added to the base
/// attributes with the target's weight (glTF `targets[i]`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MorphTarget {
    /// `POSITION` displacements.
    pub positions: Option<Vec<[f32; 3]>>,
    /// `NORMAL` displacements.
    pub normals: Option<Vec<[f32; 3]>>,
    /// `TANGENT` displacements (xyz; glTF targets have no w).
    pub tangents: Option<Vec<[f32; 3]>>,
}

impl MorphTarget {
    /// The present channels in glTF order: `("POSITION", …)`, `("NORMAL", …)`,
    /// `("TANGENT", …)`.
    pub fn channels(&self) -> impl Iterator<Item = (&'static str, &Vec<[f32; 3]>)> {
        [
            ("POSITION", &self.positions),
            ("NORMAL", &self.normals),
            ("TANGENT", &self.tangents),
        ]
        .into_iter()
        .filter_map(|(name, c)| c.as_ref().map(|c| (name, c)))
    }

    /// The same channels as `self`, empty.
    pub fn empty_like(&self) -> MorphTarget {
        MorphTarget {
            positions: self.positions.as_ref().map(|_| Vec::new()),
            normals: self.normals.as_ref().map(|_| Vec::new()),
            tangents: self.tangents.as_ref().map(|_| Vec::new()),
        }
    }

    /// Appends vertex `v` of `from` (same channels) to every channel.
    pub fn push_from(&mut self, from: &MorphTarget, v: usize) {
        for (to, from) in [
            (&mut self.positions, &from.positions),
            (&mut self.normals, &from.normals),
            (&mut self.tangents, &from.tangents),
        ] {
            if let Some(to) = to {
                to.push(from.as_ref().map_or([0.0; 3], |f| f[v]));
            }
        }
    }
}

impl Primitive {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// The LOD chain of one [`SourceMesh`]: `levels[0]` is the finest.
#[derive(Debug, Clone, Default)]
pub struct LodMesh {
    /// Index of the source mesh in [`Scene::meshes`].
    pub source: usize,
    pub name: String,
    pub levels: Vec<LodLevel>,
}

/// One level of detail: its primitives plus what was measured on it.
#[derive(Debug, Clone, Default)]
pub struct LodLevel {
    /// Same primitive order and materials as the source mesh.
    pub primitives: Vec<Primitive>,
    /// Measured symmetric Hausdorff distance to the original mesh, as a
    /// fraction (not percent) of the original's bounding-box diagonal.
    pub hausdorff: f64,
    /// Measured symmetric RMS distance, fraction of the bbox diagonal.
    pub rms: f64,
    /// `MSFT_screencoverage` value for this level (see ARCHITECTURE.md).
    pub screen_coverage: f64,
}

impl LodLevel {
    pub fn triangle_count(&self) -> usize {
        self.primitives.iter().map(Primitive::triangle_count).sum()
    }
}
