// The LODGEN_progressive stream decoded in a Web Worker (worker.js), off
// the page's main thread: both ends of the protocol.
//
// `serveDecoder(scope, meshoptDecoder)` runs in the worker: a StreamDecoder
// (lgpm.js) fed the stream's bytes as the page forwards them, posting, as
// transferable typed arrays, what the three.js loader applies:
//   ready                          the decoder is set up (meshopt's WASM in)
//   base      header, base mesh    chunk 0 decoded
//   topology  k, records first..k: v1, fStart, faces, cStart, corners
//             (+ wfaces, wafter, the wedges defined: wvals, wgroups),
//             `order`: the triangles in the split tree's draw order
//             (order.js) when k is the level the page refines to (goal)
//                                  a chunk's topology replayed, before its
//                                  positions download (the decoder's onTopology)
//   chunk     c, records first..k: q1, q0 (grid points at the chunk's end),
//             ms: the worker's decoding time so far
// (topology and chunk messages also carry `at`: when the worker had them
// done, performance.timeOrigin + now, for the loader's timeline)
//   error     message              a malformed stream (the decoder stops)
// and takes {bytes} (any split of the stream, in order), {goal: records}
// and {reset: session} (a new stream: a worker serves one load at a time,
// then the next, its JIT warm; every message it posts carries its session).
//
// `RemoteDecoder` is the page's side: it mirrors the StreamDecoder fields
// the loader reads (header, chunksDone, baseTri / baseQ / basePositions /
// baseCW, v1, fStart, faces0, cStart, corners.a, wfaces0, wafter.a, q1, q0,
// wvals, wgroups), filled from those messages, so index.js applies records
// the same way from either decoder. Bytes wait on the page until the worker
// is ready; if it fails to start (no worker script, no module workers),
// `onFail(bytes)` hands them back for a decoder on the main thread.

import { StreamDecoder } from "./lgpm.js";
import { indexArray, splitTreeOrder } from "./order.js";

// The worker side: answer `scope`'s messages (see the top of this file).
export function serveDecoder(scope, meshoptDecoder) {
  let d = null, goal = 0, posted = 0, nw = 0, ms = 0, failed = false, session = 0;
  let queue = [];
  const post = (m, transfer = []) => scope.postMessage({ ...m, session }, transfer);
  const reset = () => {
    d = new StreamDecoder(meshoptDecoder);
    // grid points only (the loader writes vertices from q1 / q0)
    d.floats = false;
    d.onTopology = topology;
    goal = posted = nw = ms = 0;
    failed = false;
  };
  // chunks decoded but not yet posted, in order (chunk 0: the base)
  const flush = () => {
    const h = d.header;
    for (; h && posted < d.chunksDone; posted++) {
      if (posted === 0) {
        const m = { type: "base", header: h, baseTri: d.baseTri, baseQ: d.baseQ, basePositions: d.basePositions, baseCW: d.baseCW || null, ...wedges() };
        post(m, [m.baseTri.buffer, m.baseQ.buffer, m.basePositions.buffer, ...(m.baseCW ? [m.baseCW.buffer] : []), ...wedgeBuffers(m)]);
        // (the decoder's copies are its own: baseTri, baseQ are kept
        // nowhere else; it needs neither after the base)
        d.baseTri = d.baseQ = d.basePositions = d.baseCW = null;
        continue;
      }
      const first = h.chunks[posted - 1].records, k = h.chunks[posted].records;
      const m = { type: "chunk", c: posted, first, k, q1: d.q1.slice(3 * first, 3 * k), q0: d.q0.slice(3 * first, 3 * k), ms, at: performance.timeOrigin + performance.now() };
      post(m, [m.q1.buffer, m.q0.buffer]);
    }
  };
  // the wedges defined since the last message: their values and groups
  const wedges = () => {
    if (!d.header.wedges) return {};
    const s = d.header.wedges.stride, m = { w0: nw, wvals: d.wvals.slice(nw * s, d.nw * s), wgroups: d.wgroups.slice(nw, d.nw) };
    nw = d.nw;
    return m;
  };
  const wedgeBuffers = (m) => (m.wvals ? [m.wvals.buffer, m.wgroups.buffer] : []);
  const topology = (k) => {
    flush();
    const first = d.header.chunks[d.chunksDone - 1].records;
    const f0 = 3 * d.fStart[first], f1 = 3 * d.fStart[k], c0 = d.cStart[first], c1 = d.cStart[k];
    const m = {
      type: "topology", k, first,
      v1: d.v1.slice(first, k), fStart: d.fStart.slice(first + 1, k + 1), faces: d.faces0.slice(f0, f1),
      cStart: d.cStart.slice(first + 1, k + 1), corners: d.corners.a.slice(c0, c1), ...wedges(),
    };
    const transfer = [m.v1.buffer, m.fStart.buffer, m.faces.buffer, m.cStart.buffer, m.corners.buffer, ...wedgeBuffers(m)];
    if (d.wfaces0) {
      m.wfaces = d.wfaces0.slice(f0, f1);
      m.wafter = d.wafter.a.slice(c0, c1);
      transfer.push(m.wfaces.buffer, m.wafter.buffer);
    }
    // (when, on the page's clock's origin: the loader's timeline)
    m.at = performance.timeOrigin + performance.now();
    if (k === goal && !d.header.wedges) {
      const t = performance.now();
      // (as long as the index state: the geometry switches between the two)
      m.order = splitTreeOrder(d.tri, d.fStart[k], d.v1, d.header.baseVertices, k, indexArray(d.header.totalVertices, Math.max(3, 3 * d.header.totalTriangles)));
      m.orderMs = performance.now() - t;
      transfer.push(m.order.buffer);
    }
    post(m, transfer);
  };
  const handle = (m) => {
    if (m.reset !== undefined) {
      session = m.reset;
      reset();
    }
    if (m.goal !== undefined) goal = m.goal;
    if (!m.bytes || failed) return;
    const t = performance.now();
    try {
      d.push(m.bytes);
      ms += performance.now() - t;
      flush();
    } catch (e) {
      failed = true;
      post({ type: "error", message: e.message || String(e) });
    }
  };
  scope.onmessage = (e) => (queue ? queue.push(e.data) : handle(e.data));
  Promise.resolve(meshoptDecoder.ready).then(() => {
    reset();
    post({ type: "ready" });
    const q = queue;
    queue = null;
    for (const m of q) handle(m);
  }, (e) => post({ type: "error", message: `the meshopt decoder: ${e.message || e}`, start: true }));
}

// A Uint32Array grown (doubling) to hold at least n values.
function room(a, n, Type = Uint32Array) {
  if (a && a.length >= n) return a;
  const b = new Type(Math.max(n, a ? 2 * a.length : 1024));
  if (a) b.set(a);
  return b;
}

let sessions = 0;

// The page's side (see the top of this file). `worker`: a Worker running
// serveDecoder; `reused`: it served a load before (it is ready: its
// decoder is reset for this one); `release(worker)`: called, instead of
// terminating it, once the stream is decoded or `terminate` is called
// (it may serve another load). Hooks the loader sets: onTopology(k, order) (order: the
// worker's draw order of level k, or null), onProgress() (a chunk
// decoded), onError(error), onFail(bytes, error) (the worker did not start:
// the bytes it was not given).
export class RemoteDecoder {
  constructor(worker, { reused = false, release = null } = {}) {
    this.worker = worker;
    this.release = release;
    this.session = reused ? ++sessions : 0;
    this.header = null;
    this.chunksDone = 0;
    this.ready = false;
    this.pending = []; // bytes waiting for the worker
    this.workerMs = 0; // the worker's decoding time so far
    this.orderMs = 0; // ... and ordering (the draw order)
    this.onTopology = null;
    this.onProgress = null;
    this.onMark = null; // (what, t): a point of the worker's, on the page's clock
    this.onError = null;
    this.onFail = null;
    // main-thread ms taking the worker's messages in
    this.spent = 0;
    worker.onmessage = (e) => this.receive(e.data);
    if (reused) {
      worker.postMessage({ reset: this.session });
      this.ready = true;
    }
    worker.onerror = (e) => {
      if (e && e.preventDefault) e.preventDefault();
      this.fail(new Error(`the decoder worker: ${(e && e.message) || "failed to start"}`));
    };
  }

  // The next bytes of the stream (in order), given to the worker: their
  // buffer moves there when the view holds all of it.
  push(bytes) {
    if (!this.ready) { this.pending.push(bytes.slice()); return; }
    const whole = bytes.byteOffset === 0 && bytes.byteLength === bytes.buffer.byteLength;
    const b = whole ? bytes : bytes.slice();
    this.worker.postMessage({ bytes: b }, [b.buffer]);
  }

  // The level (records) refine stops at: the worker orders its triangles.
  setGoal(records) {
    this.worker.postMessage({ goal: records });
  }

  fail(error) {
    if (this.failed) return;
    this.failed = true;
    this.worker.terminate();
    if (!this.ready && this.onFail) this.onFail(this.pending, error);
    else if (this.onError) this.onError(error);
    this.pending = [];
  }

  // Done with the worker: released (for another load) or terminated.
  terminate() {
    if (this.failed || this.released) return;
    this.released = true;
    this.worker.onmessage = this.worker.onerror = null;
    if (this.release) this.release(this.worker);
    else this.worker.terminate();
  }

  receive(m) {
    // (messages of a load the worker served before: not this one's)
    if (this.failed || this.released || m.session !== this.session) return;
    // (the hooks' time is the loader's: apply, prepare)
    const t = performance.now();
    let then = null;
    if (m.type === "ready") {
      this.ready = true;
      const p = this.pending;
      this.pending = [];
      for (const b of p) this.worker.postMessage({ bytes: b }, [b.buffer]);
    } else if (m.type === "error") {
      if (m.start && !this.ready) { this.fail(new Error(m.message)); return; }
      this.failed = true;
      this.worker.terminate();
      if (this.onError) this.onError(new Error(m.message));
    } else if (m.type === "base") then = this.base(m);
    else if (m.type === "topology") then = this.topology(m);
    else if (m.type === "chunk") then = this.chunk(m);
    this.spent += performance.now() - t;
    if (then) then();
  }

  base(m) {
    const h = (this.header = m.header), nc = 3 * h.totalTriangles, ns = h.splitCount;
    Object.assign(this, { baseTri: m.baseTri, baseQ: m.baseQ, basePositions: m.basePositions, baseCW: m.baseCW });
    this.faces0 = new Uint32Array(nc);
    this.faces0.set(m.baseTri, 0);
    this.v1 = new Uint32Array(ns);
    this.fStart = new Uint32Array(ns + 1);
    this.cStart = new Uint32Array(ns + 1);
    this.fStart[0] = h.baseTriangles;
    this.corners = { a: new Uint32Array(0) };
    this.q1 = new Uint16Array(3 * ns);
    this.q0 = new Uint16Array(3 * ns);
    this.wfaces0 = null;
    if (h.wedges) {
      this.wvals = new Float32Array(h.wedges.total * h.wedges.stride);
      this.wgroups = new Uint32Array(h.wedges.total);
      this.wfaces0 = new Uint32Array(nc);
      this.wfaces0.set(m.baseCW, 0);
      this.wafter = { a: new Uint32Array(0) };
      this.wedges(m);
    }
    this.chunksDone = 1;
    return this.onProgress;
  }

  wedges(m) {
    if (!m.wvals) return;
    this.wvals.set(m.wvals, m.w0 * this.header.wedges.stride);
    this.wgroups.set(m.wgroups, m.w0);
  }

  topology(m) {
    const { first, k } = m, f0 = 3 * this.fStart[first], c0 = this.cStart[first];
    this.v1.set(m.v1, first);
    this.fStart.set(m.fStart, first + 1);
    this.cStart.set(m.cStart, first + 1);
    this.faces0.set(m.faces, f0);
    this.corners.a = room(this.corners.a, c0 + m.corners.length);
    this.corners.a.set(m.corners, c0);
    if (m.wfaces) {
      this.wfaces0.set(m.wfaces, f0);
      this.wafter.a = room(this.wafter.a, c0 + m.wafter.length);
      this.wafter.a.set(m.wafter, c0);
    }
    if (this.header.wedges) this.wedges(m);
    if (m.orderMs) this.orderMs += m.orderMs;
    this.workerMark(`replayed ${k}`, m.at);
    if (m.order) this.workerMark(`ordered ${k}`, m.at + m.orderMs);
    return this.onTopology && (() => this.onTopology(k, m.order || null));
  }

  workerMark(what, at) {
    if (this.onMark && at > 0) this.onMark(`worker ${what}`, at - performance.timeOrigin);
  }

  chunk(m) {
    this.workerMark(`decoded ${m.k}`, m.at);
    this.q1.set(m.q1, 3 * m.first);
    this.q0.set(m.q0, 3 * m.first);
    this.workerMs = m.ms;
    this.chunksDone = m.c + 1;
    // the whole stream is in: the worker's state is no longer needed
    if (this.chunksDone === this.header.chunks.length) this.terminate();
    return this.onProgress;
  }
}
