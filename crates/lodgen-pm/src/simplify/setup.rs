//! Set-up (GH97 §4, §6.1): every vertex classified from its own fan
//! (interior, border, non-manifold or several fans: pinned) with its
//! quadric (face planes plus border constraint planes), the sorted edge
//! list, τ pairs, the greedy heap, and feature-edge constraint planes.

use super::{dv, Entry, Pass, Simplifier, Stats};
use crate::mesh::adjacency::{FanLookup, Fans};
use crate::mesh::Mesh;
use crate::progressive::Log;
use crate::simplify::features::Features;
use crate::simplify::heap::QuadHeap;
use crate::simplify::pairs;
use crate::simplify::quadric::Quadric;
use crate::simplify::{Boundary, Schedule, SimplifyOptions};
use glam::DVec3;
use rayon::prelude::*;
use smallvec::SmallVec;

impl Simplifier {
    /// The simplifier over `mesh` with every vertex classified and its
    /// quadric summed, and no pairs yet; with the sorted edge list (when
    /// the greedy heap or τ pairs need it) and τ.
    pub(super) fn classified(
        mesh: Mesh,
        opts: &SimplifyOptions,
    ) -> (Simplifier, Vec<(u32, u32)>, f64) {
        let nv = mesh.positions.len();
        let nt = mesh.triangles.len();
        let vtris = Fans::new(nv, &mesh.triangles, |_| true);
        let (quadric, boundary, mut corner, complex) = classify_all(&mesh, &vtris, opts);
        // A non-manifold vertex (on an edge of three or more faces, or
        // where several fans meet) follows the border corners' rule: it
        // never moves to a new position, but a neighbour may be pulled onto
        // it or it may be removed into a neighbour, along an edge of three
        // or more faces too when the link condition holds for it (a chain
        // of such edges shortens like a border line). It used to be locked,
        // then such edges were refused: beetle.obj (47 edges of three faces,
        // 45 such vertices) stopped at 181, then 166 triangles of its 2 %
        // (41) and its 10 % level had Hausdorff 5.64, then 4.24 % (`cargo
        // xtask quality --quick --meshes beetle`; 2.89 % now, see
        // docs/quality.md).
        for (c, &x) in corner.iter_mut().zip(&complex) {
            *c |= x;
        }
        let tau = opts.tau_for(mesh.diagonal());
        // Sorted edges (only the greedy heap and τ pairs need the list).
        let edges = if opts.schedule == Schedule::Greedy || tau > 0.0 {
            sorted_edges(&mesh, &vtris)
        } else {
            Vec::new()
        };

        let cost_unit = super::cost_unit(&mesh.positions);
        let mut s = Simplifier {
            opts: *opts,
            target: opts.target_for(nt),
            pos: mesh.positions,
            quadric,
            tris: mesh.triangles,
            tri_alive: vec![true; nt],
            vtris,
            partners: Vec::new(),
            version: if opts.schedule == Schedule::Greedy {
                vec![0; nv]
            } else {
                Vec::new()
            },
            alive: vec![true; nv],
            locked: vec![false; nv],
            boundary,
            corner,
            heap: QuadHeap::from_vec(Vec::new()),
            pass: Pass {
                spread_limit: f64::INFINITY,
                touched: vec![0; nv],
                ..Pass::default()
            },
            live_tris: nt,
            log: Log::with_capacity(nt / 2),
            stats: Stats {
                input_vertices: nv,
                input_triangles: nt,
                ..Stats::default()
            },
            mark: vec![0; nv],
            generation: 0,
            scratch: Vec::new(),
            fan_scratch: Vec::new(),
            plan_scratch: Vec::new(),
            cost_scale: None,
            cost_unit,
            features: None,
            attributes: None,
            meter: None,
            lifted: super::lift::Lifted::new(nv, opts.lift),
        };
        if opts.boundary == Boundary::Locked {
            for v in 0..nv {
                s.locked[v] |= s.boundary[v];
            }
        }
        s.stats.boundary_vertices = s.boundary.iter().filter(|&&b| b).count();
        s.stats.locked_vertices = (0..nv).filter(|&v| s.locked[v] || complex[v]).count();
        (s, edges, tau)
    }

    /// Find the non-edge pairs within `tau` (GH97 §3) and record them as
    /// partners; returns them.
    pub(super) fn find_partners(&mut self, edges: &[(u32, u32)], tau: f64) -> Vec<(u32, u32)> {
        let near = pairs::near_pairs(&self.pos, edges, tau);
        self.stats.near_pairs = near.len();
        if !near.is_empty() {
            self.partners = vec![Vec::new(); self.pos.len()];
        }
        for &(a, b) in &near {
            self.partners[a as usize].push(b);
            self.partners[b as usize].push(a);
        }
        near
    }

    /// [`Schedule::Greedy`]: cost every pair (edges, then τ pairs) with a
    /// vertex free to move into the heap.
    pub(super) fn fill_heap(&mut self, mut edges: Vec<(u32, u32)>, near: &[(u32, u32)]) {
        edges.extend_from_slice(near);
        let entries: Vec<Entry> = edges
            .par_iter()
            .filter(|&&(a, b)| !(self.locked[a as usize] && self.locked[b as usize]))
            .map(|&(a, b)| self.entry(a, b))
            .collect();
        self.heap = QuadHeap::from_vec(entries);
    }

    /// The open border edges `(a, b)`, `a < b`, sorted: the edges of one
    /// use, found in the fans of the vertices classified as on a border
    /// (sorting every edge of the mesh for them was 9 % of a bunny's
    /// simplification with wedges). Before the first contraction.
    pub(super) fn border_edges(&self) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        let mut nb: SmallVec<[u32; 32]> = SmallVec::new();
        for v in (0..self.pos.len() as u32).filter(|&v| self.boundary[v as usize]) {
            nb.clear();
            for &t in self.vtris.fan(v) {
                let tri = self.tris[t as usize];
                nb.extend(tri.iter().copied().filter(|&x| x > v));
            }
            nb.sort_unstable();
            for run in nb.chunk_by(|a, b| a == b) {
                if run.len() == 1 {
                    out.push((v, run[0]));
                }
            }
        }
        out
    }

    /// The interior edges `(a, b)`, `a < b`, sorted, across which the
    /// corner wedges `wedges` differ at either end (seams), from each
    /// vertex's fan (in parallel) instead of a sort of every edge. Before
    /// the first contraction.
    pub(super) fn seam_edges(&self, wedges: &[[u32; 3]]) -> Vec<(u32, u32)> {
        let wedge_at = |t: u32, v: u32| {
            let tri = self.tris[t as usize];
            let k = tri.iter().position(|&x| x == v).unwrap_or(0);
            wedges[t as usize][k]
        };
        (0..self.pos.len() as u32)
            .into_par_iter()
            .flat_map_iter(|v| {
                // (neighbour, triangle) for the neighbours above v
                let mut uses: SmallVec<[(u32, u32); 32]> = SmallVec::new();
                for &t in self.vtris.fan(v) {
                    let tri = self.tris[t as usize];
                    uses.extend(tri.iter().filter(|&&x| x > v).map(|&x| (x, t)));
                }
                uses.sort_unstable();
                let mut seams: SmallVec<[(u32, u32); 4]> = SmallVec::new();
                for run in uses.chunk_by(|a, b| a.0 == b.0) {
                    let (x, t0) = run[0];
                    let (w0, wx) = (wedge_at(t0, v), wedge_at(t0, x));
                    if run[1..]
                        .iter()
                        .any(|&(_, t)| wedge_at(t, v) != w0 || wedge_at(t, x) != wx)
                    {
                        seams.push((v, x));
                    }
                }
                seams
            })
            .collect()
    }

    pub(super) fn add_features(&mut self, edges: &[(u32, u32)]) {
        let nv = self.pos.len();
        let mut f = self
            .features
            .take()
            .unwrap_or_else(|| Features::with_borders(nv, &self.border_edges()));
        let weight = match self.opts.boundary {
            Boundary::Weighted(w) => w,
            Boundary::Locked => crate::simplify::DEFAULT_BOUNDARY_WEIGHT,
        };
        for &(a, b) in edges {
            if a as usize >= nv || b as usize >= nv {
                continue;
            }
            let faces: SmallVec<[u32; 2]> = self
                .vtris
                .fan(a)
                .iter()
                .copied()
                .filter(|&t| self.tri_alive[t as usize] && self.tris[t as usize].contains(&b))
                .collect();
            if faces.is_empty() || !f.add(a, b) {
                continue;
            }
            let (pa, pb) = (dv(self.pos[a as usize]), dv(self.pos[b as usize]));
            let e = pb - pa;
            let w = weight
                * if self.opts.area_weighted {
                    e.length_squared()
                } else {
                    1.0
                };
            for t in faces {
                let c = e.cross(face_normal(&self.pos, &self.tris[t as usize]));
                let len = c.length();
                if len > 0.0 && w > 0.0 {
                    let c = c / len;
                    let q = Quadric::from_plane(c, -c.dot(pa), w);
                    let q = Quadric { weight: 0.0, ..q };
                    self.quadric[a as usize] += q;
                    self.quadric[b as usize] += q;
                }
            }
        }
        self.features = Some(f);
    }
}

/// Every vertex's quadric, border, corner and non-manifold flags, from its own fan
/// (in parallel): border and non-manifold edges, fans, and its quadric.
fn classify_all(
    mesh: &Mesh,
    vtris: &Fans,
    opts: &SimplifyOptions,
) -> (Vec<Quadric>, Vec<bool>, Vec<bool>, Vec<bool>) {
    let nv = mesh.positions.len();
    let boundary_weight = match opts.boundary {
        Boundary::Weighted(w) => w,
        Boundary::Locked => 0.0,
    };
    // Each face's plane is made at each of its corners, not once into a
    // list: the same values (so the same sums), for a few more square
    // roots and divisions, where the list (40 bytes per triangle) was the
    // peak of a large run's preparation (bunny-4m: 178 MB over the 461 MB
    // the simplifier then holds).
    type Flags = (Vec<bool>, (Vec<bool>, Vec<bool>));
    let (quadric, (boundary, (corner, complex))): (Vec<Quadric>, Flags) = (0..nv as u32)
        .into_par_iter()
        .map(|v| {
            let i = classify_vertex(mesh, vtris.fan(v), v, opts, boundary_weight);
            (i.quadric, (i.boundary, (i.corner, i.complex)))
        })
        .unzip();
    (quadric, boundary, corner, complex)
}

/// Every edge `(a, b)`, `a < b`, once, sorted.
fn sorted_edges(mesh: &Mesh, vtris: &Fans) -> Vec<(u32, u32)> {
    (0..mesh.positions.len() as u32)
        .into_par_iter()
        .flat_map_iter(|v| {
            let mut nb: SmallVec<[u32; 32]> = SmallVec::new();
            for &t in vtris.fan(v) {
                nb.extend(
                    mesh.triangles[t as usize]
                        .iter()
                        .copied()
                        .filter(|&x| x > v),
                );
            }
            nb.sort_unstable();
            nb.dedup();
            nb.into_iter().map(move |x| (v, x))
        })
        .collect()
}

/// One vertex's classification and quadric (`Simplifier::new`).
struct VertexInfo {
    quadric: Quadric,
    /// On an open border edge.
    boundary: bool,
    /// On a border that turns by more than [`BORDER_CORNER_COS`] there
    /// (or ends, or has more than two border edges).
    corner: bool,
    /// On a non-manifold edge, or where several fans meet.
    complex: bool,
}

/// Classify `v` from its fan `ts`: each edge `(v, x)` is a border (one
/// use), interior (one use in each direction) or non-manifold (anything
/// else); interior edges join the fan's triangles, and more than one fan
/// makes `v` non-manifold too. The quadric sums `v`'s face planes and, for each
/// border edge, the constraint plane through it (GH97 §6.1).
fn classify_vertex(
    mesh: &Mesh,
    ts: &[u32],
    v: u32,
    opts: &SimplifyOptions,
    boundary_weight: f64,
) -> VertexInfo {
    let mut quadric = Quadric::default();
    for &t in ts {
        let [nx, ny, nz, d, w] = face_plane(
            &mesh.positions,
            &mesh.triangles[t as usize],
            opts.area_weighted,
        );
        if w > 0.0 {
            quadric += Quadric::from_plane(DVec3::new(nx, ny, nz), d, w);
        }
    }
    // each triangle's two other corners, in winding order: the edge to the
    // first leaves v, the edge from the second enters it
    let others = |t: u32| {
        let [a, b, c] = mesh.triangles[t as usize];
        if a == v {
            (b, c)
        } else if b == v {
            (c, a)
        } else {
            (a, b)
        }
    };
    if ts.len() <= DISK_MAX {
        let (mut leave, mut enter) = ([u32::MAX; DISK_MAX], [u32::MAX; DISK_MAX]);
        for (i, &t) in ts.iter().enumerate() {
            (leave[i], enter[i]) = others(t);
        }
        if closed_disk(&leave, &enter, ts.len()) {
            // the usual interior vertex: no border, one fan
            return VertexInfo {
                quadric,
                boundary: false,
                corner: false,
                complex: false,
            };
        }
    }
    // neighbour << 32 | (1 = edge leaves v) << 31 | fan slot: one integer
    // per use sorts as the tuple (neighbour, direction, slot) would
    let mut uses: SmallVec<[u64; 32]> = SmallVec::new();
    let edge_use =
        |x: u32, leaves: u64, slot: usize| u64::from(x) << 32 | leaves << 31 | slot as u64;
    for (i, &t) in ts.iter().enumerate() {
        let (l, e) = others(t);
        uses.push(edge_use(l, 1, i));
        uses.push(edge_use(e, 0, i));
    }
    uses.sort_unstable();
    let mut parent: SmallVec<[u32; 16]> = (0..ts.len() as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    let (mut boundary, mut complex) = (false, false);
    // unit directions of the border edges (up to three: more is a corner)
    let mut border_dirs: SmallVec<[DVec3; 3]> = SmallVec::new();
    let neighbour = |u: u64| (u >> 32) as u32;
    let leaves = |u: u64| u >> 31 & 1;
    let slot = |u: u64| (u & 0x7fff_ffff) as u32;
    for run in uses.chunk_by(|&a, &b| neighbour(a) == neighbour(b)) {
        match *run {
            [u] => {
                let (x, s) = (neighbour(u), slot(u));
                boundary = true;
                if border_dirs.len() < 3 {
                    let d = dv(mesh.positions[x as usize]) - dv(mesh.positions[v as usize]);
                    border_dirs.push(d.normalize_or_zero());
                }
                if boundary_weight > 0.0 {
                    let t = mesh.triangles[ts[s as usize] as usize];
                    if let Some(q) = border_plane(mesh, &t, v, x, opts, boundary_weight) {
                        quadric += q;
                    }
                }
            }
            [a, b] if leaves(a) != leaves(b) => {
                let (ra, rb) = (root(&mut parent, slot(a)), root(&mut parent, slot(b)));
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
            _ => complex = true,
        }
    }
    if !complex {
        let fans = (0..ts.len() as u32)
            .filter(|&i| root(&mut parent, i) == i)
            .count();
        complex = fans > 1;
    }
    // straight enough: two border edges going on nearly opposite ways
    let straight = matches!(*border_dirs, [a, b] if a.dot(b) <= -BORDER_CORNER_COS);
    VertexInfo {
        quadric,
        boundary,
        corner: boundary && !straight,
        complex,
    }
}

/// The constraint plane of the border edge `(v, x)` of triangle `t`: through
/// the edge, perpendicular to the face, weighted by `boundary_weight` (times
/// the edge's squared length when area-weighted); `None` for a degenerate
/// face. It shapes the cost, not the mean-distance normalisation (weight 0).
fn border_plane(
    mesh: &Mesh,
    t: &[u32; 3],
    v: u32,
    x: u32,
    opts: &SimplifyOptions,
    boundary_weight: f64,
) -> Option<Quadric> {
    let (pa, pb) = (
        dv(mesh.positions[v as usize]),
        dv(mesh.positions[x as usize]),
    );
    let e = pb - pa;
    let c = e.cross(face_normal(&mesh.positions, t));
    let len = c.length();
    if len <= 0.0 {
        return None;
    }
    let c = c / len;
    let w = boundary_weight
        * if opts.area_weighted {
            e.length_squared()
        } else {
            1.0
        };
    Some(Quadric {
        weight: 0.0,
        ..Quadric::from_plane(c, -c.dot(pa), w)
    })
}

/// A border vertex whose two border edges turn by more than
/// `acos(BORDER_CORNER_COS)` (45°) is a border corner: it never moves (an
/// interior or border neighbour is pulled onto it), while the others take
/// optimal placement held to the border by its constraint planes. Pinning
/// every border vertex (half-edge) cost error wherever there are borders
/// (teapot 10 % Hausdorff 0.86 → 0.60 %, 2 % 3.47 → 2.31 % of the
/// diagonal, beetle 10 % RMS 1.48 → 1.21 %, `cargo xtask quality
/// --quick`; meshes without borders unchanged); letting corners move too
/// made them creep (the `square_with_a_border_keeps_the_border_in_place`
/// test).
pub(super) const BORDER_CORNER_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Fans up to this size are tried with [`closed_disk`] first.
const DISK_MAX: usize = 16;

/// Whether the first `d` triangles of a fan, triangle `i` leaving `v`
/// towards `leave[i]` and entering it from `enter[i]` (the rest of both
/// arrays `u32::MAX`), make one closed disk: each neighbour left once and
/// entered once (so every edge is interior), and "the triangle entering
/// from where triangle `i` leaves to" is one cycle through all `d` (one
/// fan). The general path of `classify_vertex` (sorting the edge uses)
/// gives the same answer; this is the quick one for the usual vertex, and
/// `false` leaves the vertex to the general path.
fn closed_disk(leave: &[u32; DISK_MAX], enter: &[u32; DISK_MAX], d: usize) -> bool {
    if d < 2 {
        return false;
    }
    // next[i]: the (sum of the) triangles entering from leave[i], and how
    // many there are; without branches, so that it vectorises
    let mut next = [0u32; DISK_MAX];
    let mut single = true;
    for i in 0..d {
        let (mut count, mut at) = (0u32, 0u32);
        for (j, &e) in enter.iter().enumerate() {
            let hit = u32::from(e == leave[i]);
            count += hit;
            at += hit * j as u32;
        }
        single &= count == 1;
        next[i] = at;
    }
    if !single {
        return false;
    }
    // one entering triangle each: `next` is a function on 0..d, and a
    // cycle through all d from 0 makes it a bijection (leaves distinct,
    // and with one match each, enters distinct too)
    let mut i = 0;
    for _ in 1..d {
        i = next[i] as usize;
        if i == 0 {
            return false;
        }
    }
    next[i] == 0
}

/// A face's plane `[n.x, n.y, n.z, d, weight]` (unit normal, `n·x + d =
/// 0`), weight 0 when the face has no area.
type Plane = [f64; 5];

/// The plane of triangle `t`, weighted by its area or 1.
fn face_plane(positions: &[[f32; 3]], t: &[u32; 3], area_weighted: bool) -> Plane {
    let [p0, p1, p2] = t.map(|x| dv(positions[x as usize]));
    let n = (p1 - p0).cross(p2 - p0);
    let len = n.length();
    if len > 0.0 {
        let unit = n / len;
        let w = if area_weighted { 0.5 * len } else { 1.0 };
        [unit.x, unit.y, unit.z, -unit.dot(p0), w]
    } else {
        [0.0; 5]
    }
}

pub(super) fn face_normal(positions: &[[f32; 3]], t: &[u32; 3]) -> DVec3 {
    let [p0, p1, p2] = t.map(|v| dv(positions[v as usize]));
    (p1 - p0).cross(p2 - p0).normalize_or_zero()
}
#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A fan around vertex 0 as `(leave, enter)` per triangle: kind 0 a
    /// closed disk, 1 two disks on distinct neighbours, 2 a disk with one
    /// triangle turned over, 3 an open fan (a border), 4 random corners
    /// from a few neighbours; then shuffled.
    fn fan(kind: u8, d: usize, seed: u64) -> Vec<(u32, u32)> {
        let mut rng = seed | 1;
        let mut next = move || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            rng
        };
        let ring = |n: usize, base: u32| -> Vec<(u32, u32)> {
            (0..n as u32)
                .map(|i| (base + i, base + (i + 1) % n as u32))
                .collect()
        };
        let mut f = match kind {
            0 => ring(d, 1),
            1 => [ring(d.max(4) / 2, 1), ring(d.max(4) - d.max(4) / 2, 100)].concat(),
            2 => {
                let mut f = ring(d, 1);
                let (l, e) = f[0];
                f[0] = (e, l);
                f
            }
            3 => ring(d + 1, 1)[..d].to_vec(),
            _ => (0..d)
                .map(|_| {
                    let l = 1 + (next() % 5) as u32;
                    (l, 1 + (l + (next() % 4) as u32) % 5)
                })
                .collect(),
        };
        for i in (1..f.len()).rev() {
            f.swap(i, (next() % (i as u64 + 1)) as usize);
        }
        f
    }

    /// What a closed disk is, by counting: every neighbour left once and
    /// entered once, and the triangles joined across shared edges are one
    /// component.
    fn is_closed_disk(f: &[(u32, u32)]) -> bool {
        let n = |x: u32, side: fn(&(u32, u32)) -> u32| f.iter().filter(|t| side(t) == x).count();
        let edges_ok = f.iter().all(|&(l, e)| {
            n(l, |t| t.0) == 1 && n(l, |t| t.1) == 1 && n(e, |t| t.0) == 1 && n(e, |t| t.1) == 1
        });
        let mut comp: Vec<usize> = (0..f.len()).collect();
        for _ in 0..f.len() {
            for i in 0..f.len() {
                for j in 0..f.len() {
                    if f[i].0 == f[j].1 {
                        let m = comp[i].min(comp[j]);
                        (comp[i], comp[j]) = (m, m);
                    }
                }
            }
        }
        edges_ok && f.len() >= 2 && comp.iter().all(|&c| c == 0)
    }

    /// `border_edges` (from the fans of border vertices) is the sorted list
    /// of edges of one use, as sorting every edge finds it: on meshes with
    /// open borders, edges of three faces and several fans at a vertex.
    /// Fails if a border vertex is skipped, a neighbour counted twice per
    /// triangle, or the order differs.
    #[test]
    fn border_edges_are_the_edges_of_one_use() {
        use crate::shapes;
        use crate::simplify::features::sorted_borders;
        let mut fin = shapes::grid(6, 5, |x, y| 0.1 * x * y);
        let n = fin.positions.len() as u32;
        // a fin on the grid's edge 0–1 (an edge of three faces) and a
        // triangle touching the grid at vertex 8 only (two fans there)
        fin.positions
            .extend([[0.1, 0.0, 1.0], [2.0, 2.0, 1.0], [2.5, 2.0, 1.0]]);
        fin.triangles.push([0, 1, n]);
        fin.triangles.push([8, n + 1, n + 2]);
        let meshes = [
            shapes::grid(7, 4, |x, _| x),
            shapes::cube([0.0; 3], [1.0; 3], 3),
            shapes::icosphere(1),
            fin,
        ];
        for (i, m) in meshes.iter().enumerate() {
            let s = Simplifier::new(m, &SimplifyOptions::DEFAULT).unwrap();
            let expected = sorted_borders(&m.triangles);
            assert_eq!(s.border_edges(), expected, "mesh {i}");
            assert_eq!(expected.is_empty(), i == 1 || i == 2, "mesh {i}");
        }
    }

    /// A wedge per corner: its vertex's, or (one corner in `one_in`, xorshift from `rng`) a
    /// wedge of its own (`v + 1000`), so that runs of corners agree and differ.
    fn random_wedges(m: &crate::Mesh, rng: &mut u64, one_in: u64) -> Vec<[u32; 3]> {
        let mut next = || {
            *rng ^= *rng << 13;
            *rng ^= *rng >> 7;
            *rng ^= *rng << 17;
            *rng
        };
        let tris = m.triangles.iter();
        tris.map(|t| t.map(|v| if next() % one_in == 0 { v + 1000 } else { v }))
            .collect()
    }

    /// `seam_edges` (from the fans) is the sorted list of interior edges
    /// whose wedges differ, as sorting every edge finds it: random wedges
    /// (from few ids, so runs agree and differ) on meshes with borders and
    /// an edge of three faces. Fails if a run's comparison, the order or a
    /// border edge's handling differs.
    #[test]
    fn seam_edges_are_the_edges_whose_wedges_differ() {
        use crate::shapes;
        use crate::simplify::features::Features;
        let mut fin = shapes::grid(6, 5, |x, y| 0.1 * x * y);
        let n = fin.positions.len() as u32;
        fin.positions.push([0.1, 0.0, 1.0]);
        fin.triangles.push([0, 1, n]);
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        for (i, m) in [shapes::icosphere(2), shapes::grid(9, 7, |x, _| x), fin]
            .iter()
            .enumerate()
        {
            let wedges = random_wedges(m, &mut rng, 8);
            let s = Simplifier::new(m, &SimplifyOptions::DEFAULT).unwrap();
            let expected = Features::seams(&m.triangles, &wedges);
            assert!(!expected.is_empty(), "mesh {i}");
            assert_eq!(s.seam_edges(&wedges), expected, "mesh {i}");
        }
    }

    /// Every edge across which the live triangles' wedges differ stays a feature edge through a
    /// whole run, also where the end of a seam (one feature edge) is removed and its corners
    /// take the other end's wedges (`Features::mark_seams`): random wedges (many seam ends) on
    /// a sphere and a grid, checked after every contraction. Fails when a removed end leaves
    /// a seam that no feature edge holds.
    #[test]
    fn seams_stay_feature_edges_when_their_ends_go() {
        use crate::shapes;
        use crate::simplify::features::Features;
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut ends_removed = 0;
        for (i, m) in [shapes::icosphere(2), shapes::grid(9, 7, |x, y| 0.1 * x * y)]
            .iter()
            .enumerate()
        {
            let wedges = random_wedges(m, &mut rng, 6);
            let mut s =
                Simplifier::new(m, &SimplifyOptions::DEFAULT.with_target_triangles(8)).unwrap();
            s.set_wedges(wedges);
            loop {
                let f = s.features.as_ref().expect("seams");
                let ends: Vec<bool> = (0..s.pos.len() as u32).map(|v| f.is_end(v)).collect();
                let before = s.stats.collapses;
                if s.step().is_err() {
                    break;
                }
                let f = s.features.as_ref().expect("seams");
                let last = s.log.records.last().expect("a record");
                if s.stats.collapses > before && ends[last.v0 as usize] {
                    ends_removed += 1;
                }
                let live: Vec<usize> = (0..s.tris.len()).filter(|&t| s.tri_alive[t]).collect();
                let tris: Vec<[u32; 3]> = live.iter().map(|&t| s.tris[t]).collect();
                let w = f.wedges.as_ref().expect("wedges per corner");
                let wedges: Vec<[u32; 3]> = live.iter().map(|&t| w[t]).collect();
                for (a, b) in Features::seams(&tris, &wedges) {
                    assert!(f.nbrs[a].contains(&b), "mesh {i}: seam {a}–{b} not held");
                }
            }
        }
        assert!(ends_removed > 0, "no seam end was removed");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// `closed_disk` is the quick path of `classify_vertex`: it must say
        /// "closed disk" exactly when the fan is one.
        #[test]
        fn closed_disk_is_exactly_a_closed_disk(kind in 0u8..5, d in 1usize..=DISK_MAX, seed in any::<u64>()) {
            let f = fan(kind, d, seed);
            prop_assume!(f.len() <= DISK_MAX);
            let (mut leave, mut enter) = ([u32::MAX; DISK_MAX], [u32::MAX; DISK_MAX]);
            for (i, &(l, e)) in f.iter().enumerate() {
                (leave[i], enter[i]) = (l, e);
            }
            prop_assert_eq!(closed_disk(&leave, &enter, f.len()), is_closed_disk(&f), "{:?}", f);
        }
    }
}
