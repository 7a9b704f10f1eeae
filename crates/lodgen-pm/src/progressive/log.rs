//! The simplifier's log of contractions, in the welded input's numbering:
//! the records, their moved corners (packed, in record order) and wedge
//! edits, from which [`super::ProgressiveMesh::from_log`] builds the splits.

use super::split::Corner;

/// A contraction as the simplifier records it, in the welded input's
/// numbering (see `collapse`). Its moved corners are `log.moved(c)`.
/// `v0`'s position and the merged one are not stored: a removed vertex
/// keeps its last position in the simplifier's final state, and the merged
/// position is `v1`'s position after the contraction, i.e. the `p1` of the
/// next contraction into `v1`, or `v1`'s final position (`from_log`).
#[derive(Clone, Debug)]
pub(crate) struct Contraction {
    pub v0: u32,
    pub v1: u32,
    /// `v1`'s position before the contraction.
    pub p1: [f32; 3],
    pub removed: Removed,
    pub moved: std::ops::Range<u32>,
    pub error: f32,
}

/// The triangles a contraction deletes: two for an interior edge, one on a
/// border, none for a τ pair, inline (8 bytes, where a `SmallVec` took 32:
/// the log holds one per contraction, 1.9M in the clusters' logs of a
/// 4.4M-triangle scan, copied once when they are merged); `k ≥ 3` for an
/// edge of `k` faces (rare: a chain of non-manifold edges), then `t[0]` is
/// where they start in the log's [`Log::more_removed`] and `t[1]` is
/// `MANY | k`. Unused slots hold `u32::MAX` (triangle ids are below 2^30,
/// `Mesh::validate`). Read them with [`Log::removed`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Removed {
    t: [u32; 2],
}

/// `t[1]`'s flag of a [`Removed`] of three or more triangles.
const MANY: u32 = 1 << 31;

impl Removed {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        match self.t {
            [u32::MAX, u32::MAX] => 0,
            [_, u32::MAX] => 1,
            [_, k] if k & MANY != 0 => (k & !MANY) as usize,
            _ => 2,
        }
    }

    /// No triangle.
    pub const NONE: Removed = Removed { t: [u32::MAX; 2] };

    /// `ts` held inline: `None` for three or more (see [`Log::removed_of`]).
    pub fn inline(ts: &[u32]) -> Option<Removed> {
        let mut t = [u32::MAX; 2];
        t.get_mut(..ts.len())?.copy_from_slice(ts);
        Some(Removed { t })
    }
}

const _: () = assert!(std::mem::size_of::<Contraction>() == 40);

/// The simplifiers' contraction log: the records, and one arena for all
/// their moved corners (and wedge edits), so that logging a contraction
/// allocates nothing.
#[derive(Clone, Debug, Default)]
pub(crate) struct Log {
    pub records: Vec<Contraction>,
    /// Moved corners packed as `triangle << 2 | slot` (4 bytes, not 8:
    /// meshes have fewer than 2^30 triangles, see `Mesh::validate`).
    pub(super) corners: Vec<u32>,
    /// Parallel to `corners` when wedges are tracked: `[before, after]`
    /// the contraction. Empty otherwise.
    pub wedges: Vec<[u32; 2]>,
    /// The deleted triangles of the contractions along edges of three or
    /// more faces (see [`Removed`]).
    more_removed: Vec<u32>,
}

impl Log {
    pub fn with_capacity(contractions: usize) -> Log {
        Log {
            records: Vec::with_capacity(contractions),
            corners: Vec::with_capacity(contractions * 9 / 2),
            wedges: Vec::new(),
            more_removed: Vec::new(),
        }
    }

    /// `ts` as a record's [`Removed`] (three or more kept in this log).
    pub fn removed_of(&mut self, ts: &[u32]) -> Removed {
        Removed::inline(ts).unwrap_or_else(|| {
            let start = self.more_removed.len() as u32;
            self.more_removed.extend_from_slice(ts);
            Removed {
                t: [start, MANY | ts.len() as u32],
            }
        })
    }

    /// The triangles `c` deleted.
    #[inline]
    pub fn removed<'a>(&'a self, c: &'a Contraction) -> &'a [u32] {
        let (r, n) = (&c.removed, c.removed.len());
        match n {
            0..=2 => &r.t[..n],
            _ => &self.more_removed[r.t[0] as usize..r.t[0] as usize + n],
        }
    }

    /// The record of contracting `v0` into `v1` (at `p1` before it),
    /// deleting `removed`, its moved corners to be pushed next.
    pub fn begin(
        &mut self,
        v0: u32,
        v1: u32,
        p1: [f32; 3],
        removed: &[u32],
        error: f32,
    ) -> Contraction {
        Contraction {
            v0,
            v1,
            p1,
            removed: self.removed_of(removed),
            moved: self.mark()..self.mark(),
            error,
        }
    }

    /// Appends the corner arenas of `logs` one after the other, each
    /// corner's triangle mapped by `map(i, triangle)` (`i` the log's place
    /// in `logs`), on every core; returns where each log's corners start
    /// now (to add to its records' `moved`).
    pub fn append_corners(
        &mut self,
        logs: &[&Log],
        map: impl Fn(usize, u32) -> u32 + Sync,
    ) -> Vec<u32> {
        use rayon::prelude::*;
        let mut starts = Vec::with_capacity(logs.len());
        let mut end = self.corners.len();
        for l in logs {
            starts.push(end as u32);
            end += l.corners.len();
        }
        let first = self.corners.len() as u32;
        self.corners
            .par_extend((first..end as u32).into_par_iter().map(|j| {
                let i = starts.partition_point(|&s| s <= j) - 1;
                let k = logs[i].corners[(j - starts[i]) as usize];
                map(i, k >> 2) << 2 | (k & 3)
            }));
        starts
    }

    /// Room for `n` more corners.
    pub fn reserve_corners(&mut self, n: usize) {
        self.corners.reserve(n);
    }

    /// The next corner's index, for `Contraction::moved`.
    pub fn mark(&self) -> u32 {
        self.corners.len() as u32
    }

    pub fn push_corner(&mut self, c: Corner) {
        self.corners.push(c.triangle << 2 | u32::from(c.slot));
    }

    /// Moves the corner of triangle `t` (`tri`) at `v0` to `v1` and logs it;
    /// returns its slot, `None` when `tri` has no corner at `v0`.
    pub fn move_corner(&mut self, tri: &mut [u32; 3], t: u32, v0: u32, v1: u32) -> Option<usize> {
        let slot = tri.iter().position(|&x| x == v0)?;
        tri[slot] = v1;
        self.push_corner(Corner {
            triangle: t,
            slot: slot as u8,
        });
        Some(slot)
    }

    pub fn moved(&self, c: &Contraction) -> impl Iterator<Item = Corner> + '_ {
        self.corners[c.moved.start as usize..c.moved.end as usize]
            .iter()
            .map(|&k| Corner {
                triangle: k >> 2,
                slot: (k & 3) as u8,
            })
    }

    /// Writes out the wedge edits left implied by one wedge per vertex
    /// (`vw`, `Features::edits_implied`): `[vw[v0], vw[v1]]` for every
    /// corner moved so far, the contraction in progress (`v0` into `v1`,
    /// not yet in `records`) included but its last corner, whose edit the
    /// caller pushes.
    pub fn spell_out_wedges(&mut self, vw: &[u32], [v0, v1]: [u32; 2]) {
        debug_assert!(self.wedges.is_empty());
        self.wedges.reserve(self.corners.len());
        for r in &self.records {
            let e = [vw[r.v0 as usize], vw[r.v1 as usize]];
            let n = (r.moved.end - r.moved.start) as usize;
            self.wedges.extend(std::iter::repeat_n(e, n));
        }
        let e = [vw[v0 as usize], vw[v1 as usize]];
        self.wedges.resize(self.corners.len() - 1, e);
    }

    /// Rewrites the corner arena in record order, after `records[first..]`
    /// were reordered (their `moved` ranges pointing anywhere into the
    /// arena past the earlier records' corners, which stay in order): each
    /// record's corners then follow the previous record's, as `push_corner`
    /// leaves them (`pop` and `spell_out_wedges` rely on it). Without
    /// wedge edits (they are not reordered).
    pub fn reorder_corners_from(&mut self, first: usize) {
        debug_assert!(self.wedges.is_empty());
        let keep = self.records[..first]
            .last()
            .map_or(0, |r| r.moved.end as usize);
        let mut corners = Vec::with_capacity(self.corners.len() - keep);
        for r in &mut self.records[first..] {
            let start = (keep + corners.len()) as u32;
            corners.extend_from_slice(&self.corners[r.moved.start as usize..r.moved.end as usize]);
            r.moved = start..(keep + corners.len()) as u32;
        }
        self.corners.truncate(keep);
        self.corners.extend_from_slice(&corners);
    }

    /// Drops records `m..` with their corners and wedge edits, and returns
    /// their memory (the vectors shrink in place: no copy). Corners are in
    /// record order (see [`Self::reorder_corners`]).
    pub fn free_from(&mut self, m: usize) {
        let Some(start) = self.records[m.min(self.records.len())..]
            .iter()
            .map(|r| r.moved.start as usize)
            .min()
        else {
            return;
        };
        debug_assert!(self.records[..m]
            .iter()
            .all(|r| r.moved.end as usize <= start));
        self.records.truncate(m);
        self.records.shrink_to_fit();
        self.corners.truncate(start);
        self.corners.shrink_to_fit();
        if !self.wedges.is_empty() {
            self.wedges.truncate(start);
            self.wedges.shrink_to_fit();
        }
    }

    /// Remove the newest record and its corners.
    pub fn pop(&mut self) -> Option<Contraction> {
        let c = self.records.pop()?;
        self.corners.truncate(c.moved.start as usize);
        if c.removed.len() > 2 {
            self.more_removed.truncate(c.removed.t[0] as usize);
        }
        self.wedges
            .truncate(self.wedges.len().min(c.moved.start as usize));
        Some(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every count of deleted triangles reads back as written, inline (0,
    /// 1, 2, ids up to 2^30 − 1) or in `more_removed` (3 and more, one
    /// after another), and `pop` gives the list's tail back. Fails when
    /// the 8-byte encoding confuses two inline triangles with a list.
    #[test]
    fn removed_triangles_read_back() {
        let top = (1u32 << 30) - 1;
        let cases: Vec<Vec<u32>> = vec![
            vec![],
            vec![0],
            vec![top],
            vec![7, top],
            vec![top, 0],
            vec![1, 2, 3],
            vec![top, 5, 9, 11, 4],
            vec![8, 6],
        ];
        let mut log = Log::with_capacity(cases.len());
        for (i, ts) in cases.iter().enumerate() {
            let c = log.begin(i as u32, 99, [0.0; 3], ts, 0.5);
            assert_eq!(c.removed.len(), ts.len());
            log.records.push(c);
        }
        for (c, ts) in log.records.iter().zip(&cases) {
            assert_eq!(log.removed(c), &ts[..]);
        }
        assert_eq!(log.more_removed.len(), 8);
        // popped newest first: the lists of 3 and 5 leave `more_removed`
        for ts in cases.iter().rev() {
            let c = log.pop().unwrap();
            assert_eq!(c.removed.len(), ts.len());
        }
        assert!(log.more_removed.is_empty());
    }
}
