//! The topology both sides of the stream keep while replaying splits: the
//! triangle list and, per vertex, the triangles holding it. Faces of a split
//! are coded against the split vertex's ring, corner edits as a bit mask
//! over the corners it holds (after the new faces are appended).

use crate::progressive::Corner;

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
    pub fans: Vec<Vec<u32>>,
}

impl Topo {
    pub fn new(vertices: usize, triangles: &[[u32; 3]]) -> Topo {
        let mut fans = vec![Vec::new(); vertices];
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
    pub fn ring(&self, triangles: &[[u32; 3]], v: u32) -> Vec<u32> {
        let mut ring: Vec<u32> = self.fans[v as usize]
            .iter()
            .flat_map(|&t| triangles[t as usize])
            .filter(|&u| u != v)
            .collect();
        ring.sort_unstable();
        ring.dedup();
        ring
    }

    pub fn add_vertex(&mut self) {
        self.fans.push(Vec::new());
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
    pub fn corners(&self, triangles: &[[u32; 3]], v: u32) -> Vec<Corner> {
        let mut out = Vec::new();
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

/// The third vertices of the wing faces ([`wing_faces`]): the
/// parallelogram predictor's wings.
pub(super) fn wings(faces: &[[u32; 3]], v0: u32, v1: u32) -> Option<(u32, u32)> {
    let third = |f: &[u32; 3]| f.iter().copied().find(|&c| c != v0 && c != v1);
    let (i, j) = wing_faces(faces, v0, v1)?;
    Some((third(&faces[i])?, third(&faces[j])?))
}

/// The prediction of a new vertex's grid point at the end of its chunk:
/// the parallelogram `x_a + x_b − v1` of its wings when it has two, else
/// `2 · start − end` of `v1` when `v1` existed at the chunk's start (the
/// contraction put `v1` between the two), else `v1`'s point. `q` holds the
/// end-of-chunk points of every vertex below the new one. Wrapping `u16`
/// arithmetic: the residual is taken modulo 2^16.
pub(super) fn predict_new(
    q: &[[u16; 3]],
    wings: Option<(u32, u32)>,
    v1: u32,
    v1_start: Option<[u16; 3]>,
) -> [u16; 3] {
    let p1 = q[v1 as usize];
    match (wings, v1_start) {
        (Some((a, b)), _) => {
            let (a, b) = (q[a as usize], q[b as usize]);
            [0, 1, 2].map(|i| a[i].wrapping_add(b[i]).wrapping_sub(p1[i]))
        }
        (None, Some(s)) => [0, 1, 2].map(|i| s[i].wrapping_mul(2).wrapping_sub(p1[i])),
        (None, None) => p1,
    }
}
