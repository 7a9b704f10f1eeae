//! lodgen-pm: progressive meshes by pair contraction.

pub mod bvh;
pub mod measure;
