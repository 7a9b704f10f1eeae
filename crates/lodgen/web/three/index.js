// lodgen-three: stream a lodgen GLB's LODGEN_progressive vertex splits into
// three.js (docs/LODGEN_progressive.md).
//
//   import { loadProgressive, coverageDistance } from "lodgen-three";
//   import { MeshoptDecoder } from "meshoptimizer";
//   const loader = new GLTFLoader().setMeshoptDecoder(MeshoptDecoder);
//   const p = await loadProgressive("model.glb", { loader, meshoptDecoder: MeshoptDecoder });
//   scene.add(p.gltf.scene);                    // the coarsest level, at once
//   p.addEventListener("level", (e) => render()); // e.level (finest = 0), e.triangles
//   p.addEventListener("prepare", () => render()); // optional (see prepare)
//   await p.refine();                           // or p.refine(level): stop at a level
//
// loadProgressive reads the file from its start in one request, as the
// bytes arrive: the GLB header and JSON, the data no level owns (images),
// the coarsest MSFT_lod level, which
// GLTFLoader parses at once (a GLTFLoader plugin finds the primitive
// carrying LODGEN_progressive), and, where lodgen puts it right behind, the
// stream up to the `prefetch` level; then it lets the rest of the file go.
// `refine` gives the mesh a BufferGeometry sized for the finest level once
// the stream's base is in, fetches any chunk still missing in one range
// request, and applies each level (decoded as its bytes arrive) with update
// ranges, dispatching a "level" event per level (a level waits up to
// `holdMs` for the next ones the line brings by then: one frame for them).
// The stream is decoded in a module worker (worker.js, remote.js: the
// page forwards its bytes, the worker posts records, positions and the
// draw order as transferable arrays), or on the main thread (`worker:
// false`, or no Web Workers).
// `refineForScreen(camera, renderer)` refines to the level the file's
// MSFT_screencoverage asks for at the object's current size on screen.
//
// coverageDistance({ camera, radius }) is a `calculateDistance` hook for
// three-gltf-extensions' MSFT_lod plugin that honours MSFT_screencoverage.

import {
  BufferAttribute,
  BufferGeometry,
  EventDispatcher,
  Sphere,
  Vector3,
} from "three";
import { StreamDecoder, parseHeader } from "./lgpm.js";
import { indexArray, splitTreeOrder } from "./order.js";
import { RemoteDecoder } from "./remote.js";

const EXTENSION = "LODGEN_progressive";

// Screen coverage as MSFT_lod defines it (projected bounding-sphere area /
// screen area) of a sphere of `radius` at `distance` from a perspective camera.
export function screenCoverage(camera, radius, distance) {
  const r = radius / (Math.max(distance, 1e-12) * Math.tan((camera.fov * Math.PI) / 360));
  return Math.min(1, (Math.PI * r * r) / (4 * camera.aspect));
}

// The distance at which a sphere of `radius` covers `coverage` of the screen.
export function distanceForCoverage(camera, radius, coverage) {
  const r = Math.sqrt((4 * camera.aspect * coverage) / Math.PI);
  return radius / (Math.tan((camera.fov * Math.PI) / 360) * r);
}

// calculateDistance hook for three-gltf-extensions' GLTFLodExtension: level
// L (finest = 0) takes over where the coverage drops below the finer level's
// MSFT_screencoverage value, for a bounding sphere of `radius` seen by
// `camera` (perspective; the distances are computed once, for its current
// fov and aspect).
export function coverageDistance({ camera, radius }) {
  return (level, lowestLevel, coverages) => {
    if (level === 0) return 0;
    const c = coverages[level - 1];
    if (!(c > 0)) return Infinity;
    return distanceForCoverage(camera, radius, c);
  };
}

async function fetchRange(url, start, end, fetchOptions) {
  const resp = await fetch(url, { ...fetchOptions, headers: { Range: `bytes=${start}-${end - 1}` } });
  if (resp.status !== 206 && resp.status !== 200) throw new Error(`${url}: HTTP ${resp.status}`);
  const bytes = new Uint8Array(await resp.arrayBuffer());
  // a server that ignores ranges sends the whole file
  return resp.status === 200 ? bytes.subarray(start, end) : bytes;
}

// The file read from its start in one request (`bytes=0-`), as the bytes
// arrive: `until(n)` waits for the first n bytes (fewer at the end of the
// file), `bytes` holds what came so far; `cancel()` lets the rest go.
class FileStart {
  constructor(url, fetchOptions) {
    this.url = url;
    this.bytes = new Uint8Array(65536);
    this.have = 0;
    this.done = false;
    this.reader = fetch(url, { ...fetchOptions, headers: { Range: "bytes=0-" } }).then((resp) => {
      if (resp.status !== 206 && resp.status !== 200) throw new Error(`${url}: HTTP ${resp.status}`);
      return resp.body.getReader();
    });
  }
  // the next piece of the body (null at its end), not kept in `bytes`
  async next() {
    if (this.done) return null;
    const { done, value } = await (await this.reader).read();
    if (done) { this.done = true; return null; }
    return value;
  }
  async until(n) {
    while (this.have < n) {
      const v = await this.next();
      if (!v) break;
      if (this.have + v.length > this.bytes.length) {
        const b = new Uint8Array(Math.max(2 * this.bytes.length, this.have + v.length));
        b.set(this.bytes.subarray(0, this.have));
        this.bytes = b;
      }
      this.bytes.set(v, this.have);
      this.have += v.length;
    }
    return this.bytes.subarray(0, this.have);
  }
  cancel() {
    this.done = true;
    this.reader.then((r) => r.cancel(), () => {});
  }
}

// GLB header + JSON from the start of the file: {json, binStart, binLength}.
async function readGlbJson(file) {
  const head = await file.until(20);
  const dv = new DataView(head.buffer, head.byteOffset, Math.min(head.length, 20));
  if (head.length < 20 || dv.getUint32(0, true) !== 0x46546c67) throw new Error(`${file.url}: not a GLB`);
  const jsonLength = dv.getUint32(12, true);
  const all = await file.until(28 + jsonLength);
  if (all.length < 28 + jsonLength) throw new Error(`${file.url}: the GLB ends in its JSON chunk`);
  const json = JSON.parse(new TextDecoder().decode(all.subarray(20, 20 + jsonLength)));
  const tail = new DataView(all.buffer, all.byteOffset + 20 + jsonLength, 8);
  return { json, binStart: 20 + jsonLength + 8, binLength: tail.getUint32(0, true) };
}

// The extension, its mesh, and the MSFT_lod chain node that shows the finest level.
function findExtension(json) {
  for (let m = 0; m < (json.meshes || []).length; m++) {
    const prims = json.meshes[m].primitives || [];
    for (let p = 0; p < prims.length; p++) {
      const ext = prims[p].extensions && prims[p].extensions[EXTENSION];
      if (!ext) continue;
      const nodes = json.nodes || [];
      let lodNode = -1, chain = null;
      nodes.forEach((n, i) => {
        const lod = n.extensions && n.extensions.MSFT_lod;
        if (!lod) return;
        const ids = [i, ...lod.ids];
        if (ids.some((id) => nodes[id] && nodes[id].mesh === m)) { lodNode = i; chain = ids; }
      });
      return { mesh: m, primitive: p, ext, lodNode, chain };
    }
  }
  return null;
}

// Byte range [lo, hi) of buffer 0 holding everything `mesh`'s primitives read.
function meshRange(json, mesh) {
  let lo = Infinity, hi = 0;
  const view = (v) => {
    const bv = json.bufferViews[v];
    const mo = bv.extensions && bv.extensions.EXT_meshopt_compression;
    const src = mo && json.buffers[mo.buffer].uri === undefined ? mo : bv;
    if (src.buffer !== 0) return;
    lo = Math.min(lo, src.byteOffset || 0);
    hi = Math.max(hi, (src.byteOffset || 0) + src.byteLength);
  };
  for (const prim of json.meshes[mesh].primitives) {
    const accessors = [...Object.values(prim.attributes), prim.indices].filter((a) => a !== undefined);
    for (const a of accessors) if (json.accessors[a].bufferView !== undefined) view(json.accessors[a].bufferView);
  }
  return lo < hi ? [lo, hi] : [0, 0];
}

function glb(json, bin) {
  let jsonBytes = new TextEncoder().encode(JSON.stringify(json));
  const pad = (n) => (4 - (n % 4)) % 4;
  const jl = jsonBytes.length + pad(jsonBytes.length);
  const bl = bin.length + pad(bin.length);
  const out = new Uint8Array(12 + 8 + jl + 8 + bl);
  const dv = new DataView(out.buffer);
  dv.setUint32(0, 0x46546c67, true);
  dv.setUint32(4, 2, true);
  dv.setUint32(8, out.length, true);
  dv.setUint32(12, jl, true);
  dv.setUint32(16, 0x4e4f534a, true);
  out.set(jsonBytes, 20);
  out.fill(0x20, 20 + jsonBytes.length, 20 + jl);
  dv.setUint32(20 + jl, bl, true);
  dv.setUint32(24 + jl, 0x004e4942, true);
  out.set(bin, 28 + jl);
  return out.buffer;
}

// The GLTFLoader plugin: remembers the three.js Mesh of the primitive that
// carries the extension.
class LodgenProgressivePlugin {
  constructor(parser, found, onMesh) {
    this.name = EXTENSION;
    this.parser = parser;
    this.found = found;
    this.onMesh = onMesh;
  }
  afterRoot(gltf) {
    const { mesh, primitive } = this.found;
    let target = null;
    gltf.scene.traverse((o) => {
      const a = this.parser.associations.get(o);
      if (o.isMesh && a && a.meshes === mesh && (a.primitives === undefined || a.primitives === primitive)) target = target || o;
    });
    // the stream holds every primitive of the mesh: hide the others
    gltf.scene.traverse((o) => {
      const a = this.parser.associations.get(o);
      if (o.isMesh && o !== target && a && a.meshes === mesh) o.visible = false;
    });
    this.onMesh(target);
    return null;
  }
}

// A loaded progressive GLB: the scene (coarsest level) and the stream.
export class ProgressiveMesh extends EventDispatcher {
  constructor({ url, fetchOptions, meshoptDecoder, json, binStart, found, worker }) {
    super();
    this.url = url;
    this.fetchOptions = fetchOptions;
    this.found = found;
    this.json = json;
    this.binStart = binStart;
    this.meshoptDecoder = meshoptDecoder;
    this.goal = 0; // the records refine stops at (the furthest asked for)
    this.spentPushing = 0; // main-thread ms in decoder.push
    this.useDecoder(worker ? new RemoteDecoder(worker.worker, worker) : new StreamDecoder(meshoptDecoder));
    this.drawOrder = null; // {records, index}: the triangles in draw order
    const bv = json.bufferViews[found.ext.bufferView];
    this.streamStart = binStart + (bv.byteOffset || 0);
    this.streamLength = bv.byteLength;
    this.chunkEnds = found.ext.chunks || null;
    this.levels = found.ext.levels; // records per level, finest first
    this.applied = 0; // records applied to the geometry
    this.mesh = null;
    this.fetched = 0; // stream chunks decoded
    this.requested = 0; // stream chunks requested
    this.wanted = -1; // the last chunk asked for
    this.lineOpen = false; // the file's first response reads on into the stream
    this.received = 0; // stream bytes received
    this.geometry = null; // the stream's, once its base is in
    this.t0 = performance.now();
    this.timeline = [];
    // main-thread ms spent so far: decoding the stream, applying records
    // (index edits, positions, corner copies), computing normals
    // (and ordering the last level's triangles: order)
    // (with the decoder in a worker: decode = handing it the bytes and
    // taking its records in; worker = its own decoding, incl. the draw order)
    this.spent = { decode: 0, apply: 0, normals: 0, order: 0, worker: 0 };
  }

  // The decoder: a StreamDecoder on the main thread, or a RemoteDecoder
  // (remote.js) whose StreamDecoder runs in a worker; the loader reads the
  // same fields of either. A worker that fails to start hands its bytes
  // back to a StreamDecoder here.
  useDecoder(d) {
    this.decoder = d;
    this.inWorker = d instanceof RemoteDecoder;
    // records' positions as grid points only (writeVertices)
    d.floats = false;
    // the level refine stops at is drawn in the split tree's order
    // (order.js), worked out once its chunk's topology is in, while its
    // positions still download (drawOrderFor; in the worker, which posts it)
    d.onTopology = (k, order) => {
      this.drawOrderFor(k, order ? null : d.tri, order);
      this.prepare(k);
    };
    if (!this.inWorker) return;
    d.onMark = (what, t) => this.mark(what, t);
    d.onProgress = () => {
      this.fetched = d.chunksDone;
      this.spent.worker = d.workerMs;
      this.spent.decode = this.spentPushing + d.spent;
      this.wake();
    };
    d.onError = (e) => {
      this.error = this.error || e;
      this.wake();
    };
    d.onFail = (bytes, e) => {
      this.workerError = e.message;
      this.useDecoder(new StreamDecoder(this.meshoptDecoder));
      try {
        for (const b of bytes) this.decoder.push(b);
      } catch (err) {
        this.error = this.error || err;
      }
      this.fetched = this.decoder.chunksDone;
      this.wake();
    };
    if (this.goal) d.setGoal(this.goal);
  }

  // Stops the decoder's worker, if any (it stops by itself once the whole
  // stream is decoded): refine can then go no further than decoded.
  dispose() {
    if (this.inWorker) this.decoder.terminate();
  }

  // Once chunk 0 (header + base mesh) is decoded: set up the geometry
  // sized for the finest level, in place of the coarse level's own.
  async start() {
    if (this.geometry) return;
    if (!this.chunkEnds) {
      const head = await fetchRange(this.url, this.streamStart, this.streamStart + Math.min(this.streamLength, 4096), this.fetchOptions);
      this.chunkEnds = parseHeader(head).chunkEnds;
    }
    this.request(0);
    await this.waitChunks(1);
    if (this.geometry) return;
    const d = this.decoder, h = d.header;
    const prim = this.json.meshes[this.found.mesh].primitives[this.found.primitive];
    const acc = this.json.accessors[prim.attributes.POSITION];
    // same space as the level's POSITION: normalized i16 grid points
    // (KHR_mesh_quantization, q - s) or floats
    this.quantized = acc.componentType === 5122 && acc.normalized && h.bits === 16;
    // (setting up the geometry counts as applying)
    const t = performance.now(), n0 = this.spent.normals;
    const g = new BufferGeometry();
    const Pos = this.quantized ? Int16Array : Float32Array;
    // the index state (vertex ids) and each vertex's position
    this.indices = indexArray(h.totalVertices, Math.max(3, h.totalTriangles * 3));
    this.vpos = new Pos(h.totalVertices * 3);
    if (h.wedges) this.cornerGeometry(g, Pos);
    else {
      g.setAttribute("position", new BufferAttribute(this.vpos, 3, this.quantized));
      g.setIndex(new BufferAttribute(this.indices, 1));
      g.setAttribute("normal", new BufferAttribute(new Int8Array(h.totalVertices * 3), 3, true));
      g.attributes.normal.setUsage(35048);
      g.index.setUsage(35048);
    }
    g.attributes.position.setUsage(35048); // DYNAMIC_DRAW
    // every level's positions lie in the grid's box: one bounding sphere
    g.boundingSphere = this.quantized ? new Sphere(new Vector3(0, 0, 0), Math.sqrt(3))
      : new Sphere(new Vector3(...h.center), h.half * Math.sqrt(3));
    this.geometry = g;
    this.writeBase();
    this.indices.set(d.baseTri, 0);
    this.nt = h.baseTriangles;
    this.finishUpdate(0, 0, 0, h.baseTriangles * 3);
    this.spent.apply += performance.now() - t - (this.spent.normals - n0);
    if (this.mesh) {
      this.mesh.geometry.dispose();
      this.mesh.geometry = g;
    }
    this.mark("base");
  }

  // A point of the load's timeline (this.timeline: {what, t, bytes}; t in
  // ms from the load's start, bytes = stream bytes received so far); `at`
  // (performance.now() time): a point the decoder's worker reported,
  // placed in time order.
  mark(what, at) {
    const t = (at === undefined ? performance.now() : at) - this.t0, tl = this.timeline;
    let i = tl.length;
    while (at !== undefined && i > 0 && tl[i - 1].t > t) i--;
    tl.splice(i, 0, { what, t, bytes: this.received });
  }

  // A stream with wedges: drawn indexed, one vertex per distinct (vertex,
  // wedge) pair of the drawn corners (a wedge may sit at two vertices, a
  // vertex carry several wedges), its position and the streamed attributes
  // three.js draws (NORMAL, TEXCOORD_0..3, COLOR_0, TANGENT) copied from
  // the pair's vertex and wedge at each level. Pairs are numbered in order
  // of first appearance in the corners, so at most one per corner; the
  // vertex attributes are sized for about as many pairs as the stream has
  // wedges or vertices (spot's finest level: 3,225 pairs for 17,568
  // corners), a first upload of what is drawn, and grow when a level
  // draws more (pairCapacity).
  cornerGeometry(g, Pos) {
    const d = this.decoder, h = d.header, n = 3 * h.totalTriangles;
    const names = { NORMAL: "normal", TEXCOORD_0: "uv", TEXCOORD_1: "uv1", TEXCOORD_2: "uv2", TEXCOORD_3: "uv3", COLOR_0: "color", TANGENT: "tangent" };
    this.cw = new Uint32Array(n);
    this.cw.set(d.baseCW, 0);
    // each corner's pair (the drawn index), each pair's vertex and wedge,
    // and per vertex its pairs' list (head, stamped per rebuild; next)
    this.pairs = {
      index: indexArray(n, n), v: new Uint32Array(n), w: new Uint32Array(n), next: new Int32Array(n),
      head: new Int32Array(h.totalVertices), stamp: new Uint32Array(h.totalVertices), now: 0, count: 0,
    };
    g.setIndex(new BufferAttribute(this.pairs.index, 1));
    g.index.setUsage(35048);
    this.pairCap = Math.min(n, Math.ceil(1.25 * Math.max(h.wedges.total, h.totalVertices)) + 64);
    g.setAttribute("position", new BufferAttribute(new Pos(this.pairCap * 3), 3, this.quantized));
    this.channels = [];
    for (const c of h.wedges.channels) {
      const name = names[c.name];
      if (!name || g.attributes[name]) continue;
      g.setAttribute(name, new BufferAttribute(new Float32Array(this.pairCap * c.components), c.components));
      g.attributes[name].setUsage(35048);
      // TEXCOORD_0 streamed over its range while the file stores it as
      // normalized u16 whose range the material's KHR_texture_transform
      // gives back (lodgen --quantize on glTF input, UVs leaving [0, 1]):
      // the geometry takes the file's values, (uv - offset) / scale, so
      // three.js applies the range once
      const remap = c.name === "TEXCOORD_0" && c.encoding === 4 ? this.uvTransform() : null;
      this.channels.push({ c, attr: g.attributes[name], remap });
    }
    if (!g.attributes.normal) {
      // none streamed: each pair gets its vertex's computed normal
      g.setAttribute("normal", new BufferAttribute(new Int8Array(this.pairCap * 3), 3, true));
      g.attributes.normal.setUsage(35048);
      this.vnormal = new Int8Array(h.totalVertices * 3);
    }
  }

  // Room for `np` pairs in the vertex attributes: when a level draws more
  // pairs than they hold, each is replaced by one twice as large (at most
  // one per corner), its values kept; the geometry is disposed so that the
  // renderer drops the old buffers and uploads the new ones whole.
  pairCapacity(np) {
    if (np <= this.pairCap) return;
    const g = this.geometry, cap = Math.min(3 * this.decoder.header.totalTriangles, Math.max(np, 2 * this.pairCap));
    for (const name of Object.keys(g.attributes)) {
      const a = g.attributes[name], b = new a.array.constructor(cap * a.itemSize);
      b.set(a.array);
      const r = new BufferAttribute(b, a.itemSize, a.normalized);
      r.setUsage(a.usage);
      g.setAttribute(name, r);
      for (const ch of this.channels) if (ch.attr === a) ch.attr = r;
    }
    this.pairCap = cap;
    g.dispose();
  }

  // Number the drawn corners' distinct (vertex, wedge) pairs in order of
  // first appearance: pairs.index per corner, pairs.v / pairs.w per pair.
  numberPairs() {
    const P = this.pairs, n = 3 * this.nt, idx = this.indices, cw = this.cw;
    const { index, v: pv, w: pw, next, head, stamp } = P;
    const now = (P.now = (P.now + 1) >>> 0 || 1);
    let count = 0;
    for (let c = 0; c < n; c++) {
      const v = idx[c], w = cw[c], first = stamp[v] === now ? head[v] : -1;
      let p = first;
      while (p >= 0 && pw[p] !== w) p = next[p];
      if (p < 0) {
        p = count++;
        pv[p] = v; pw[p] = w; next[p] = first;
        head[v] = p; stamp[v] = now;
      }
      index[c] = p;
    }
    P.count = count;
    return count;
  }

  // Corner geometry: the drawn corners' pairs, each pair's position and
  // attributes.
  writeCorners() {
    const g = this.geometry, n = 3 * this.nt, vp = this.vpos, np = this.numberPairs();
    this.pairCapacity(np);
    const { v: pv, w: pw } = this.pairs;
    const pos = g.attributes.position.array, vals = this.decoder.wvals, stride = this.decoder.header.wedges.stride;
    for (let p = 0; p < np; p++) {
      const v = 3 * pv[p];
      pos[3 * p] = vp[v]; pos[3 * p + 1] = vp[v + 1]; pos[3 * p + 2] = vp[v + 2];
    }
    for (const { c: ch, attr, remap } of this.channels) {
      const out = attr.array, k = ch.components;
      for (let p = 0; p < np; p++) {
        const from = pw[p] * stride + ch.offset;
        for (let j = 0; j < k; j++) out[p * k + j] = vals[from + j];
      }
      if (remap) for (let i = 0; i < np * k; i++) out[i] = (out[i] - remap.offset[i % 2]) / remap.scale[i % 2];
    }
    if (this.vnormal) {
      const vn = this.computeNormals(this.vnormal), out = g.attributes.normal.array;
      for (let p = 0; p < np; p++) {
        const v = 3 * pv[p];
        out[3 * p] = vn[v]; out[3 * p + 1] = vn[v + 1]; out[3 * p + 2] = vn[v + 2];
      }
    }
    for (const name of Object.keys(g.attributes)) {
      const a = g.attributes[name];
      a.clearUpdateRanges();
      a.addUpdateRange(0, np * a.itemSize);
      a.needsUpdate = true;
    }
    g.index.clearUpdateRanges();
    g.index.addUpdateRange(0, n);
    g.index.needsUpdate = true;
    g.setDrawRange(0, n);
  }

  // The KHR_texture_transform ({offset, scale}) of the streamed
  // primitive's material on a texture reading TEXCOORD_0, when the file
  // stores TEXCOORD_0 as normalized u16; else null.
  uvTransform() {
    const json = this.json, prim = json.meshes[this.found.mesh].primitives[this.found.primitive];
    const acc = json.accessors[prim.attributes.TEXCOORD_0];
    if (!acc || acc.componentType !== 5123 || !acc.normalized || prim.material === undefined) return null;
    const find = (o) => {
      if (!o || typeof o !== "object") return null;
      for (const [k, v] of Object.entries(o)) {
        const t = k.endsWith("Texture") && v && v.index !== undefined && (v.texCoord || 0) === 0
          && v.extensions && v.extensions.KHR_texture_transform;
        const r = t ? { offset: t.offset || [0, 0], scale: t.scale || [1, 1] } : find(v);
        if (r) return r;
      }
      return null;
    };
    return find((json.materials || [])[prim.material]);
  }

  // The base vertices' positions.
  writeBase() {
    const d = this.decoder, a = this.vpos, s = d.header.scale, n = 3 * d.header.baseVertices;
    if (this.quantized) for (let i = 0; i < n; i++) a[i] = d.baseQ[i] - s;
    else a.set(d.basePositions.subarray(0, n), 0);
  }

  // Records a .. k's positions, in order: each record's v1 and v0 at their
  // chunk-end grid points, so a level shows exactly its positions even when
  // the decoder is already further on; as normalized i16 (q - s), or as
  // f32 the way the decoder's p1 / p0 are (center + (q - s) / s * half in
  // double precision, rounded once).
  writeVertices(a, k) {
    const d = this.decoder, h = d.header, out = this.vpos, s = h.scale, base = h.baseVertices;
    const f1 = d.q1, f0 = d.q0;
    if (this.quantized) {
      for (let i = a; i < k; i++) {
        const o1 = 3 * d.v1[i], o0 = 3 * (base + i), r = 3 * i;
        for (let j = 0; j < 3; j++) {
          out[o1 + j] = f1[r + j] - s;
          out[o0 + j] = f0[r + j] - s;
        }
      }
      return;
    }
    const c = h.center, half = h.half;
    for (let i = a; i < k; i++) {
      const o1 = 3 * d.v1[i], o0 = 3 * (base + i), r = 3 * i;
      for (let j = 0; j < 3; j++) {
        out[o1 + j] = Math.fround(c[j] + ((f1[r + j] - s) / s) * half);
        out[o0 + j] = Math.fround(c[j] + ((f0[r + j] - s) / s) * half);
      }
    }
  }

  finishUpdate(vFrom, vTo, iFrom, iTo) {
    if (this.cw) { this.writeCorners(); return; }
    const g = this.geometry, p = g.attributes.position;
    p.clearUpdateRanges();
    // the level refine stops at in its draw order (else the index state):
    // a switch of arrays uploads every drawn index; the draw order
    // prepare put in is uploaded already, or its update still pending
    if (this.applied === this.goal) this.drawOrderFor(this.applied, this.indices);
    const o = this.drawOrder, drawn = o && o.records === this.applied && this.applied > 0 ? o.index : this.indices;
    if (g.index.array !== drawn || drawn === this.indices) {
      g.index.clearUpdateRanges();
      if (g.index.array !== drawn) {
        g.index.array = drawn;
        iFrom = 0;
        iTo = 3 * this.nt;
      }
      if (iTo > iFrom) g.index.addUpdateRange(iFrom, iTo - iFrom);
      g.index.needsUpdate = true;
    }
    if (vTo > vFrom) p.addUpdateRange(3 * vFrom, 3 * (vTo - vFrom));
    p.needsUpdate = true;
    g.setDrawRange(0, 3 * this.nt);
    const normal = g.attributes.normal;
    // (summed in the drawn order: in the split tree's, the reads are local)
    this.computeNormals(normal.array, drawn);
    normal.clearUpdateRanges();
    normal.addUpdateRange(0, 3 * (this.decoder.header.baseVertices + this.applied));
    normal.needsUpdate = true;
  }

  // Area-weighted vertex normals of the drawn triangles, from the drawn
  // positions (grid points: one scale on every axis, so the directions are
  // the positions'),
  // as snorm8 like `--quantize` writes them, into `out` (3 per vertex).
  computeNormals(out, idx = this.indices) {
    const t = performance.now();
    this.sumNormals(out, idx);
    this.spent.normals += performance.now() - t;
    return out;
  }

  sumNormals(out, idx) {
    const d = this.decoder, q = this.vpos, n3 = 3 * this.nt;
    const nv = d.header.baseVertices + this.applied;
    const acc = this.normalSums || (this.normalSums = new Float32Array(3 * d.header.totalVertices));
    acc.fill(0, 0, 3 * nv);
    for (let i = 0; i < n3; i += 3) {
      const a = 3 * idx[i], b = 3 * idx[i + 1], c = 3 * idx[i + 2];
      const ax = q[a], ay = q[a + 1], az = q[a + 2];
      const ux = q[b] - ax, uy = q[b + 1] - ay, uz = q[b + 2] - az;
      const vx = q[c] - ax, vy = q[c + 1] - ay, vz = q[c + 2] - az;
      const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
      acc[a] += nx; acc[a + 1] += ny; acc[a + 2] += nz;
      acc[b] += nx; acc[b + 1] += ny; acc[b + 2] += nz;
      acc[c] += nx; acc[c + 1] += ny; acc[c + 2] += nz;
    }
    for (let v = 0; v < 3 * nv; v += 3) {
      const x = acc[v], y = acc[v + 1], z = acc[v + 2], len = Math.sqrt(x * x + y * y + z * z);
      const k = len > 0 ? 127 / len : 0;
      out[v] = Math.round(x * k);
      out[v + 1] = Math.round(y * k);
      out[v + 2] = Math.round(z * k);
    }
    return out;
  }

  // Make sure chunks up to `last` are requested: one HTTP range for every
  // chunk not yet asked for, read as it arrives (each chunk decoded as soon
  // as its bytes are there, while the next ones download).
  request(last) {
    last = Math.min(last, this.chunkEnds.length - 1);
    this.wanted = Math.max(this.wanted, last);
    // the file's first response still decides how far it reads (readOn):
    // what it leaves is asked for then
    if (this.lineOpen) return;
    if (this.requested > last) return;
    const from = this.requested || 0;
    this.requested = last + 1;
    const start = from === 0 ? 0 : this.chunkEnds[from - 1], end = this.chunkEnds[last];
    const prev = this.pump || Promise.resolve();
    this.pump = prev.then(() => this.streamRange(start, end)).catch((e) => {
      this.error = e;
      this.wake();
    });
  }

  async streamRange(start, end) {
    const a = this.streamStart + start, b = this.streamStart + end;
    const resp = await fetch(this.url, { ...this.fetchOptions, headers: { Range: `bytes=${a}-${b - 1}` } });
    if (resp.status !== 206 && resp.status !== 200) throw new Error(`${this.url}: HTTP ${resp.status}`);
    if (resp.status === 200 || !resp.body) {
      const all = new Uint8Array(await resp.arrayBuffer());
      this.take(resp.status === 200 ? all.subarray(a, b) : all);
      return;
    }
    const reader = resp.body.getReader();
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      this.take(value);
    }
  }

  // Feed the stream from `file` (read from the start of the file, already
  // at or before the stream) up to the end of the chunk that completes
  // `records` records, or of a later one `request` asked for meanwhile
  // (the stream's header, its first bytes, has the chunk table), then let
  // the rest of the file go and ask for any chunk still wanted.
  async readOn(file, records) {
    let h = null;
    for (let n = 256; !h; n *= 2) {
      const b = await file.until(this.streamStart + n);
      try {
        h = parseHeader(b.subarray(this.streamStart));
      } catch (e) {
        // (a header cut short throws lgpm.js's NeedMore, the only error
        // without a message: read on)
        if (e.message || b.length < this.streamStart + n) throw e;
      }
    }
    const end = () => {
      const last = Math.min(Math.max(h.chunks.findIndex((c) => c.records >= records), this.wanted), h.chunkEnds.length - 1);
      this.requested = last + 1; // (what the line brings: see hold)
      return this.streamStart + h.chunkEnds[last];
    };
    // file offset of the next piece `file.next()` gives
    let at = file.have;
    const buffered = file.bytes.subarray(this.streamStart, Math.min(at, end()));
    if (buffered.length) this.take(buffered.slice());
    while (at < end()) {
      const v = await file.next();
      if (!v) throw new Error(`${this.url}: the file ends in the stream`);
      const n = v.length, from = Math.max(0, this.streamStart - at), e = end(), to = Math.min(n, e - at);
      // let the rest go before decoding the last piece
      if (at + n >= e) file.cancel();
      // (a worker's decoder takes the bytes' buffer: v is then empty)
      if (to > from) this.take(v.subarray(from, to));
      at += n;
    }
    file.cancel();
    // the chunks whose bytes are in (a worker may still decode them)
    this.requested = h.chunkEnds.filter((x) => x <= this.received).length;
    this.lineOpen = false;
    if (this.wanted >= this.requested) this.request(this.wanted);
  }

  take(bytes) {
    if (!this.received) {
      this.mark("stream first bytes");
      this.since = performance.now(); // for the line's rate (hold)
    }
    this.received += bytes.length;
    if (this.received === this.streamLength) this.mark("stream last bytes");
    // (onTopology's draw order and prepare count as theirs)
    const t = performance.now(), o0 = this.spent.order + this.spent.apply;
    this.decoder.push(bytes);
    const ms = performance.now() - t - (this.spent.order + this.spent.apply - o0);
    this.spentPushing += ms;
    this.spent.decode += ms;
    this.fetched = this.decoder.chunksDone;
    this.wake();
  }

  wake() {
    const w = this.wakers || [];
    this.wakers = [];
    for (const f of w) f();
  }

  // Resolves once `n` chunks are decoded.
  async waitChunks(n) {
    while (this.decoder.chunksDone < n) {
      if (this.error) throw this.error;
      await new Promise((r) => (this.wakers = this.wakers || []).push(r));
    }
    if (this.error && this.decoder.chunksDone < n) throw this.error;
  }

  // Apply every decoded record up to `k` to the geometry: the records'
  // faces in one copy, then their corner edits in order; one update range
  // for the vertices and one for the indices.
  applyTo(k) {
    if (k <= this.applied) return;
    const t = performance.now(), n0 = this.spent.normals;
    this.applyRecords(k);
    this.spent.apply += performance.now() - t - (this.spent.normals - n0);
  }

  // When k is the level refine stops at: its triangles in the split
  // tree's draw order (order.js), from `tri`, an index state after record
  // k: the decoder's once the topology of records 0 .. k is replayed (its
  // onTopology, at a chunk's end, before the chunk's positions download),
  // else the loader's own once the level is applied (finishUpdate draws
  // the level in that order). Not for streams with wedges (their drawn
  // index is per (vertex, wedge) pair).
  drawOrderFor(k, tri, given = null) {
    const d = this.decoder, h = d.header;
    if (k !== this.goal || k === 0 || h.wedges || (this.drawOrder && this.drawOrder.records === k)) return;
    // (the worker's, or none: the goal reached it late; finishUpdate's then)
    if (given || !tri) {
      if (given) {
        this.drawOrder = { records: k, index: given };
        this.mark(`draw order ${k}`);
      }
      return;
    }
    const t = performance.now();
    // (a new array while the one there is drawn: it is the GPU's until replaced)
    const old = this.drawOrder && this.drawOrder.index, g = this.geometry;
    const index = old && !(g && g.index.array === old) ? old : indexArray(h.totalVertices, Math.max(3, 3 * h.totalTriangles));
    splitTreeOrder(tri, d.fStart[k], d.v1, h.baseVertices, k, index);
    this.drawOrder = { records: k, index };
    this.spent.order += performance.now() - t;
    this.mark(`draw order ${k}`);
  }

  // Once the topology of the level refine stops at (records .. k, the
  // decoder's onTopology) is in, every record before its chunk applied and
  // at least an eighth of the chunk's bytes still to come (else the
  // level itself comes about as soon as a frame drawn now would, and
  // behind it): the geometry takes that level's triangles (its draw order)
  // before their positions come, each new vertex where the vertex it
  // splits is drawn now, with its normal, so every new face is degenerate
  // and the picture is the current level's; then a "prepare" event. A
  // frame drawn meanwhile (a render loop's next) uploads the level's
  // index buffer (bunny-1m: 13 MB of the 18 MB the finest level uploads)
  // while its positions still download; the level itself then uploads
  // positions and normals only.
  prepare(k) {
    const d = this.decoder, h = d.header, g = this.geometry, o = this.drawOrder, a = this.applied;
    if (!g || this.cw || !o || o.records !== k || a >= k || this.prepared === k) return;
    const c = h.chunks.findIndex((x) => x.records >= k);
    if (c <= 0 || h.chunks[c - 1].records !== a) return;
    if (8 * (this.chunkEnds[c] - this.received) < this.chunkEnds[c] - this.chunkEnds[c - 1]) return;
    const t = performance.now(), base = h.baseVertices, v1 = d.v1, pos = this.vpos, nrm = g.attributes.normal.array;
    for (let i = a; i < k; i++) {
      const u = 3 * v1[i], w = 3 * (base + i);
      pos[w] = pos[u]; pos[w + 1] = pos[u + 1]; pos[w + 2] = pos[u + 2];
      nrm[w] = nrm[u]; nrm[w + 1] = nrm[u + 1]; nrm[w + 2] = nrm[u + 2];
    }
    g.index.array = o.index;
    g.index.clearUpdateRanges();
    g.index.addUpdateRange(0, 3 * d.fStart[k]);
    for (const attr of [g.attributes.position, g.attributes.normal]) {
      attr.clearUpdateRanges();
      attr.addUpdateRange(3 * (base + a), 3 * (k - a));
      attr.needsUpdate = true;
    }
    g.index.needsUpdate = true;
    g.setDrawRange(0, 3 * d.fStart[k]);
    this.spent.apply += performance.now() - t;
    this.prepared = k;
    this.mark(`prepared ${k}`);
    this.dispatchEvent({ type: "prepare", records: k, triangles: d.fStart[k] });
  }

  applyRecords(k) {
    const d = this.decoder, idx = this.indices, cw = this.cw, a = this.applied;
    const f0 = 3 * d.fStart[a], f1 = 3 * d.fStart[k];
    idx.set(d.faces0.subarray(f0, f1), f0);
    if (cw) {
      cw.set(d.wfaces0.subarray(f0, f1), f0);
      for (let j = d.cStart[a]; j < d.cStart[k]; j++) cw[d.corners.a[j]] = d.wafter.a[j];
    }
    let vLo = Infinity, iLo = f0;
    const corners = d.corners.a, cs = d.cStart, base = d.header.baseVertices;
    for (let i = a; i < k; i++) {
      const v0 = base + i;
      if (d.v1[i] < vLo) vLo = d.v1[i];
      for (let j = cs[i]; j < cs[i + 1]; j++) {
        const c = corners[j];
        idx[c] = v0;
        if (c < iLo) iLo = c;
      }
    }
    this.nt = d.fStart[k];
    this.mark(`indices ${k}`);
    // vertices: grid points at the chunk's end
    this.writeVertices(a, k);
    this.mark(`vertices ${k}`);
    this.applied = k;
    this.finishUpdate(vLo, base + k, iLo, f1);
  }

  // The level (finest = 0) whose records are all applied.
  level() {
    let best = this.levels.length - 1;
    this.levels.forEach((k, i) => { if (k <= this.applied && i < best) best = i; });
    return best;
  }

  // Refine up to MSFT_lod level `level` (finest = 0; default: the finest),
  // fetching the chunks that hold it; a "level" event per level reached
  // (the first, records 0, once the stream's geometry holds the base).
  // A level decoded waits, at most `holdMs`, for the next ones whose bytes
  // the line brings by then (at the rate the stream's bytes have come so
  // far): they are then applied in one go, an event each, so a render loop
  // draws them in one frame instead of drawing levels seen for a few ms.
  async refine(level = 0) {
    await this.start();
    const want = this.levels[Math.max(0, Math.min(level, this.levels.length - 1))];
    this.goal = Math.max(this.goal, want);
    if (this.inWorker) this.decoder.setGoal(this.goal);
    const h = this.decoder.header;
    const chunkOf = (k) => h.chunks.findIndex((c) => c.records >= k);
    this.request(chunkOf(want));
    const steps = [...new Set(this.levels)].filter((k) => k > this.applied && k <= want).sort((a, b) => a - b);
    if (!this.baseShown) steps.unshift(0);
    for (let i = 0; i < steps.length;) {
      if (steps[i] > 0) {
        await this.waitChunks(chunkOf(steps[i]) + 1);
        this.mark(`decoded ${steps[i]}`);
      }
      const deadline = performance.now() + this.holdMs;
      let j = i + 1;
      while (j < steps.length && (await this.hold(chunkOf(steps[j]) + 1, deadline))) this.mark(`decoded ${steps[j++]}`);
      for (; i < j; i++) {
        const k = steps[i];
        if (k > 0) {
          this.applyTo(k);
          this.mark(`applied ${k}`);
        }
        this.baseShown = true;
        this.dispatchEvent({ type: "level", level: k > 0 ? this.levels.indexOf(k) : this.levels.length - 1, records: k, triangles: this.nt });
      }
    }
    return this.level();
  }

  // Whether the first `n` chunks are decoded, now or by `deadline` (ms,
  // performance.now()): waited for when they are asked for and the rate
  // the stream's bytes have come at so far brings them by then.
  async hold(n, deadline) {
    if (this.decoder.chunksDone >= n) return true;
    const left = deadline - performance.now();
    if (!(left > 0) || n > this.requested || !this.since) return false;
    const elapsed = performance.now() - this.since, need = this.chunkEnds[n - 1] - this.received;
    if (!(elapsed > 0) || need * elapsed > left * this.received) return false;
    this.mark(`hold for ${need} B`);
    let timer;
    await Promise.race([this.waitChunks(n), new Promise((r) => { timer = setTimeout(r, left); })]);
    clearTimeout(timer);
    return this.decoder.chunksDone >= n;
  }

  // Refine to the level MSFT_screencoverage asks for at the mesh's current
  // projected size (the level is never coarsened: the finer data stays).
  async refineForScreen(camera) {
    await this.start();
    const coverages = this.screenCoverages();
    if (!coverages || !this.mesh) return this.refine(0);
    const sphere = new Sphere().copy(this.geometry.boundingSphere).applyMatrix4(this.mesh.matrixWorld);
    const d = camera.getWorldPosition(new Vector3()).distanceTo(sphere.center);
    const c = screenCoverage(camera, sphere.radius, d);
    let level = coverages.findIndex((x) => c >= x);
    if (level < 0) level = this.levels.length - 1;
    return this.refine(level);
  }

  screenCoverages() {
    const n = this.found.lodNode;
    const node = n >= 0 ? this.json.nodes[n] : null;
    return node && node.extras && node.extras.MSFT_screencoverage;
  }
}

// Decoder workers done with a load, by script URL (at most 2): the next
// load takes one, ready and its JIT warm.
const idleWorkers = [];

// The decoder's worker for loadProgressive's `worker` option, or null:
// {worker, reused, release} (RemoteDecoder's arguments).
function startWorker(option) {
  if (option === false || typeof Worker !== "function") return null;
  // yours: reset for each load, never terminated but on its errors
  if (option && typeof option.postMessage === "function") return { worker: option, reused: true, release: () => {} };
  try {
    const url = String(option === undefined || option === true ? new URL("./worker.js", import.meta.url) : option);
    const release = (w) => {
      idleWorkers.push({ url, worker: w });
      while (idleWorkers.length > 2) idleWorkers.shift().worker.terminate();
    };
    const i = idleWorkers.findIndex((w) => w.url === url);
    if (i >= 0) return { worker: idleWorkers.splice(i, 1)[0].worker, reused: true, release };
    return { worker: new Worker(url, { type: "module" }), reused: false, release };
  } catch {
    return null;
  }
}

// Load a lodgen GLB progressively (see the top of this file). Options:
// `loader` (a GLTFLoader, with its MeshoptDecoder set when the file uses
// EXT_meshopt_compression), `meshoptDecoder` (awaited `.ready`),
// `fetchOptions` (passed to fetch), `prefetch` (a level, 0 = finest: request
// the stream up to it right away, in parallel with the coarse level, when
// you will refine to it anyway), `holdMs` (default 50; 0: every level on
// its own as soon as it is decoded): a level decoded waits up to that many
// ms for the next ones the line brings by then, all applied in one go (see
// refine), `worker` (where the stream is decoded: by default, in browsers
// with Web Workers, a module worker, `new URL("./worker.js",
// import.meta.url)`, started as soon as the file's JSON shows the
// extension, so it is ready before the stream's bytes come; a URL or
// string: that worker script instead (e.g. your bundle of
// lodgen-three/worker.js); a Worker already started with it; false: on
// the main thread, as where there are no workers; a worker that fails to
// start falls back to the main thread, `workerError` says why).
// Resolves, with the ProgressiveMesh, as soon
// as the coarsest level is parsed (`.gltf`: draw it); `refine` swaps in the
// stream's geometry once its base chunk is in ("level" event, records 0).
// A file without the extension is loaded whole by `loader` (`.gltf` set,
// nothing to refine).
export async function loadProgressive(url, { loader, meshoptDecoder, fetchOptions = {}, prefetch, holdMs = 50, worker }) {
  const t0 = performance.now();
  await meshoptDecoder.ready;
  // one request from the start of the file: lodgen writes the JSON, the
  // coarsest level and the stream first, in that order
  const file = new FileStart(url, fetchOptions);
  const { json, binStart, binLength } = await readGlbJson(file);
  const found = findExtension(json);
  if (!found) {
    file.cancel();
    const gltf = await loader.loadAsync(url);
    return Object.assign(new EventDispatcher(), { gltf, refine: async () => 0, levels: [] });
  }
  const coarseJson = structuredClone(json);
  // show the coarsest mesh where the MSFT_lod chain shows its finest
  if (found.lodNode >= 0) {
    const node = coarseJson.nodes[found.lodNode];
    node.mesh = found.mesh;
    delete node.extensions.MSFT_lod;
  }
  // from the start of the binary chunk: lodgen puts the data no level owns
  // (images, skins, animations) first, then the coarsest level
  const hi = meshRange(json, found.mesh)[1], lo = 0;
  const bin = new Uint8Array(binLength);
  const p = new ProgressiveMesh({ url, fetchOptions, meshoptDecoder, json, binStart, found, worker: startWorker(worker) });
  p.holdMs = holdMs;
  p.t0 = t0;
  p.mark("json");
  if (p.inWorker) p.mark(p.decoder.session ? "worker reused" : "worker started");
  const wantRecords = prefetch === undefined ? 0 : p.levels[Math.max(0, Math.min(prefetch, p.levels.length - 1))];
  // the coarse level near the start (lodgen's files): read on to it
  const coarseNear = hi > lo && binStart + lo - file.have <= 65536;
  const coarse = hi <= lo ? null : coarseNear ? file.until(binStart + hi).then((b) => b.slice(binStart + lo, binStart + hi))
    : fetchRange(url, binStart + lo, binStart + hi, fetchOptions);
  // the stream right after it: read on in the same response up to the
  // chunk that holds `prefetch` (its header, the first bytes, says which),
  // then let the rest go
  const onLine = coarseNear && p.chunkEnds && p.streamStart >= binStart + hi && p.streamStart - (binStart + hi) <= 64;
  if (onLine) {
    p.lineOpen = true;
    p.pump = coarse.then(() => p.readOn(file, wantRecords)).catch((e) => { p.error = e; p.wake(); });
  } else if (p.chunkEnds) {
    // in parallel with the coarse level: the stream up to `prefetch` in one
    // streamed range request (the base alone, or the whole stream, need
    // no chunk table; else the header's says which chunk, once it is in)
    const known = wantRecords === 0 ? 0 : wantRecords === Math.max(...p.levels) ? p.chunkEnds.length - 1 : -1;
    p.request(Math.max(known, 0));
    if (known < 0) p.waitChunks(1).then(() => p.request(p.decoder.header.chunks.findIndex((c) => c.records >= wantRecords)), () => {});
  }
  if (!coarseNear) file.cancel();
  if (coarse) bin.set(await coarse, lo);
  if (!onLine) file.cancel();
  p.mark("coarse bytes");
  const plugin = (parser) => new LodgenProgressivePlugin(parser, found, (m) => { p.mesh = m; });
  loader.register(plugin);
  try {
    p.gltf = await loader.parseAsync(glb(coarseJson, bin), "");
  } finally {
    loader.unregister(plugin);
  }
  p.mark("coarse parsed");
  const prim = json.meshes[found.mesh].primitives[found.primitive];
  p.coarseTriangles = json.accessors[prim.indices].count / 3;
  p.nt = p.coarseTriangles;
  return p;
}
