//! Wedge references and values, the same on both sides of the stream.
//!
//! A corner's wedge is coded against a **candidate list**: the wedges of
//! the corners at the same vertex in the triangles sharing an edge with the
//! corner's triangle, then (for a corner edit) the corner's wedge before the
//! split, then every other wedge at the vertex (fan order, each once). Code
//! `0` = a new wedge, `k` in `1..=n` = candidate `k − 1`, `k > n` = the
//! existing wedge `count − (k − n)`. A new wedge's quantized values are
//! predicted from wedges already known: across the split's two wing faces
//! (parallelogram) for `v0`'s corners, else the wedge of another corner of
//! its triangle (`v1`'s first), else 0.

use super::columns::ColumnReader;
use super::types::{invalid, AttrEncoding, StreamError, WedgeAttributes, WedgeLayout};

/// A corner whose wedge is not known (yet).
pub(super) const NONE: u32 = u32::MAX;

/// The record a reference belongs to: its vertices and, when it has two
/// wings, the triangles of its two wing faces.
#[derive(Clone, Copy)]
pub(super) struct Rec {
    pub v0: u32,
    pub v1: u32,
    pub wings: Option<(u32, u32)>,
}

/// The state both sides keep: every corner's wedge, every wedge's quantized
/// values, and the layout of those values.
#[derive(Clone, Debug, Default)]
pub(super) struct Shared {
    /// Per triangle, the wedge of each corner (stream numbering; [`NONE`]
    /// while not known).
    pub cw: Vec<[u32; 3]>,
    /// Wedges defined so far.
    pub count: u32,
    /// Quantized values, `stride` per wedge.
    pub qv: Vec<u16>,
    pub stride: usize,
    /// Per channel: its first lane in `qv` when quantized.
    pub lane: Vec<Option<usize>>,
    /// `f32` values, `fstride` per wedge, and each `f32` channel's first lane.
    pub fv: Vec<f32>,
    pub fstride: usize,
    pub flane: Vec<Option<usize>>,
    pub encodings: Vec<AttrEncoding>,
    /// Scratch: the candidate list.
    pub cand: Vec<u32>,
}

impl Shared {
    pub fn new(encodings: &[AttrEncoding], components: &[u8]) -> Shared {
        let mut stride = 0;
        let lane = encodings
            .iter()
            .zip(components)
            .map(|(e, &c)| {
                (*e != AttrEncoding::F32).then(|| {
                    stride += usize::from(c);
                    stride - usize::from(c)
                })
            })
            .collect();
        let mut fstride = 0;
        let flane = encodings
            .iter()
            .zip(components)
            .map(|(e, &c)| {
                (*e == AttrEncoding::F32).then(|| {
                    fstride += usize::from(c);
                    fstride - usize::from(c)
                })
            })
            .collect();
        Shared {
            stride,
            lane,
            fstride,
            flane,
            encodings: encodings.to_vec(),
            ..Shared::default()
        }
    }

    /// Fill `self.cand` for corner `(t, s)` (see the module docs).
    pub fn candidates(
        &mut self,
        tri: &[[u32; 3]],
        fans: &[super::topo::Fan],
        t: u32,
        s: usize,
        before: Option<u32>,
    ) {
        let cand = &mut self.cand;
        cand.clear();
        let f = tri[t as usize];
        let u = f[s];
        let (a, b) = (f[(s + 1) % 3], f[(s + 2) % 3]);
        let fan = &fans[u as usize];
        let push = |w: u32, cand: &mut Vec<u32>| {
            if w != NONE && !cand.contains(&w) {
                cand.push(w);
            }
        };
        for &t2 in fan {
            let g = tri[t2 as usize];
            if t2 != t && ((a != u && g.contains(&a)) || (b != u && g.contains(&b))) {
                for (&x, &w) in g.iter().zip(&self.cw[t2 as usize]) {
                    if x == u {
                        push(w, cand);
                    }
                }
            }
        }
        if let Some(w) = before {
            push(w, cand);
        }
        for &t2 in fan {
            let g = tri[t2 as usize];
            if t2 != t {
                for (&x, &w) in g.iter().zip(&self.cw[t2 as usize]) {
                    if x == u {
                        push(w, cand);
                    }
                }
            }
        }
    }

    /// The code of existing wedge `id` against the candidates.
    pub fn code_of(&self, id: u32) -> u32 {
        match self.cand.iter().position(|&w| w == id) {
            Some(k) => k as u32 + 1,
            None => self.cand.len() as u32 + (self.count - id),
        }
    }

    /// The wedge a non-zero `code` names, or `None` when out of range.
    pub fn wedge_of(&self, code: u32) -> Option<u32> {
        let n = self.cand.len() as u32;
        if code <= n {
            return Some(self.cand[code as usize - 1]);
        }
        let back = code - n;
        (back <= self.count).then(|| self.count - back)
    }

    /// Which known wedges predict the values of a new wedge at corner
    /// `(t, s)`.
    pub fn predictor(&self, tri: &[[u32; 3]], t: u32, s: usize, rec: Option<Rec>) -> Pred {
        let cw = &self.cw;
        let f = tri[t as usize];
        let w = cw[t as usize];
        if let Some(Rec {
            v0,
            v1,
            wings: Some((ta, tb)),
        }) = rec
        {
            if f[s] == v0 && (t == ta || t == tb) {
                let t2 = if t == ta { tb } else { ta };
                let g = tri[t2 as usize];
                let third = |h: [u32; 3]| (0..3).find(|&i| h[i] != v0 && h[i] != v1);
                let at = |h: [u32; 3], v: u32| (0..3).find(|&i| h[i] == v);
                if let (Some(x), Some(y), Some(s1), Some(s2)) =
                    (third(f), third(g), at(f, v1), at(g, v1))
                {
                    let w2 = cw[t2 as usize];
                    let (wx, wy, w1) = (w[x], w2[y], w[s1]);
                    if wx != NONE && wy != NONE && w1 != NONE && w1 == w2[s2] {
                        return Pred::Para(wx, wy, w1);
                    }
                }
            }
        }
        let v1_slot = rec.and_then(|r| (0..3).find(|&i| i != s && f[i] == r.v1 && w[i] != NONE));
        let other = v1_slot.or_else(|| {
            [(s + 1) % 3, (s + 2) % 3]
                .into_iter()
                .find(|&i| w[i] != NONE)
        });
        other.map_or(Pred::Zero, |i| Pred::One(w[i]))
    }

    /// The predicted quantized values (`stride` lanes) into `out`.
    pub fn predict_q(&self, p: Pred, out: &mut [u16]) {
        let get = |id: u32| &self.qv[id as usize * self.stride..][..self.stride];
        match p {
            Pred::Zero => out.fill(0),
            Pred::One(w) => out.copy_from_slice(get(w)),
            Pred::Para(a, b, c) => {
                let (a, b, c) = (get(a), get(b), get(c));
                for i in 0..self.stride {
                    out[i] = a[i].wrapping_add(b[i]).wrapping_sub(c[i]);
                }
            }
        }
    }

    /// The predicted bits of the `f32` values (`fstride` lanes) into `out`:
    /// the parallelogram computed in `f64` and rounded once; 0 when not
    /// finite.
    pub fn predict_f(&self, p: Pred, out: &mut [u32]) {
        let get = |id: u32| &self.fv[id as usize * self.fstride..][..self.fstride];
        match p {
            Pred::Zero => out.fill(0),
            Pred::One(w) => {
                for (o, x) in out.iter_mut().zip(get(w)) {
                    *o = x.to_bits();
                }
            }
            Pred::Para(a, b, c) => {
                let (a, b, c) = (get(a), get(b), get(c));
                for i in 0..self.fstride {
                    let x = (f64::from(a[i]) + f64::from(b[i]) - f64::from(c[i])) as f32;
                    out[i] = if x.is_finite() { x.to_bits() } else { 0 };
                }
            }
        }
    }
}

/// The source of a new wedge's predicted values.
#[derive(Clone, Copy)]
pub(super) enum Pred {
    Zero,
    One(u32),
    /// `a + b − c`.
    Para(u32, u32, u32),
}

/// A residual of `f32` bit patterns as a small unsigned number (zigzag).
pub(super) fn zigzag(r: u32) -> u32 {
    (r << 1) ^ ((r as i32 >> 31) as u32)
}

pub(super) fn unzigzag(z: u32) -> u32 {
    (z >> 1) ^ (z & 1).wrapping_neg()
}

/// The corners of a record's new faces (triangles `first .. first + nf`)
/// in coding order: every corner not at `v0`, face by face, then the
/// corners at `v0`.
pub(super) fn face_corner_order(
    tri: &[[u32; 3]],
    first: usize,
    nf: usize,
    v0: u32,
) -> impl Iterator<Item = (u32, usize)> + '_ {
    let all = move || (first..first + nf).flat_map(|t| (0..3).map(move |s| (t as u32, s)));
    all()
        .filter(move |&(t, s)| tri[t as usize][s] != v0)
        .chain(all().filter(move |&(t, s)| tri[t as usize][s] == v0))
}

/// Lanes of a quantized channel's column element: its components rounded
/// up to an even number (elements of whole 4-byte words).
pub(super) fn padded(components: u8) -> usize {
    usize::from(components).next_multiple_of(2)
}

/// One chunk's wedge columns on the decoder side, consumed reference by
/// reference.
pub(super) struct WedgeColumns {
    refs: Vec<u32>,
    pos: usize,
    groups: Vec<u32>,
    /// Per channel: the new wedges' `f32` values, or the residuals of a
    /// quantized channel (padded lanes).
    values: Vec<Vec<u32>>,
    residuals: Vec<Vec<u16>>,
    new: usize,
    at: usize,
    scratch: Vec<u16>,
    fscratch: Vec<u32>,
}

/// The decoder's wedges: the shared state and every wedge's values.
#[derive(Clone, Debug, Default)]
pub(super) struct WedgeState {
    pub sh: Shared,
    pub attributes: WedgeAttributes,
}

impl WedgeColumns {
    pub fn read(
        r: &mut ColumnReader,
        layout: &WedgeLayout,
        limit: usize,
    ) -> Result<Self, StreamError> {
        let at = r.offset();
        let refs: Vec<u32> = r.vertices("wedge reference", None, limit)?;
        let new = refs.iter().filter(|&&c| c == 0).count();
        let groups = if layout.groups > 1 {
            r.vertices("wedge group", Some(new), 0)?
        } else {
            Vec::new()
        };
        let mut values = Vec::with_capacity(layout.channels.len());
        let mut residuals = Vec::with_capacity(layout.channels.len());
        for (c, e) in layout.channels.iter().zip(&layout.encodings) {
            if *e == AttrEncoding::F32 {
                let raw = r.strided("attribute", Some(new), 0, 4 * usize::from(c.components))?;
                values.push(
                    raw.chunks_exact(4)
                        .map(|b| unzigzag(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
                        .collect(),
                );
                residuals.push(Vec::new());
            } else {
                let lanes = padded(c.components);
                let raw = r.strided("attribute", Some(new), 0, 2 * lanes)?;
                let sums: Vec<u16> = raw
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]))
                    .collect();
                let mut res = sums.clone();
                for i in (lanes..res.len()).rev() {
                    res[i] = sums[i].wrapping_sub(sums[i - lanes]);
                }
                residuals.push(res);
                values.push(Vec::new());
            }
        }
        Ok(WedgeColumns {
            refs,
            pos: 0,
            groups,
            values,
            residuals,
            new: 0,
            at,
            scratch: Vec::new(),
            fscratch: Vec::new(),
        })
    }

    /// The next reference, at corner `(t, s)` (a corner edit when `before`
    /// is given), as a wedge id, defining the wedge when new; recorded at
    /// the corner.
    #[allow(clippy::too_many_arguments)]
    pub fn next(
        &mut self,
        ws: &mut WedgeState,
        layout: &WedgeLayout,
        tri: &[[u32; 3]],
        fans: &[super::topo::Fan],
        (t, s): (u32, usize),
        before: Option<u32>,
        rec: Option<Rec>,
    ) -> Result<u32, StreamError> {
        let at = self.at;
        let code = *self
            .refs
            .get(self.pos)
            .ok_or_else(|| invalid(at, "the wedge reference column ends early"))?;
        self.pos += 1;
        ws.sh.candidates(tri, fans, t, s, before);
        let id = if code > 0 {
            ws.sh
                .wedge_of(code)
                .ok_or_else(|| invalid(at, format!("wedge reference {code} out of range")))?
        } else {
            self.define(ws, layout, tri, (t, s), rec)?
        };
        ws.sh.cw[t as usize][s] = id;
        Ok(id)
    }

    fn define(
        &mut self,
        ws: &mut WedgeState,
        layout: &WedgeLayout,
        tri: &[[u32; 3]],
        (t, s): (u32, usize),
        rec: Option<Rec>,
    ) -> Result<u32, StreamError> {
        let at = self.at;
        let a = &mut ws.attributes;
        if a.count >= layout.total {
            return Err(invalid(
                at,
                format!("more wedges than the {} announced", layout.total),
            ));
        }
        let g = self.groups.get(self.new).copied().unwrap_or(0);
        if g >= layout.groups {
            return Err(invalid(at, format!("wedge group {g} out of range")));
        }
        a.groups.push(g);
        let mut pred = std::mem::take(&mut self.scratch);
        let mut fpred = std::mem::take(&mut self.fscratch);
        pred.resize(ws.sh.stride, 0);
        fpred.resize(ws.sh.fstride, 0);
        let p = ws.sh.predictor(tri, t, s, rec);
        ws.sh.predict_q(p, &mut pred);
        ws.sh.predict_f(p, &mut fpred);
        for (ci, (c, e)) in layout.channels.iter().zip(&layout.encodings).enumerate() {
            let n = usize::from(c.components);
            match ws.sh.lane[ci] {
                None => {
                    let lane = ws.sh.flane[ci].unwrap_or(0);
                    let res = &self.values[ci][self.new * n..][..n];
                    for k in 0..n {
                        let x = f32::from_bits(fpred[lane + k].wrapping_add(res[k]));
                        ws.sh.fv.push(x);
                        a.values.push(x);
                    }
                }
                Some(lane) => {
                    let res = &self.residuals[ci][self.new * padded(c.components)..];
                    for k in 0..n {
                        let q = pred[lane + k].wrapping_add(res[k]);
                        if q > e.max() {
                            return Err(invalid(
                                at,
                                format!("attribute value {q} over {}", e.max()),
                            ));
                        }
                        ws.sh.qv.push(q);
                        a.values.push(e.dequantize(q));
                    }
                }
            }
        }
        self.scratch = pred;
        self.fscratch = fpred;
        self.new += 1;
        a.count += 1;
        ws.sh.count += 1;
        Ok(ws.sh.count - 1)
    }

    pub fn finish(&self) -> Result<(), StreamError> {
        if self.pos == self.refs.len() {
            Ok(())
        } else {
            Err(invalid(self.at, "wedge references left over"))
        }
    }
}
