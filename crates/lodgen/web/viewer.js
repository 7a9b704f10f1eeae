// lodgen view: a WebGL2 viewer for the LODGEN_progressive split stream.
//
// Shows the base (coarsest) mesh as soon as the header and base have arrived,
// fetches /stream.bin in chunks with HTTP Range requests and applies each
// vertex-split record as soon as its bytes are there. A slider moves through
// the decoded records (refine / coarsen), buttons jump to the MSFT_lod
// levels, and "auto" picks the level from the projected screen coverage.
//
// The stream layout is docs/LODGEN_progressive.md; the decoder below mirrors
// crates/lodgen-pm/src/stream.rs and yields the same f32 positions
// (origin + q * step in double precision, rounded once to f32).
//
// A stream with wedges (header flag 2) also carries every corner's wedge and
// every wedge's attribute values (NORMAL, TEXCOORD_0, COLOR_0, … as the
// input had them): the mesh is then drawn corner by corner with them, shaded
// by the "shading" menu (UV checker, normals, colour, primitive).
//
// For tests, window.lodgen exposes: triangles(), vertices(), indexHash(),
// attributeHash(), channels(), setShading(mode), refineTo(k), applied(),
// decoded(), complete(), info, history, levels(), pixelStats(),
// setCamera(yaw, pitch, distanceFactor), error().
"use strict";

// ------------------------------------------------------------------ decoder

const NEED_MORE = { needMore: true };

class Reader {
  constructor(bytes, pos, offset) {
    this.b = bytes;
    this.pos = pos;
    this.offset = offset; // stream offset of bytes[0]
  }
  byte() {
    if (this.pos >= this.b.length) throw NEED_MORE;
    return this.b[this.pos++];
  }
  varint() {
    let v = 0;
    let mul = 1;
    for (let i = 0; i < 8; i++) {
      const b = this.byte();
      v += (b & 0x7f) * mul;
      if ((b & 0x80) === 0) return v;
      mul *= 128;
    }
    throw new Error(`byte ${this.offset + this.pos}: varint too long`);
  }
  zz() {
    const v = this.varint();
    return v % 2 === 0 ? v / 2 : -(v + 1) / 2;
  }
  bounded(limit, what) {
    const at = this.offset + this.pos;
    const v = this.varint();
    if (v > limit) throw new Error(`byte ${at}: ${what} ${v} exceeds ${limit}`);
    return v;
  }
  f32() {
    if (this.pos + 4 > this.b.length) throw NEED_MORE;
    const v = new DataView(this.b.buffer, this.b.byteOffset + this.pos, 4).getFloat32(0, true);
    this.pos += 4;
    return v;
  }
}

class StreamDecoder {
  constructor() {
    this.pending = new Uint8Array(0);
    this.consumed = 0;
    this.header = null;
    this.baseReady = false;
    this.records = []; // {v1, v0, p1, pm, p0, faces: Uint32Array, corners: Uint32Array (t*3+slot)}
    // decode-side state: the mesh with every decoded record applied
    this.q = null; // Uint32Array, 3 per vertex
    this.nv = 0;
    this.tri = null; // Uint32Array, 3 per triangle
    this.nt = 0;
    this.basePositions = null;
    this.baseTri = null;
  }

  push(chunk) {
    const merged = new Uint8Array(this.pending.length + chunk.length);
    merged.set(this.pending, 0);
    merged.set(chunk, this.pending.length);
    this.pending = merged;
    const before = this.records.length;
    let r = new Reader(this.pending, 0, this.consumed);
    try {
      // header and base are taken in one piece each: on running out of
      // bytes, nothing of them is consumed (r.pos goes back to 0)
      if (!this.header) {
        try {
          this.header = this.parseHeader(r);
        } catch (e) {
          if (e === NEED_MORE) r.pos = 0;
          throw e;
        }
        this.eat(r.pos);
        r = new Reader(this.pending, 0, this.consumed);
      }
      if (!this.baseReady) {
        try {
          this.parseBase(r);
        } catch (e) {
          if (e === NEED_MORE) r.pos = 0;
          throw e;
        }
        this.eat(r.pos);
        r = new Reader(this.pending, 0, this.consumed);
      }
      const h = this.header;
      while (this.records.length < h.splitCount) {
        const mark = r.pos;
        try {
          this.parseRecord(r);
        } catch (e) {
          if (e === NEED_MORE) r.pos = mark;
          throw e;
        }
      }
      if (r.pos < r.b.length) throw new Error(`${r.b.length - r.pos} bytes follow the last record`);
      if (this.nt !== h.totalTriangles) throw new Error("the records restore a different triangle count");
      if (h.wedges && this.nw !== h.wedges.total) throw new Error("the records define a different wedge count");
    } catch (e) {
      if (e !== NEED_MORE) throw e;
    }
    this.eat(r.pos);
    return this.records.length - before;
  }

  eat(n) {
    this.consumed += n;
    this.pending = this.pending.slice(n);
  }

  complete() {
    return !!this.header && this.baseReady && this.records.length === this.header.splitCount &&
      this.pending.length === 0 && (!this.header.wedges || this.nw === this.header.wedges.total);
  }

  parseHeader(r) {
    const magic = [0x4c, 0x47, 0x50, 0x4d]; // "LGPM"
    for (const m of magic) if (r.byte() !== m) throw new Error("not a lodgen progressive stream");
    const version = r.byte();
    if (version !== 1) throw new Error(`unsupported stream version ${version}`);
    const flags = r.byte();
    if (flags & ~3) throw new Error(`unknown flags ${flags}`);
    const bits = r.byte();
    if (bits < 1 || bits > 30) throw new Error(`grid bits ${bits}`);
    const origin = [r.f32(), r.f32(), r.f32()];
    const step = r.f32();
    const max = 0xfffffffe;
    const h = {
      flags, bits, origin, step,
      baseVertices: r.bounded(max, "base vertices"),
      baseTriangles: r.bounded(max, "base triangles"),
      splitCount: r.bounded(max, "split count"),
      totalVertices: r.bounded(max, "total vertices"),
      totalTriangles: r.bounded(max, "total triangles"),
      levels: [],
    };
    if (h.totalVertices !== h.baseVertices + h.splitCount) throw new Error("inconsistent vertex counts");
    if (h.totalTriangles < h.baseTriangles) throw new Error("inconsistent triangle counts");
    const n = r.bounded(max, "level count");
    for (let i = 0; i < n; i++) h.levels.push(r.bounded(h.splitCount, "level"));
    h.wedges = null;
    if (flags & 2) {
      const total = r.bounded(max, "wedge count");
      const groups = r.bounded(max, "group count");
      if (groups === 0) throw new Error("zero wedge groups");
      const nch = r.bounded(64, "channel count");
      const channels = [];
      let stride = 0;
      for (let i = 0; i < nch; i++) {
        const len = r.bounded(64, "channel name length");
        const bytes = new Uint8Array(len);
        for (let j = 0; j < len; j++) bytes[j] = r.byte();
        const name = new TextDecoder("utf-8", { fatal: true }).decode(bytes);
        if (!name) throw new Error("empty channel name");
        const components = r.byte();
        if (components < 1 || components > 16) throw new Error(`${components} components`);
        channels.push({ name, components, offset: stride });
        stride += components;
      }
      h.wedges = { total, groups, channels, stride };
    }
    return h;
  }

  // One wedge reference: 0 = a new wedge (group if several, then its values),
  // k >= 1 = wedge count - k. New wedges go to `tmp` until the piece commits.
  readWedge(r, tmp) {
    const w = this.header.wedges;
    const code = r.bounded(tmp.n, "wedge reference");
    if (code > 0) return tmp.n - code;
    if (tmp.n >= w.total) throw new Error(`more wedges than the ${w.total} announced`);
    tmp.groups.push(w.groups > 1 ? r.bounded(w.groups - 1, "wedge group") : 0);
    for (let i = 0; i < w.stride; i++) tmp.vals.push(r.f32());
    return tmp.n++;
  }

  commitWedges(tmp) {
    const w = this.header.wedges;
    this.wvals.set(tmp.vals, this.nw * w.stride);
    this.wgroups.set(tmp.groups, this.nw);
    this.nw = tmp.n;
  }

  deq(qx, qy, qz, out, o) {
    const h = this.header;
    out[o] = Math.fround(h.origin[0] + qx * h.step);
    out[o + 1] = Math.fround(h.origin[1] + qy * h.step);
    out[o + 2] = Math.fround(h.origin[2] + qz * h.step);
  }

  coord(v) {
    if (!(v >= 0 && v <= 2 ** this.header.bits - 1)) throw new Error(`coordinate ${v} outside the grid`);
    return v;
  }

  parseBase(r) {
    const h = this.header;
    const q = new Uint32Array(h.totalVertices * 3);
    const prev = [0, 0, 0];
    for (let v = 0; v < h.baseVertices; v++) {
      for (let a = 0; a < 3; a++) {
        prev[a] += r.zz();
        q[v * 3 + a] = this.coord(prev[a]);
      }
    }
    const tri = new Uint32Array(h.totalTriangles * 3);
    let p = 0;
    for (let i = 0; i < h.baseTriangles * 3; i++) {
      p += r.zz();
      if (p < 0 || p >= h.baseVertices) throw new Error(`base corner ${p} out of range`);
      tri[i] = p;
    }
    let tmp = null;
    if (h.wedges) {
      tmp = { n: 0, vals: [], groups: [] };
      this.baseCW = new Uint32Array(h.baseTriangles * 3);
      for (let i = 0; i < h.baseTriangles * 3; i++) this.baseCW[i] = this.readWedge(r, tmp);
      this.wvals = new Float32Array(h.wedges.total * h.wedges.stride);
      this.wgroups = new Uint32Array(h.wedges.total);
      this.nw = 0;
      this.cw = new Uint32Array(h.totalTriangles * 3);
      this.cw.set(this.baseCW, 0);
      this.commitWedges(tmp);
    }
    // complete: commit
    this.q = q;
    this.tri = tri;
    this.baseTri = tri.slice(0, h.baseTriangles * 3);
    this.nv = h.baseVertices;
    this.nt = h.baseTriangles;
    this.basePositions = new Float32Array(h.baseVertices * 3);
    for (let v = 0; v < h.baseVertices; v++) this.deq(q[3 * v], q[3 * v + 1], q[3 * v + 2], this.basePositions, 3 * v);
    this.baseReady = true;
  }

  parseRecord(r) {
    const h = this.header;
    const v0 = this.nv;
    const head = r.varint();
    let nf = head % 4;
    if (nf === 3) nf += r.bounded(65536, "face count");
    const nc = Math.floor(head / 4);
    if (this.nt + nf > h.totalTriangles) throw new Error("more triangles than announced");
    if (nc > 3 * (this.nt + nf)) throw new Error("too many corner edits");
    if (v0 === 0) throw new Error("nothing to split");
    const v1 = v0 - 1 - r.bounded(v0 - 1, "v1 distance");
    const q = this.q;
    const q1 = [0, 0, 0], q0 = [0, 0, 0];
    for (let a = 0; a < 3; a++) q1[a] = this.coord(q[3 * v1 + a] + r.zz());
    for (let a = 0; a < 3; a++) q0[a] = this.coord(q1[a] + r.zz());
    const faces = new Uint32Array(nf * 3);
    for (let i = 0; i < nf * 3; i++) {
      const code = r.bounded(v0 + 1, "face corner code");
      faces[i] = code === 0 ? v0 : code === 1 ? v1 : v0 - (code - 1);
    }
    const count = this.nt + nf;
    const corners = new Uint32Array(nc);
    let prev = count;
    for (let i = 0; i < nc; i++) {
      const code = r.varint();
      const gap = Math.floor(code / 4), slot = code % 4;
      if (slot > 2 || gap >= prev) throw new Error("corner edit out of range");
      const t = prev - 1 - gap;
      corners[nc - 1 - i] = t * 3 + slot;
      prev = t + 1;
    }
    let wfaces = null, wafter = null, wbefore = null, tmp = null;
    if (h.wedges) {
      tmp = { n: this.nw, vals: [], groups: [] };
      wfaces = new Uint32Array(nf * 3);
      for (let i = 0; i < nf * 3; i++) wfaces[i] = this.readWedge(r, tmp);
      wafter = new Uint32Array(nc);
      wbefore = new Uint32Array(nc);
      for (let i = 0; i < nc; i++) wafter[nc - 1 - i] = this.readWedge(r, tmp);
    }
    if (h.flags & 1) r.f32();
    // validate corners against the decode-side mesh (faces appended)
    for (let i = 0; i < nc; i++) {
      const c = corners[i];
      const value = c < this.nt * 3 ? this.tri[c] : faces[c - this.nt * 3];
      if (value !== v1 || (i > 0 && corners[i - 1] === c)) throw new Error(`corner ${c} does not hold v1`);
    }
    // commit
    const rec = { v1, v0, p1: new Float32Array(3), pm: new Float32Array(3), p0: new Float32Array(3), faces, corners,
      wfaces, wafter, wbefore };
    if (h.wedges) {
      this.cw.set(wfaces, this.nt * 3);
      for (let i = 0; i < nc; i++) {
        wbefore[i] = this.cw[corners[i]];
        this.cw[corners[i]] = wafter[i];
      }
      this.commitWedges(tmp);
    }
    this.deq(q[3 * v1], q[3 * v1 + 1], q[3 * v1 + 2], rec.pm, 0);
    this.deq(q1[0], q1[1], q1[2], rec.p1, 0);
    this.deq(q0[0], q0[1], q0[2], rec.p0, 0);
    for (let a = 0; a < 3; a++) {
      q[3 * v1 + a] = q1[a];
      q[3 * v0 + a] = q0[a];
    }
    this.tri.set(faces, this.nt * 3);
    this.nt += nf;
    for (const c of corners) this.tri[c] = v0;
    this.nv += 1;
    this.records.push(rec);
  }
}

// The displayed mesh: base + records[0..applied], refined and coarsened in place.
class Display {
  constructor(dec) {
    const h = dec.header;
    this.dec = dec;
    this.pos = new Float32Array(h.totalVertices * 3);
    this.pos.set(dec.basePositions, 0);
    this.idx = new Uint32Array(h.totalTriangles * 3);
    this.idx.set(dec.baseTri, 0);
    this.nv = h.baseVertices;
    this.nt = h.baseTriangles;
    this.applied = 0;
    this.dirty = true;
    this.cw = null; // every corner's wedge, with wedges
    if (h.wedges) {
      this.cw = new Uint32Array(h.totalTriangles * 3);
      this.cw.set(dec.baseCW, 0);
    }
  }
  refine(n) {
    const recs = this.dec.records;
    const end = Math.min(this.applied + n, recs.length);
    for (let i = this.applied; i < end; i++) {
      const r = recs[i];
      this.pos.set(r.p1, 3 * r.v1);
      this.pos.set(r.p0, 3 * r.v0);
      if (this.cw) {
        this.cw.set(r.wfaces, this.nt * 3);
        for (let j = 0; j < r.corners.length; j++) this.cw[r.corners[j]] = r.wafter[j];
      }
      this.idx.set(r.faces, this.nt * 3);
      this.nt += r.faces.length / 3;
      for (const c of r.corners) this.idx[c] = r.v0;
      this.nv += 1;
    }
    if (end !== this.applied) this.dirty = true;
    this.applied = end;
  }
  coarsen(n) {
    const recs = this.dec.records;
    const start = Math.max(0, this.applied - n);
    for (let i = this.applied - 1; i >= start; i--) {
      const r = recs[i];
      for (const c of r.corners) this.idx[c] = r.v1;
      if (this.cw) for (let j = 0; j < r.corners.length; j++) this.cw[r.corners[j]] = r.wbefore[j];
      this.nt -= r.faces.length / 3;
      this.nv -= 1;
      this.pos.set(r.pm, 3 * r.v1);
    }
    if (start !== this.applied) this.dirty = true;
    this.applied = start;
  }
  seek(k) {
    k = Math.max(0, Math.min(k, this.dec.records.length));
    if (k > this.applied) this.refine(k - this.applied);
    else this.coarsen(this.applied - k);
  }
  indexHash() {
    // FNV-1a 32 over the indices as little-endian u32 (view.rs index_hash)
    let h = 0x811c9dc5;
    for (let i = 0; i < this.nt * 3; i++) {
      let v = this.idx[i];
      for (let b = 0; b < 4; b++) {
        h ^= v & 0xff;
        h = Math.imul(h, 0x01000193) >>> 0;
        v >>>= 8;
      }
    }
    return h >>> 0;
  }
  attributeHash() {
    // FNV-1a 32 over each corner's wedge group and values (f32 bits), as
    // little-endian u32, corners in index order (view.rs attribute_hash)
    const w = this.dec.header.wedges;
    if (!w) return 0;
    const bits = new Uint32Array(this.dec.wvals.buffer);
    let h = 0x811c9dc5;
    const put = (x) => {
      for (let b = 0; b < 4; b++) {
        h ^= x & 0xff;
        h = Math.imul(h, 0x01000193) >>> 0;
        x >>>= 8;
      }
    };
    for (let i = 0; i < this.nt * 3; i++) {
      const c = this.cw[i];
      put(this.dec.wgroups[c]);
      for (let j = 0; j < w.stride; j++) put(bits[c * w.stride + j]);
    }
    return h >>> 0;
  }
}

// ------------------------------------------------------------------ math

function perspective(fovy, aspect, near, far) {
  const f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
  return [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0];
}

function lookAt(eye, c, up) {
  let z = [eye[0] - c[0], eye[1] - c[1], eye[2] - c[2]];
  let l = Math.hypot(...z); z = z.map((x) => x / l);
  let x = [up[1] * z[2] - up[2] * z[1], up[2] * z[0] - up[0] * z[2], up[0] * z[1] - up[1] * z[0]];
  l = Math.hypot(...x) || 1; x = x.map((v) => v / l);
  const y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  return [x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0, -dot(x, eye), -dot(y, eye), -dot(z, eye), 1];
}

function mul(a, b) {
  const o = new Array(16).fill(0);
  for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) for (let k = 0; k < 4; k++) o[c * 4 + r] += a[k * 4 + r] * b[c * 4 + k];
  return o;
}

// ------------------------------------------------------------------ viewer

// Attribute locations: 0 position, 1 NORMAL, 2 TEXCOORD_0, 3 COLOR_0, 4 group.
const VS = `#version 300 es
in vec3 pos;
in vec3 nrm;
in vec2 uv;
in vec4 col;
in float grp;
uniform mat4 mvp;
out vec3 wpos;
out vec3 vnrm;
out vec2 vuv;
out vec4 vcol;
flat out float vgrp;
void main() {
  wpos = pos; vnrm = nrm; vuv = uv; vcol = col; vgrp = grp;
  gl_Position = mvp * vec4(pos, 1.0);
}`;

// Shading modes: 0 faceted, 1 NORMAL, 2 UV checker (TEXCOORD_0), 3 COLOR_0,
// 4 primitive (wedge group).
const SHADING = ["faceted", "normals", "uv checker", "color", "primitive"];

const FS = `#version 300 es
precision highp float;
in vec3 wpos;
in vec3 vnrm;
in vec2 vuv;
in vec4 vcol;
flat in float vgrp;
uniform vec3 eye;
uniform int mode;
out vec4 color;
void main() {
  vec3 n = normalize(cross(dFdx(wpos), dFdy(wpos)));
  if (mode == 1 && dot(vnrm, vnrm) > 0.0) n = normalize(vnrm);
  vec3 l = normalize(eye - wpos);
  float d = abs(dot(n, l));
  vec3 albedo = vec3(0.78, 0.74, 0.66);
  if (mode == 2) {
    vec2 c = floor(vuv * 16.0);
    float k = mod(c.x + c.y, 2.0);
    albedo = mix(vec3(0.95, 0.55, 0.15), vec3(0.2, 0.45, 0.9), k);
  } else if (mode == 3) {
    albedo = vcol.rgb;
  } else if (mode == 4) {
    float h = fract(vgrp * 0.618034);
    albedo = clamp(abs(mod(h * 6.0 + vec3(0.0, 4.0, 2.0), 6.0) - 3.0) - 1.0, 0.0, 1.0) * 0.7 + 0.2;
  }
  color = vec4(vec3(0.12, 0.13, 0.16) + d * albedo, 1.0);
}`;

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const state = {
  info: null, dec: new StreamDecoder(), disp: null, gl: null, prog: null, vao: null, pbuf: null, ibuf: null,
  uploadedV: 0, uploadedT: 0, follow: true, auto: false, culled: false, shading: 0, abufs: null,
  yaw: 0.6, pitch: 0.25, distFactor: 2.6, center: [0, 0, 0], radius: 1, history: [], error: null, bytes: 0,
};

function fail(e) {
  state.error = String(e && e.message ? e.message : e);
  $("error").textContent = state.error;
}

function initGL() {
  const canvas = $("gl");
  const gl = canvas.getContext("webgl2", { antialias: true, preserveDrawingBuffer: true });
  if (!gl) throw new Error("WebGL2 is not available");
  const sh = (type, src) => {
    const s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  };
  const p = gl.createProgram();
  gl.attachShader(p, sh(gl.VERTEX_SHADER, VS));
  gl.attachShader(p, sh(gl.FRAGMENT_SHADER, FS));
  ["pos", "nrm", "uv", "col", "grp"].forEach((n, i) => gl.bindAttribLocation(p, i, n));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
  state.gl = gl;
  state.prog = p;
}

// The channel `name` of the stream's wedges: {offset, components} or null.
function channel(name) {
  const w = state.dec.header && state.dec.header.wedges;
  return (w && w.channels.find((c) => c.name === name)) || null;
}

// Shading modes this stream can show.
function shadingModes() {
  const w = state.dec.header && state.dec.header.wedges;
  const modes = [0];
  if (w) {
    if (channel("NORMAL")) modes.push(1);
    if (channel("TEXCOORD_0")) modes.push(2);
    if (channel("COLOR_0")) modes.push(3);
    if (w.groups > 1) modes.push(4);
  }
  return modes;
}

function setShading(mode) {
  if (!shadingModes().includes(mode)) return false;
  state.shading = mode;
  $("shade").value = String(mode);
  requestFrame();
  return true;
}

function initMesh() {
  const gl = state.gl, d = state.dec, h = d.header;
  state.disp = new Display(d);
  // bounds of the base mesh: centre and radius for the camera
  const bp = d.basePositions;
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < bp.length; i += 3) for (let a = 0; a < 3; a++) { lo[a] = Math.min(lo[a], bp[i + a]); hi[a] = Math.max(hi[a], bp[i + a]); }
  state.center = lo.map((l, a) => (l + hi[a]) / 2);
  state.radius = Math.max(1e-9, Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2);
  state.vao = gl.createVertexArray();
  gl.bindVertexArray(state.vao);
  if (h.wedges) {
    // drawn corner by corner: position and the corner's wedge values
    const corners = Math.max(1, h.totalTriangles * 3);
    const make = (loc, name, n) => {
      const buf = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      gl.bufferData(gl.ARRAY_BUFFER, corners * n * 4, gl.DYNAMIC_DRAW);
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, n, gl.FLOAT, false, 0, 0);
      return { loc, n, buf, ch: name ? channel(name) : null, data: new Float32Array(corners * n) };
    };
    state.abufs = [make(0, null, 3)];
    if (channel("NORMAL")) state.abufs.push(make(1, "NORMAL", 3)); else gl.vertexAttrib3f(1, 0, 0, 0);
    if (channel("TEXCOORD_0")) state.abufs.push(make(2, "TEXCOORD_0", 2));
    if (channel("COLOR_0")) state.abufs.push(make(3, "COLOR_0", 4)); else gl.vertexAttrib4f(3, 1, 1, 1, 1);
    state.abufs.push(make(4, "", 1));
  } else {
    state.pbuf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, state.pbuf);
    gl.bufferData(gl.ARRAY_BUFFER, h.totalVertices * 12, gl.DYNAMIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    state.ibuf = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, state.ibuf);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, Math.max(4, h.totalTriangles * 12), gl.DYNAMIC_DRAW);
  }
  gl.bindVertexArray(null);
  const sel = $("shade");
  for (const m of shadingModes()) {
    const o = document.createElement("option");
    o.value = String(m);
    o.textContent = SHADING[m];
    sel.appendChild(o);
  }
  const modes = shadingModes();
  setShading(modes.includes(2) ? 2 : modes.includes(1) ? 1 : 0);
  $("total").textContent = h.splitCount;
  const lv = $("levels");
  (state.info.levels || h.levels).forEach((k, i) => {
    const b = document.createElement("button");
    b.textContent = `L${i} (${k})`;
    b.title = `MSFT_lod level ${i} (finest first): ${k} records`;
    b.onclick = () => { state.follow = false; setAuto(false); refineTo(k); };
    lv.appendChild(b);
  });
}

function upload() {
  const gl = state.gl, disp = state.disp;
  if (!disp.dirty) return;
  if (state.abufs) {
    // expand corners: position of the corner's vertex, values of its wedge
    const d = state.dec, stride = d.header.wedges.stride, n = disp.nt * 3;
    for (const a of state.abufs) {
      const out = a.data;
      if (a.loc === 0) {
        for (let i = 0; i < n; i++) {
          const v = 3 * disp.idx[i];
          out[3 * i] = disp.pos[v]; out[3 * i + 1] = disp.pos[v + 1]; out[3 * i + 2] = disp.pos[v + 2];
        }
      } else if (a.loc === 4) {
        for (let i = 0; i < n; i++) out[i] = d.wgroups[disp.cw[i]];
      } else {
        const o = a.ch.offset, k = a.n;
        for (let i = 0; i < n; i++) {
          const w = disp.cw[i] * stride + o;
          for (let j = 0; j < k; j++) out[k * i + j] = d.wvals[w + j];
        }
      }
      gl.bindBuffer(gl.ARRAY_BUFFER, a.buf);
      if (n > 0) gl.bufferSubData(gl.ARRAY_BUFFER, 0, out, 0, n * a.n);
    }
    disp.dirty = false;
    return;
  }
  gl.bindBuffer(gl.ARRAY_BUFFER, state.pbuf);
  gl.bufferSubData(gl.ARRAY_BUFFER, 0, disp.pos, 0, disp.nv * 3);
  gl.bindVertexArray(state.vao);
  gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, state.ibuf);
  if (disp.nt > 0) gl.bufferSubData(gl.ELEMENT_ARRAY_BUFFER, 0, disp.idx, 0, disp.nt * 3);
  gl.bindVertexArray(null);
  disp.dirty = false;
}

function camera() {
  const canvas = $("gl");
  const aspect = canvas.width / Math.max(1, canvas.height);
  const fov = Math.PI / 4;
  const dist = state.radius * state.distFactor;
  const c = state.center;
  const eye = [
    c[0] + dist * Math.cos(state.pitch) * Math.sin(state.yaw),
    c[1] + dist * Math.sin(state.pitch),
    c[2] + dist * Math.cos(state.pitch) * Math.cos(state.yaw),
  ];
  const proj = perspective(fov, aspect, dist / 100, dist * 10);
  // screen coverage as Babylon.js and the glTF writer define it: projected
  // bounding-sphere area / screen area
  const r = state.radius / (dist * Math.tan(fov / 2)); // in half-heights
  const coverage = Math.min(1, (Math.PI * r * r) / (4 * aspect));
  return { eye, mvp: mul(proj, lookAt(eye, c, [0, 1, 0])), coverage };
}

function levelForCoverage(coverage) {
  const levels = state.info.levels || [];
  const s = state.info.screenCoverage || [];
  for (let i = 0; i < levels.length; i++) if (i < s.length && coverage >= s[i]) return i;
  return -1; // culled
}

function render() {
  const gl = state.gl, canvas = $("gl");
  const w = Math.round(canvas.clientWidth * devicePixelRatio), h = Math.round(canvas.clientHeight * devicePixelRatio);
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  gl.viewport(0, 0, canvas.width, canvas.height);
  gl.clearColor(0.106, 0.114, 0.133, 1);
  gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
  if (!state.disp) return;
  const cam = camera();
  state.culled = false;
  if (state.auto) {
    const lvl = levelForCoverage(cam.coverage);
    state.culled = lvl < 0;
    if (lvl >= 0) state.disp.seek(state.info.levels[lvl]);
    $("coverage").textContent = `coverage ${cam.coverage.toExponential(3)} → ${lvl < 0 ? "culled" : "level " + lvl}`;
  } else {
    $("coverage").textContent = `coverage ${cam.coverage.toExponential(3)}`;
  }
  upload();
  gl.enable(gl.DEPTH_TEST);
  gl.useProgram(state.prog);
  gl.uniformMatrix4fv(gl.getUniformLocation(state.prog, "mvp"), false, cam.mvp);
  gl.uniform3fv(gl.getUniformLocation(state.prog, "eye"), cam.eye);
  gl.uniform1i(gl.getUniformLocation(state.prog, "mode"), state.shading);
  gl.bindVertexArray(state.vao);
  if (!state.culled && state.disp.nt > 0) {
    if (state.abufs) gl.drawArrays(gl.TRIANGLES, 0, state.disp.nt * 3);
    else gl.drawElements(gl.TRIANGLES, state.disp.nt * 3, gl.UNSIGNED_INT, 0);
  }
  gl.bindVertexArray(null);
  updatePanel();
}

function updatePanel() {
  const disp = state.disp;
  $("tris").textContent = disp ? disp.nt : 0;
  $("verts").textContent = disp ? disp.nv : 0;
  $("applied").textContent = disp ? disp.applied : 0;
  $("decoded").textContent = state.dec.records.length;
  $("bytes").textContent = state.bytes;
  const s = $("level");
  s.max = state.dec.records.length;
  if (disp && Number(s.value) !== disp.applied) s.value = disp.applied;
}

let framePending = false;
function requestFrame() {
  if (framePending) return;
  framePending = true;
  requestAnimationFrame(() => { framePending = false; try { render(); } catch (e) { fail(e); } });
}

function refineTo(k) {
  if (!state.disp) return 0;
  state.disp.seek(k);
  requestFrame();
  return state.disp.applied;
}

function setAuto(on) {
  state.auto = on;
  $("auto").checked = on;
  requestFrame();
}

async function load() {
  initGL();
  const info = await (await fetch("info.json")).json();
  state.info = info;
  $("name").textContent = info.name;
  $("source").textContent = `(${info.source})`;
  const chunk = Number(params.get("chunk")) || info.chunkBytes || 65536;
  const total = info.streamBytes;
  for (let start = 0; start < total; start += chunk) {
    const end = Math.min(total, start + chunk) - 1;
    const resp = await fetch("stream.bin", { headers: { Range: `bytes=${start}-${end}` }, cache: "no-store" });
    if (resp.status !== 206 && resp.status !== 200) throw new Error(`stream.bin: HTTP ${resp.status}`);
    let bytes = new Uint8Array(await resp.arrayBuffer());
    if (resp.status === 200) bytes = bytes.subarray(start, end + 1); // server ignored the range
    state.bytes += bytes.length;
    state.dec.push(bytes);
    if (!state.disp && state.dec.baseReady) initMesh();
    if (state.disp && state.follow && !state.auto) state.disp.seek(state.dec.records.length);
    state.history.push({ bytes: state.bytes, decoded: state.dec.records.length, applied: state.disp ? state.disp.applied : -1 });
    requestFrame();
    await new Promise((r) => setTimeout(r, 0)); // let a frame show what arrived
  }
  if (!state.dec.complete()) throw new Error("the stream ended before its last record");
  requestFrame();
}

function bindControls() {
  const canvas = $("gl");
  let drag = null;
  canvas.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    state.yaw -= (e.clientX - drag[0]) * 0.01;
    state.pitch = Math.max(-1.5, Math.min(1.5, state.pitch + (e.clientY - drag[1]) * 0.01));
    drag = [e.clientX, e.clientY];
    requestFrame();
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    state.distFactor = Math.max(1.05, Math.min(500, state.distFactor * Math.exp(e.deltaY * 0.001)));
    requestFrame();
  }, { passive: false });
  $("level").addEventListener("input", (e) => { state.follow = false; setAuto(false); refineTo(Number(e.target.value)); });
  $("auto").addEventListener("change", (e) => { state.follow = false; setAuto(e.target.checked); });
  $("shade").addEventListener("change", (e) => setShading(Number(e.target.value)));
  window.addEventListener("resize", requestFrame);
}

window.lodgen = {
  triangles: () => (state.disp ? state.disp.nt : 0),
  vertices: () => (state.disp ? state.disp.nv : 0),
  indexHash: () => (state.disp ? state.disp.indexHash() : 0),
  attributeHash: () => (state.disp ? state.disp.attributeHash() : 0),
  channels: () => {
    const w = state.dec.header && state.dec.header.wedges;
    return w ? w.channels.map((c) => c.name) : [];
  },
  shadingModes: () => shadingModes().map((m) => SHADING[m]),
  setShading: (name) => { const ok = setShading(SHADING.indexOf(name)); render(); return ok; },
  refineTo: (k) => { state.follow = false; setAuto(false); const a = refineTo(k); render(); return a; },
  applied: () => (state.disp ? state.disp.applied : 0),
  decoded: () => state.dec.records.length,
  complete: () => state.dec.complete(),
  levels: () => (state.info ? state.info.levels : []),
  info: () => state.info,
  history: () => state.history,
  error: () => state.error,
  setAuto: (on) => { state.follow = false; setAuto(on); render(); return state.disp ? state.disp.applied : 0; },
  culled: () => state.culled,
  setCamera: (yaw, pitch, distFactor) => {
    state.yaw = yaw; state.pitch = pitch; state.distFactor = distFactor; render();
  },
  // mean and variance of the rendered luminance: a blank canvas has variance 0
  pixelStats: () => {
    const gl = state.gl, w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    render();
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let s = 0, s2 = 0;
    const n = w * h;
    for (let i = 0; i < px.length; i += 4) {
      const l = 0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2];
      s += l; s2 += l * l;
    }
    const mean = s / n;
    return { width: w, height: h, mean, variance: s2 / n - mean * mean };
  },
};

bindControls();
load().catch(fail);
