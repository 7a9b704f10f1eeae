// LODGEN_progressive stream decoder (layout version 3, docs/LODGEN_progressive.md),
// a second, independent implementation of crates/lodgen-pm/src/progressive/stream/.
// Used by the `lodgen view` page (viewer.js) and the three.js loader
// (three/index.js). The columns are decoded by meshoptimizer's
// MeshoptDecoder (npm package `meshoptimizer`), passed to the constructor:
//
//   import { MeshoptDecoder } from "meshoptimizer";
//   await MeshoptDecoder.ready;
//   const d = new StreamDecoder(MeshoptDecoder);
//   d.push(bytes);                 // any split of the stream; decodes whole chunks
//   d.records                      // [{v1, v0, p1, pm, p0, faces, corners, wfaces, wafter, wbefore}]
//
// Positions come out as grid points (d.q, Uint16Array, 3 per vertex) and as
// f32 (center + (q - s) / s * half in double precision, rounded once).
// `corners` are corner indices t * 3 + slot; p1 / pm / p0, faces and corners
// are plain arrays.

const FACE_ESCAPE = 255;
const NONE = 0xffffffff;
// attribute encodings: 0 f32, 1 unorm16, 2 snorm8, 3 unorm8
const ENC_MAX = [0, 65535, 254, 255];
function dequantize(e, q) {
  return Math.fround(e === 1 ? q / 65535 : e === 2 ? (q - 127) / 127 : q / 255);
}
const RING_CODES = 42;
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
  if (version !== 3) throw new Error(`unsupported stream version ${version}`);
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
      if (c.encoding > 3) throw new Error(`unknown attribute encoding ${c.encoding}`);
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

// Residuals from the prefix sums a u16x4 column stores (x, y, z, 0).
function differences(sums) {
  const n = sums.length / 4, out = new Uint16Array(n * 3);
  let px = 0, py = 0, pz = 0;
  for (let i = 0; i < n; i++) {
    const x = sums[4 * i], y = sums[4 * i + 1], z = sums[4 * i + 2];
    out[3 * i] = (x - px) & 0xffff;
    out[3 * i + 1] = (y - py) & 0xffff;
    out[3 * i + 2] = (z - pz) & 0xffff;
    px = x; py = y; pz = z;
  }
  return out;
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

function wings(faces, v0, v1) {
  const w = wingFaces(faces, v0, v1);
  if (!w) return null;
  const third = (k) => { for (let j = 0; j < 3; j++) { const x = faces[3 * k + j]; if (x !== v0 && x !== v1) return x; } return -1; };
  return [third(w[0]), third(w[1])];
}

export class StreamDecoder {
  constructor(meshoptDecoder) {
    this.mo = meshoptDecoder;
    this.pending = new Uint8Array(0);
    this.consumed = 0;
    this.header = null;
    this.chunksDone = 0;
    this.baseReady = false;
    this.records = [];
    this.levelEvents = [];
  }

  push(chunk) {
    const merged = new Uint8Array(this.pending.length + chunk.length);
    merged.set(this.pending, 0);
    merged.set(chunk, this.pending.length);
    this.pending = merged;
    const before = this.records.length;
    if (!this.header) {
      try {
        this.header = parseHeader(this.pending);
      } catch (e) {
        if (e instanceof NeedMore) return 0;
        throw e;
      }
      this.eat(this.header.headerBytes);
    }
    const h = this.header;
    while (this.chunksDone < h.chunks.length && this.pending.length >= h.chunks[this.chunksDone].bytes) {
      const c = h.chunks[this.chunksDone];
      const bytes = this.pending.subarray(0, c.bytes);
      if (this.chunksDone === 0) this.decodeBase(bytes, this.consumed);
      else this.decodeChunk(bytes, this.consumed, c.records - h.chunks[this.chunksDone - 1].records);
      this.chunksDone++;
      this.eat(c.bytes);
    }
    if (this.chunksDone === h.chunks.length) {
      if (this.pending.length) throw new Error(`${this.pending.length} bytes follow the last chunk`);
      if (this.nt !== h.totalTriangles) throw new Error("the records restore a different triangle count");
      if (h.wedges && this.nw !== h.wedges.total) throw new Error("the records define a different wedge count");
    }
    return this.records.length - before;
  }

  eat(n) {
    this.consumed += n;
    this.pending = this.pending.slice(n);
  }

  complete() {
    return !!this.header && this.chunksDone === this.header.chunks.length && this.pending.length === 0;
  }

  deq(q, v, out, o) {
    const h = this.header, s = h.scale;
    for (let a = 0; a < 3; a++) out[o + a] = Math.fround(h.center[a] + ((q[3 * v + a] - s) / s) * h.half);
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
    for (const v of flat) if (v >= nv) throw new Error(`base corner ${v} out of range`);
    this.tri = new Uint32Array(h.totalTriangles * 3);
    this.tri.set(flat, 0);
    this.nt = h.baseTriangles;
    this.nv = nv;
    this.q = q;
    this.fans = [];
    for (let v = 0; v < nv; v++) this.fans.push([]);
    for (let t = 0; t < this.nt; t++) this.addFan(t);
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
      this.cand = [];
      this.nw = 0;
      this.cw = new Uint32Array(h.totalTriangles * 3);
      this.cw.fill(NONE, 0, 3 * h.baseTriangles);
      const wc = this.wedgeColumns(cols);
      for (let i = 0; i < 3 * h.baseTriangles; i++) wc.next((i / 3) | 0, i % 3, undefined, null);
      wc.finish();
      this.baseCW = this.cw.slice(0, 3 * h.baseTriangles);
    }
    cols.finish("the base chunk");
    this.baseTri = flat;
    this.basePositions = new Float32Array(nv * 3);
    for (let v = 0; v < nv; v++) this.deq(q, v, this.basePositions, 3 * v);
    this.baseReady = true;
  }

  addFan(t) {
    const tri = this.tri;
    for (let i = 0; i < 3; i++) {
      const v = tri[3 * t + i];
      if ((i > 0 && tri[3 * t] === v) || (i > 1 && tri[3 * t + 1] === v)) continue;
      this.fans[v].push(t);
    }
  }

  // The vertices sharing a triangle with v, ascending, each once (a
  // scratch array, valid until the next call).
  ring(v) {
    const r = this.ringBuf || (this.ringBuf = []), tri = this.tri, fan = this.fans[v];
    let n = 0;
    for (let i = 0; i < fan.length; i++) {
      const o = 3 * fan[i];
      for (let j = 0; j < 3; j++) {
        const u = tri[o + j];
        if (u === v) continue;
        // insertion into the sorted prefix, skipping repeats
        let k = n;
        while (k > 0 && r[k - 1] > u) k--;
        if (k > 0 && r[k - 1] === u) continue;
        for (let m = n; m > k; m--) r[m] = r[m - 1];
        r[k] = u;
        n++;
      }
    }
    r.length = n;
    return r;
  }

  // The candidate wedges of corner (t, s) (docs/LODGEN_progressive.md):
  // wedges at its vertex in the triangles sharing an edge with t, then
  // `before`, then every other wedge at the vertex.
  candidates(t, s, before) {
    const tri = this.tri, cw = this.cw, cand = this.cand;
    cand.length = 0;
    const o = 3 * t, u = tri[o + s], a = tri[o + ((s + 1) % 3)], b = tri[o + ((s + 2) % 3)];
    const fan = this.fans[u];
    const push = (w) => { if (w !== NONE && !cand.includes(w)) cand.push(w); };
    for (let i = 0; i < fan.length; i++) {
      const t2 = fan[i];
      if (t2 === t) continue;
      const p = 3 * t2, g0 = tri[p], g1 = tri[p + 1], g2 = tri[p + 2];
      if ((a !== u && (g0 === a || g1 === a || g2 === a)) || (b !== u && (g0 === b || g1 === b || g2 === b))) {
        if (g0 === u) push(cw[p]);
        if (g1 === u) push(cw[p + 1]);
        if (g2 === u) push(cw[p + 2]);
      }
    }
    if (before !== undefined) push(before);
    for (let i = 0; i < fan.length; i++) {
      const t2 = fan[i];
      if (t2 === t) continue;
      const p = 3 * t2;
      if (tri[p] === u) push(cw[p]);
      if (tri[p + 1] === u) push(cw[p + 1]);
      if (tri[p + 2] === u) push(cw[p + 2]);
    }
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

  // wedge references of a chunk: refs, groups, values; next(t, s, before,
  // rec) = the wedge of corner (t, s), recorded there
  wedgeColumns(cols) {
    const w = this.header.wedges, dec = this;
    const refs = cols.u32("wedge reference");
    let fresh = 0;
    for (const c of refs) if (c === 0) fresh++;
    const groups = w.groups > 1 ? cols.u32("wedge group", fresh) : null;
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
    let pos = 0, k = 0;
    const define = (t, s, rec) => {
      if (dec.nw >= w.total) throw new Error(`more wedges than the ${w.total} announced`);
      const g = groups ? groups[k] : 0;
      if (g >= w.groups) throw new Error(`wedge group ${g} out of range`);
      const id = dec.nw;
      dec.wgroups[id] = g;
      const p = dec.predictor(t, s, rec), qp = dec.qpred, fp = dec.fpred, qs = w.qstride, fs = w.fstride;
      if (p[0] === 0) { qp.fill(0); fp.fill(0); }
      else if (p[0] === 1) {
        for (let i = 0; i < qs; i++) qp[i] = dec.qv[p[1] * qs + i];
        for (let i = 0; i < fs; i++) fp[i] = dec.fvBits[p[1] * fs + i];
      } else {
        for (let i = 0; i < qs; i++) qp[i] = dec.qv[p[1] * qs + i] + dec.qv[p[2] * qs + i] - dec.qv[p[3] * qs + i];
        for (let i = 0; i < fs; i++) {
          const x = Math.fround(dec.fv[p[1] * fs + i] + dec.fv[p[2] * fs + i] - dec.fv[p[3] * fs + i]);
          if (Number.isFinite(x)) { dec.f32[0] = x; fp[i] = dec.f32Bits[0]; } else fp[i] = 0;
        }
      }
      w.channels.forEach((c, ci) => {
        const out = id * w.stride + c.offset;
        if (c.encoding === 0) {
          for (let j = 0; j < c.components; j++) {
            const bits = (fp[c.flane + j] + values[ci][k * c.components + j]) >>> 0;
            dec.fvBits[id * fs + c.flane + j] = bits;
            dec.wvalsBits[out + j] = bits;
          }
        } else {
          for (let j = 0; j < c.components; j++) {
            const q = (qp[c.qlane + j] + values[ci][k * c.padded + j]) & 0xffff;
            if (q > ENC_MAX[c.encoding]) throw new Error(`attribute value ${q} over ${ENC_MAX[c.encoding]}`);
            dec.qv[id * qs + c.qlane + j] = q;
            dec.wvals[out + j] = dequantize(c.encoding, q);
          }
        }
      });
      k++;
      return dec.nw++;
    };
    return {
      next(t, s, before, rec) {
        if (pos >= refs.length) throw new Error("the wedge reference column ends early");
        const code = refs[pos++];
        dec.candidates(t, s, before);
        let id;
        if (code === 0) id = define(t, s, rec);
        else {
          const n = dec.cand.length;
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
    };
  }

  decodeChunk(bytes, offset, n) {
    const h = this.header, cols = new Columns(this.mo, bytes, offset);
    const v1s = cols.u32("split vertex", n);
    const codes = cols.vertices("face code", 4, n);
    const extra = words(cols.u32("escape"), "escape");
    const mask = cols.bits("corner mask");
    const moved = differences(cols.u16x4("moved position"));
    const fresh = differences(cols.u16x4("new position", n));
    const wc = h.wedges ? this.wedgeColumns(cols) : null;
    const errors = h.flags & 1 ? cols.u32("error", n) : null;
    cols.finish("the chunk");
    const va = this.nv, recs = [];
    for (let i = 0; i < n; i++) recs.push(this.replay(v1s[i], codes, i, extra, mask, wc));
    if (!extra.done() || !mask.done()) throw new Error("escape or corner-mask values left over");
    if (wc) wc.finish();
    this.positions(recs, moved, fresh, va);
    for (const r of recs) this.records.push(r);
    void errors;
  }

  faces(codes, i, extra, v0, v1, ring) {
    let nf = codes[4 * i];
    if (nf === 255) nf = extra.next();
    if (nf > 65536) throw new Error(`${nf} faces in one split`);
    const cs = [];
    for (let k = 0; k < nf; k++) {
      const c = k < 2 ? codes[4 * i + 1 + k] : extra.next();
      if (c > 255) throw new Error("face code over 255");
      cs.push(c);
    }
    const faces = new Array(3 * nf);
    cs.forEach((c, k) => {
      if (c === FACE_ESCAPE) {
        for (let j = 0; j < 3; j++) {
          const x = extra.next();
          const v = x === 0 ? v0 : x === 1 ? v1 : x - 1 <= v0 ? v0 - (x - 1) : -1;
          if (v < 0) throw new Error("escaped face corner out of range");
          faces[3 * k + j] = v;
        }
      } else {
        const p = c % 6, r = Math.floor(c / 6);
        if (r >= RING_CODES || r >= ring.length) throw new Error(`face code ${c} beyond the ring of ${v1}`);
        const perm = PERMS[p];
        faces[3 * k + perm[0]] = v0;
        faces[3 * k + perm[1]] = v1;
        faces[3 * k + perm[2]] = ring[r];
      }
    });
    return faces;
  }

  replay(v1, codes, i, extra, mask, wc) {
    const h = this.header, v0 = this.nv;
    if (v1 >= v0) throw new Error(`split vertex ${v1} does not exist yet`);
    const ring = this.ring(v1);
    const faces = this.faces(codes, i, extra, v0, v1, ring);
    const nf = faces.length / 3;
    if (this.nt + nf > h.totalTriangles) throw new Error("more triangles than announced");
    this.fans.push([]);
    this.nv++;
    this.tri.set(faces, 3 * this.nt);
    for (let k = 0; k < nf; k++) this.addFan(this.nt + k);
    this.nt += nf;
    const held = [];
    for (const t of this.fans[v1]) for (let s = 0; s < 3; s++) if (this.tri[3 * t + s] === v1) held.push(3 * t + s);
    const corners = [];
    for (const c of held) {
      if (!mask.next()) continue;
      corners.push(c);
      const t = (c / 3) | 0;
      this.tri[c] = v0;
      const tri = this.tri;
      if (tri[3 * t] !== v1 && tri[3 * t + 1] !== v1 && tri[3 * t + 2] !== v1) {
        const f = this.fans[v1], j = f.indexOf(t);
        if (j >= 0) f.splice(j, 1);
      }
      const f0 = this.fans[v0];
      let k = f0.length;
      while (k > 0 && f0[k - 1] > t) k--;
      if (k === 0 || f0[k - 1] !== t) f0.splice(k, 0, t);
    }
    const rec = { v1, v0, p1: [0, 0, 0], pm: [0, 0, 0], p0: [0, 0, 0], faces, corners,
      wfaces: null, wafter: null, wbefore: null };
    if (wc) {
      const first = this.nt - nf, cw = this.cw, tri = this.tri;
      const wf = wingFaces(faces, v0, v1);
      const ctx = { v0, v1, wings: wf ? [first + wf[0], first + wf[1]] : null };
      cw.fill(NONE, 3 * first, 3 * this.nt);
      for (let pass = 0; pass < 2; pass++) {
        for (let c = 3 * first; c < 3 * this.nt; c++) {
          if ((tri[c] === v0) === (pass === 1)) wc.next((c / 3) | 0, c % 3, undefined, ctx);
        }
      }
      rec.wfaces = cw.slice(3 * first, 3 * this.nt);
      rec.wafter = new Uint32Array(corners.length);
      rec.wbefore = new Uint32Array(corners.length);
      corners.forEach((c, k) => { rec.wbefore[k] = cw[c]; cw[c] = NONE; });
      corners.forEach((c, k) => { rec.wafter[k] = wc.next((c / 3) | 0, c % 3, rec.wbefore[k], ctx); });
    }
    return rec;
  }

  // Grid points at the chunk's end, then each record's p1 / p0 / p_merged.
  positions(recs, moved, fresh, va) {
    const q = this.q, lim = 2 * this.header.scale;
    const slot = new Map(), start = [];
    for (const r of recs) {
      if (r.v1 < va && !slot.has(r.v1)) {
        slot.set(r.v1, start.length);
        start.push([q[3 * r.v1], q[3 * r.v1 + 1], q[3 * r.v1 + 2]]);
      }
    }
    if (start.length * 3 !== moved.length) throw new Error(`${moved.length / 3} moved positions for ${start.length} moved vertices`);
    const set = (v, a, x) => {
      if (x > lim) throw new Error("position outside the grid");
      q[3 * v + a] = x;
    };
    for (const [v, k] of slot) for (let a = 0; a < 3; a++) set(v, a, (start[k][a] + moved[3 * k + a]) & 0xffff);
    recs.forEach((r, i) => {
      const w = wings(r.faces, r.v0, r.v1);
      const s = r.v1 < va ? start[slot.get(r.v1)] : null;
      for (let a = 0; a < 3; a++) {
        const p1 = q[3 * r.v1 + a];
        const pred = w ? q[3 * w[0] + a] + q[3 * w[1] + a] - p1 : s ? 2 * s[a] - p1 : p1;
        set(r.v0, a, (pred + fresh[3 * i + a]) & 0xffff);
      }
    });
    // replay positions in order: p_merged is the position before the split
    if (!this.cur) {
      this.cur = new Float32Array(this.header.totalVertices * 3);
      this.cur.set(this.basePositions, 0);
    }
    for (const r of recs) {
      this.deq(q, r.v1, r.p1, 0);
      this.deq(q, r.v0, r.p0, 0);
      const c = this.cur;
      for (let a = 0; a < 3; a++) {
        r.pm[a] = c[3 * r.v1 + a];
        c[3 * r.v1 + a] = r.p1[a];
        c[3 * r.v0 + a] = r.p0[a];
      }
    }
  }
}
