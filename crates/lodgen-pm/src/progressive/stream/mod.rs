//! The vertex-split log as a compact byte stream: the payload of the
//! `LODGEN_progressive` glTF extension (`docs/LODGEN_progressive.md` is the
//! normative description of the layout; this module is its reference
//! implementation).
//!
//! Layout (version 7), in short: a header (grid, counts, level table, wedge
//! table, chunk table), then one **chunk** per step of the level chain: the
//! base mesh, then the records up to each level's count, coarse → fine. A
//! chunk is a sequence of **columns** (one per kind of value: split vertex,
//! face codes, corner-edit masks, position residuals, wedge references,
//! attribute values; a chunk's topology and wedge columns in blocks of
//! [`BLOCK_RECORDS`] records, then its positions), each coded with
//! meshoptimizer's vertex or index codec
//! so that browsers decode them with the `meshoptimizer` npm package's
//! `MeshoptDecoder` (no entropy coder of our own).
//!
//! Topology is exact: the faces of a split are coded against the split
//! vertex's current ring (`topo.rs`), its corner edits predicted from its
//! faces (or, where that misses, a bit mask over the corners it holds), so
//! after `k` decoded records the triangle list equals
//! `pm.mesh_at_splits(k)`'s index for index, for every `k`. Positions are
//! snapped to a uniform grid ([`Grid`], the `KHR_mesh_quantization` grid
//! lodgen's `--quantize` writes) and stored once per chunk: each vertex a
//! chunk creates or moves gets its position *at the end of the chunk*,
//! predicted from its neighbours (a new vertex: its ring's centroid) or its
//! previous position (a moved one).
//! So at every chunk end (every level) the decoded positions equal the
//! level's positions quantized on the grid; between two levels a vertex
//! already sits where the next level puts it.
//!
//! Owns [`encode`], [`decode`], the incremental [`StreamDecoder`],
//! [`StreamError`] and [`EncodeError`]. Bytes in, bytes out: no I/O, no
//! printing.

mod columns;
mod decode;
mod encode;
mod header;
mod stats;
mod topo;
mod types;
mod wedges;

pub use decode::{decode, decode_header, decode_with_attributes, Decoded, StreamDecoder};
pub use encode::{encode, encode_with_attributes};
pub use stats::{column_stats, ColumnStat};
pub use types::{
    AttrEncoding, Channel, ChunkInfo, EncodeError, EncodeOptions, Grid, Range, StreamError,
    StreamHeader, WedgeAttributes, WedgeLayout, BLOCK_RECORDS, FLAG_ERRORS, FLAG_WEDGES, MAGIC,
    MAX_CHANNELS, MAX_CHANNEL_NAME, MAX_COMPONENTS, VERSION,
};
