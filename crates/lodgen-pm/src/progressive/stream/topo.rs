//! The topology both sides of the stream keep while replaying splits: the
//! triangle list and, per vertex, the triangles holding it. Faces of a split
//! are coded against the split vertex's ring, corner edits predicted from
//! the faces ([`predict_mask`]) or, where that misses, as a bit mask over
//! the corners it holds (after the new faces are appended).

use crate::progressive::Corner;
use smallvec::SmallVec;

/// A split's ring or held corners, inline (a fan has some six triangles:
/// one allocation per list and split was a tenth of a stream's encoding).
pub(super) type Small<T> = SmallVec<[T; 24]>;

/// A vertex's triangles, inline up to eight (most fans: one allocation
/// per vertex the splits add was the encoder's and decoder's largest
/// allocator traffic).
pub(super) type Fan = SmallVec<[u32; 8]>;

/// Face code for "the three corners follow in the escape column".
pub(super) const FACE_ESCAPE: u8 = 255;
/// Ring positions a one-byte face code can name (`6 · 42 = 252`).
const RING_CODES: usize = 42;
/// Where v0, v1 and the ring vertex x sit in a face, per permutation code.
const PERMS: [[usize; 3]; 6] = [
    [0, 1, 2],
    [1, 2, 0],
    [2, 0, 1],
    [1, 0, 2],
    [0, 2, 1],
    [2, 1, 0],
];

/// Triangles and vertex → triangle fans (each fan ascending, no repeats).
#[derive(Clone, Debug, Default)]
pub(super) struct Topo {
    pub fans: Vec<Fan>,
}

impl Topo {
    pub fn new(vertices: usize, triangles: &[[u32; 3]]) -> Topo {
        let mut fans = vec![Fan::new(); vertices];
        for (t, tri) in triangles.iter().enumerate() {
            for (i, &v) in tri.iter().enumerate() {
                if !tri[..i].contains(&v) {
                    fans[v as usize].push(t as u32);
                }
            }
        }
        Topo { fans }
    }

    /// The vertices sharing a triangle with `v`, ascending, `v` excluded.
    pub fn ring(&self, triangles: &[[u32; 3]], v: u32) -> Small<u32> {
        let mut ring: Small<u32> = self.fans[v as usize]
            .iter()
            .flat_map(|&t| triangles[t as usize])
            .filter(|&u| u != v)
            .collect();
        ring.sort_unstable();
        ring.dedup();
        ring
    }

    pub fn add_vertex(&mut self) {
        self.fans.push(Fan::new());
    }

    /// Append face `f` (its vertices exist).
    pub fn add_face(&mut self, triangles: &mut Vec<[u32; 3]>, f: [u32; 3]) {
        let t = triangles.len() as u32;
        triangles.push(f);
        for (i, &v) in f.iter().enumerate() {
            if !f[..i].contains(&v) {
                self.fans[v as usize].push(t);
            }
        }
    }

    /// Every corner holding `v`, ascending (triangle, slot).
    pub fn corners(&self, triangles: &[[u32; 3]], v: u32) -> Small<Corner> {
        let mut out = Small::new();
        for &t in &self.fans[v as usize] {
            for slot in 0..3u8 {
                if triangles[t as usize][slot as usize] == v {
                    out.push(Corner { triangle: t, slot });
                }
            }
        }
        out
    }

    /// Move corner `c` from `v1` (which it holds) to `v0`.
    pub fn move_corner(&mut self, triangles: &mut [[u32; 3]], c: Corner, v1: u32, v0: u32) {
        let tri = &mut triangles[c.triangle as usize];
        tri[c.slot as usize] = v0;
        if !tri.contains(&v1) {
            let fan = &mut self.fans[v1 as usize];
            if let Ok(i) = fan.binary_search(&c.triangle) {
                fan.remove(i);
            }
        }
        let fan = &mut self.fans[v0 as usize];
        if let Err(i) = fan.binary_search(&c.triangle) {
            fan.insert(i, c.triangle);
        }
    }
}

/// The one-byte code of face `f` of the split of `v1` into `v1`, `v0`, given
/// `v1`'s ring before the split, or [`FACE_ESCAPE`].
pub(super) fn face_code(f: [u32; 3], v0: u32, v1: u32, ring: &[u32]) -> u8 {
    for (p, perm) in PERMS.iter().enumerate() {
        if f[perm[0]] != v0 || f[perm[1]] != v1 {
            continue;
        }
        if let Ok(k) = ring.binary_search(&f[perm[2]]) {
            if k < RING_CODES {
                return (p + 6 * k) as u8;
            }
        }
    }
    FACE_ESCAPE
}

/// The face a non-escape code names, or `None` if the ring is too short.
pub(super) fn face_of(code: u8, v0: u32, v1: u32, ring: &[u32]) -> Option<[u32; 3]> {
    let (p, k) = (usize::from(code) % 6, usize::from(code) / 6);
    if k >= RING_CODES {
        return None;
    }
    let x = *ring.get(k)?;
    let mut f = [0; 3];
    let perm = PERMS[p];
    f[perm[0]] = v0;
    f[perm[1]] = v1;
    f[perm[2]] = x;
    Some(f)
}

/// The escape coding of one corner of a face: 0 = v0, 1 = v1, k ≥ 2 =
/// vertex `v0 − (k − 1)`.
pub(super) fn corner_code(c: u32, v0: u32, v1: u32) -> u32 {
    if c == v0 {
        0
    } else if c == v1 {
        1
    } else {
        v0 - c + 1
    }
}

pub(super) fn corner_of(code: u32, v0: u32, v1: u32) -> Option<u32> {
    match code {
        0 => Some(v0),
        1 => Some(v1),
        k => (k - 1 <= v0).then(|| v0 - (k - 1)),
    }
}

/// The indices (in `faces`) of a split's first two faces holding both `v0`
/// and `v1` and one other vertex, when both exist and their third vertices
/// differ: the split's wing faces.
pub(super) fn wing_faces(faces: &[[u32; 3]], v0: u32, v1: u32) -> Option<(usize, usize)> {
    let mut xs = faces.iter().enumerate().filter_map(|(i, f)| {
        let mut others = f.iter().copied().filter(|&c| c != v0 && c != v1);
        let x = others.next()?;
        (others.next().is_none() && f.contains(&v0) && f.contains(&v1)).then_some((i, x))
    });
    let (i, a) = xs.next()?;
    let (j, b) = xs.next()?;
    (a != b).then_some((i, j))
}

/// The prediction of a new vertex's grid point at the end of its chunk:
/// the centroid of its ring once its record is applied (`ring`: the
/// vertices sharing a triangle with it then, all lower-numbered, their
/// end-of-chunk points in `q`), each axis `⌊(2·Σ + n) / 2n⌋` (rounded half
/// up); `v1`'s point when the ring is empty.
pub(super) fn predict_new(q: &[[u16; 3]], ring: &[u32], v1: u32) -> [u16; 3] {
    if ring.is_empty() {
        return q[v1 as usize];
    }
    let n = ring.len() as u64;
    let mut sum = [0u64; 3];
    for &u in ring {
        for (s, &c) in sum.iter_mut().zip(&q[u as usize]) {
            *s += u64::from(c);
        }
    }
    sum.map(|s| ((2 * s + n) / (2 * n)) as u16)
}

/// The corner edits a split most likely makes, one flag per corner of
/// `held` (the corners at `v1` once the split's faces are appended, as
/// [`Topo::corners`] lists them): in an oriented manifold fan the new
/// faces' wings `x` cut `v1`'s old triangles in two arcs, and `v0` takes
/// the arc that starts at the old triangle whose edge with `x` runs the
/// same way as the new face's edge `x → v0` (`v1 → x`; or `x → v1` for a
/// face with `v0 → x`), spreading across edges `{v1, y}` with `y` no wing.
/// `first`: the first new triangle. A guess, right on most splits; the
/// stream codes the edits explicitly where it is wrong.
pub(super) fn predict_mask(
    triangles: &[[u32; 3]],
    fan: &[u32],
    first: u32,
    faces: &[[u32; 3]],
    (v0, v1): (u32, u32),
    held: &[Corner],
    out: &mut Vec<bool>,
) {
    let old: Small<u32> = fan.iter().copied().filter(|&t| t < first).collect();
    let mut taken: Small<bool> = smallvec::smallvec![false; old.len()];
    let mut wings: SmallVec<[u32; 2]> = SmallVec::new();
    let mut queue: Small<usize> = Small::new();
    for f in faces {
        if !(f.contains(&v0) && f.contains(&v1)) {
            continue;
        }
        let mut others = (0..3).filter(|&j| f[j] != v0 && f[j] != v1);
        let (Some(ix), None) = (others.next(), others.next()) else {
            continue;
        };
        let x = f[ix];
        wings.push(x);
        let (from, to) = if f[(ix + 1) % 3] == v0 {
            (v1, x)
        } else {
            (x, v1)
        };
        for (k, &t) in old.iter().enumerate() {
            let g = triangles[t as usize];
            if !taken[k] && (0..3).any(|j| g[j] == from && g[(j + 1) % 3] == to) {
                taken[k] = true;
                queue.push(k);
            }
        }
    }
    while let Some(k) = queue.pop() {
        for y in triangles[old[k] as usize] {
            if y == v1 || wings.contains(&y) {
                continue;
            }
            for (m, &u) in old.iter().enumerate() {
                if !taken[m] && triangles[u as usize].contains(&y) {
                    taken[m] = true;
                    queue.push(m);
                }
            }
        }
    }
    out.clear();
    out.extend(
        held.iter()
            .map(|c| old.binary_search(&c.triangle).is_ok_and(|k| taken[k])),
    );
}
