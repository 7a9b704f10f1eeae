//! The decoder: chunk by chunk, each as soon as all its bytes are there.

use super::columns::{differences, BitReader, ColumnReader, Words};
use super::header::{self, ReadError, Reader};
use super::topo::{self, Topo, FACE_ESCAPE};
use super::types::{
    invalid, StreamError, StreamHeader, WedgeAttributes, WedgeLayout, BLOCK_RECORDS, FLAG_ERRORS,
};
use super::wedges::{face_corner_order, Rec, Shared, WedgeColumns, WedgeState, NONE};
use crate::mesh::Mesh;
use crate::progressive::{Corners, ProgressiveMesh, SplitWedges, VertexSplit, WedgeLog};
use smallvec::SmallVec;

/// Bound on preallocation from header counts, so a hostile header cannot
/// make the decoder reserve gigabytes before any data arrives.
const MAX_PREALLOC: usize = 1 << 20;

/// The decoder's mesh: topology, grid points, positions, wedges.
#[derive(Clone, Debug, Default)]
struct State {
    mesh: Mesh,
    topo: Topo,
    q: Vec<[u16; 3]>,
    wedges: Option<WedgeState>,
    /// Per vertex: index in the current chunk's moved list + 1 (0 = none).
    moved_slot: Vec<u32>,
}

fn decode_base(h: &StreamHeader, bytes: &[u8], base: usize) -> Result<State, StreamError> {
    let mut r = ColumnReader {
        bytes,
        pos: 0,
        base,
    };
    let nv = h.base_vertices;
    let at = r.offset();
    let q: Vec<[u16; 4]> = r.vertices("base position", Some(nv), 0)?;
    let limit = 2 * h.grid.scale() as u16;
    if q.iter().any(|p| p[..3].iter().any(|&c| c > limit)) {
        return Err(invalid(at, "base position outside the grid"));
    }
    let at = r.offset();
    let flat = r.sequence("base triangle", 3 * h.base_triangles)?;
    if flat.iter().any(|&v| v as usize >= nv) {
        return Err(invalid(at, "base corner out of range"));
    }
    let triangles: Vec<[u32; 3]> = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let wedges = match &h.wedges {
        Some(layout) => {
            let components: Vec<u8> = layout.channels.iter().map(|c| c.components).collect();
            let mut ws = WedgeState {
                sh: Shared::new(&layout.encodings, &components),
                attributes: WedgeAttributes {
                    channels: layout.channels.clone(),
                    ..WedgeAttributes::default()
                },
            };
            ws.sh.cw = Vec::with_capacity(h.total_triangles.min(MAX_PREALLOC));
            ws.sh.cw.resize(h.base_triangles, [NONE; 3]);
            let mut wc = WedgeColumns::read(&mut r, layout, 3 * h.base_triangles)?;
            let fans = Topo::new(nv, &triangles).fans;
            for t in 0..h.base_triangles as u32 {
                for s in 0..3 {
                    wc.next(&mut ws, layout, &triangles, &fans, (t, s), None, None)?;
                }
            }
            wc.finish()?;
            Some(ws)
        }
        None => None,
    };
    r.finish("the base chunk")?;
    let q: Vec<[u16; 3]> = q.iter().map(|p| [p[0], p[1], p[2]]).collect();
    let mut positions = Vec::with_capacity(h.total_vertices.min(MAX_PREALLOC));
    positions.extend(q.iter().map(|&p| h.grid.dequantize(p)));
    let mut mesh_triangles = Vec::with_capacity(h.total_triangles.min(MAX_PREALLOC));
    mesh_triangles.extend_from_slice(&triangles);
    Ok(State {
        topo: Topo::new(nv, &triangles),
        mesh: Mesh {
            positions,
            triangles: mesh_triangles,
        },
        q,
        wedges,
        moved_slot: vec![0; nv],
    })
}

/// The columns of one block of a record chunk (version 7: the topology and
/// wedge columns of up to [`BLOCK_RECORDS`] records), read before its replay.
struct ChunkColumns<'a> {
    v1: Vec<u32>,
    codes: Vec<[u8; 4]>,
    extra: Words,
    mask: BitReader<'a>,
    wedges: Option<WedgeColumns>,
}

/// What the replay of a chunk keeps across its blocks.
#[derive(Default)]
struct ChunkRings {
    /// Each record's `v0` ring once applied (flat, `ring_ends` per record).
    rings: Vec<u32>,
    ring_ends: Vec<usize>,
    predicted: Vec<bool>,
}

fn read_block<'a>(
    h: &StreamHeader,
    r: &mut ColumnReader<'a>,
    n: usize,
) -> Result<ChunkColumns<'a>, StreamError> {
    let v1 = r.vertices("split vertex", Some(n), 0)?;
    let codes = r.vertices("face code", Some(n), 0)?;
    let at = r.offset();
    let words = r.vertices("escape", None, 8 * h.total_triangles + n)?;
    let mask = r.bits("corner mask", 8 * r.bytes.len())?;
    let wedges = match &h.wedges {
        Some(layout) => Some(WedgeColumns::read(
            r,
            layout,
            3 * h.total_triangles + 8 * r.bytes.len(),
        )?),
        None => None,
    };
    Ok(ChunkColumns {
        v1,
        codes,
        extra: Words { words, pos: 0, at },
        mask,
        wedges,
    })
}

/// The faces of one record (the ring is `v1`'s before the split).
fn faces(
    c: &mut ChunkColumns<'_>,
    i: usize,
    v0: u32,
    v1: u32,
    ring: &[u32],
    at: usize,
) -> Result<SmallVec<[[u32; 3]; 2]>, StreamError> {
    let head = c.codes[i];
    let nf = if head[0] == 255 {
        c.extra.next()? as usize
    } else {
        usize::from(head[0])
    };
    if nf > 1 << 16 {
        return Err(invalid(at, format!("{nf} faces in one split")));
    }
    let mut codes: SmallVec<[u8; 4]> = SmallVec::new();
    for k in 0..nf {
        let code = match k {
            0 | 1 => head[1 + k],
            _ => u8::try_from(c.extra.next()?)
                .map_err(|_| invalid(at, "face code over 255 in the escape column"))?,
        };
        codes.push(code);
    }
    let mut out = SmallVec::with_capacity(nf);
    for code in codes {
        let f = if code == FACE_ESCAPE {
            let mut f = [0; 3];
            for x in &mut f {
                *x = topo::corner_of(c.extra.next()?, v0, v1)
                    .ok_or_else(|| invalid(at, "escaped face corner out of range"))?;
            }
            f
        } else {
            topo::face_of(code, v0, v1, ring)
                .ok_or_else(|| invalid(at, format!("face code {code} beyond the ring of {v1}")))?
        };
        out.push(f);
    }
    Ok(out)
}

/// Replay record `i` of the chunk on the topology (and wedges); the
/// positions are filled in later.
fn replay(
    h: &StreamHeader,
    st: &mut State,
    (c, k): (&mut ChunkColumns<'_>, &mut ChunkRings),
    i: usize,
    at: usize,
) -> Result<(VertexSplit, Option<SplitWedges>), StreamError> {
    let v0 = st.topo.fans.len() as u32;
    let v1 = c.v1[i];
    if v1 >= v0 {
        return Err(invalid(at, format!("split vertex {v1} does not exist yet")));
    }
    let ring = st.topo.ring(&st.mesh.triangles, v1);
    let faces = faces(c, i, v0, v1, &ring, at)?;
    if st.mesh.triangles.len() + faces.len() > h.total_triangles {
        return Err(invalid(at, "more triangles than the header announced"));
    }
    st.topo.add_vertex();
    st.moved_slot.push(0);
    for &f in &faces {
        st.topo.add_face(&mut st.mesh.triangles, f);
    }
    let held = st.topo.corners(&st.mesh.triangles, v1);
    let explicit = match c.codes[i][3] {
        0 => false,
        1 => true,
        x => return Err(invalid(at, format!("corner-edit flag {x}"))),
    };
    if !explicit {
        let first = (st.mesh.triangles.len() - faces.len()) as u32;
        let fan = &st.topo.fans[v1 as usize];
        let ends = (v0, v1);
        topo::predict_mask(
            &st.mesh.triangles,
            fan,
            first,
            &faces,
            ends,
            &held,
            &mut k.predicted,
        );
    }
    let mut corners = Corners::new();
    for (j, &corner) in held.iter().enumerate() {
        if if explicit {
            c.mask.next()?
        } else {
            k.predicted[j]
        } {
            st.topo.move_corner(&mut st.mesh.triangles, corner, v1, v0);
            corners.push(corner);
        }
    }
    k.rings.extend(st.topo.ring(&st.mesh.triangles, v0));
    k.ring_ends.push(k.rings.len());
    let wedges = match (&h.wedges, &mut st.wedges, &mut c.wedges) {
        (Some(layout), Some(ws), Some(wc)) => {
            let first = st.mesh.triangles.len() - faces.len();
            let rec = Rec {
                v0,
                v1,
                wings: topo::wing_faces(&faces, v0, v1)
                    .map(|(a, b)| ((first + a) as u32, (first + b) as u32)),
            };
            let ctx = (&st.mesh.triangles[..], &st.topo.fans[..], rec);
            Some(replay_wedges(ws, wc, layout, ctx, first, &corners)?)
        }
        _ => None,
    };
    let split = VertexSplit {
        v1,
        v0,
        p1: [0.0; 3],
        p_merged: [0.0; 3],
        p0: [0.0; 3],
        faces,
        corners,
        error: 0.0,
    };
    Ok((split, wedges))
}

fn replay_wedges(
    ws: &mut WedgeState,
    wc: &mut WedgeColumns,
    layout: &WedgeLayout,
    (tri, fans, rec): (&[[u32; 3]], &[topo::Fan], Rec),
    first: usize,
    corners: &Corners,
) -> Result<SplitWedges, StreamError> {
    ws.sh.cw.resize(tri.len(), [NONE; 3]);
    for (t, s) in face_corner_order(tri, first, tri.len() - first, rec.v0) {
        wc.next(ws, layout, tri, fans, (t, s), None, Some(rec))?;
    }
    let wf = ws.sh.cw[first..].iter().copied().collect();
    let before: SmallVec<[u32; 8]> = corners
        .iter()
        .map(|k| std::mem::replace(&mut ws.sh.cw[k.triangle as usize][k.slot as usize], NONE))
        .collect();
    let mut edits = Vec::with_capacity(corners.len());
    for (k, b) in corners.iter().zip(before) {
        let after = wc.next(
            ws,
            layout,
            tri,
            fans,
            (k.triangle, usize::from(k.slot)),
            Some(b),
            Some(rec),
        )?;
        edits.push([b, after]);
    }
    Ok(SplitWedges {
        faces: wf,
        corners: edits,
    })
}

/// Decode the grid points at the chunk's end and fill in the splits'
/// positions, applying them.
fn positions(
    h: &StreamHeader,
    st: &mut State,
    c: &PositionColumns,
    splits: &mut [VertexSplit],
    va: usize,
    at: usize,
) -> Result<(), StreamError> {
    let limit = 2 * h.grid.scale() as u16;
    let check = |q: [u16; 3]| {
        if q.iter().all(|&x| x <= limit) {
            Ok(q)
        } else {
            Err(invalid(at, "position outside the grid"))
        }
    };
    let mut moved = Vec::new();
    for s in splits.iter() {
        if (s.v1 as usize) < va && st.moved_slot[s.v1 as usize] == 0 {
            moved.push(s.v1);
            st.moved_slot[s.v1 as usize] = moved.len() as u32;
        }
    }
    if moved.len() != c.moved.len() {
        return Err(invalid(
            at,
            format!(
                "{} moved positions for {} moved vertices",
                c.moved.len(),
                moved.len()
            ),
        ));
    }
    let start: Vec<[u16; 3]> = moved.iter().map(|&v| st.q[v as usize]).collect();
    for ((&v, s), r) in moved.iter().zip(&start).zip(&c.moved) {
        st.q[v as usize] = check([0, 1, 2].map(|k| s[k].wrapping_add(r[k])))?;
    }
    let mut from = 0;
    for ((s, r), &to) in splits.iter().zip(&c.new).zip(&c.rings.ring_ends) {
        let pred = topo::predict_new(&st.q, &c.rings.rings[from..to], s.v1);
        from = to;
        st.q.push(check([0, 1, 2].map(|k| pred[k].wrapping_add(r[k])))?);
    }
    for &v in &moved {
        st.moved_slot[v as usize] = 0;
    }
    for s in splits.iter_mut() {
        s.p1 = h.grid.dequantize(st.q[s.v1 as usize]);
        s.p0 = h.grid.dequantize(st.q[s.v0 as usize]);
        s.p_merged = st.mesh.positions[s.v1 as usize];
        st.mesh.positions[s.v1 as usize] = s.p1;
        st.mesh.positions.push(s.p0);
    }
    Ok(())
}

type ChunkOut = (Vec<VertexSplit>, Vec<SplitWedges>);

/// Decode the chunk of `n` records in `bytes` (starting at stream offset
/// `base`) and apply it.
fn decode_chunk(
    h: &StreamHeader,
    st: &mut State,
    bytes: &[u8],
    base: usize,
    n: usize,
) -> Result<ChunkOut, StreamError> {
    let mut r = ColumnReader {
        bytes,
        pos: 0,
        base,
    };
    let va = st.q.len();
    let mut splits = Vec::with_capacity(n);
    let mut wedges = Vec::new();
    let mut rings = ChunkRings {
        ring_ends: Vec::with_capacity(n),
        ..ChunkRings::default()
    };
    // the blocks of topology and wedge columns, each replayed in turn
    for from in (0..n).step_by(BLOCK_RECORDS) {
        let m = BLOCK_RECORDS.min(n - from);
        let mut c = read_block(h, &mut r, m)?;
        for i in 0..m {
            let (s, w) = replay(h, st, (&mut c, &mut rings), i, base)?;
            splits.push(s);
            wedges.extend(w);
        }
        c.extra.finish()?;
        c.mask.finish()?;
        if let Some(wc) = &c.wedges {
            wc.finish()?;
        }
    }
    let moved: Vec<[u16; 4]> = r.vertices("moved position", None, n)?;
    let new: Vec<[u16; 4]> = r.vertices("new position", Some(n), 0)?;
    if h.flags & FLAG_ERRORS != 0 {
        let errors: Vec<u32> = r.vertices("error", Some(n), 0)?;
        for (s, e) in splits.iter_mut().zip(errors) {
            s.error = f32::from_bits(e);
        }
    }
    r.finish("the chunk")?;
    let c = PositionColumns {
        moved: differences(&moved),
        new: differences(&new),
        rings,
    };
    positions(h, st, &c, &mut splits, va, base)?;
    Ok((splits, wedges))
}

/// A chunk's position columns, and its records' `v0` rings.
struct PositionColumns {
    moved: Vec<[u16; 3]>,
    new: Vec<[u16; 3]>,
    rings: ChunkRings,
}

/// Decodes a stream fed in pieces of any size: the header as soon as its
/// bytes are there, then each chunk (the base mesh, then the records up to
/// each level) as soon as it is whole.
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
    /// Chunks decoded so far.
    chunks: usize,
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

    /// Append bytes and decode every chunk now complete. Returns the number
    /// of records decoded by this call. After an error every later call
    /// returns the same error.
    pub fn push(&mut self, bytes: &[u8]) -> Result<usize, StreamError> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        self.pending.extend_from_slice(bytes);
        let before = self.splits.len();
        let result = self.drain();
        if let Err(e) = &result {
            self.failed = Some(e.clone());
        }
        result.map(|()| self.splits.len() - before)
    }

    fn take(&mut self, n: usize) {
        self.consumed += n;
        self.pending.drain(..n);
    }

    fn drain(&mut self) -> Result<(), StreamError> {
        if self.header.is_none() {
            let mut r = Reader {
                bytes: &self.pending,
                pos: 0,
            };
            match header::parse(&mut r) {
                Ok(h) => {
                    let used = r.pos;
                    self.splits.reserve(h.split_count.min(MAX_PREALLOC));
                    self.header = Some(h);
                    self.take(used);
                }
                Err(ReadError::NeedMore) => return Ok(()),
                Err(ReadError::Bad(e)) => return Err(e),
            }
        }
        let Some(h) = self.header.take() else {
            return Ok(());
        };
        let result = self.drain_chunks(&h);
        self.header = Some(h);
        result
    }

    fn drain_chunks(&mut self, h: &StreamHeader) -> Result<(), StreamError> {
        while let Some(chunk) = h.chunks.get(self.chunks) {
            if self.pending.len() < chunk.bytes {
                return Ok(());
            }
            let bytes = &self.pending[..chunk.bytes];
            if self.chunks == 0 {
                self.state = decode_base(h, bytes, self.consumed)?;
                self.base = Some(self.state.mesh.clone());
                if let Some(w) = &self.state.wedges {
                    self.base_wedges = w.sh.cw.clone();
                }
            } else {
                let n = chunk.records - h.chunks[self.chunks - 1].records;
                let (s, w) = decode_chunk(h, &mut self.state, bytes, self.consumed, n)?;
                self.splits.extend(s);
                self.split_wedges.extend(w);
            }
            self.chunks += 1;
            self.take(chunk.bytes);
        }
        if !self.pending.is_empty() {
            return Err(StreamError::TrailingBytes(self.pending.len()));
        }
        if self.state.mesh.triangles.len() != h.total_triangles {
            return Err(invalid(
                self.consumed,
                format!(
                    "the records restore {} triangles, the header announced {}",
                    self.state.mesh.triangles.len(),
                    h.total_triangles
                ),
            ));
        }
        if let (Some(layout), Some(ws)) = (&h.wedges, &self.state.wedges) {
            if ws.attributes.count != layout.total {
                return Err(invalid(
                    self.consumed,
                    format!(
                        "the records define {} wedges, the header announced {}",
                        ws.attributes.count, layout.total
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The header, once its bytes have arrived.
    pub fn header(&self) -> Option<&StreamHeader> {
        self.header.as_ref()
    }

    /// The base mesh (positions on the grid), once its chunk has arrived.
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
        self.state.wedges.as_ref().map(|w| w.sh.cw.as_slice())
    }

    /// The values of every wedge decoded so far, when the stream carries
    /// wedges: wedge `w` of [`Self::wedges`] has `attributes().wedge(w)`.
    pub fn attributes(&self) -> Option<&WedgeAttributes> {
        self.state.wedges.as_ref().map(|w| &w.attributes)
    }

    /// Header and every chunk decoded, nothing left over.
    pub fn is_complete(&self) -> bool {
        self.failed.is_none()
            && self.pending.is_empty()
            && self
                .header
                .as_ref()
                .is_some_and(|h| self.chunks == h.chunks.len())
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
                per_vertex: None,
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
    /// Positions on the grid (exact at every chunk end), exact topology,
    /// and the wedge log when the stream carries wedges.
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

/// Decode only the header (for sizing and the chunk table before the rest
/// arrives).
pub fn decode_header(bytes: &[u8]) -> Result<StreamHeader, StreamError> {
    let mut r = Reader { bytes, pos: 0 };
    header::parse(&mut r).map_err(|e| match e {
        ReadError::NeedMore => StreamError::Truncated(bytes.len()),
        ReadError::Bad(e) => e,
    })
}
