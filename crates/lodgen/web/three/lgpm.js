// LODGEN_progressive stream decoder (layout version 7, docs/LODGEN_progressive.md),
// a second, independent implementation of crates/lodgen-pm/src/progressive/stream/.
// Used by the `lodgen view` page (viewer.js) and the three.js loader
// (three/index.js). The columns are decoded by meshoptimizer's
// MeshoptDecoder (npm package `meshoptimizer`), passed to the constructor:
//
//   import { MeshoptDecoder } from "meshoptimizer";
//   await MeshoptDecoder.ready;
//   const d = new StreamDecoder(MeshoptDecoder);
//   d.push(bytes);                 // any split of the stream, as it arrives
//   d.count                        // records decoded so far
//   d.record(i)                    // {v1, v0, p1, pm, p0, faces, corners, wfaces, wafter, wbefore}
//                                  // (p1 / pm / p0 null after d.floats = false)
//
// A chunk's topology (and wedges) is replayed block by block (BLOCK_RECORDS
// records each) as soon as each block's topology columns and wedge
// references are in (the new wedges' values once their columns follow),
// its positions once the chunk is whole. Records
// are kept in typed arrays (see StreamDecoder), nothing is allocated per
// record. Positions come out as grid points (d.q, Uint16Array, 3 per
// vertex) and as f32 (center + (q - s) / s * half in double precision,
// rounded once). `corners` are corner indices t * 3 + slot.

const FACE_ESCAPE = 255;
const NONE = 0xffffffff;
// attribute encodings: 0 f32, 1 unorm16, 2 snorm8, 3 unorm8, 4 unorm16 over
// offset ..= offset + scale (c.offset0, c.scale)
const ENC_MAX = [0, 65535, 254, 255, 65535];
function dequantize(c, q) {
  const e = c.encoding;
  return Math.fround(e === 1 ? q / 65535 : e === 2 ? (q - 127) / 127 : e === 3 ? q / 255 : c.offset0 + c.scale * (q / 65535));
}
const RING_CODES = 42;
// records per block of a chunk's topology and wedge columns (version 7)
export const BLOCK_RECORDS = 8192;
const PERMS = [[0, 1, 2], [1, 2, 0], [2, 0, 1], [1, 0, 2], [0, 2, 1], [2, 1, 0]];

class NeedMore extends Error {}

class Bytes {
  constructor(b, pos, offset) {
    this.b = b;
    this.pos = pos;
    this.offset = offset; // stream offset of b[0]
  }
  at() {
    return this.offset + this.pos;
  }
  byte() {
    if (this.pos >= this.b.length) throw new NeedMore();
    return this.b[this.pos++];
  }
  varint() {
    let v = 0, mul = 1;
    for (let i = 0; i < 8; i++) {
      const b = this.byte();
      v += (b & 0x7f) * mul;
      if ((b & 0x80) === 0) return v;
      mul *= 128;
    }
    throw new Error(`byte ${this.at()}: varint too long`);
  }
  bounded(limit, what) {
    const at = this.at();
    const v = this.varint();
    if (v > limit) throw new Error(`byte ${at}: ${what} ${v} exceeds ${limit}`);
    return v;
  }
  f32() {
    if (this.pos + 4 > this.b.length) throw new NeedMore();
    const v = new DataView(this.b.buffer, this.b.byteOffset + this.pos, 4).getFloat32(0, true);
    this.pos += 4;
    return v;
  }
  f64() {
    if (this.pos + 8 > this.b.length) throw new NeedMore();
    const v = new DataView(this.b.buffer, this.b.byteOffset + this.pos, 8).getFloat64(0, true);
    this.pos += 8;
    return v;
  }
}

// Parse the header from a prefix of the stream; throws NeedMore when short.
export function parseHeader(bytes) {
  const r = new Bytes(bytes, 0, 0);
  for (const m of [0x4c, 0x47, 0x50, 0x4d]) if (r.byte() !== m) throw new Error("not a lodgen progressive stream");
  const version = r.byte();
  if (version !== 7) throw new Error(`unsupported stream version ${version}`);
  const flags = r.byte();
  if (flags & ~3) throw new Error(`unknown flags ${flags}`);
  const bits = r.byte();
  if (bits < 2 || bits > 16) throw new Error(`grid bits ${bits}`);
  const center = [r.f64(), r.f64(), r.f64()];
  const half = r.f64();
  if (!(center.every(Number.isFinite) && Number.isFinite(half) && half > 0)) throw new Error("bad grid");
  const max = 0xfffffffe;
  const h = {
    flags, bits, center, half, scale: 2 ** (bits - 1) - 1,
    baseVertices: r.bounded(max, "base vertices"),
    baseTriangles: r.bounded(max, "base triangles"),
    splitCount: r.bounded(max, "split count"),
    totalVertices: r.bounded(max, "total vertices"),
    totalTriangles: r.bounded(max, "total triangles"),
    levels: [],
    wedges: null,
    chunks: [],
  };
  if (h.totalVertices !== h.baseVertices + h.splitCount) throw new Error("inconsistent vertex counts");
  if (h.totalTriangles < h.baseTriangles) throw new Error("inconsistent triangle counts");
  const n = r.bounded(65536, "level count");
  for (let i = 0; i < n; i++) h.levels.push(r.bounded(h.splitCount, "level"));
  if (flags & 2) {
    const total = r.bounded(max, "wedge count");
    const groups = r.bounded(max, "group count");
    if (groups === 0) throw new Error("zero wedge groups");
    const nch = r.bounded(64, "channel count");
    const channels = [];
    let stride = 0;
    for (let i = 0; i < nch; i++) {
      const len = r.bounded(64, "channel name length");
      const name = new TextDecoder("utf-8", { fatal: true }).decode(Uint8Array.from({ length: len }, () => r.byte()));
      if (!name) throw new Error("empty channel name");
      const components = r.byte();
      if (components < 1 || components > 16) throw new Error(`${components} components`);
      channels.push({ name, components, offset: stride });
      stride += components;
    }
    // per channel its encoding, and its lanes among the quantized (qlane)
    // or the f32 (flane) values of a wedge
    let qstride = 0, fstride = 0;
    for (const c of channels) {
      c.encoding = r.byte();
      if (c.encoding > 4) throw new Error(`unknown attribute encoding ${c.encoding}`);
      if (c.encoding === 4) {
        c.offset0 = r.f32();
        c.scale = r.f32();
        if (!Number.isFinite(c.offset0) || !Number.isFinite(c.scale) || !(c.scale > 0)) {
          throw new Error(`attribute range offset ${c.offset0} scale ${c.scale} (finite, scale > 0)`);
        }
      }
      if (c.encoding === 0) { c.flane = fstride; fstride += c.components; }
      else { c.qlane = qstride; qstride += c.components; c.padded = c.components + (c.components & 1); }
    }
    h.wedges = { total, groups, channels, stride, qstride, fstride };
  }
  const nc = r.bounded(65536, "chunk count");
  if (nc === 0) throw new Error("no chunks");
  let prev = 0;
  for (let i = 0; i < nc; i++) {
    const records = r.bounded(h.splitCount, "chunk record count");
    if (i === 0 ? records !== 0 : records <= prev) throw new Error(`chunk ${i} ends at record ${records}`);
    h.chunks.push({ records, bytes: r.bounded(0xffffffff, "chunk length") });
    prev = records;
  }
  if (prev !== h.splitCount) throw new Error("the chunks do not end at the last record");
  h.headerBytes = r.pos;
  // byte offset of the end of every chunk (chunk 0 = the base mesh)
  let end = h.headerBytes;
  h.chunkEnds = h.chunks.map((c) => (end += c.bytes));
  return h;
}

// The columns of one chunk, read in order.
class Columns {
  constructor(mo, bytes, offset) {
    this.mo = mo;
    this.r = new Bytes(bytes, 0, offset);
  }
  next(what, expect) {
    const at = this.r.at();
    const count = this.r.varint();
    if (expect !== undefined && count !== expect) throw new Error(`byte ${at}: ${what} column holds ${count} values, expected ${expect}`);
    const len = this.r.varint();
    if (len > this.r.b.length - this.r.pos) throw new Error(`byte ${at}: ${what} column runs past the chunk`);
    if (count > 1024 * (len + 16)) throw new Error(`byte ${at}: ${what} column: ${count} values in ${len} bytes`);
    const src = this.r.b.subarray(this.r.pos, this.r.pos + len);
    this.r.pos += len;
    return { count, src, at };
  }
  // vertex-codec column of `size`-byte elements, as a Uint8Array
  vertices(what, size, expect) {
    const { count, src, at } = this.next(what, expect);
    const out = new Uint8Array(count * size);
    if (count === 0) {
      if (src.length) throw new Error(`byte ${at}: empty ${what} column with bytes`);
      return out;
    }
    try {
      this.mo.decodeVertexBuffer(out, count, size, src);
    } catch (e) {
      throw new Error(`byte ${at}: ${what} column: ${e.message}`);
    }
    return out;
  }
  u32(what, expect) {
    const b = this.vertices(what, 4, expect);
    return new Uint32Array(b.buffer, b.byteOffset, b.length / 4);
  }
  u16x4(what, expect) {
    const b = this.vertices(what, 8, expect);
    return new Uint16Array(b.buffer, b.byteOffset, b.length / 2);
  }
  sequence(what, expect) {
    const { count, src, at } = this.next(what, expect);
    const out = new Uint32Array(count);
    if (count === 0) return out;
    try {
      this.mo.decodeIndexSequence(new Uint8Array(out.buffer), count, 4, src);
    } catch (e) {
      throw new Error(`byte ${at}: ${what} column: ${e.message}`);
    }
    return out;
  }
  bits(what) {
    const { count, src, at } = this.next(what);
    if (src.length !== Math.ceil(count / 8)) throw new Error(`byte ${at}: ${what} column: ${count} bits in ${src.length} bytes`);
    let pos = 0;
    return {
      next() {
        if (pos >= count) throw new Error(`byte ${at}: the corner-mask column ends early`);
        const b = (src[pos >> 3] >> (pos & 7)) & 1;
        pos++;
        return b === 1;
      },
      done: () => pos === count,
    };
  }
  finish(what) {
    if (this.r.pos !== this.r.b.length) throw new Error(`${this.r.b.length - this.r.pos} bytes left over in ${what}`);
  }
}


// The wing faces of a split: indices (in faces / 3) of its first two faces
// holding v0, v1 and exactly one other corner, when their third vertices differ.
function wingFaces(faces, v0, v1) {
  const xs = [], is = [];
  for (let f = 0; f < faces.length && xs.length < 2; f += 3) {
    const a = faces[f], b = faces[f + 1], c = faces[f + 2];
    if ((a !== v0 && b !== v0 && c !== v0) || (a !== v1 && b !== v1 && c !== v1)) continue;
    let n = 0, x = -1;
    if (a !== v0 && a !== v1) { n++; x = a; }
    if (b !== v0 && b !== v1) { n++; x = b; }
    if (c !== v0 && c !== v1) { n++; x = c; }
    if (n === 1) { xs.push(x); is.push(f / 3); }
  }
  return xs.length === 2 && xs[0] !== xs[1] ? is : null;
}

function words(arr, what) {
  let pos = 0;
  return {
    next() {
      if (pos >= arr.length) throw new Error(`the ${what} column ends early`);
      return arr[pos++];
    },
    done: () => pos === arr.length,
  };
}

// A Uint32Array that grows by doubling.
class U32List {
  constructor(n = 1024) {
    this.a = new Uint32Array(n);
    this.n = 0;
  }
  push(x) {
    if (this.n === this.a.length) {
      const b = new Uint32Array(2 * this.a.length);
      b.set(this.a);
      this.a = b;
    }
    this.a[this.n++] = x;
  }
}

// Insert u into the ascending r[0 .. n] unless there; returns the new length.
function insertSorted(r, n, u) {
  let k = n;
  while (k > 0 && r[k - 1] > u) k--;
  if (k > 0 && r[k - 1] === u) return n;
  for (let m = n; m > k; m--) r[m] = r[m - 1];
  r[k] = u;
  return n + 1;
}

// Push u on the list unless it is among its entries from r0 on.
function ringPush(list, r0, u) {
  const a = list.a;
  for (let m = r0; m < list.n; m++) if (a[m] === u) return;
  list.push(u);
}

// Whether `b[from..have]` holds the next `n` columns whole.
function columnsIn(b, from, have, n) {
  let pos = from;
  const varint = () => {
    let v = 0, mul = 1;
    for (let i = 0; i < 8; i++) {
      if (pos >= have) return -1;
      const x = b[pos++];
      v += (x & 0x7f) * mul;
      if ((x & 0x80) === 0) return v;
      mul *= 128;
    }
    return -1;
  };
  for (let i = 0; i < n; i++) {
    if (varint() < 0) return false;
    const len = varint();
    if (len < 0) return false;
    pos += len;
    if (pos > have) return false;
  }
  return true;
}

// Records are kept column-wise in typed arrays (no object per record):
// record i restores vertex v0 = baseVertices + i, splitting v1[i]; its faces
// are triangles fStart[i] .. fStart[i + 1] (their corners as appended in
// faces0, which also holds the base triangles); its corner edits are
// corners[cStart[i] .. cStart[i + 1]] (corner index t * 3 + slot). With
// wedges: wfaces0 (the appended faces' wedges, base corners included),
// wafter / wbefore parallel to corners. Positions: p1 / p0 / pm, 3 per record.
export class StreamDecoder {
  constructor(meshoptDecoder) {
    this.mo = meshoptDecoder;
    // whether records get f32 positions (p1, p0, pm) besides their grid
    // points (q1, q0): a client drawing grid points (the three.js loader on
    // a KHR_mesh_quantization file, or computing them from q1 / q0 as
    // deq does) turns it off before pushing bytes, and skips a pass over
    // the records, the f32 copy of every vertex (`cur`) and their arrays
    // (bunny-1m: 26 MB of 98); p1 / p0 / pm are then null
    this.floats = true;
    this.headBytes = new Uint8Array(0); // bytes before the header is parsed
    this.consumed = 0; // stream offset of the current chunk
    this.header = null;
    this.chunksDone = 0;
    this.baseReady = false;
    this.count = 0; // records decoded (topology and positions)
    this.buf = null; // the current chunk's bytes, `have` of them in
    this.have = 0;
    this.topo = null; // the current chunk's topology, replayed before its positions
    // called with k once the topology of records 0 .. k is replayed (a
    // chunk's end, before its positions): tri[0 .. 3 * nt] then holds
    // the index state after record k (the three.js loader orders the
    // triangles it will draw meanwhile)
    this.onTopology = null;
  }

  // Take the next bytes of the stream (any split); decodes what is whole:
  // a chunk's topology (and wedges) once its first columns are in, its
  // positions once all of it is. Returns the number of records completed.
  push(chunk) {
    const before = this.count;
    if (!this.header) {
      const merged = new Uint8Array(this.headBytes.length + chunk.length);
      merged.set(this.headBytes, 0);
      merged.set(chunk, this.headBytes.length);
      try {
        this.header = parseHeader(merged);
      } catch (e) {
        if (e instanceof NeedMore) { this.headBytes = merged; return 0; }
        throw e;
      }
      this.headBytes = null;
      this.consumed = this.header.headerBytes;
      chunk = merged.subarray(this.header.headerBytes);
    }
    const h = this.header;
    let at = 0;
    while (at < chunk.length) {
      if (this.chunksDone === h.chunks.length) throw new Error(`${chunk.length - at} bytes follow the last chunk`);
      const c = h.chunks[this.chunksDone];
      if (!this.buf) { this.buf = new Uint8Array(c.bytes); this.have = 0; }
      const n = Math.min(c.bytes - this.have, chunk.length - at);
      this.buf.set(chunk.subarray(at, at + n), this.have);
      this.have += n;
      at += n;
      if (this.chunksDone === 0) {
        if (this.have === c.bytes) this.decodeBase(this.buf, this.consumed);
      } else {
        this.decodeChunk(this.buf, this.have, this.consumed, c.records - h.chunks[this.chunksDone - 1].records);
      }
      if (this.have === c.bytes) {
        this.consumed += c.bytes;
        this.chunksDone++;
        this.buf = null;
        this.have = 0;
      }
    }
    if (this.complete()) {
      if (this.nt !== h.totalTriangles) throw new Error("the records restore a different triangle count");
      if (h.wedges && this.nw !== h.wedges.total) throw new Error("the records define a different wedge count");
    }
    return this.count - before;
  }

  complete() {
    return !!this.header && this.chunksDone === this.header.chunks.length;
  }

  deq(q, v, out, o) {
    const h = this.header, s = h.scale;
    for (let a = 0; a < 3; a++) out[o + a] = Math.fround(h.center[a] + ((q[3 * v + a] - s) / s) * h.half);
  }

  // Record i as an object of subarrays (for callers that want one).
  record(i) {
    const f = 3 * this.fStart[i], g = 3 * this.fStart[i + 1], c = this.cStart[i], d = this.cStart[i + 1];
    return {
      v1: this.v1[i], v0: this.header.baseVertices + i,
      p1: this.p1 && this.p1.subarray(3 * i, 3 * i + 3), pm: this.pm && this.pm.subarray(3 * i, 3 * i + 3),
      p0: this.p0 && this.p0.subarray(3 * i, 3 * i + 3),
      faces: this.faces0.subarray(f, g), corners: this.corners.a.subarray(c, d),
      wfaces: this.wfaces0 ? this.wfaces0.subarray(f, g) : null,
      wafter: this.wfaces0 ? this.wafter.a.subarray(c, d) : null,
      wbefore: this.wfaces0 ? this.wbefore.a.subarray(c, d) : null,
    };
  }

  decodeBase(bytes, offset) {
    const h = this.header, cols = new Columns(this.mo, bytes, offset), nv = h.baseVertices;
    const q4 = cols.u16x4("base position", nv);
    const q = new Uint16Array(h.totalVertices * 3);
    const lim = 2 * h.scale;
    for (let v = 0; v < nv; v++) {
      for (let a = 0; a < 3; a++) {
        const x = q4[4 * v + a];
        if (x > lim) throw new Error("base position outside the grid");
        q[3 * v + a] = x;
      }
    }
    const flat = cols.sequence("base triangle", 3 * h.baseTriangles);
    for (let i = 0; i < flat.length; i++) if (flat[i] >= nv) throw new Error(`base corner ${flat[i]} out of range`);
    const nc = 3 * h.totalTriangles, ns = h.splitCount;
    this.tri = new Uint32Array(nc);
    this.tri.set(flat, 0);
    this.faces0 = new Uint32Array(nc);
    this.faces0.set(flat, 0);
    // the corners at each vertex, ascending: a linked list per vertex
    this.head = new Uint32Array(h.totalVertices).fill(NONE);
    this.tail = new Uint32Array(h.totalVertices).fill(NONE);
    this.nextC = new Uint32Array(nc);
    this.v1 = new Uint32Array(ns);
    this.fStart = new Uint32Array(ns + 1);
    this.cStart = new Uint32Array(ns + 1);
    this.fStart[0] = h.baseTriangles;
    this.corners = new U32List();
    this.q1 = new Uint16Array(3 * ns); // grid points of p1 / p0
    this.q0 = new Uint16Array(3 * ns);
    this.p1 = this.floats ? new Float32Array(3 * ns) : null;
    this.p0 = this.floats ? new Float32Array(3 * ns) : null;
    this.pm = this.floats ? new Float32Array(3 * ns) : null;
    this.scratch = new Uint32Array(64);
    this.ringBuf = new Uint32Array(128); // ring(): 2 per corner at most
    this.movedOf = new Int32Array(h.totalVertices).fill(-1);
    this.oldT = new Uint32Array(64); // v1's old triangles, from ring()
    this.oldK = new Uint32Array(64); // v1's old corners: their index in oldT
    this.oldC = new Uint32Array(64); // v1's old corners, ascending
    this.oldA = new Uint32Array(64); // per old triangle: the vertex after v1
    this.oldB = new Uint32Array(64); // and the one before
    this.queueT = new Uint32Array(64); // predictMask scratch
    this.taken = new Uint8Array(64);
    this.wingT = new Uint32Array(8);
    this.nt = h.baseTriangles;
    this.nv = nv;
    this.q = q;
    for (let c = 0; c < 3 * this.nt; c++) this.append(c);
    this.wfaces0 = null;
    if (h.wedges) {
      const w = h.wedges;
      this.wvals = new Float32Array(w.total * w.stride);
      this.wvalsBits = new Uint32Array(this.wvals.buffer);
      this.wgroups = new Uint32Array(w.total);
      this.qv = new Uint16Array(w.total * w.qstride);
      this.fv = new Float32Array(w.total * w.fstride);
      this.fvBits = new Uint32Array(this.fv.buffer);
      this.qpred = new Uint16Array(w.qstride);
      this.fpred = new Uint32Array(w.fstride);
      this.f32 = new Float32Array(1);
      this.f32Bits = new Uint32Array(this.f32.buffer);
      this.cand = new Uint32Array(64);
      this.candN = 0;
      this.nw = 0;
      this.cw = new Uint32Array(nc);
      this.cw.fill(NONE, 0, 3 * h.baseTriangles);
      this.wfaces0 = new Uint32Array(nc);
      this.wafter = new U32List();
      this.wbefore = new U32List();
      const wc = this.wedgeColumns(cols);
      for (let i = 0; i < 3 * h.baseTriangles; i++) wc.next((i / 3) | 0, i % 3, undefined, null);
      wc.finish();
      wc.values(cols);
      this.baseCW = this.cw.slice(0, 3 * h.baseTriangles);
      this.wfaces0.set(this.baseCW, 0);
    }
    cols.finish("the base chunk");
    this.baseTri = flat;
    this.baseQ = q.slice(0, 3 * nv);
    this.basePositions = new Float32Array(nv * 3);
    for (let v = 0; v < nv; v++) this.deq(q, v, this.basePositions, 3 * v);
    this.cur = this.floats ? new Float32Array(h.totalVertices * 3) : null;
    if (this.cur) this.cur.set(this.basePositions, 0);
    this.baseReady = true;
  }

  // Corner c (the largest so far) joins its vertex's list.
  append(c) {
    const v = this.tri[c];
    this.nextC[c] = NONE;
    if (this.head[v] === NONE) this.head[v] = c;
    else this.nextC[this.tail[v]] = c;
    this.tail[v] = c;
  }

  // Corners cs[k0 .. k1] (ascending, all in `from`'s list) leave it and
  // join `to`'s, in order: one pass over each list.
  moveCorners(cs, k0, k1, from, to) {
    if (k0 === k1) return;
    const next = this.nextC, head = this.head, tail = this.tail;
    let p = NONE, x = head[from], k = k0;
    while (k < k1) {
      const nx = next[x];
      if (x === cs[k]) {
        if (p === NONE) head[from] = nx;
        else next[p] = nx;
        if (tail[from] === x) tail[from] = p;
        k++;
      } else p = x;
      x = nx;
    }
    p = NONE;
    x = head[to];
    for (k = k0; k < k1; k++) {
      const c = cs[k];
      while (x !== NONE && x < c) { p = x; x = next[x]; }
      next[c] = x;
      if (p === NONE) head[to] = c;
      else next[p] = c;
      p = c;
    }
    if (x === NONE) tail[to] = p;
  }

  // Room for n old triangles / corners at v1 in the scratch arrays.
  growOld(n) {
    if (n < this.oldC.length) return;
    const grow = (a) => { const b = new a.constructor(2 * n); b.set(a); return b; };
    this.oldT = grow(this.oldT); this.oldK = grow(this.oldK); this.oldC = grow(this.oldC);
    this.oldA = grow(this.oldA); this.oldB = grow(this.oldB);
    const r = new Uint32Array(4 * n);
    r.set(this.ringBuf);
    this.ringBuf = r;
    this.queueT = grow(this.queueT); this.taken = grow(this.taken);
  }

  // The vertices sharing a triangle with v, ascending, each once (a
  // scratch array, its first this.ringN entries, valid until the next call). Also v's corners into
  // oldC[0 .. this.nOldC], their triangles (each once) into
  // oldT[0 .. this.nOldT] (oldA / oldB: the vertices after / before v's
  // first corner there), oldK[j] = the index in oldT of corner j.
  ring(v) {
    const tri = this.tri, next = this.nextC;
    let r = this.ringBuf, oldA = this.oldA, oldB = this.oldB, oldT = this.oldT, oldK = this.oldK, oldC = this.oldC;
    let n = 0, nc = 0, nt = 0, last = -1;
    for (let c = this.head[v]; c !== NONE; c = next[c]) {
      const t = (c / 3) | 0, o = 3 * t, s = c - o;
      if (nc === oldC.length) {
        this.growOld(nc);
        r = this.ringBuf; oldA = this.oldA; oldB = this.oldB; oldT = this.oldT; oldK = this.oldK; oldC = this.oldC;
      }
      if (t !== last) {
        // a triangle's other vertices are the ones after / before v's
        // first corner there (v itself again when it holds v twice)
        last = t;
        const x = tri[o + (s === 2 ? 0 : s + 1)], y = tri[o + (s === 0 ? 2 : s - 1)];
        oldA[nt] = x;
        oldB[nt] = y;
        oldT[nt++] = t;
        if (x !== v) n = insertSorted(r, n, x);
        if (y !== v) n = insertSorted(r, n, y);
      }
      oldK[nc] = nt - 1;
      oldC[nc++] = c;
    }
    this.ringN = n;
    this.nOldC = nc;
    this.nOldT = nt;
    return r;
  }

  // The candidate wedges of corner (t, s) (docs/LODGEN_progressive.md):
  // wedges at its vertex in the triangles sharing an edge with t, then
  // `before`, then every other wedge at the vertex.
  // (this.cand[0 .. this.candN]; nothing allocated but when it grows).
  // Only the first `need` are wanted: the list stops there.
  candidates(t, s, before, need) {
    const tri = this.tri, cw = this.cw, next = this.nextC;
    this.candN = 0;
    const o = 3 * t, u = tri[o + s], a = tri[o + ((s + 1) % 3)], b = tri[o + ((s + 2) % 3)];
    for (let c = this.head[u]; c !== NONE; c = next[c]) {
      const p = c - (c % 3);
      if (p === o) continue;
      const g0 = tri[p], g1 = tri[p + 1], g2 = tri[p + 2];
      if ((a !== u && (g0 === a || g1 === a || g2 === a)) || (b !== u && (g0 === b || g1 === b || g2 === b))) {
        this.candPush(cw[c]);
        if (this.candN >= need) return;
      }
    }
    if (before !== undefined) {
      this.candPush(before);
      if (this.candN >= need) return;
    }
    for (let c = this.head[u]; c !== NONE; c = next[c]) {
      if (c - (c % 3) === o) continue;
      this.candPush(cw[c]);
      if (this.candN >= need) return;
    }
  }

  // w joins the candidates unless NONE or there already.
  candPush(w) {
    if (w === NONE) return;
    const cand = this.cand, n = this.candN;
    for (let i = 0; i < n; i++) if (cand[i] === w) return;
    if (n === cand.length) {
      this.cand = new Uint32Array(2 * n);
      this.cand.set(cand);
    }
    this.cand[n] = w;
    this.candN = n + 1;
  }

  // The wedges predicting a new wedge's values at corner (t, s):
  // [kind, a, b, c], kind 0 = none, 1 = a, 2 = a + b - c.
  predictor(t, s, rec) {
    const tri = this.tri, cw = this.cw, o = 3 * t;
    if (rec && rec.wings && tri[o + s] === rec.v0 && (t === rec.wings[0] || t === rec.wings[1])) {
      const { v0, v1 } = rec, t2 = t === rec.wings[0] ? rec.wings[1] : rec.wings[0], p = 3 * t2;
      let x = -1, y = -1, s1 = -1, s2 = -1;
      for (let i = 0; i < 3; i++) {
        if (x < 0 && tri[o + i] !== v0 && tri[o + i] !== v1) x = i;
        if (y < 0 && tri[p + i] !== v0 && tri[p + i] !== v1) y = i;
        if (s1 < 0 && tri[o + i] === v1) s1 = i;
        if (s2 < 0 && tri[p + i] === v1) s2 = i;
      }
      if (x >= 0 && y >= 0 && s1 >= 0 && s2 >= 0) {
        const wx = cw[o + x], wy = cw[p + y], w1 = cw[o + s1];
        if (wx !== NONE && wy !== NONE && w1 !== NONE && w1 === cw[p + s2]) return [2, wx, wy, w1];
      }
    }
    if (rec) for (let i = 0; i < 3; i++) if (i !== s && tri[o + i] === rec.v1 && cw[o + i] !== NONE) return [1, cw[o + i]];
    for (const i of [(s + 1) % 3, (s + 2) % 3]) if (cw[o + i] !== NONE) return [1, cw[o + i]];
    return [0];
  }
  // The wedge columns of a block (or of the base corners): the references
  // and groups first; next(t, s, before, rec) = the wedge of corner (t, s),
  // recorded there, a new wedge numbered and its predictor kept; then
  // values(cols), once the channel columns are in (they follow the
  // references: the block's topology and wedge ids are replayed while they
  // download), gives the new wedges their values, in the order defined.
  wedgeColumns(cols) {
    const w = this.header.wedges, dec = this;
    const refs = cols.u32("wedge reference");
    let fresh = 0;
    for (const c of refs) if (c === 0) fresh++;
    const groups = w.groups > 1 ? cols.u32("wedge group", fresh) : null;
    // per new wedge: its predictor (kind, a, b, c; see predictor)
    const preds = new Uint32Array(4 * fresh), firstId = dec.nw;
    let pos = 0, k = 0;
    const define = (t, s, rec) => {
      if (dec.nw >= w.total) throw new Error(`more wedges than the ${w.total} announced`);
      const g = groups ? groups[k] : 0;
      if (g >= w.groups) throw new Error(`wedge group ${g} out of range`);
      dec.wgroups[dec.nw] = g;
      const p = dec.predictor(t, s, rec);
      preds[4 * k] = p[0];
      for (let i = 1; i < p.length; i++) preds[4 * k + i] = p[i];
      k++;
      return dec.nw++;
    };
    return {
      next(t, s, before, rec) {
        if (pos >= refs.length) throw new Error("the wedge reference column ends early");
        const code = refs[pos++];
        let id;
        if (code === 0) id = define(t, s, rec);
        else {
          // (candidate `code`, or, past the list's end, its length)
          dec.candidates(t, s, before, code);
          const n = dec.candN;
          if (code <= n) id = dec.cand[code - 1];
          else if (code - n <= dec.nw) id = dec.nw - (code - n);
          else throw new Error(`wedge reference ${code} out of range`);
        }
        dec.cw[3 * t + s] = id;
        return id;
      },
      finish() {
        if (pos !== refs.length) throw new Error("wedge references left over");
      },
      values(cols) {
        // per channel: zigzag f32 bit residuals, or quantized residuals (padded lanes)
        const values = w.channels.map((c) => {
          if (c.encoding === 0) {
            const b = cols.vertices("attribute", 4 * c.components, fresh);
            const z = new Uint32Array(b.buffer, b.byteOffset, b.length / 4);
            for (let i = 0; i < z.length; i++) z[i] = (z[i] >>> 1) ^ -(z[i] & 1);
            return z;
          }
          const b = cols.vertices("attribute", 2 * c.padded, fresh);
          const sums = new Uint16Array(b.buffer, b.byteOffset, b.length / 2), res = new Uint16Array(sums.length);
          for (let i = 0; i < sums.length; i++) res[i] = i < c.padded ? sums[i] : sums[i] - sums[i - c.padded];
          return res;
        });
        const qp = dec.qpred, fp = dec.fpred, qs = w.qstride, fs = w.fstride;
        for (let j = 0; j < k; j++) {
          const id = firstId + j, kind = preds[4 * j], a = preds[4 * j + 1], b = preds[4 * j + 2], c = preds[4 * j + 3];
          if (kind === 0) { qp.fill(0); fp.fill(0); }
          else if (kind === 1) {
            for (let i = 0; i < qs; i++) qp[i] = dec.qv[a * qs + i];
            for (let i = 0; i < fs; i++) fp[i] = dec.fvBits[a * fs + i];
          } else {
            for (let i = 0; i < qs; i++) qp[i] = dec.qv[a * qs + i] + dec.qv[b * qs + i] - dec.qv[c * qs + i];
            for (let i = 0; i < fs; i++) {
              const x = Math.fround(dec.fv[a * fs + i] + dec.fv[b * fs + i] - dec.fv[c * fs + i]);
              if (Number.isFinite(x)) { dec.f32[0] = x; fp[i] = dec.f32Bits[0]; } else fp[i] = 0;
            }
          }
          for (let ci = 0; ci < w.channels.length; ci++) {
            const ch = w.channels[ci], out = id * w.stride + ch.offset, r = values[ci];
            if (ch.encoding === 0) {
              for (let m = 0; m < ch.components; m++) {
                const bits = (fp[ch.flane + m] + r[j * ch.components + m]) >>> 0;
                dec.fvBits[id * fs + ch.flane + m] = bits;
                dec.wvalsBits[out + m] = bits;
              }
            } else {
              for (let m = 0; m < ch.components; m++) {
                const q = (qp[ch.qlane + m] + r[j * ch.padded + m]) & 0xffff;
                if (q > ENC_MAX[ch.encoding]) throw new Error(`attribute value ${q} over ${ENC_MAX[ch.encoding]}`);
                dec.qv[id * qs + ch.qlane + m] = q;
                dec.wvals[out + m] = dequantize(ch, q);
              }
            }
          }
        }
      },
    };
  }

  // A chunk of n records, `have` of its bytes in: the topology (and the
  // wedges, whose columns come before the positions) is replayed block by
  // block, each once its columns are in, while the rest of the chunk still
  // downloads; the positions once the chunk is whole.
  decodeChunk(bytes, have, offset, n) {
    const h = this.header, whole = have === bytes.length;
    if (!this.topo) {
      const cols = new Columns(this.mo, bytes, offset);
      this.topo = { cols, wc: null, first: this.count, done: 0, va: this.nv, rings: new U32List(8 * n + 8), ringEnd: new Uint32Array(n) };
    }
    const topo = this.topo, cols = topo.cols, w = h.wedges;
    // a block's columns before its replay: v1, face codes, escapes, corner
    // mask (and the wedge references and groups); its wedges' values
    // (one column per channel) are needed only after it
    const before = 4 + (w ? 1 + (w.groups > 1 ? 1 : 0) : 0);
    for (;;) {
      if (topo.wc) {
        // a block replayed, its new wedges waiting for their values
        if (!whole && !columnsIn(bytes, cols.r.pos, have, w.channels.length)) return;
        topo.wc.values(cols);
        topo.wc = null;
        if (topo.done === n && this.onTopology) this.onTopology(topo.first + n);
      }
      if (topo.done === n) break;
      if (!whole && !columnsIn(bytes, cols.r.pos, have, before)) return;
      const m = Math.min(BLOCK_RECORDS, n - topo.done), at = topo.first + topo.done;
      const v1s = cols.u32("split vertex", m);
      const codes = cols.vertices("face code", 4, m);
      const extra = words(cols.u32("escape"), "escape");
      const mask = cols.bits("corner mask");
      // the wedges are coded in replay order
      topo.wc = w ? this.wedgeColumns(cols) : null;
      for (let i = 0; i < m; i++) this.replay(at + i, v1s[i], codes, i, extra, mask, topo);
      if (!extra.done() || !mask.done()) throw new Error("escape or corner-mask values left over");
      if (topo.wc) topo.wc.finish();
      topo.done += m;
      // the chunk's topology is whole: tri holds the index state after it
      // (with wedges: once their values are in, above)
      if (!topo.wc && topo.done === n && this.onTopology) this.onTopology(topo.first + n);
    }
    if (!whole) return;
    const { first, va } = topo;
    const moved = cols.u16x4("moved position");
    const fresh = cols.u16x4("new position", n);
    if (h.flags & 1) cols.u32("error", n);
    cols.finish("the chunk");
    this.positions(first, n, moved, fresh, va, topo);
    this.topo = null;
    this.count += n;
  }

  // Replays record i (topology, and wedges with `topo.wc`), appending it to
  // the record columns and v0's ring to `topo.rings`.
  replay(i, v1, codes, ci, extra, mask, topo) {
    const wc = topo.wc;
    const h = this.header, v0 = this.nv, tri = this.tri;
    if (v1 >= v0) throw new Error(`split vertex ${v1} does not exist yet`);
    const ring = this.ring(v1);
    let nf = codes[4 * ci];
    if (nf === 255) nf = extra.next();
    if (nf > 65536) throw new Error(`${nf} faces in one split`);
    const first = this.nt;
    if (first + nf > h.totalTriangles) throw new Error("more triangles than announced");
    if (this.scratch.length < nf) this.scratch = new Uint32Array(2 * nf);
    const cs = this.scratch;
    for (let k = 0; k < nf; k++) {
      const c = k < 2 ? codes[4 * ci + 1 + k] : extra.next();
      if (c > 255) throw new Error("face code over 255");
      cs[k] = c;
    }
    for (let k = 0; k < nf; k++) {
      const c = cs[k], o = 3 * (first + k);
      if (c === FACE_ESCAPE) {
        for (let j = 0; j < 3; j++) {
          const x = extra.next();
          const v = x === 0 ? v0 : x === 1 ? v1 : x - 1 <= v0 ? v0 - (x - 1) : -1;
          if (v < 0) throw new Error("escaped face corner out of range");
          tri[o + j] = v;
        }
      } else {
        const p = c % 6, r = (c / 6) | 0;
        if (r >= RING_CODES || r >= this.ringN) throw new Error(`face code ${c} beyond the ring of ${v1}`);
        const perm = PERMS[p];
        tri[o + perm[0]] = v0;
        tri[o + perm[1]] = v1;
        tri[o + perm[2]] = ring[r];
      }
    }
    const faces0 = this.faces0;
    for (let c = 3 * first, e = 3 * (first + nf); c < e; c++) faces0[c] = tri[c];
    this.nv++;
    this.nt += nf;
    for (let c = 3 * first; c < 3 * this.nt; c++) this.append(c);
    this.v1[i] = v1;
    this.fStart[i + 1] = this.nt;
    // the corners at v1 (ascending), each moved to v0 when the mask (or,
    // without one, the prediction) says so
    const corners = this.corners, c0 = corners.n, next = this.nextC, flag = codes[4 * ci + 3];
    if (flag > 1) throw new Error(`corner-edit flag ${flag}`);
    if (flag === 1) {
      for (let c = this.head[v1]; c !== NONE; c = next[c]) if (mask.next()) corners.push(c);
    } else this.predictMask(v0, v1, first);
    for (let k = c0; k < corners.n; k++) tri[corners.a[k]] = v0;
    this.moveCorners(corners.a, c0, corners.n, v1, v0);
    this.cStart[i + 1] = corners.n;
    // v0's ring (each vertex once; the centroid needs no order)
    const rings = topo.rings, r0 = rings.n;
    if (flag === 0 && this.nOldT === this.nOldC) {
      // predicted, v1 once in each old triangle: v0's triangles are the
      // taken old ones (their other vertices oldA / oldB) and the new
      // faces holding v0
      const taken = this.taken, oa = this.oldA, ob = this.oldB;
      for (let k = 0, n = this.nOldT; k < n; k++) {
        if (!taken[k]) continue;
        ringPush(rings, r0, oa[k]);
        ringPush(rings, r0, ob[k]);
      }
      for (let c = 3 * first, e = 3 * this.nt; c < e; c += 3) {
        const x = tri[c], y = tri[c + 1], z = tri[c + 2];
        if (x !== v0 && y !== v0 && z !== v0) continue;
        if (x !== v0) ringPush(rings, r0, x);
        if (y !== v0) ringPush(rings, r0, y);
        if (z !== v0) ringPush(rings, r0, z);
      }
    } else {
      for (let c = this.head[v0]; c !== NONE; c = next[c]) {
        const o = c - (c % 3);
        for (let j = 0; j < 3; j++) if (tri[o + j] !== v0) ringPush(rings, r0, tri[o + j]);
      }
    }
    topo.ringEnd[i - topo.first] = topo.rings.n;
    if (wc) {
      const cw = this.cw, end = 3 * this.nt;
      const wf = wingFaces(this.faces0.subarray(3 * first, end), v0, v1);
      const ctx = { v0, v1, wings: wf ? [first + wf[0], first + wf[1]] : null };
      cw.fill(NONE, 3 * first, end);
      for (let pass = 0; pass < 2; pass++) {
        for (let c = 3 * first; c < end; c++) {
          if ((tri[c] === v0) === (pass === 1)) wc.next((c / 3) | 0, c % 3, undefined, ctx);
        }
      }
      this.wfaces0.set(cw.subarray(3 * first, end), 3 * first);
      for (let k = c0; k < corners.n; k++) {
        const c = corners.a[k];
        this.wbefore.push(cw[c]);
        cw[c] = NONE;
      }
      for (let k = c0; k < corners.n; k++) {
        const c = corners.a[k];
        this.wafter.push(wc.next((c / 3) | 0, c % 3, this.wbefore.a[k], ctx));
      }
    }
  }

  // The predicted corner edits of a split (topo.rs predict_mask), pushed on
  // this.corners: the new faces' wings x cut v1's old triangles (below
  // `first`) in two arcs; v0 takes the one starting at the old triangle
  // with edge v1 -> x (x -> v1 when the face has v0 -> x), spreading across
  // edges {v1, y}, y no wing.
  predictMask(v0, v1, first) {
    // v1's old triangles and corners, as ring(v1) left them; v1 once in
    // each (the usual case): its edges are v1 -> oldA, oldB -> v1
    const tri = this.tri, no = this.nOldT, once = no === this.nOldC, oa = this.oldA, ob = this.oldB;
    if (this.wingT.length < this.nt - first) this.wingT = new Uint32Array(2 * (this.nt - first));
    const old = this.oldT, queue = this.queueT, taken = this.taken, wings = this.wingT;
    for (let k = 0; k < no; k++) taken[k] = 0;
    let nw = 0, nq = 0;
    for (let t = first; t < this.nt; t++) {
      const o = 3 * t, f0 = tri[o], f1 = tri[o + 1], f2 = tri[o + 2];
      if ((f0 !== v0 && f1 !== v0 && f2 !== v0) || (f0 !== v1 && f1 !== v1 && f2 !== v1)) continue;
      let m = 0, ix = -1;
      for (let j = 0; j < 3; j++) if (tri[o + j] !== v0 && tri[o + j] !== v1) { m++; if (ix < 0) ix = j; }
      if (m !== 1) continue;
      const x = tri[o + ix];
      wings[nw++] = x;
      const from = tri[o + ((ix + 1) % 3)] === v0 ? v1 : x, to = from === v1 ? x : v1;
      for (let k = 0; k < no; k++) {
        if (taken[k]) continue;
        if (once) {
          if (from === v1 ? oa[k] === to : ob[k] === from) { taken[k] = 1; queue[nq++] = k; }
          continue;
        }
        const p = 3 * old[k];
        for (let j = 0; j < 3; j++) {
          if (tri[p + j] === from && tri[p + ((j + 1) % 3)] === to) { taken[k] = 1; queue[nq++] = k; break; }
        }
      }
    }
    // across edges {v1, y}: the old triangles are the ones at v1, and
    // oldA / oldB hold every other vertex of each
    while (nq > 0) {
      const k = queue[--nq], ya = oa[k], yb = ob[k];
      let sa = ya !== v1, sb = yb !== v1;
      for (let w = 0; w < nw; w++) {
        if (wings[w] === ya) sa = false;
        if (wings[w] === yb) sb = false;
      }
      if (!sa && !sb) continue;
      // one pass for both edges (the taken set is their closure: order is free)
      for (let m = 0; m < no; m++) {
        if (taken[m]) continue;
        const a = oa[m], b = ob[m];
        if ((sa && (a === ya || b === ya)) || (sb && (a === yb || b === yb))) { taken[m] = 1; queue[nq++] = m; }
      }
    }
    const oc = this.oldC, ok = this.oldK, corners = this.corners;
    for (let j = 0, n = this.nOldC; j < n; j++) if (taken[ok[j]]) corners.push(oc[j]);
  }

  // Grid points at the chunk's end for records first .. first + n, then
  // each record's p1 / p0 / p_merged.
  positions(first, n, movedSums, freshSums, va, topo) {
    const q = this.q, lim = 2 * this.header.scale, slot = this.movedOf;
    // the moved vertices: distinct v1 < va, in order of first appearance
    const moved = [];
    for (let i = first; i < first + n; i++) {
      const v = this.v1[i];
      if (v < va && slot[v] < 0) { slot[v] = moved.length; moved.push(v); }
    }
    if (moved.length * 4 !== movedSums.length) throw new Error(`${movedSums.length / 4} moved positions for ${moved.length} moved vertices`);
    let px = 0, py = 0, pz = 0;
    for (let k = 0; k < moved.length; k++) {
      const v = moved[k], x = movedSums[4 * k], y = movedSums[4 * k + 1], z = movedSums[4 * k + 2];
      const r0 = x - px, r1 = y - py, r2 = z - pz;
      px = x; py = y; pz = z;
      for (let a = 0; a < 3; a++) {
        const e = (q[3 * v + a] + (a === 0 ? r0 : a === 1 ? r1 : r2)) & 0xffff;
        if (e > lim) throw new Error("position outside the grid");
        q[3 * v + a] = e;
      }
    }
    // each new vertex predicted by its ring's centroid (rounded half up)
    const rings = topo.rings.a, ends = topo.ringEnd;
    px = py = pz = 0;
    for (let j = 0; j < n; j++) {
      const i = first + j, v1 = this.v1[i], v0 = this.header.baseVertices + i;
      const x = freshSums[4 * j], y = freshSums[4 * j + 1], z = freshSums[4 * j + 2];
      const r0 = x - px, r1 = y - py, r2 = z - pz;
      px = x; py = y; pz = z;
      const from = j === 0 ? 0 : ends[j - 1], to = ends[j], m = to - from;
      let s0 = q[3 * v1], s1 = q[3 * v1 + 1], s2 = q[3 * v1 + 2];
      if (m > 0) {
        let t0 = 0, t1 = 0, t2 = 0;
        for (let k = from; k < to; k++) {
          const u = 3 * rings[k];
          t0 += q[u]; t1 += q[u + 1]; t2 += q[u + 2];
        }
        s0 = Math.floor((2 * t0 + m) / (2 * m));
        s1 = Math.floor((2 * t1 + m) / (2 * m));
        s2 = Math.floor((2 * t2 + m) / (2 * m));
      }
      const e0 = (s0 + r0) & 0xffff, e1 = (s1 + r1) & 0xffff, e2 = (s2 + r2) & 0xffff;
      if (e0 > lim || e1 > lim || e2 > lim) throw new Error("position outside the grid");
      q[3 * v0] = e0; q[3 * v0 + 1] = e1; q[3 * v0 + 2] = e2;
    }
    for (const v of moved) slot[v] = -1;
    const base = this.header.baseVertices, q1 = this.q1, q0 = this.q0;
    for (let i = first; i < first + n; i++) {
      const u = 3 * this.v1[i], w = 3 * (base + i), r = 3 * i;
      q1[r] = q[u]; q1[r + 1] = q[u + 1]; q1[r + 2] = q[u + 2];
      q0[r] = q[w]; q0[r + 1] = q[w + 1]; q0[r + 2] = q[w + 2];
    }
    if (!this.floats) return;
    // replay positions in order: p_merged is the position before the split
    const c = this.cur;
    for (let i = first; i < first + n; i++) {
      const v1 = this.v1[i], v0 = this.header.baseVertices + i;
      this.deq(q, v1, this.p1, 3 * i);
      this.deq(q, v0, this.p0, 3 * i);
      for (let a = 0; a < 3; a++) {
        this.pm[3 * i + a] = c[3 * v1 + a];
        c[3 * v1 + a] = this.p1[3 * i + a];
        c[3 * v0 + a] = this.p0[3 * i + a];
      }
    }
  }
}
