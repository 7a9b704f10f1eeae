//! lodgen: mesh readers, the LOD builder, the glTF `MSFT_lod` writer and the
//! `lodgen` command, on top of the `lodgen-pm` core.

pub mod assets;
pub mod batch;
pub mod cli;
pub mod coverage;
pub mod fuzz;
pub mod gltf_out;
pub mod inspect;
pub mod interrupt;
pub mod io;
pub mod lod;
pub mod manifest;
pub mod progressive;
#[cfg(feature = "python")]
pub mod python;
pub mod scene;
pub mod summary;
pub mod view;
