// lodgen view: a WebGL2 viewer for the LODGEN_progressive split stream.
//
// Shows the base (coarsest) mesh as soon as the header and base have arrived,
// fetches /stream.bin in pieces with HTTP Range requests and applies each
// chunk of vertex-split records (one per level) as soon as its bytes are there. A slider moves through
// the decoded records (refine / coarsen), buttons jump to the MSFT_lod
// levels, and "auto" picks the level from the projected screen coverage.
//
// The stream layout is docs/LODGEN_progressive.md; the decoder (three/lgpm.js)
// mirrors crates/lodgen-pm/src/progressive/stream/ and yields the same f32
// positions; its columns are decoded by meshoptimizer's MeshoptDecoder
// (meshopt_decoder.mjs, from the `meshoptimizer` npm package, MIT).
// Records arrive chunk by chunk: one chunk per MSFT_lod level.
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
import { MeshoptDecoder } from "./meshopt_decoder.mjs";
import { StreamDecoder } from "./three/lgpm.js";

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
    const end = Math.min(this.applied + n, this.dec.count);
    for (let i = this.applied; i < end; i++) {
      const r = this.dec.record(i);
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
    const start = Math.max(0, this.applied - n);
    for (let i = this.applied - 1; i >= start; i--) {
      const r = this.dec.record(i);
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
    k = Math.max(0, Math.min(k, this.dec.count));
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
  info: null, dec: new StreamDecoder(MeshoptDecoder), disp: null, gl: null, prog: null, vao: null, pbuf: null, ibuf: null,
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
  $("decoded").textContent = state.dec.count;
  $("bytes").textContent = state.bytes;
  const s = $("level");
  s.max = state.dec.count;
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
  await MeshoptDecoder.ready;
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
    if (state.disp && state.follow && !state.auto) state.disp.seek(state.dec.count);
    state.history.push({ bytes: state.bytes, decoded: state.dec.count, applied: state.disp ? state.disp.applied : -1 });
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
  decoded: () => state.dec.count,
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
