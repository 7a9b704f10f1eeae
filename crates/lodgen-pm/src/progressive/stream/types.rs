//! The stream's public types: constants, [`Grid`], options, errors,
//! channels and wedge values, the header; shared by the encoder and the
//! decoder.

use thiserror::Error;

/// The four bytes every stream starts with.
pub const MAGIC: [u8; 4] = *b"LGPM";
/// The layout version this module writes and reads.
pub const VERSION: u8 = 7;
/// Records per block of a chunk's topology (and wedge) columns (version 7):
/// a chunk of `n` records holds `⌈n / BLOCK_RECORDS⌉` blocks, all but the
/// last of this many records, so a client reading the chunk as it arrives
/// replays each block once its columns are in.
pub const BLOCK_RECORDS: usize = 8192;
/// Header flag: the stream stores every record's `error` (`f32`).
pub const FLAG_ERRORS: u8 = 1;
/// Header flag: the stream carries wedges (attributes per corner): a wedge
/// table in the header, the base corners' wedges, and each record's face
/// and corner-edit wedges, each new wedge with its values.
pub const FLAG_WEDGES: u8 = 2;
/// Longest channel name (bytes) and most components per channel a stream
/// may declare.
pub const MAX_CHANNEL_NAME: usize = 64;
pub const MAX_COMPONENTS: u8 = 16;
/// Most channels a stream may declare.
pub const MAX_CHANNELS: usize = 64;

/// The quantization grid of a stream's positions: on each axis
/// `q = round((p − center) / half · s)` clamped to `−s ..= s`, stored as
/// `q + s`, with `s = 2^(bits−1) − 1`; decoded as `center + (q − s) / s ·
/// half` in `f64`, rounded once to `f32`. With `bits = 16` and the level
/// chain's box this is exactly the `KHR_mesh_quantization` grid lodgen's
/// `--quantize` writes (normalized `i16` = `q − s`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub center: [f64; 3],
    /// Half the largest extent of the box (> 0).
    pub half: f64,
    /// Bits per axis, 2..=16.
    pub bits: u8,
}

impl Grid {
    /// The grid of `bits` bits over the bounding box of `points` (center,
    /// half the largest extent; 1 when the box is a point). Non-finite
    /// coordinates are skipped.
    pub fn around<'a>(points: impl IntoIterator<Item = &'a [f32; 3]>, bits: u8) -> Grid {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in points {
            if p.iter().all(|c| c.is_finite()) {
                for a in 0..3 {
                    lo[a] = lo[a].min(f64::from(p[a]));
                    hi[a] = hi[a].max(f64::from(p[a]));
                }
            }
        }
        if lo[0] > hi[0] {
            return Grid {
                center: [0.0; 3],
                half: 1.0,
                bits: bits.clamp(2, 16),
            };
        }
        let center = [0, 1, 2].map(|a| (lo[a] + hi[a]) * 0.5);
        let half = (0..3).map(|a| (hi[a] - lo[a]) * 0.5).fold(0.0, f64::max);
        Grid {
            center,
            half: if half > 0.0 { half } else { 1.0 },
            bits: bits.clamp(2, 16),
        }
    }

    /// `s`: the grid point of `center` and the largest offset from it.
    pub fn scale(&self) -> f64 {
        f64::from((1u32 << (self.bits - 1)) - 1)
    }

    /// The grid point of `p` (the same arithmetic as lodgen's quantized
    /// glTF positions; NaN goes to the center, outside the box is clamped).
    pub fn quantize(&self, p: [f32; 3]) -> [u16; 3] {
        let s = self.scale();
        [0, 1, 2].map(|a| {
            let q = ((f64::from(p[a]) - self.center[a]) / self.half * s)
                .round()
                .clamp(-s, s) as i32;
            (q + s as i32) as u16
        })
    }

    /// The position of grid point `q`.
    pub fn dequantize(&self, q: [u16; 3]) -> [f32; 3] {
        let s = self.scale();
        [0, 1, 2].map(|a| (self.center[a] + (f64::from(q[a]) - s) / s * self.half) as f32)
    }

    /// Half a grid step: the largest distance of a decoded coordinate from
    /// the original inside the box (before the `f32` rounding).
    pub fn error_bound(&self) -> f64 {
        self.half / self.scale() / 2.0
    }
}

/// How to encode.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct EncodeOptions {
    /// Grid bits per axis, 2..=16, when `grid` is not given. Default
    /// value: 16.
    pub bits: u8,
    /// Store each split's quadric error (a column of `f32`). Default
    /// value: false.
    pub errors: bool,
    /// The grid; default: [`Grid::around`] every position the log ever
    /// holds, with `bits`.
    pub grid: Option<Grid>,
    /// Store every attribute value as exact `f32` instead of the compact
    /// encodings of [`AttrEncoding::choose`]. Default value: false.
    pub exact_attributes: bool,
}

impl EncodeOptions {
    pub const DEFAULT: EncodeOptions = EncodeOptions {
        bits: 16,
        errors: false,
        grid: None,
        exact_attributes: false,
    };

    pub fn with_bits(mut self, bits: u8) -> Self {
        self.bits = bits.clamp(2, 16);
        self
    }

    pub fn with_errors(mut self, on: bool) -> Self {
        self.errors = on;
        self
    }

    /// Keep attribute values exact (`f32`) instead of quantizing them.
    pub fn with_exact_attributes(mut self, on: bool) -> Self {
        self.exact_attributes = on;
        self
    }

    /// Quantize on `grid` (e.g. the file's `KHR_mesh_quantization` grid).
    pub fn with_grid(mut self, grid: Grid) -> Self {
        self.grid = Some(Grid {
            bits: grid.bits.clamp(2, 16),
            ..grid
        });
        self
    }
}

impl Default for EncodeOptions {
    fn default() -> Self {
        EncodeOptions::DEFAULT
    }
}

/// Why bytes were refused. Offsets are byte offsets in the whole stream.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum StreamError {
    #[error("not a lodgen progressive stream (bad magic)")]
    Magic,
    #[error("unsupported stream version {0} (this reader knows version {VERSION})")]
    Version(u8),
    #[error("the stream ends early, at byte {0}")]
    Truncated(usize),
    #[error("byte {offset}: {what}")]
    Invalid { offset: usize, what: String },
    #[error("{0} bytes follow the last chunk")]
    TrailingBytes(usize),
}

/// Why `encode_with_attributes` refused its input (a caller's mistake,
/// not a stream's).
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum EncodeError {
    #[error("the progressive mesh has no wedge log (it was not simplified with wedges)")]
    NoWedges,
    #[error("channel {index}: {what}")]
    Channel { index: usize, what: String },
    #[error("{values} attribute values are not a whole number of wedges of {stride}")]
    Values { values: usize, stride: usize },
    #[error("{groups} groups given for {wedges} wedges")]
    Groups { groups: usize, wedges: usize },
    #[error("wedge {wedge} is used by the log but has no values ({wedges} wedges given)")]
    WedgeOutOfRange { wedge: u32, wedges: usize },
}

/// One attribute every wedge of a stream carries: its name (lodgen writes
/// glTF semantics: `NORMAL`, `TEXCOORD_0`, …) and its component count.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Channel {
    pub name: String,
    pub components: u8,
}

/// The attribute values of every wedge: what `encode_with_attributes`
/// takes (indexed by the log's wedge ids) and what the decoder yields
/// (indexed by the stream's wedge numbering, order of first appearance).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WedgeAttributes {
    pub channels: Vec<Channel>,
    /// Wedge-major: wedge `w`'s values are `values[w · stride ..][..stride]`,
    /// channels in order.
    pub values: Vec<f32>,
    /// Group of each wedge (lodgen: the primitive, hence the material);
    /// empty means every wedge is in group 0.
    pub groups: Vec<u32>,
    /// Number of wedges (needed when there are no channels).
    pub count: usize,
}

impl WedgeAttributes {
    /// Values per wedge: the channels' components summed.
    pub fn stride(&self) -> usize {
        self.channels
            .iter()
            .map(|c| usize::from(c.components))
            .sum()
    }

    /// Wedge `w`'s values.
    pub fn wedge(&self, w: u32) -> &[f32] {
        let s = self.stride();
        &self.values[w as usize * s..][..s]
    }

    /// Wedge `w`'s group.
    pub fn group(&self, w: u32) -> u32 {
        self.groups.get(w as usize).copied().unwrap_or(0)
    }

    /// Where channel `name` starts in a wedge's values, and its size.
    pub fn channel(&self, name: &str) -> Option<(usize, usize)> {
        let mut at = 0;
        for c in &self.channels {
            if c.name == name {
                return Some((at, usize::from(c.components)));
            }
            at += usize::from(c.components);
        }
        None
    }

    pub(super) fn check(&self) -> Result<(), EncodeError> {
        if self.channels.len() > MAX_CHANNELS {
            return Err(EncodeError::Channel {
                index: MAX_CHANNELS,
                what: format!("more than {MAX_CHANNELS} channels"),
            });
        }
        for (index, c) in self.channels.iter().enumerate() {
            if c.name.is_empty() || c.name.len() > MAX_CHANNEL_NAME {
                return Err(EncodeError::Channel {
                    index,
                    what: format!("name of {} bytes (1..={MAX_CHANNEL_NAME})", c.name.len()),
                });
            }
            if !(1..=MAX_COMPONENTS).contains(&c.components) {
                return Err(EncodeError::Channel {
                    index,
                    what: format!("{} components (1..={MAX_COMPONENTS})", c.components),
                });
            }
        }
        let stride = self.stride();
        if self.values.len() != self.count * stride {
            return Err(EncodeError::Values {
                values: self.values.len(),
                stride,
            });
        }
        if !self.groups.is_empty() && self.groups.len() != self.count {
            return Err(EncodeError::Groups {
                groups: self.groups.len(),
                wedges: self.count,
            });
        }
        Ok(())
    }
}

/// How a channel's values are stored: exact `f32`, or the normalized
/// integers lodgen's `--quantize` writes in glTF (`KHR_mesh_quantization`),
/// decoded as the glTF spec dequantizes them (`q / 65535`, `q / 127`,
/// `q / 255`, each computed in `f64` and rounded once to `f32`), or unorm16
/// over a stated range (`offset + scale · q / 65535`, the
/// `KHR_texture_transform` way).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AttrEncoding {
    /// Exact `f32` (code 0).
    F32,
    /// Unsigned normalized 16-bit, values in [0, 1] (code 1): texture
    /// coordinates.
    Unorm16,
    /// Signed normalized 8-bit, values in [-1, 1] (code 2): normals,
    /// tangents.
    Snorm8,
    /// Unsigned normalized 8-bit, values in [0, 1] (code 3): colours.
    Unorm8,
    /// Unsigned 16-bit over `offset ..= offset + scale` (code 4, followed in
    /// the header by `offset` and `scale` as little-endian `f32`): texture
    /// coordinates that leave [0, 1].
    Unorm16Range(Range),
}

/// The span of a [`AttrEncoding::Unorm16Range`] channel: every component's
/// values lie in `offset ..= offset + scale` (`scale` finite, > 0).
#[derive(Clone, Copy, Debug)]
pub struct Range {
    pub offset: f32,
    pub scale: f32,
}

impl PartialEq for Range {
    fn eq(&self, o: &Range) -> bool {
        self.offset.to_bits() == o.offset.to_bits() && self.scale.to_bits() == o.scale.to_bits()
    }
}

impl Eq for Range {}

impl Range {
    /// The smallest range (in `f32`) holding every value, or `None` when a
    /// value is not finite or all are equal.
    pub fn around(values: impl Iterator<Item = f32>) -> Option<Range> {
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for x in values {
            if !x.is_finite() {
                return None;
            }
            lo = lo.min(x);
            hi = hi.max(x);
        }
        let mut scale = (f64::from(hi) - f64::from(lo)) as f32;
        while f64::from(lo) + f64::from(scale) < f64::from(hi) {
            scale = f32::from_bits(scale.to_bits() + 1);
        }
        (lo <= hi && scale > 0.0 && scale.is_finite()).then_some(Range { offset: lo, scale })
    }

    /// Whether a header may hold it.
    pub fn valid(self) -> bool {
        self.offset.is_finite() && self.scale.is_finite() && self.scale > 0.0
    }
}

impl AttrEncoding {
    pub fn code(self) -> u8 {
        match self {
            AttrEncoding::F32 => 0,
            AttrEncoding::Unorm16 => 1,
            AttrEncoding::Snorm8 => 2,
            AttrEncoding::Unorm8 => 3,
            AttrEncoding::Unorm16Range(_) => 4,
        }
    }

    /// The encoding of `code` (for code 4 with `range`); `None` when unknown.
    pub fn from_code(code: u8, range: Range) -> Option<AttrEncoding> {
        Some(match code {
            0 => AttrEncoding::F32,
            1 => AttrEncoding::Unorm16,
            2 => AttrEncoding::Snorm8,
            3 => AttrEncoding::Unorm8,
            4 => AttrEncoding::Unorm16Range(range),
            _ => return None,
        })
    }

    /// How the stream stores glTF attribute `name` whose values are
    /// `values`: what lodgen's `--quantize` writes (`NORMAL` / `TANGENT`
    /// snorm8, `TEXCOORD_n` unorm16 and `COLOR_n` unorm8 when every value is
    /// in [0, 1]), a `TEXCOORD_n` leaving [0, 1] unorm16 over its range;
    /// else (and for joints and weights) `f32`.
    pub fn choose(name: &str, values: impl Iterator<Item = f32> + Clone) -> AttrEncoding {
        let unit = |x: f32| (0.0..=1.0).contains(&x);
        if name == "NORMAL" || name == "TANGENT" {
            if values.clone().all(f32::is_finite) {
                return AttrEncoding::Snorm8;
            }
        } else if name.starts_with("TEXCOORD_") {
            if values.clone().all(unit) {
                return AttrEncoding::Unorm16;
            }
            if let Some(r) = Range::around(values) {
                return AttrEncoding::Unorm16Range(r);
            }
        } else if name.starts_with("COLOR_") && values.clone().all(unit) {
            return AttrEncoding::Unorm8;
        }
        AttrEncoding::F32
    }

    /// Largest stored integer (`F32`: none).
    pub(super) fn max(self) -> u16 {
        match self {
            AttrEncoding::F32 => 0,
            AttrEncoding::Unorm16 | AttrEncoding::Unorm16Range(_) => u16::MAX,
            AttrEncoding::Snorm8 => 254,
            AttrEncoding::Unorm8 => 255,
        }
    }

    /// The stored integer of `x` (snorm8 offset by 127 to be unsigned), as
    /// the glTF writer rounds and clamps it.
    pub fn quantize(self, x: f32) -> u16 {
        let x = f64::from(x);
        match self {
            AttrEncoding::F32 => 0,
            AttrEncoding::Unorm16 => (x * 65535.0).round().clamp(0.0, 65535.0) as u16,
            AttrEncoding::Snorm8 => ((x * 127.0).round().clamp(-127.0, 127.0) + 127.0) as u16,
            AttrEncoding::Unorm8 => (x * 255.0).round().clamp(0.0, 255.0) as u16,
            AttrEncoding::Unorm16Range(r) => ((x - f64::from(r.offset)) / f64::from(r.scale)
                * 65535.0)
                .round()
                .clamp(0.0, 65535.0) as u16,
        }
    }

    /// The value of stored integer `q`.
    pub fn dequantize(self, q: u16) -> f32 {
        let q = f64::from(q);
        (match self {
            AttrEncoding::F32 => 0.0,
            AttrEncoding::Unorm16 => q / 65535.0,
            AttrEncoding::Snorm8 => (q - 127.0) / 127.0,
            AttrEncoding::Unorm8 => q / 255.0,
            AttrEncoding::Unorm16Range(r) => {
                f64::from(r.offset) + f64::from(r.scale) * (q / 65535.0)
            }
        }) as f32
    }

    /// `x` after the round trip through this encoding (`F32`: itself).
    pub fn round_trip(self, x: f32) -> f32 {
        match self {
            AttrEncoding::F32 => x,
            e => e.dequantize(e.quantize(x)),
        }
    }
}

/// The wedge part of a header (present with [`FLAG_WEDGES`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WedgeLayout {
    /// Wedges the whole stream defines.
    pub total: usize,
    /// Groups are `0 .. groups`; with one group none is stored.
    pub groups: u32,
    pub channels: Vec<Channel>,
    /// Parallel to `channels`: how each is stored.
    pub encodings: Vec<AttrEncoding>,
}

/// One chunk of the stream: the records it completes and its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChunkInfo {
    /// Records applied once this chunk is decoded (0 for the base chunk).
    pub records: usize,
    /// Bytes of the chunk.
    pub bytes: usize,
}

/// The fixed part of a stream: the grid, counts for preallocation, the
/// level table, the wedge table and the chunk table.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamHeader {
    pub flags: u8,
    pub grid: Grid,
    pub base_vertices: usize,
    pub base_triangles: usize,
    pub split_count: usize,
    pub total_vertices: usize,
    pub total_triangles: usize,
    /// Record counts, in the order given to `encode`, each reproducing
    /// one chosen level exactly.
    pub levels: Vec<usize>,
    /// The wedge table, when the stream carries attributes.
    pub wedges: Option<WedgeLayout>,
    /// The base chunk, then one chunk per distinct level record count
    /// (ascending) and the last record.
    pub chunks: Vec<ChunkInfo>,
    /// Bytes of the header itself (where chunk 0 starts).
    pub header_bytes: usize,
}

impl StreamHeader {
    /// The bound on each decoded coordinate's distance to the original,
    /// excluding the final `f32` rounding: half a grid step.
    pub fn error_bound(&self) -> f64 {
        self.grid.error_bound()
    }

    /// Byte offset of chunk `i` in the stream.
    pub fn chunk_offset(&self, i: usize) -> usize {
        self.header_bytes + self.chunks[..i].iter().map(|c| c.bytes).sum::<usize>()
    }
}

pub(super) fn invalid(offset: usize, what: impl Into<String>) -> StreamError {
    StreamError::Invalid {
        offset,
        what: what.into(),
    }
}

/// Chunk boundaries for `levels` on a log of `splits` records: the
/// distinct non-zero level counts and `splits`, ascending.
pub(super) fn chunk_ends(levels: &[usize], splits: usize) -> Vec<usize> {
    let mut ends: Vec<usize> = levels
        .iter()
        .map(|&k| k.min(splits))
        .chain([splits])
        .filter(|&k| k > 0)
        .collect();
    ends.sort_unstable();
    ends.dedup();
    ends
}
