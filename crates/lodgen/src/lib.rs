//! lodgen: mesh readers, the LOD builder, the glTF `MSFT_lod` writer and the
//! `lodgen` command, on top of the `lodgen-pm` core.

pub mod io;
pub mod scene;
