//! What to build: [`BuildOptions`] (levels, method, measurement, attribute
//! weights, triangle floor) and the [`Progress`] events a build reports.

use lodgen_pm::levels::LevelSpec;
use lodgen_pm::metric::MeasureOptions;
use lodgen_pm::{AdaptiveOptions, Method, SimplifyOptions};

use crate::scene::Primitive;

/// Which levels to build.
#[derive(Clone, Debug, PartialEq)]
pub enum LevelRequest {
    /// Ratios and/or triangle counts.
    Specs(Vec<LevelSpec>),
    /// Measured symmetric Hausdorff bounds, as fractions of the bounding-box
    /// diagonal: each level is the coarsest whose measured error stays
    /// within its bound.
    MaxErrors(Vec<f64>),
}

/// Options of [`build_lods`].
#[derive(Clone, Debug)]
pub struct BuildOptions {
    pub levels: LevelRequest,
    pub simplify: SimplifyOptions,
    /// QEM (default) or one of the curvature-adaptive methods of seed 001.
    pub method: Method,
    /// Options of the curvature-adaptive methods.
    pub adaptive: AdaptiveOptions,
    pub measure: MeasureOptions,
    /// Measure each level's error (default). When false, a level's error is
    /// the quadric's estimate (the largest recorded contraction error still
    /// in it; RMS unknown) and `MeshBuild::measured` says so.
    pub measured: bool,
    /// Weights of the attribute term of the cost (`lodgen_pm::simplify::features`).
    pub attribute_weights: AttributeWeights,
    /// Floor per mesh: no level has fewer triangles than this (nor fewer
    /// than 1), so a mesh with at most this many is written unsimplified.
    /// Default value: [`DEFAULT_MIN_TRIANGLES`].
    pub min_triangles: usize,
    /// Where the QEM simplification reports its stage and the share of its
    /// target reached, for a progress display on another thread (`None`:
    /// not reported).
    pub meter: Option<std::sync::Arc<lodgen_pm::Meter>>,
    /// Keep each mesh's progressive mesh and its maps in
    /// [`crate::lod::MeshBuild::simplified`] (default). When false they are
    /// freed as soon as the levels are extracted, before the error
    /// measurement builds its hierarchy (peak memory of a scan: the two
    /// were the run's peak), and `simplified.pm`, `vertex_map` and
    /// `triangle_map` are empty; the CLI keeps them for `--progressive` only.
    pub keep_progressive: bool,
    /// Keep each mesh's input geometry in the scene (default). When false,
    /// [`crate::lod::build_lods_isolated`] frees each simplified mesh's
    /// input positions and indices once its levels are extracted and
    /// checked to be measurable, before the error measurement (peak memory
    /// of a scan: 80 MB of the 4.4M-triangle run's); the scene then keeps
    /// every other part of the mesh (attributes, materials, names). The CLI
    /// keeps the input for `--progressive` only, whose stream reads it.
    pub keep_input: bool,
    /// Move each written level's vertices towards the original after
    /// simplification ([`lodgen_pm::polish_clusters`], paired through the
    /// simplification's clusters; `None`: off, the default).
    /// Polishing starts from the levels as the progressive mesh gives them
    /// (lifted off their chords by default,
    /// [`lodgen_pm::SimplifyOptions::lift`]). The written levels and their
    /// measured errors are the polished ones; the progressive mesh and its
    /// stream keep the logged positions.
    pub polish: Option<lodgen_pm::PolishOptions>,
    /// Fix each written level's worst spot ([`lodgen_pm::polish::fix_worst`];
    /// `None`: off, the default): each round measures the level, moves the
    /// three corners of the face at its maximum to lower the largest
    /// distance around them, measures again and keeps the move only when the
    /// Hausdorff distance fell and the RMS stayed within
    /// [`WorstOptions::rms_growth`](lodgen_pm::polish::WorstOptions) of the
    /// unfixed level's. A level's reported error is the measurement of the
    /// level as written (after [`Self::polish`], when both are on). Needs
    /// [`Self::measured`]; each round costs one more measurement of the
    /// level. The progressive mesh and its stream keep the logged positions.
    pub fix_worst: Option<lodgen_pm::polish::WorstOptions>,
    /// Given each level's primitives as they will be written, while another
    /// level is measured (`None`: nobody; the default): see [`LevelHook`].
    pub level_ready: Option<LevelHook>,
}

/// What [`BuildOptions::level_ready`] calls: `(mesh, level, primitives)`,
/// the index of the source mesh, the level (0 finest) and its primitives
/// exactly as the mesh's [`crate::scene::LodMesh`] will hold them, on a
/// pool thread beside the measurement of another level (`rayon::join`), so
/// that a writer prepares a level's buffers while the build goes on (the
/// CLI's `gltf_out::PreparedLevels`). Not every level is given (the last
/// one measured is not: nothing is left to overlap it with), and a mesh
/// whose build then fails (written unsimplified, one level) may have had
/// levels given: the caller keeps what it made for the meshes that were
/// built only.
#[derive(Clone)]
pub struct LevelHook(pub LevelFn);

/// The function a [`LevelHook`] holds.
pub type LevelFn = std::sync::Arc<dyn Fn(usize, usize, &[Primitive]) + Send + Sync>;

impl std::fmt::Debug for LevelHook {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LevelHook")
    }
}

/// Default of [`BuildOptions::min_triangles`]: 8. Cards, quads, decals and
/// billboards (2–8 triangles) are kept as they are: any contraction of such a
/// part moves its outline by the part's own size, and a level of 1–7
/// triangles saves nothing a draw call would notice. A box (12) or more is
/// simplified down to 8 at most.
pub const DEFAULT_MIN_TRIANGLES: usize = 8;

/// Weights of each attribute in the cost (Hoppe 1999 attribute quadrics,
/// `lodgen_pm::simplify::features`): a difference of 1 in an attribute at weight 1
/// costs like a displacement by the bounding-box diagonal. 0 leaves an
/// attribute out (its seams are still kept).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttributeWeights {
    /// Unit normals (a difference of 2 is opposite). Default value: 0.05.
    pub normal: f32,
    /// Every `TEXCOORD_n` set. Default value: 0.5.
    pub uv: f32,
    /// Every `COLOR_n` set, RGBA. Default value: 0.5.
    pub color: f32,
}

impl AttributeWeights {
    /// What measured best on spot.obj (`cargo xtask attributes`, smooth
    /// normals, pass schedule): 0.05 / 0.5 is the pair that beats
    /// meshoptimizer's `simplify_with_attributes` on mean and RMS UV and
    /// normal error at 50 %, 10 % and 2 % (0.05 / 0.25, best under the
    /// greedy schedule, is 0.4° behind on the mean normal at 2 %), and keeps
    /// the geometric Hausdorff error below meshoptimizer's too. Colour is not
    /// measured (no test mesh has colours); it gets the UV weight, being
    /// in the same [0, 1] range.
    pub const DEFAULT: AttributeWeights = AttributeWeights {
        normal: 0.05,
        uv: 0.5,
        color: 0.5,
    };
}

impl Default for AttributeWeights {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            levels: LevelRequest::Specs(vec![
                LevelSpec::Ratio(0.5),
                LevelSpec::Ratio(0.1),
                LevelSpec::Ratio(0.02),
            ]),
            simplify: SimplifyOptions::DEFAULT,
            method: Method::Qem,
            adaptive: AdaptiveOptions::DEFAULT,
            measure: MeasureOptions::DEFAULT,
            measured: true,
            attribute_weights: AttributeWeights::DEFAULT,
            min_triangles: DEFAULT_MIN_TRIANGLES,
            meter: None,
            keep_progressive: true,
            keep_input: true,
            polish: None,
            fix_worst: None,
            level_ready: None,
        }
    }
}

/// Progress events, for a progress bar (the builder never prints). In
/// order: `Reading`, then per mesh `Simplifying` and one `Measuring` per
/// level, then `Writing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Parsing the input file (sent by [`crate::cli::build_file`]).
    Reading,
    /// Writing the output file (sent by [`crate::cli::build_file`]).
    Writing,
    Simplifying {
        mesh: usize,
        of: usize,
    },
    Measuring {
        mesh: usize,
        level: usize,
        of: usize,
    },
}
