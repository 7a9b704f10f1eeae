//! The vertex-split log as a compact, self-delimiting byte stream: the
//! payload of the `LODGEN_progressive` glTF extension (see
//! `docs/LODGEN_progressive.md`, which is the normative description of the
//! layout; this module is its reference implementation).
//!
//! Owns [`encode`], [`decode`], the incremental [`StreamDecoder`] and
//! [`StreamError`]. Bytes in, bytes out: no I/O, no printing.
//!
//! Layout, all integers LEB128 varints unless noted (`zz` = zigzag-signed):
//! ```text
//! header   "LGPM" · version u8 (=1) · flags u8 · bits u8 · origin f32le×3 · step f32le
//!          base_vertices · base_triangles · split_count · total_vertices ·
//!          total_triangles · level_count · levels[level_count]
//! base     base_vertices × (zz dq.x, zz dq.y, zz dq.z)   delta to the previous vertex
//!          base_triangles × 3 × zz (corner − previous corner)
//! record   head = corners·4 + min(faces, 3) · [faces − 3 if faces ≥ 3]
//!          v0 − 1 − v1
//!          zz (q(p1) − q(v1 now)) ×3 · zz (q(p0) − q(p1)) ×3
//!          faces × 3 × corner code: 0 = v0, 1 = v1, k ≥ 2 = vertex v0 − (k − 1)
//!          corners, descending: (gap << 2 | slot), gap of the first from
//!          triangle_count − 1 (after the faces are appended), then from the
//!          previous corner's triangle
//!          [wedges, if flags & 2: faces × 3 wedge refs · corners × 1 wedge ref
//!           (the wedge after the split, in the stored corner order)]
//!          [error f32le, if flags & 1]
//! ```
//! With flags & 2 the header ends with `total_wedges · group_count ·
//! channel_count · (name_len · name · components u8) × channel_count` and
//! the base with `base_triangles × 3` wedge refs; a wedge ref is `0` for a
//! new wedge (then its group varint when `group_count > 1`, then its
//! values as `f32le`) or `k ≥ 1` for wedge `count − k`.
//! `v0` is implicit (`base_vertices + record index`) and `p_merged` is the
//! decoder's current position of `v1`, so neither is stored.
//!
//! What is preserved: the base mesh's triangles, every split's `v1`, `v0`,
//! `faces` and `corners` exactly, so `decode(encode(pm))` refined `k` steps has
//! exactly the triangles of `pm.mesh_at_splits(k)` for every `k`. Positions
//! are snapped to a uniform grid: `origin + q · step`, `q` an integer in
//! `0 ..= 2^bits − 1` on each axis, `step` the largest bounding-box extent of
//! every position the log ever holds divided by `2^bits − 1` (rounded up to
//! an `f32`). Each decoded coordinate is within `step / 2` of the original,
//! plus the `f32` rounding of the result (half an ulp of the coordinate).
//! Split errors are kept only with [`EncodeOptions::errors`] (otherwise
//! decoded as 0).
//!
//! With [`encode_with_attributes`] every corner's wedge at every step and
//! every wedge's values are exact too: [`decode_with_attributes`] gives the
//! log's wedges renumbered by first appearance, with their values.

use crate::mesh::Mesh;
use crate::progressive::{Corner, ProgressiveMesh, SplitWedges, VertexSplit, WedgeLog};
use smallvec::SmallVec;
use thiserror::Error;

/// The four bytes every stream starts with.
pub const MAGIC: [u8; 4] = *b"LGPM";
/// The layout version this module writes and reads.
pub const VERSION: u8 = 1;
/// Header flag: every record ends with its `error` as `f32` LE.
pub const FLAG_ERRORS: u8 = 1;
/// Header flag: the stream carries wedges (attributes per corner): a wedge
/// table in the header, the base corners' wedges, and each record's face
/// and corner-edit wedges, each new wedge with its values inline.
pub const FLAG_WEDGES: u8 = 2;
/// Longest channel name (bytes) and most components per channel a stream
/// may declare.
pub const MAX_CHANNEL_NAME: usize = 64;
pub const MAX_COMPONENTS: u8 = 16;
/// Most channels a stream may declare.
pub const MAX_CHANNELS: usize = 64;
/// Bound on preallocation from header counts, so a hostile header cannot
/// make the decoder reserve gigabytes before any data arrives.
const MAX_PREALLOC: usize = 1 << 20;

/// How to encode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct EncodeOptions {
    /// Grid bits per axis, 1..=30. Default value: 16 (error ≤ largest
    /// extent / 131070 per axis).
    pub bits: u8,
    /// Store each split's quadric error (4 bytes per record). Default
    /// value: false.
    pub errors: bool,
}

impl EncodeOptions {
    pub const DEFAULT: EncodeOptions = EncodeOptions {
        bits: 16,
        errors: false,
    };

    pub fn with_bits(mut self, bits: u8) -> Self {
        self.bits = bits.clamp(1, 30);
        self
    }

    pub fn with_errors(mut self, on: bool) -> Self {
        self.errors = on;
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
    #[error("{0} bytes follow the last record")]
    TrailingBytes(usize),
}

/// Why [`encode_with_attributes`] refused its input (a caller's mistake,
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

/// The attribute values of every wedge: what [`encode_with_attributes`]
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

    fn check(&self) -> Result<(), EncodeError> {
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

/// The wedge part of a header (present with [`FLAG_WEDGES`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WedgeLayout {
    /// Wedges the whole stream defines.
    pub total: usize,
    /// Groups are `0 .. groups`; with one group none is stored.
    pub groups: u32,
    pub channels: Vec<Channel>,
}

fn invalid(offset: usize, what: impl Into<String>) -> StreamError {
    StreamError::Invalid {
        offset,
        what: what.into(),
    }
}

/// The fixed part of a stream: counts for preallocation, the quantization
/// grid and the level table.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamHeader {
    pub flags: u8,
    pub bits: u8,
    /// Grid origin: position = origin + q · step.
    pub origin: [f32; 3],
    pub step: f32,
    pub base_vertices: usize,
    pub base_triangles: usize,
    pub split_count: usize,
    pub total_vertices: usize,
    pub total_triangles: usize,
    /// Record counts, in the order given to [`encode`], each reproducing
    /// one chosen level exactly.
    pub levels: Vec<usize>,
    /// The wedge table, when the stream carries attributes.
    pub wedges: Option<WedgeLayout>,
}

impl StreamHeader {
    /// The bound on each decoded coordinate's distance to the original,
    /// excluding the final `f32` rounding: `step / 2`.
    pub fn error_bound(&self) -> f64 {
        f64::from(self.step) / 2.0
    }

    fn dequantize(&self, q: [u32; 3]) -> [f32; 3] {
        [0, 1, 2]
            .map(|i| (f64::from(self.origin[i]) + f64::from(q[i]) * f64::from(self.step)) as f32)
    }

    fn quantize(&self, p: [f32; 3]) -> [u32; 3] {
        let max = ((1u64 << self.bits) - 1) as f64;
        [0, 1, 2].map(|i| {
            let q = ((f64::from(p[i]) - f64::from(self.origin[i])) / f64::from(self.step)).round();
            // NaN → 0 (`as` saturates); outside the grid → clamped
            q.clamp(0.0, max) as u32
        })
    }
}

// ---------------------------------------------------------------- encoding

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn put_zz(out: &mut Vec<u8>, v: i64) {
    put_varint(out, ((v << 1) ^ (v >> 63)) as u64);
}

fn put_f32(out: &mut Vec<u8>, v: f32) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// The grid of [`EncodeOptions::bits`] bits covering every position the log
/// ever holds (base positions and every split's `p1`, `p0`; `p_merged` is
/// always one of these).
fn grid(pm: &ProgressiveMesh, bits: u8) -> ([f32; 3], f32) {
    let all = pm
        .base
        .positions
        .iter()
        .chain(pm.splits.iter().flat_map(|s| [&s.p1, &s.p0]))
        .filter(|p| p.iter().all(|c| c.is_finite()));
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in all {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    if lo[0] > hi[0] {
        return ([0.0; 3], 1.0);
    }
    let extent = (0..3)
        .map(|i| f64::from(hi[i]) - f64::from(lo[i]))
        .fold(0.0, f64::max);
    if extent == 0.0 {
        return (lo, 1.0);
    }
    let exact = extent / ((1u64 << bits) - 1) as f64;
    let mut step = exact as f32;
    // round up, so the far corner of the box still fits in 2^bits − 1 steps
    while f64::from(step) < exact {
        step = f32::from_bits(step.to_bits() + 1);
    }
    (lo, step)
}

/// Encode `pm` with `levels` (record counts, each clamped to `pm.len()`):
/// positions and topology only, whether or not `pm` has a wedge log (see
/// [`encode_with_attributes`]).
///
/// Non-finite coordinates cannot be represented: they are snapped onto the
/// grid (NaN to its origin). Meshes from [`crate::simplify()`] never have them.
pub fn encode(pm: &ProgressiveMesh, levels: &[usize], opts: EncodeOptions) -> Vec<u8> {
    encode_inner(pm, levels, opts, None)
}

/// [`encode`], plus every corner's wedge and every wedge's attribute values,
/// so a client refining the stream draws each step with the input's own
/// attributes (a fully refined stream has exactly the input's values at
/// every corner). `attributes` is indexed by the log's wedge ids
/// (`pm.wedges`; for [`crate::simplify_with_wedges`], the input vertex
/// indices). Values are stored as `f32`, exactly; each wedge once, where it
/// is first used.
pub fn encode_with_attributes(
    pm: &ProgressiveMesh,
    levels: &[usize],
    opts: EncodeOptions,
    attributes: &WedgeAttributes,
) -> Result<Vec<u8>, EncodeError> {
    let log = pm.wedges.as_ref().ok_or(EncodeError::NoWedges)?;
    attributes.check()?;
    let used = log
        .base
        .iter()
        .flatten()
        .chain(log.splits.iter().flat_map(|s| {
            s.faces
                .iter()
                .flatten()
                .chain(s.corners.iter().map(|c| &c[1]))
        }));
    let mut seen = vec![false; attributes.count];
    let mut total = 0usize;
    for &w in used {
        let slot = seen
            .get_mut(w as usize)
            .ok_or(EncodeError::WedgeOutOfRange {
                wedge: w,
                wedges: attributes.count,
            })?;
        if !*slot {
            *slot = true;
            total += 1;
        }
    }
    Ok(encode_inner(
        pm,
        levels,
        opts,
        Some((log, attributes, total)),
    ))
}

/// Writes wedge references: `0` plus the wedge's group and values when it
/// is new, else `count − id`.
struct WedgeWriter<'a> {
    attributes: &'a WedgeAttributes,
    groups: u32,
    /// Log wedge id → stream id + 1 (0 = not yet written).
    ids: Vec<u32>,
    count: u32,
}

impl WedgeWriter<'_> {
    fn put(&mut self, out: &mut Vec<u8>, w: u32) {
        let id = &mut self.ids[w as usize];
        if *id == 0 {
            put_varint(out, 0);
            if self.groups > 1 {
                put_varint(out, u64::from(self.attributes.group(w)));
            }
            for &v in self.attributes.wedge(w) {
                put_f32(out, v);
            }
            self.count += 1;
            *id = self.count;
        } else {
            put_varint(out, u64::from(self.count + 1 - *id));
        }
    }
}

fn encode_inner(
    pm: &ProgressiveMesh,
    levels: &[usize],
    opts: EncodeOptions,
    wedges: Option<(&WedgeLog, &WedgeAttributes, usize)>,
) -> Vec<u8> {
    let bits = opts.bits.clamp(1, 30);
    let (origin, step) = grid(pm, bits);
    let total_triangles =
        pm.base.triangles.len() + pm.splits.iter().map(|s| s.faces.len()).sum::<usize>();
    let groups = wedges.map_or(1, |(_, a, _)| {
        a.groups.iter().max().map_or(1, |&g| g.saturating_add(1))
    });
    let header = StreamHeader {
        flags: u8::from(opts.errors) * FLAG_ERRORS + u8::from(wedges.is_some()) * FLAG_WEDGES,
        bits,
        origin,
        step,
        base_vertices: pm.base.positions.len(),
        base_triangles: pm.base.triangles.len(),
        split_count: pm.splits.len(),
        total_vertices: pm.base.positions.len() + pm.splits.len(),
        total_triangles,
        levels: levels.iter().map(|&k| k.min(pm.splits.len())).collect(),
        wedges: wedges.map(|(_, a, total)| WedgeLayout {
            total,
            groups,
            channels: a.channels.clone(),
        }),
    };
    let mut out = Vec::with_capacity(64 + 12 * header.total_vertices + 8 * total_triangles);
    out.extend_from_slice(&MAGIC);
    out.push(VERSION);
    out.push(header.flags);
    out.push(bits);
    for c in origin {
        put_f32(&mut out, c);
    }
    put_f32(&mut out, step);
    for n in [
        header.base_vertices,
        header.base_triangles,
        header.split_count,
        header.total_vertices,
        header.total_triangles,
        header.levels.len(),
    ] {
        put_varint(&mut out, n as u64);
    }
    for &k in &header.levels {
        put_varint(&mut out, k as u64);
    }
    if let Some(layout) = &header.wedges {
        put_varint(&mut out, layout.total as u64);
        put_varint(&mut out, u64::from(layout.groups));
        put_varint(&mut out, layout.channels.len() as u64);
        for c in &layout.channels {
            put_varint(&mut out, c.name.len() as u64);
            out.extend_from_slice(c.name.as_bytes());
            out.push(c.components);
        }
    }
    let mut ww = wedges.map(|(log, a, _)| {
        (
            log,
            WedgeWriter {
                attributes: a,
                groups,
                ids: vec![0; a.count],
                count: 0,
            },
        )
    });

    // base mesh
    let mut q: Vec<[u32; 3]> = Vec::with_capacity(header.total_vertices);
    let mut prev = [0u32; 3];
    for p in &pm.base.positions {
        let qp = header.quantize(*p);
        for i in 0..3 {
            put_zz(&mut out, i64::from(qp[i]) - i64::from(prev[i]));
        }
        prev = qp;
        q.push(qp);
    }
    let mut prev = 0u32;
    for t in &pm.base.triangles {
        for &c in t {
            put_zz(&mut out, i64::from(c) - i64::from(prev));
            prev = c;
        }
    }
    if let Some((log, w)) = &mut ww {
        for &c in log.base.iter().flatten() {
            w.put(&mut out, c);
        }
    }

    // records
    let mut triangles = pm.base.triangles.len();
    for (i, s) in pm.splits.iter().enumerate() {
        let v0 = (pm.base.positions.len() + i) as u32;
        debug_assert_eq!(s.v0, v0);
        debug_assert!(s.v1 < v0);
        let nf = s.faces.len();
        put_varint(&mut out, (s.corners.len() as u64) * 4 + nf.min(3) as u64);
        if nf >= 3 {
            put_varint(&mut out, (nf - 3) as u64);
        }
        put_varint(&mut out, u64::from(v0 - 1 - s.v1));
        let q1 = header.quantize(s.p1);
        let q0 = header.quantize(s.p0);
        let cur = q[s.v1 as usize];
        for a in 0..3 {
            put_zz(&mut out, i64::from(q1[a]) - i64::from(cur[a]));
        }
        for a in 0..3 {
            put_zz(&mut out, i64::from(q0[a]) - i64::from(q1[a]));
        }
        q[s.v1 as usize] = q1;
        q.push(q0);
        for f in &s.faces {
            for &c in f {
                let code = if c == v0 {
                    0
                } else if c == s.v1 {
                    1
                } else {
                    u64::from(v0 - c) + 1
                };
                put_varint(&mut out, code);
            }
        }
        triangles += nf;
        let mut prev = triangles as u64;
        for c in s.corners.iter().rev() {
            let gap = prev - 1 - u64::from(c.triangle);
            put_varint(&mut out, (gap << 2) | u64::from(c.slot));
            prev = u64::from(c.triangle) + 1;
        }
        if let Some((log, w)) = &mut ww {
            let sw = &log.splits[i];
            for &c in sw.faces.iter().flatten() {
                w.put(&mut out, c);
            }
            for c in sw.corners.iter().rev() {
                w.put(&mut out, c[1]);
            }
        }
        if opts.errors {
            put_f32(&mut out, s.error);
        }
    }
    out
}

// ---------------------------------------------------------------- decoding

/// Reads from a byte slice; running out of bytes is `NeedMore`, which the
/// incremental decoder turns into "wait", the one-shot decoder into
/// [`StreamError::Truncated`].
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    /// Offset of `bytes[0]` in the whole stream (for error messages).
    base: usize,
}

enum ReadError {
    NeedMore,
    Bad(StreamError),
}

impl From<StreamError> for ReadError {
    fn from(e: StreamError) -> Self {
        ReadError::Bad(e)
    }
}

impl<'a> Reader<'a> {
    fn offset(&self) -> usize {
        self.base + self.pos
    }

    fn byte(&mut self) -> Result<u8, ReadError> {
        let b = *self.bytes.get(self.pos).ok_or(ReadError::NeedMore)?;
        self.pos += 1;
        Ok(b)
    }

    fn varint(&mut self) -> Result<u64, ReadError> {
        let start = self.offset();
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = self.byte()?;
            let bits = u64::from(b & 0x7f);
            if shift == 63 && bits > 1 {
                break;
            }
            v |= bits << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(invalid(start, "varint longer than 64 bits").into())
    }

    fn zz(&mut self) -> Result<i64, ReadError> {
        let v = self.varint()?;
        Ok(((v >> 1) as i64) ^ -((v & 1) as i64))
    }

    /// A varint that must fit `limit` (inclusive).
    fn bounded(&mut self, limit: u64, what: &str) -> Result<u64, ReadError> {
        let start = self.offset();
        let v = self.varint()?;
        if v > limit {
            return Err(invalid(start, format!("{what} {v} exceeds {limit}")).into());
        }
        Ok(v)
    }

    fn f32(&mut self) -> Result<f32, ReadError> {
        let mut b = [0u8; 4];
        for x in &mut b {
            *x = self.byte()?;
        }
        Ok(f32::from_le_bytes(b))
    }
}

fn parse_header(r: &mut Reader) -> Result<StreamHeader, ReadError> {
    for &m in &MAGIC {
        if r.byte()? != m {
            return Err(StreamError::Magic.into());
        }
    }
    let version = r.byte()?;
    if version != VERSION {
        return Err(StreamError::Version(version).into());
    }
    let at = r.offset();
    let flags = r.byte()?;
    if flags & !(FLAG_ERRORS | FLAG_WEDGES) != 0 {
        return Err(invalid(at, format!("unknown flags {flags:#04x}")).into());
    }
    let at = r.offset();
    let bits = r.byte()?;
    if !(1..=30).contains(&bits) {
        return Err(invalid(at, format!("grid bits {bits} outside 1..=30")).into());
    }
    let at = r.offset();
    let origin = [r.f32()?, r.f32()?, r.f32()?];
    let step = r.f32()?;
    if !(origin.iter().all(|c| c.is_finite()) && step.is_finite() && step > 0.0) {
        return Err(invalid(at, "non-finite grid origin or non-positive step").into());
    }
    let max = u64::from(u32::MAX - 1);
    let base_vertices = r.bounded(max, "base vertex count")? as usize;
    let base_triangles = r.bounded(max, "base triangle count")? as usize;
    let split_count = r.bounded(max, "split count")? as usize;
    let at = r.offset();
    let total_vertices = r.bounded(max, "total vertex count")? as usize;
    if total_vertices != base_vertices + split_count {
        return Err(invalid(
            at,
            format!(
                "total vertices {total_vertices} ≠ base {base_vertices} + splits {split_count}"
            ),
        )
        .into());
    }
    let at = r.offset();
    let total_triangles = r.bounded(max, "total triangle count")? as usize;
    if total_triangles < base_triangles {
        return Err(invalid(at, "total triangles below the base count").into());
    }
    let level_count = r.bounded(max, "level count")? as usize;
    let mut levels = Vec::with_capacity(level_count.min(64));
    for _ in 0..level_count {
        levels.push(r.bounded(split_count as u64, "level record count")? as usize);
    }
    let wedges = if flags & FLAG_WEDGES != 0 {
        let total = r.bounded(max, "wedge count")? as usize;
        let at = r.offset();
        let groups = r.bounded(max, "group count")? as u32;
        if groups == 0 {
            return Err(invalid(at, "zero wedge groups").into());
        }
        let n = r.bounded(MAX_CHANNELS as u64, "channel count")? as usize;
        let mut channels = Vec::with_capacity(n);
        for _ in 0..n {
            let at = r.offset();
            let len = r.bounded(MAX_CHANNEL_NAME as u64, "channel name length")? as usize;
            let mut name = Vec::with_capacity(len);
            for _ in 0..len {
                name.push(r.byte()?);
            }
            let name = String::from_utf8(name)
                .ok()
                .filter(|n| !n.is_empty())
                .ok_or_else(|| invalid(at, "channel name empty or not UTF-8"))?;
            let at = r.offset();
            let components = r.byte()?;
            if !(1..=MAX_COMPONENTS).contains(&components) {
                return Err(invalid(
                    at,
                    format!("{components} components (1..={MAX_COMPONENTS})"),
                )
                .into());
            }
            channels.push(Channel { name, components });
        }
        Some(WedgeLayout {
            total,
            groups,
            channels,
        })
    } else {
        None
    };
    Ok(StreamHeader {
        flags,
        bits,
        origin,
        step,
        base_vertices,
        base_triangles,
        split_count,
        total_vertices,
        total_triangles,
        levels,
        wedges,
    })
}

/// The decoder's state of the mesh, in quantized and dequantized form.
#[derive(Clone, Debug, Default)]
struct State {
    q: Vec<[u32; 3]>,
    mesh: Mesh,
    wedges: Option<WedgeState>,
}

/// The decoder's wedges: every current corner's, and every wedge's values.
#[derive(Clone, Debug, Default)]
struct WedgeState {
    corners: Vec<[u32; 3]>,
    attributes: WedgeAttributes,
}

/// Wedges met while parsing one piece (base or record), committed with it.
#[derive(Clone, Debug, Default)]
struct NewWedges {
    /// Wedges defined before this piece.
    start: usize,
    values: Vec<f32>,
    groups: Vec<u32>,
}

impl NewWedges {
    /// Wedges defined so far, this piece's included (each new wedge
    /// pushes one group).
    fn count(&self) -> usize {
        self.start + self.groups.len()
    }

    /// One wedge reference: `0` = a new wedge (its group when there are
    /// several, then its values), `k ≥ 1` = wedge `count − k`.
    fn read(&mut self, r: &mut Reader, layout: &WedgeLayout) -> Result<u32, ReadError> {
        let at = r.offset();
        let count = self.count();
        let code = r.bounded(count as u64, "wedge reference")?;
        if code > 0 {
            return Ok((count as u64 - code) as u32);
        }
        if count >= layout.total {
            return Err(invalid(
                at,
                format!("more wedges than the {} announced", layout.total),
            )
            .into());
        }
        let group = if layout.groups > 1 {
            r.bounded(u64::from(layout.groups) - 1, "wedge group")? as u32
        } else {
            0
        };
        self.groups.push(group);
        for c in &layout.channels {
            for _ in 0..c.components {
                self.values.push(r.f32()?);
            }
        }
        Ok(count as u32)
    }

    fn commit(self, a: &mut WedgeAttributes) {
        a.values.extend_from_slice(&self.values);
        a.count += self.groups.len();
        a.groups.extend_from_slice(&self.groups);
    }
}

/// The wedge part of one parsed record.
struct RecordWedges {
    faces: SmallVec<[[u32; 3]; 2]>,
    /// Parallel to the split's (ascending) corners: the wedge after.
    after: Vec<u32>,
    new: NewWedges,
}

fn grid_coord(h: &StreamHeader, at: usize, v: i64) -> Result<u32, StreamError> {
    if (0..=((1i64 << h.bits) - 1)).contains(&v) {
        Ok(v as u32)
    } else {
        Err(invalid(
            at,
            format!("coordinate {v} outside the {}-bit grid", h.bits),
        ))
    }
}

fn parse_base(r: &mut Reader, h: &StreamHeader) -> Result<State, ReadError> {
    let mut q = Vec::with_capacity(h.total_vertices.min(MAX_PREALLOC));
    let mut prev = [0i64; 3];
    for _ in 0..h.base_vertices {
        let at = r.offset();
        let mut p = [0u32; 3];
        for a in 0..3 {
            let v = prev[a].saturating_add(r.zz()?);
            p[a] = grid_coord(h, at, v)?;
            prev[a] = v;
        }
        q.push(p);
    }
    let mut triangles = Vec::with_capacity(h.total_triangles.min(MAX_PREALLOC));
    let mut prev = 0i64;
    for _ in 0..h.base_triangles {
        let mut t = [0u32; 3];
        for c in &mut t {
            let at = r.offset();
            let v = prev.saturating_add(r.zz()?);
            if !(0..h.base_vertices as i64).contains(&v) {
                return Err(invalid(at, format!("base corner {v} out of range")).into());
            }
            *c = v as u32;
            prev = v;
        }
        triangles.push(t);
    }
    let wedges = match &h.wedges {
        Some(layout) => {
            let mut new = NewWedges::default();
            let mut corners = Vec::with_capacity(h.total_triangles.min(MAX_PREALLOC));
            for _ in 0..h.base_triangles {
                corners.push([
                    new.read(r, layout)?,
                    new.read(r, layout)?,
                    new.read(r, layout)?,
                ]);
            }
            let mut attributes = WedgeAttributes {
                channels: layout.channels.clone(),
                ..WedgeAttributes::default()
            };
            new.commit(&mut attributes);
            Some(WedgeState {
                corners,
                attributes,
            })
        }
        None => None,
    };
    let mut positions = Vec::with_capacity(h.total_vertices.min(MAX_PREALLOC));
    positions.extend(q.iter().map(|&p| h.dequantize(p)));
    Ok(State {
        q,
        mesh: Mesh {
            positions,
            triangles,
        },
        wedges,
    })
}

/// One parsed record: the split, its new quantized positions, its wedges.
struct Record {
    split: VertexSplit,
    q1: [u32; 3],
    q0: [u32; 3],
    wedges: Option<RecordWedges>,
}

/// Parse one record against `state` without changing it.
fn parse_record(r: &mut Reader, h: &StreamHeader, state: &State) -> Result<Record, ReadError> {
    let v0 = state.mesh.positions.len() as u32;
    let at = r.offset();
    let head = r.varint()?;
    let mut nf = (head & 3) as usize;
    if nf == 3 {
        nf += r.bounded(1 << 16, "face count")? as usize;
    }
    let nc = head >> 2;
    if nc > 3 * (state.mesh.triangles.len() + nf) as u64 {
        return Err(invalid(
            at,
            format!("{nc} corner edits, more than the mesh has corners"),
        )
        .into());
    }
    let nc = nc as usize;
    if state.mesh.triangles.len() + nf > h.total_triangles {
        return Err(invalid(at, "more triangles than the header announced").into());
    }
    if v0 == 0 {
        return Err(invalid(at, "a split needs at least one vertex to split").into());
    }
    let d = r.bounded(u64::from(v0 - 1), "v1 distance")?;
    let v1 = v0 - 1 - d as u32;
    let at = r.offset();
    let cur = state.q[v1 as usize];
    let mut q1 = [0u32; 3];
    for a in 0..3 {
        q1[a] = grid_coord(h, at, i64::from(cur[a]).saturating_add(r.zz()?))?;
    }
    let mut q0 = [0u32; 3];
    for a in 0..3 {
        q0[a] = grid_coord(h, at, i64::from(q1[a]).saturating_add(r.zz()?))?;
    }
    let mut faces: SmallVec<[[u32; 3]; 2]> = SmallVec::with_capacity(nf);
    for _ in 0..nf {
        let mut f = [0u32; 3];
        for c in &mut f {
            let code = r.bounded(u64::from(v0) + 1, "face corner code")?;
            *c = match code {
                0 => v0,
                1 => v1,
                k => v0 - (k - 1) as u32,
            };
        }
        faces.push(f);
    }
    let count = (state.mesh.triangles.len() + nf) as u64;
    let mut corners = Vec::with_capacity(nc.min(64));
    let mut prev = count;
    for _ in 0..nc {
        let at = r.offset();
        let code = r.varint()?;
        let (gap, slot) = (code >> 2, (code & 3) as u8);
        if slot > 2 || gap >= prev {
            return Err(invalid(
                at,
                format!("corner edit (gap {gap}, slot {slot}) out of range"),
            )
            .into());
        }
        let t = prev - 1 - gap;
        corners.push(Corner {
            triangle: t as u32,
            slot,
        });
        prev = t + 1;
    }
    corners.reverse();
    let wedges = match (&h.wedges, &state.wedges) {
        (Some(layout), Some(ws)) => {
            let mut new = NewWedges {
                start: ws.attributes.count,
                ..NewWedges::default()
            };
            let mut wf = SmallVec::with_capacity(nf);
            for _ in 0..nf {
                wf.push([
                    new.read(r, layout)?,
                    new.read(r, layout)?,
                    new.read(r, layout)?,
                ]);
            }
            let mut after = Vec::with_capacity(nc);
            for _ in 0..nc {
                after.push(new.read(r, layout)?);
            }
            after.reverse();
            Some(RecordWedges {
                faces: wf,
                after,
                new,
            })
        }
        _ => None,
    };
    let error = if h.flags & FLAG_ERRORS != 0 {
        r.f32()?
    } else {
        0.0
    };
    // semantic checks: every edited corner must hold v1 once the faces are
    // appended (so replay never trips over a corner it does not own), and
    // be edited once
    let base = state.mesh.triangles.len();
    for (i, c) in corners.iter().enumerate() {
        let t = c.triangle as usize;
        let value = if t < base {
            state.mesh.triangles[t][c.slot as usize]
        } else {
            faces[t - base][c.slot as usize]
        };
        if value != v1 || (i > 0 && corners[i - 1] == *c) {
            return Err(invalid(
                at,
                format!("corner {}:{} does not hold v1 = {v1}", c.triangle, c.slot),
            )
            .into());
        }
    }
    let split = VertexSplit {
        v1,
        v0,
        p1: h.dequantize(q1),
        p_merged: state.mesh.positions[v1 as usize],
        p0: h.dequantize(q0),
        faces,
        corners: SmallVec::from_vec(corners),
        error,
    };
    Ok(Record {
        split,
        q1,
        q0,
        wedges,
    })
}

/// Apply a parsed record; returns its wedge edits (with the wedges before).
fn apply(state: &mut State, rec: Record) -> (VertexSplit, Option<SplitWedges>) {
    let Record {
        split: s,
        q1,
        q0,
        wedges,
    } = rec;
    let split_wedges = match (wedges, state.wedges.as_mut()) {
        (Some(w), Some(ws)) => {
            ws.corners.extend_from_slice(&w.faces);
            let corners = s
                .corners
                .iter()
                .zip(&w.after)
                .map(|(c, &after)| {
                    let cw = &mut ws.corners[c.triangle as usize][c.slot as usize];
                    let before = std::mem::replace(cw, after);
                    [before, after]
                })
                .collect();
            w.new.commit(&mut ws.attributes);
            Some(SplitWedges {
                faces: w.faces,
                corners,
            })
        }
        _ => None,
    };
    state.q[s.v1 as usize] = q1;
    state.q.push(q0);
    state.mesh.positions[s.v1 as usize] = s.p1;
    state.mesh.positions.push(s.p0);
    state.mesh.triangles.extend_from_slice(&s.faces);
    for c in &s.corners {
        state.mesh.triangles[c.triangle as usize][c.slot as usize] = s.v0;
    }
    (s, split_wedges)
}

/// Decodes a stream fed in pieces of any size: the header and base mesh as
/// soon as their bytes are there, then each record as soon as it is whole.
///
/// ```
/// use lodgen_pm::{shapes, simplify, SimplifyOptions};
/// use lodgen_pm::stream::{encode, EncodeOptions, StreamDecoder};
/// let m = shapes::icosphere(2);
/// let pm = simplify(&m.positions, &m.indices(), &SimplifyOptions::DEFAULT.with_target_triangles(20))
///     .unwrap().pm;
/// let bytes = encode(&pm, &[0, pm.len()], EncodeOptions::DEFAULT);
/// let mut d = StreamDecoder::new();
/// for chunk in bytes.chunks(7) {
///     d.push(chunk).unwrap();
/// }
/// assert!(d.is_complete());
/// assert_eq!(d.mesh().triangles.len(), m.triangles.len());
/// ```
#[derive(Clone, Debug, Default)]
pub struct StreamDecoder {
    pending: Vec<u8>,
    /// Stream offset of `pending[0]`.
    consumed: usize,
    header: Option<StreamHeader>,
    base: Option<Mesh>,
    state: State,
    splits: Vec<VertexSplit>,
    /// The base corners' wedges and each record's wedge edits, when the
    /// stream has wedges.
    base_wedges: Vec<[u32; 3]>,
    split_wedges: Vec<SplitWedges>,
    /// First error: the decoder refuses further input after it.
    failed: Option<StreamError>,
}

impl StreamDecoder {
    pub fn new() -> StreamDecoder {
        StreamDecoder::default()
    }

    /// Append bytes and decode everything now complete. Returns the number
    /// of records decoded by this call. After an error every later call
    /// returns the same error.
    pub fn push(&mut self, bytes: &[u8]) -> Result<usize, StreamError> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        self.pending.extend_from_slice(bytes);
        let before = self.splits.len();
        let result = self.drain();
        // drop consumed bytes
        if let Err(e) = &result {
            self.failed = Some(e.clone());
        }
        result.map(|()| self.splits.len() - before)
    }

    fn drain(&mut self) -> Result<(), StreamError> {
        if self.header.is_none() {
            let mut r = Reader {
                bytes: &self.pending,
                pos: 0,
                base: self.consumed,
            };
            match parse_header(&mut r) {
                Ok(h) => {
                    let used = r.pos;
                    self.splits.reserve(h.split_count.min(MAX_PREALLOC));
                    self.header = Some(h);
                    self.consumed += used;
                    self.pending.drain(..used);
                }
                Err(ReadError::NeedMore) => return Ok(()),
                Err(ReadError::Bad(e)) => return Err(e),
            }
        }
        let Some(h) = self.header.as_ref() else {
            return Ok(());
        };
        let mut r = Reader {
            bytes: &self.pending,
            pos: 0,
            base: self.consumed,
        };
        let mut result = Ok(());
        if self.base.is_none() {
            match parse_base(&mut r, h) {
                Ok(state) => {
                    self.base = Some(state.mesh.clone());
                    if let Some(w) = &state.wedges {
                        self.base_wedges = w.corners.clone();
                    }
                    self.state = state;
                }
                // the base is taken in one piece: wait for all of it
                Err(ReadError::NeedMore) => return Ok(()),
                Err(ReadError::Bad(e)) => return Err(e),
            }
        }
        loop {
            if self.splits.len() == h.split_count {
                if r.pos < r.bytes.len() {
                    result = Err(StreamError::TrailingBytes(r.bytes.len() - r.pos));
                } else if self.state.mesh.triangles.len() != h.total_triangles {
                    result = Err(invalid(
                        r.offset(),
                        format!(
                            "the records restore {} triangles, the header announced {}",
                            self.state.mesh.triangles.len(),
                            h.total_triangles
                        ),
                    ));
                } else if let (Some(layout), Some(ws)) = (&h.wedges, &self.state.wedges) {
                    if ws.attributes.count != layout.total {
                        result = Err(invalid(
                            r.offset(),
                            format!(
                                "the records define {} wedges, the header announced {}",
                                ws.attributes.count, layout.total
                            ),
                        ));
                    }
                }
                break;
            }
            let mark = r.pos;
            match parse_record(&mut r, h, &self.state) {
                Ok(rec) => {
                    let (s, w) = apply(&mut self.state, rec);
                    self.splits.push(s);
                    self.split_wedges.extend(w);
                }
                Err(ReadError::NeedMore) => {
                    r.pos = mark;
                    break;
                }
                Err(ReadError::Bad(e)) => {
                    result = Err(e);
                    break;
                }
            }
        }
        let used = r.pos;
        self.consumed += used;
        self.pending.drain(..used);
        result
    }

    /// The header, once its bytes have arrived.
    pub fn header(&self) -> Option<&StreamHeader> {
        self.header.as_ref()
    }

    /// The base mesh (positions on the grid), once its bytes have arrived.
    pub fn base(&self) -> Option<&Mesh> {
        self.base.as_ref()
    }

    /// Every record decoded so far, coarse → fine.
    pub fn splits(&self) -> &[VertexSplit] {
        &self.splits
    }

    /// The mesh with every decoded record applied (empty before the base).
    pub fn mesh(&self) -> &Mesh {
        &self.state.mesh
    }

    /// The wedge of every corner of [`Self::mesh`], when the stream carries
    /// wedges (stream numbering: order of first appearance).
    pub fn wedges(&self) -> Option<&[[u32; 3]]> {
        self.state.wedges.as_ref().map(|w| w.corners.as_slice())
    }

    /// The values of every wedge decoded so far, when the stream carries
    /// wedges: wedge `w` of [`Self::wedges`] has `attributes().wedge(w)`.
    pub fn attributes(&self) -> Option<&WedgeAttributes> {
        self.state.wedges.as_ref().map(|w| &w.attributes)
    }

    /// Header, base and every announced record decoded, nothing left over.
    pub fn is_complete(&self) -> bool {
        self.failed.is_none()
            && self.pending.is_empty()
            && self
                .header
                .as_ref()
                .is_some_and(|h| self.base.is_some() && self.splits.len() == h.split_count)
    }

    /// The progressive mesh and level table, once the stream is complete.
    /// `vertex_origin` and `triangle_origin` are the identity (the stream
    /// does not carry the input's numbering).
    pub fn finish(self) -> Result<(ProgressiveMesh, Vec<usize>), StreamError> {
        self.finish_with_attributes().map(|d| (d.pm, d.levels))
    }

    /// [`Self::finish`], with the wedge values when the stream has them
    /// (`pm.wedges` then holds every corner's wedge at every step, in the
    /// stream's numbering).
    pub fn finish_with_attributes(self) -> Result<Decoded, StreamError> {
        if let Some(e) = self.failed {
            return Err(e);
        }
        if !self.is_complete() {
            return Err(StreamError::Truncated(self.consumed + self.pending.len()));
        }
        let (Some(h), Some(base)) = (self.header, self.base) else {
            return Err(StreamError::Truncated(self.consumed));
        };
        let pm = ProgressiveMesh {
            base,
            splits: self.splits,
            vertex_origin: (0..h.total_vertices as u32).collect(),
            triangle_origin: (0..h.total_triangles as u32).collect(),
            wedges: h.wedges.as_ref().map(|_| WedgeLog {
                base: self.base_wedges,
                splits: self.split_wedges,
            }),
        };
        Ok(Decoded {
            pm,
            levels: h.levels,
            attributes: self.state.wedges.map(|w| w.attributes),
        })
    }
}

/// A whole decoded stream.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// Positions on the grid, exact topology, and the wedge log when the
    /// stream carries wedges.
    pub pm: ProgressiveMesh,
    /// Record count of each level, as encoded.
    pub levels: Vec<usize>,
    /// Every wedge's values (indexed like `pm.wedges`), when carried.
    pub attributes: Option<WedgeAttributes>,
}

/// Decode a whole stream: the progressive mesh (positions on the grid) and
/// the level table.
pub fn decode(bytes: &[u8]) -> Result<(ProgressiveMesh, Vec<usize>), StreamError> {
    let mut d = StreamDecoder::new();
    d.push(bytes)?;
    d.finish()
}

/// Decode a whole stream with its attributes (see
/// [`StreamDecoder::finish_with_attributes`]).
pub fn decode_with_attributes(bytes: &[u8]) -> Result<Decoded, StreamError> {
    let mut d = StreamDecoder::new();
    d.push(bytes)?;
    d.finish_with_attributes()
}

/// Decode only the header (for sizing before the rest arrives).
pub fn decode_header(bytes: &[u8]) -> Result<StreamHeader, StreamError> {
    let mut r = Reader {
        bytes,
        pos: 0,
        base: 0,
    };
    parse_header(&mut r).map_err(|e| match e {
        ReadError::NeedMore => StreamError::Truncated(bytes.len()),
        ReadError::Bad(e) => e,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varints_round_trip_at_the_edges() {
        for v in [
            0u64,
            1,
            127,
            128,
            16383,
            16384,
            u64::from(u32::MAX),
            u64::MAX,
        ] {
            let mut out = Vec::new();
            put_varint(&mut out, v);
            let mut r = Reader {
                bytes: &out,
                pos: 0,
                base: 0,
            };
            assert!(matches!(r.varint(), Ok(x) if x == v));
            assert_eq!(r.pos, out.len());
        }
        for v in [
            0i64,
            1,
            -1,
            63,
            -64,
            64,
            i64::from(i32::MIN),
            i64::MAX,
            i64::MIN,
        ] {
            let mut out = Vec::new();
            put_zz(&mut out, v);
            let mut r = Reader {
                bytes: &out,
                pos: 0,
                base: 0,
            };
            assert!(matches!(r.zz(), Ok(x) if x == v));
        }
    }

    #[test]
    fn overlong_varint_is_an_error() {
        let bytes = [0xffu8; 11];
        let mut r = Reader {
            bytes: &bytes,
            pos: 0,
            base: 0,
        };
        assert!(matches!(
            r.varint(),
            Err(ReadError::Bad(StreamError::Invalid { .. }))
        ));
    }
}
