//! The LOD builder: one simplification pass per [`SourceMesh`], every
//! requested level cut from its vertex-split log, each level measured
//! against the original and turned back into primitives.
//!
//! Owns the mapping between the scene's primitives and the core's single
//! welded mesh, the level selection (ratios, counts, measured error bounds)
//! and attribute transfer. No file I/O, no printing: progress goes through
//! a callback.
//!
//! Primitives of one mesh are simplified *jointly*: their positions are
//! welded together, so material borders are shared vertices and no crack
//! opens between primitives. Each output triangle keeps the primitive
//! (material) of the input triangle it descends from.
//!
//! Attributes live on corners (wedges). Flat vertices with the same
//! primitive, position and attribute bits are one wedge; the core welds
//! positions for topology and treats every edge across which wedges differ
//! — UV seams, hard normals, colour or skin discontinuities, material
//! borders — as a feature edge that collapses only along itself
//! (`lodgen_pm::simplify::features`); the cost adds attribute quadrics per wedge
//! (`AttributeWeights`). The log tracks each corner's wedge, and a level's
//! corner starts from the attributes of its wedge (a source vertex of the
//! same chart): JOINTS / WEIGHTS of every set stay those of that one vertex
//! (never interpolated, weights renormalised to sum 1 over all sets), while
//! normals, UVs, tangents and colours of every level below the input are
//! fitted to the input surface (`lodgen_pm::attrfit`: least squares, chart
//! by chart, seams keep their input values), then normals renormalised,
//! tangents re-orthogonalised against them, colours clamped to [0, 1].
//!
//! # Files
//! `options` (what to build) → `build` (the driver) over `flat` (the
//! flattened input), `wedges` (wedges, attribute cost, QEM on wedges),
//! `measure` (a level's error), `reference` (a large original's hierarchy
//! built in the welded input's numbering), `select` (split count per level), `fit`
//! (per-level attribute fit), `extract` (level → primitives) and `unit`
//! (normals, tangents, weights made valid); `stream` (attributes for the
//! `LODGEN_progressive` stream); `error`.

mod build;
mod error;
mod extract;
mod fit;
mod flat;
mod measure;
mod options;
mod reference;
mod select;
mod stream;
mod unit;
mod wedges;

pub use build::{build_lods, build_lods_isolated, build_one, BuildTimes, MeshBuild, SceneBuild};
pub use error::BuildError;
pub use options::{
    AttributeWeights, BuildOptions, LevelFn, LevelHook, LevelRequest, Progress,
    DEFAULT_MIN_TRIANGLES,
};
pub use stream::stream_attributes;
pub use wedges::simplify_mesh;
