//! Why a build fails: [`BuildError`].

use lodgen_pm::metric;
use lodgen_pm::MeshError;
use thiserror::Error;

/// Why a mesh could not be turned into LODs.
#[derive(Debug, Error)]
pub enum BuildError {
    #[error("mesh {index} ({name:?}): {source}")]
    Mesh {
        index: usize,
        name: String,
        source: MeshError,
    },
    #[error("mesh {index} ({name:?}): measuring a level failed: {source}")]
    Measure {
        index: usize,
        name: String,
        source: metric::MeasureError,
    },
    #[error("no levels requested")]
    NoLevels,
    /// [`super::BuildOptions::meter`] was cancelled ([`lodgen_pm::Meter::cancel`]).
    #[error("cancelled")]
    Cancelled,
}
