//! lodgen-pm: progressive meshes by pair contraction.
