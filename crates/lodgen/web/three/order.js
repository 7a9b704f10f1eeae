// A vertex-cache-friendly draw order for a replayed LODGEN_progressive
// index state (used by index.js; docs/performance.md, "Stream bench
// (issue 18, session 22)").
//
// The stream appends each split's faces where the split comes, so the
// finest level's triangles come in split order, scattered over the surface
// (bunny-1m: 2.2 vertices shaded per triangle with a 16-entry FIFO, against
// 0.69 for the plain file's meshopt order; SwiftShader draws it ~2× slower).
// The splits form a forest: record i's vertex v0 = baseVertices + i is a
// child of the vertex it splits, v1[i], and the base vertices are its roots
// in their own order (the coarsest level's, which the writer ordered for
// the vertex cache). A depth-first preorder of that forest numbers each
// subtree, a patch of the surface around its root at every scale, in one
// run; drawing each triangle at the rank of its first-visited vertex (a
// counting sort, O(vertices + triangles)) gives bunny-1m 0.91 vertices per
// triangle (full Morton order of the centroids: 0.92).

// The first `nt` triangles of `tri` (vertex ids, 3 per triangle) after
// the first `records` splits of a stream with `baseVertices` base vertices
// and split vertices `v1`, written into `out` (at least 3 * nt long) in
// that order: each triangle once, its corners as in `tri`. `out` is
// returned.
export function splitTreeOrder(tri, nt, v1, baseVertices, records, out) {
  const nv = baseVertices + records;
  // subtree sizes: a vertex's children are later records (their v1 is
  // it), so one pass from the last record adds each subtree, finished, to
  // its parent's (one more entry: the counting sort's below)
  const size = new Uint32Array(nv + 1).fill(1);
  for (let i = records - 1; i >= 0; i--) size[v1[i]] += size[baseVertices + i];
  // preorder ranks: roots in their order, each vertex before its subtree,
  // its children's subtrees latest split first (it holds the finest patch
  // next to its parent): in record order, each child takes the last free
  // run of its parent's range (end: one past it)
  const rank = new Uint32Array(nv), end = new Uint32Array(nv);
  for (let v = 0, r = 0; v < baseVertices; v++) {
    rank[v] = r;
    r += size[v];
    end[v] = r;
  }
  for (let i = 0; i < records; i++) {
    const p = v1[i], v = baseVertices + i, r = end[p] - size[v];
    end[p] = r;
    rank[v] = r;
    end[v] = r + size[v];
  }
  // triangles by the smallest rank of their corners (a counting sort, stable)
  const key = new Uint32Array(nt), start = size;
  start.fill(0);
  for (let t = 0, o = 0; t < nt; t++, o += 3) {
    const a = rank[tri[o]], b = rank[tri[o + 1]], c = rank[tri[o + 2]];
    const k = a < b ? (a < c ? a : c) : b < c ? b : c;
    key[t] = k;
    start[k + 1]++;
  }
  for (let v = 0; v < nv; v++) start[v + 1] += start[v];
  for (let t = 0, o = 0; t < nt; t++, o += 3) {
    const p = 3 * start[key[t]]++;
    out[p] = tri[o];
    out[p + 1] = tri[o + 1];
    out[p + 2] = tri[o + 2];
  }
  return out;
}

// An index array for `n` indices into `vertices` vertices: 16-bit when
// every index fits below 65535 (WebGL2 restarts primitives at 0xffff), as
// glTF files of such meshes store them (the plain file's draw uploads half
// the index bytes a 32-bit one would), else 32-bit.
export function indexArray(vertices, n) {
  return vertices <= 65535 ? new Uint16Array(n) : new Uint32Array(n);
}
