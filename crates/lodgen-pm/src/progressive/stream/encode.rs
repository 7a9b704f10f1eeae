//! The encoder: header, base chunk, one chunk per level step.

use super::columns::{prefix_sums, BitWriter, ColumnWriter};
use super::header;
use super::topo::{self, Topo, FACE_ESCAPE};
use super::types::{
    chunk_ends, AttrEncoding, ChunkInfo, EncodeError, EncodeOptions, Grid, StreamHeader,
    WedgeAttributes, WedgeLayout, BLOCK_RECORDS, FLAG_ERRORS, FLAG_WEDGES,
};
use super::wedges::{face_corner_order, padded, zigzag, Rec, Shared, NONE};
use crate::progressive::{ProgressiveMesh, WedgeLog};

/// Encode `pm` with `levels` (record counts, each clamped to `pm.len()`):
/// positions and topology only, whether or not `pm` has a wedge log (see
/// [`encode_with_attributes`]).
///
/// Non-finite coordinates cannot be represented: they are snapped onto the
/// grid (NaN to its center). Meshes from [`crate::simplify()`] never have
/// them.
pub fn encode(pm: &ProgressiveMesh, levels: &[usize], opts: EncodeOptions) -> Vec<u8> {
    encode_inner(pm, levels, opts, None)
}

/// [`encode`], plus every corner's wedge and every wedge's attribute values,
/// so a client refining the stream draws each level with the input's own
/// attributes. `attributes` is indexed by the log's wedge ids (`pm.wedges`;
/// for [`crate::simplify_with_wedges`], the input vertex indices). Values
/// are stored as `f32`, exactly; each wedge once, where it is first used.
pub fn encode_with_attributes(
    pm: &ProgressiveMesh,
    levels: &[usize],
    opts: EncodeOptions,
    attributes: &WedgeAttributes,
) -> Result<Vec<u8>, EncodeError> {
    let log = pm.wedges.as_ref().ok_or(EncodeError::NoWedges)?;
    attributes.check()?;
    let mut seen = vec![false; attributes.count];
    let mut total = 0usize;
    let mut mark = |w: u32| {
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
        Ok::<(), EncodeError>(())
    };
    log.base.iter().flatten().try_for_each(|&w| mark(w))?;
    for (i, s) in pm.splits.iter().enumerate() {
        let e = log.split(i, s);
        e.faces.iter().flatten().try_for_each(|&w| mark(w))?;
        e.corners.iter().try_for_each(|c| mark(c[1]))?;
    }
    Ok(encode_inner(
        pm,
        levels,
        opts,
        Some((log, attributes, total)),
    ))
}

/// Collects one chunk's wedge references (codes of [`Shared`]), the new
/// wedges' groups and values.
struct WedgeWriter<'a> {
    attributes: &'a WedgeAttributes,
    groups: u32,
    sh: Shared,
    /// Log wedge id → stream id + 1 (0 = not yet written).
    ids: Vec<u32>,
    refs: Vec<u32>,
    new_groups: Vec<u32>,
    /// Per channel, the new wedges' values as little-endian bytes: `f32`,
    /// or the running sums of the quantized residuals (`u16` lanes).
    values: Vec<Vec<u8>>,
    /// Per quantized channel, the running sums.
    sums: Vec<u16>,
    scratch: Vec<u16>,
}

impl WedgeWriter<'_> {
    /// Code log wedge `w` at corner `(t, s)` (whose wedge was `before` when
    /// it is a corner edit) and record it there.
    #[allow(clippy::too_many_arguments)]
    fn put(
        &mut self,
        tri: &[[u32; 3]],
        fans: &[topo::Fan],
        t: u32,
        s: usize,
        w: u32,
        before: Option<u32>,
        rec: Option<Rec>,
    ) {
        self.sh.candidates(tri, fans, t, s, before);
        let id = match self.ids[w as usize] {
            0 => {
                self.refs.push(0);
                self.define(tri, t, s, w, rec)
            }
            k => {
                self.refs.push(self.sh.code_of(k - 1));
                k - 1
            }
        };
        self.sh.cw[t as usize][s] = id;
    }

    /// Define log wedge `w` as the next stream wedge, first used at corner
    /// `(t, s)`.
    fn define(&mut self, tri: &[[u32; 3]], t: u32, s: usize, w: u32, rec: Option<Rec>) -> u32 {
        let a = self.attributes;
        self.new_groups.push(a.group(w));
        let mut pred = std::mem::take(&mut self.scratch);
        let mut fpred = vec![0; self.sh.fstride];
        pred.resize(self.sh.stride, 0);
        let p = self.sh.predictor(tri, t, s, rec);
        self.sh.predict_q(p, &mut pred);
        self.sh.predict_f(p, &mut fpred);
        let values = a.wedge(w);
        let mut at = 0;
        for (ci, (c, out)) in a.channels.iter().zip(&mut self.values).enumerate() {
            let n = usize::from(c.components);
            let e = self.sh.encodings[ci];
            match self.sh.lane[ci] {
                None => {
                    let lane = self.sh.flane[ci].unwrap_or(0);
                    for (k, v) in values[at..at + n].iter().enumerate() {
                        self.sh.fv.push(*v);
                        let r = zigzag(v.to_bits().wrapping_sub(fpred[lane + k]));
                        out.extend_from_slice(&r.to_le_bytes());
                    }
                }
                Some(lane) => {
                    for k in 0..padded(c.components) {
                        let q = if k < n { e.quantize(values[at + k]) } else { 0 };
                        let r = if k < n {
                            q.wrapping_sub(pred[lane + k])
                        } else {
                            0
                        };
                        if k < n {
                            self.sh.qv.push(q);
                            let sum = &mut self.sums[lane + k];
                            *sum = sum.wrapping_add(r);
                            out.extend_from_slice(&sum.to_le_bytes());
                        } else {
                            out.extend_from_slice(&[0, 0]);
                        }
                    }
                }
            }
            at += n;
        }
        self.scratch = pred;
        let id = self.sh.count;
        self.sh.count += 1;
        self.ids[w as usize] = id + 1;
        id
    }

    /// The chunk's wedge columns: references, groups (with several), values
    /// per channel.
    fn flush(&mut self, cw: &mut ColumnWriter) {
        cw.vertices(&self.refs);
        if self.groups > 1 {
            cw.vertices(&self.new_groups);
        }
        let n = self.new_groups.len();
        for (ci, (c, v)) in self
            .attributes
            .channels
            .iter()
            .zip(&mut self.values)
            .enumerate()
        {
            let size = match self.sh.lane[ci] {
                None => 4 * usize::from(c.components),
                Some(_) => 2 * padded(c.components),
            };
            cw.strided(v, n, size);
            v.clear();
        }
        self.sums.fill(0);
        self.refs.clear();
        self.new_groups.clear();
    }
}

/// What the encoder replays alongside the log.
struct State<'a> {
    grid: Grid,
    triangles: Vec<[u32; 3]>,
    topo: Topo,
    /// Current positions (exact).
    positions: Vec<[f32; 3]>,
    /// Grid points as of the last chunk end.
    q: Vec<[u16; 3]>,
    /// Per vertex: index in the current chunk's moved list + 1 (0 = none).
    moved_slot: Vec<u32>,
    wedges: Option<(&'a WedgeLog, WedgeWriter<'a>)>,
    errors: bool,
}

fn base_chunk(pm: &ProgressiveMesh, st: &mut State) -> Vec<u8> {
    let mut cw = ColumnWriter::default();
    let q: Vec<[u16; 4]> = st.q.iter().map(|p| [p[0], p[1], p[2], 0]).collect();
    cw.vertices(&q);
    let flat: Vec<u32> = pm.base.triangles.iter().flatten().copied().collect();
    cw.sequence(&flat, pm.base.positions.len());
    if let Some((log, w)) = &mut st.wedges {
        for (t, ws) in log.base.iter().enumerate() {
            for (s, &c) in ws.iter().enumerate() {
                w.put(&st.triangles, &st.topo.fans, t as u32, s, c, None, None);
            }
        }
        w.flush(&mut cw);
    }
    cw.out
}

/// One record's topology columns.
#[derive(Default)]
struct TopoColumns {
    v1: Vec<u32>,
    codes: Vec<[u8; 4]>,
    extra: Vec<u32>,
    mask: BitWriter,
    errors: Vec<u32>,
    /// Each record's `v0` ring once applied (flat, `ring_ends` per record).
    rings: Vec<u32>,
    ring_ends: Vec<usize>,
    predicted: Vec<bool>,
}

/// Replay record `i` on the topology and write its columns.
fn record(pm: &ProgressiveMesh, i: usize, st: &mut State, cols: &mut TopoColumns) {
    let s = &pm.splits[i];
    let v0 = (pm.base.positions.len() + i) as u32;
    debug_assert_eq!(s.v0, v0);
    let ring = st.topo.ring(&st.triangles, s.v1);
    let codes: topo::Small<u8> = s
        .faces
        .iter()
        .map(|&f| topo::face_code(f, v0, s.v1, &ring))
        .collect();
    let nf = s.faces.len();
    cols.v1.push(s.v1);
    cols.codes.push([
        nf.min(255) as u8,
        codes.first().copied().unwrap_or(0),
        codes.get(1).copied().unwrap_or(0),
        0,
    ]);
    if nf >= 255 {
        cols.extra.push(nf as u32);
    }
    cols.extra
        .extend(codes.iter().skip(2).map(|&c| u32::from(c)));
    for (f, &c) in s.faces.iter().zip(&codes) {
        if c == FACE_ESCAPE {
            cols.extra
                .extend(f.iter().map(|&x| topo::corner_code(x, v0, s.v1)));
        }
    }
    st.topo.add_vertex();
    st.positions.push(s.p0);
    st.positions[s.v1 as usize] = s.p1;
    for &f in &s.faces {
        st.topo.add_face(&mut st.triangles, f);
    }
    let held = st.topo.corners(&st.triangles, s.v1);
    let edited: topo::Small<bool> = held
        .iter()
        .map(|c| s.corners.binary_search(c).is_ok())
        .collect();
    debug_assert_eq!(edited.iter().filter(|&&e| e).count(), s.corners.len());
    let first = (st.triangles.len() - nf) as u32;
    let fan = &st.topo.fans[s.v1 as usize];
    topo::predict_mask(
        &st.triangles,
        fan,
        first,
        &s.faces,
        (v0, s.v1),
        &held,
        &mut cols.predicted,
    );
    if cols.predicted[..] != edited[..] {
        cols.codes.last_mut().expect("pushed above")[3] = 1;
        for &e in &edited {
            cols.mask.push(e);
        }
    }
    for (c, &e) in held.iter().zip(&edited) {
        if e {
            st.topo.move_corner(&mut st.triangles, *c, s.v1, v0);
        }
    }
    cols.rings.extend(st.topo.ring(&st.triangles, v0));
    cols.ring_ends.push(cols.rings.len());
    if let Some((log, w)) = &mut st.wedges {
        let sw = log.split(i, s);
        let first = st.triangles.len() - nf;
        let rec = Rec {
            v0,
            v1: s.v1,
            wings: topo::wing_faces(&s.faces, v0, s.v1)
                .map(|(a, b)| ((first + a) as u32, (first + b) as u32)),
        };
        w.sh.cw.resize(st.triangles.len(), [NONE; 3]);
        let order: Vec<(u32, usize)> = face_corner_order(&st.triangles, first, nf, v0).collect();
        for (t, k) in order {
            let c = sw.faces[t as usize - first][k];
            w.put(&st.triangles, &st.topo.fans, t, k, c, None, Some(rec));
        }
        let before: Vec<u32> = s
            .corners
            .iter()
            .map(|c| std::mem::replace(&mut w.sh.cw[c.triangle as usize][c.slot as usize], NONE))
            .collect();
        for ((c, e), b) in s.corners.iter().zip(&sw.corners).zip(before) {
            let (t, k) = (c.triangle, usize::from(c.slot));
            w.put(&st.triangles, &st.topo.fans, t, k, e[1], Some(b), Some(rec));
        }
    }
    if st.errors {
        cols.errors.push(s.error.to_bits());
    }
}

/// The chunk of records `a .. b`: its topology and wedge columns in blocks
/// of [`BLOCK_RECORDS`] records, then its positions (version 7).
fn record_chunk(pm: &ProgressiveMesh, a: usize, b: usize, st: &mut State) -> Vec<u8> {
    let va = pm.base.positions.len() + a;
    let mut cols = TopoColumns::default();
    let mut moved: Vec<u32> = Vec::new();
    let mut cw = ColumnWriter::default();
    for i in a..b {
        record(pm, i, st, &mut cols);
        if (i + 1 - a) % BLOCK_RECORDS == 0 || i + 1 == b {
            write_block(&mut cw, &mut cols, st);
        }
        let v1 = pm.splits[i].v1;
        if (v1 as usize) < va && st.moved_slot[v1 as usize] == 0 {
            moved.push(v1);
            st.moved_slot[v1 as usize] = moved.len() as u32;
        }
    }
    // positions at the chunk's end: the moved old vertices, then the new
    let start: Vec<[u16; 3]> = moved.iter().map(|&v| st.q[v as usize]).collect();
    let mut moved_res = Vec::with_capacity(moved.len());
    for (&v, s) in moved.iter().zip(&start) {
        let q = st.grid.quantize(st.positions[v as usize]);
        moved_res.push([0, 1, 2].map(|k| q[k].wrapping_sub(s[k])));
        st.q[v as usize] = q;
    }
    let mut new_res = Vec::with_capacity(b - a);
    let mut from = 0;
    for (i, &to) in (a..b).zip(&cols.ring_ends) {
        let pred = topo::predict_new(&st.q, &cols.rings[from..to], pm.splits[i].v1);
        from = to;
        let q = st.grid.quantize(st.positions[va + i - a]);
        new_res.push([0, 1, 2].map(|k| q[k].wrapping_sub(pred[k])));
        st.q.push(q);
    }
    for &v in &moved {
        st.moved_slot[v as usize] = 0;
    }
    cw.vertices(&prefix_sums(&moved_res));
    cw.vertices(&prefix_sums(&new_res));
    if st.errors {
        cw.vertices(&cols.errors);
    }
    cw.out
}

/// A block's topology columns and (with wedges) its wedge columns, which
/// come before the chunk's positions: a decoder replays the block while
/// the rest of the chunk still downloads.
fn write_block(cw: &mut ColumnWriter, cols: &mut TopoColumns, st: &mut State) {
    cw.vertices(&cols.v1);
    cw.vertices(&cols.codes);
    cw.vertices(&cols.extra);
    cw.bits(&cols.mask);
    if let Some((_, w)) = &mut st.wedges {
        w.flush(cw);
    }
    cols.v1.clear();
    cols.codes.clear();
    cols.extra.clear();
    cols.mask = BitWriter::default();
}

fn components(a: &WedgeAttributes) -> Vec<u8> {
    a.channels.iter().map(|c| c.components).collect()
}

/// Each channel's encoding: [`AttrEncoding::choose`] on its values, or
/// `f32` everywhere when `exact`.
fn encodings_for(a: &WedgeAttributes, exact: bool) -> Vec<AttrEncoding> {
    let stride = a.stride();
    let mut at = 0;
    a.channels
        .iter()
        .map(|c| {
            let n = usize::from(c.components);
            let from = at;
            at += n;
            if exact || stride == 0 {
                return AttrEncoding::F32;
            }
            let values = a
                .values
                .chunks_exact(stride)
                .flat_map(|w| w[from..from + n].iter().copied());
            AttrEncoding::choose(&c.name, values)
        })
        .collect()
}

fn encode_inner(
    pm: &ProgressiveMesh,
    levels: &[usize],
    opts: EncodeOptions,
    wedges: Option<(&WedgeLog, &WedgeAttributes, usize)>,
) -> Vec<u8> {
    let grid = opts.grid.unwrap_or_else(|| {
        let all = pm
            .base
            .positions
            .iter()
            .chain(pm.splits.iter().flat_map(|s| [&s.p1, &s.p0]));
        Grid::around(all, opts.bits)
    });
    let total_vertices = pm.base.positions.len() + pm.splits.len();
    let total_triangles =
        pm.base.triangles.len() + pm.splits.iter().map(|s| s.faces.len()).sum::<usize>();
    let groups = wedges.map_or(1, |(_, a, _)| {
        a.groups.iter().max().map_or(1, |&g| g.saturating_add(1))
    });
    let encodings: Vec<AttrEncoding> = wedges.map_or_else(Vec::new, |(_, a, _)| {
        encodings_for(a, opts.exact_attributes)
    });
    let mut st = State {
        grid,
        triangles: pm.base.triangles.clone(),
        topo: Topo::new(pm.base.positions.len(), &pm.base.triangles),
        positions: pm.base.positions.clone(),
        q: pm
            .base
            .positions
            .iter()
            .map(|&p| grid.quantize(p))
            .collect(),
        moved_slot: vec![0; total_vertices],
        wedges: wedges.map(|(log, a, _)| {
            let mut sh = Shared::new(&encodings, &components(a));
            sh.cw = vec![[NONE; 3]; pm.base.triangles.len()];
            let lanes = sh.stride;
            (
                log,
                WedgeWriter {
                    attributes: a,
                    groups,
                    sh,
                    ids: vec![0; a.count],
                    refs: Vec::new(),
                    new_groups: Vec::new(),
                    values: vec![Vec::new(); a.channels.len()],
                    sums: vec![0; lanes],
                    scratch: Vec::new(),
                },
            )
        }),
        errors: opts.errors,
    };
    let mut chunks = vec![(0, base_chunk(pm, &mut st))];
    let mut a = 0;
    for b in chunk_ends(levels, pm.splits.len()) {
        chunks.push((b, record_chunk(pm, a, b, &mut st)));
        a = b;
    }
    let header = StreamHeader {
        flags: u8::from(opts.errors) * FLAG_ERRORS + u8::from(wedges.is_some()) * FLAG_WEDGES,
        grid,
        base_vertices: pm.base.positions.len(),
        base_triangles: pm.base.triangles.len(),
        split_count: pm.splits.len(),
        total_vertices,
        total_triangles,
        levels: levels.iter().map(|&k| k.min(pm.splits.len())).collect(),
        wedges: wedges.map(|(_, a, total)| WedgeLayout {
            total,
            groups,
            channels: a.channels.clone(),
            encodings: encodings.clone(),
        }),
        chunks: chunks
            .iter()
            .map(|(records, bytes)| ChunkInfo {
                records: *records,
                bytes: bytes.len(),
            })
            .collect(),
        header_bytes: 0,
    };
    let mut out = header::write(&header);
    for (_, c) in chunks {
        out.extend_from_slice(&c);
    }
    out
}
