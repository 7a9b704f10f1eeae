//! The encoder: header, base chunk, one chunk per level step.

use super::columns::{prefix_sums, BitWriter, ColumnWriter};
use super::header;
use super::topo::{self, Topo, FACE_ESCAPE};
use super::types::{
    chunk_ends, ChunkInfo, EncodeError, EncodeOptions, Grid, StreamHeader, WedgeAttributes,
    WedgeLayout, FLAG_ERRORS, FLAG_WEDGES,
};
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

/// Collects one chunk's wedge references (`0` = a new wedge, else `count −
/// id`), the new wedges' groups and values.
struct WedgeWriter<'a> {
    attributes: &'a WedgeAttributes,
    groups: u32,
    /// Log wedge id → stream id + 1 (0 = not yet written).
    ids: Vec<u32>,
    count: u32,
    refs: Vec<u32>,
    new_groups: Vec<u32>,
    /// Per channel, the new wedges' values as little-endian bytes.
    values: Vec<Vec<u8>>,
}

impl WedgeWriter<'_> {
    fn put(&mut self, w: u32) {
        let id = &mut self.ids[w as usize];
        if *id == 0 {
            self.refs.push(0);
            self.new_groups.push(self.attributes.group(w));
            let mut at = 0;
            let values = self.attributes.wedge(w);
            for (c, out) in self.attributes.channels.iter().zip(&mut self.values) {
                let n = usize::from(c.components);
                for v in &values[at..at + n] {
                    out.extend_from_slice(&v.to_le_bytes());
                }
                at += n;
            }
            self.count += 1;
            *id = self.count;
        } else {
            self.refs.push(self.count + 1 - *id);
        }
    }

    /// The chunk's wedge columns: references, groups (with several), values
    /// per channel.
    fn flush(&mut self, cw: &mut ColumnWriter) {
        cw.vertices(&self.refs);
        if self.groups > 1 {
            cw.vertices(&self.new_groups);
        }
        let n = self.new_groups.len();
        for (c, v) in self.attributes.channels.iter().zip(&mut self.values) {
            cw.strided(v, n, 4 * usize::from(c.components));
            v.clear();
        }
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
        for &c in log.base.iter().flatten() {
            w.put(c);
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
}

/// Replay record `i` on the topology and write its columns.
fn record(pm: &ProgressiveMesh, i: usize, st: &mut State, cols: &mut TopoColumns) {
    let s = &pm.splits[i];
    let v0 = (pm.base.positions.len() + i) as u32;
    debug_assert_eq!(s.v0, v0);
    let ring = st.topo.ring(&st.triangles, s.v1);
    let codes: Vec<u8> = s
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
    let edited: Vec<bool> = held
        .iter()
        .map(|c| s.corners.binary_search(c).is_ok())
        .collect();
    debug_assert_eq!(edited.iter().filter(|&&e| e).count(), s.corners.len());
    for (c, &e) in held.iter().zip(&edited) {
        cols.mask.push(e);
        if e {
            st.topo.move_corner(&mut st.triangles, *c, s.v1, v0);
        }
    }
    if let Some((log, w)) = &mut st.wedges {
        let sw = &log.splits[i];
        for &c in sw.faces.iter().flatten() {
            w.put(c);
        }
        for c in &sw.corners {
            w.put(c[1]);
        }
    }
    if st.errors {
        cols.errors.push(s.error.to_bits());
    }
}

/// The chunk of records `a .. b`.
fn record_chunk(pm: &ProgressiveMesh, a: usize, b: usize, st: &mut State) -> Vec<u8> {
    let va = pm.base.positions.len() + a;
    let mut cols = TopoColumns::default();
    let mut moved: Vec<u32> = Vec::new();
    let mut wings = Vec::with_capacity(b - a);
    for i in a..b {
        record(pm, i, st, &mut cols);
        let (v0, v1) = ((va + i - a) as u32, pm.splits[i].v1);
        if (v1 as usize) < va && st.moved_slot[v1 as usize] == 0 {
            moved.push(v1);
            st.moved_slot[v1 as usize] = moved.len() as u32;
        }
        wings.push(topo::wings(&pm.splits[i].faces, v0, v1));
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
    for (i, w) in (a..b).zip(wings) {
        let v1 = pm.splits[i].v1;
        let slot = st.moved_slot[v1 as usize];
        let v1_start = ((v1 as usize) < va).then(|| start[slot as usize - 1]);
        let pred = topo::predict_new(&st.q, w, v1, v1_start);
        let q = st.grid.quantize(st.positions[va + i - a]);
        new_res.push([0, 1, 2].map(|k| q[k].wrapping_sub(pred[k])));
        st.q.push(q);
    }
    for &v in &moved {
        st.moved_slot[v as usize] = 0;
    }
    let mut cw = ColumnWriter::default();
    cw.vertices(&cols.v1);
    cw.vertices(&cols.codes);
    cw.vertices(&cols.extra);
    cw.bits(&cols.mask);
    cw.vertices(&prefix_sums(&moved_res));
    cw.vertices(&prefix_sums(&new_res));
    if let Some((_, w)) = &mut st.wedges {
        w.flush(&mut cw);
    }
    if st.errors {
        cw.vertices(&cols.errors);
    }
    cw.out
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
            (
                log,
                WedgeWriter {
                    attributes: a,
                    groups,
                    ids: vec![0; a.count],
                    count: 0,
                    refs: Vec::new(),
                    new_groups: Vec::new(),
                    values: vec![Vec::new(); a.channels.len()],
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
