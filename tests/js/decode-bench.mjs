#!/usr/bin/env node
// Decode speed of the LODGEN_progressive stream decoder in node: decodes the
// whole stream of a progressive GLB `runs` times (64 KiB pushes), prints
// wall and CPU microseconds per split for each run, and a signature of the
// decoded records, their wedges included (to check two decoders agree).
//
//   node decode-bench.mjs FILE.glb [runs] [DECODER.js] [--slices] [--against OLD.js]
//
// DECODER.js (an absolute path) defaults to crates/lodgen/web/three/lgpm.js;
// e.g. `git show REV:crates/lodgen/web/three/lgpm.js > /tmp/old.mjs` to
// compare against an older decoder. `--slices`: the bytes pushed as
// stream-bench's server sends them (8 KiB slices of the file, at file
// offsets), and also printed: the median ms of the last two pushes (what
// is left to decode once the last-but-one slice is in). `--against
// OLD.js`: OLD.js and DECODER.js alternate run by run in one process
// (`runs` each, the first fifth not counted: JIT warm-up), and it prints
// each one's median CPU ms per decode and their ratio (a figure the
// machine's load moves less than wall times), and both signatures.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { MeshoptDecoder } from 'meshoptimizer';
const here = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2), flags = { slices: false, against: null }, pos = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--slices') flags.slices = true;
  else if (args[i] === '--against') flags.against = args[++i];
  else pos.push(args[i]);
}
const [file, runsArg, decArg] = pos;
if (!file) { console.error('decode-bench.mjs: needs FILE.glb [runs] [DECODER.js] [--slices] [--against OLD.js]'); process.exit(2); }
const dec = decArg || path.join(here, '../../crates/lodgen/web/three/lgpm.js');
const decoders = [(await import(pathToFileURL(dec).href)).StreamDecoder];
if (flags.against) decoders.unshift((await import(pathToFileURL(path.resolve(flags.against)).href)).StreamDecoder);
await MeshoptDecoder.ready;
const b = fs.readFileSync(file);
const jl = b.readUInt32LE(12);
const json = JSON.parse(b.subarray(20, 20 + jl).toString());
const binStart = 20 + jl + 8;
let ext = null;
for (const m of json.meshes) for (const p of m.primitives) if (p.extensions && p.extensions.LODGEN_progressive) ext = p.extensions.LODGEN_progressive;
const bv = json.bufferViews[ext.bufferView];
const s0 = binStart + (bv.byteOffset || 0), s = new Uint8Array(b.buffer, b.byteOffset + s0, bv.byteLength);
// push boundaries (stream offsets)
const cuts = [0];
if (flags.slices) for (let x = 8192 * Math.ceil((s0 + 1) / 8192); x < s0 + s.length; x += 8192) cuts.push(x - s0);
else for (let x = 65536; x < s.length; x += 65536) cuts.push(x);
cuts.push(s.length);
const runs = Number(runsArg || 5);
// hash of final output for identity check
const mix = (arr) => { let x = 0; for (let i = 0; i < arr.length; i++) x = (Math.imul(x, 31) + (arr[i] >>> 0)) | 0; return x >>> 0; };
const signature = (d) => [mix(d.faces0), mix(d.corners.a.subarray(0, d.corners.n)), mix(new Uint32Array(d.p0.buffer)), mix(new Uint32Array(d.p1.buffer)), mix(new Uint32Array(d.pm.buffer)), mix(d.v1), mix(d.cStart),
  // with wedges: the faces' and edited corners' wedges, each wedge's values and group
  ...(d.wfaces0 ? [mix(d.wfaces0), mix(d.wafter.a.subarray(0, d.wafter.n)), mix(d.wbefore.a.subarray(0, d.wbefore.n)), mix(new Uint32Array(d.wvals.buffer)), mix(d.wgroups)] : [])].join(',');
const res = decoders.map(() => ({ ts: [], cs: [], tails: [], d: null }));
for (let r = 0; r < runs * decoders.length; r++) {
  const k = r % decoders.length, o = res[k];
  const t0 = process.hrtime.bigint(), u0 = process.cpuUsage();
  const d = new decoders[k](MeshoptDecoder);
  let tail = 0;
  for (let i = 1; i < cuts.length; i++) {
    const t = performance.now();
    d.push(s.subarray(cuts[i - 1], cuts[i]));
    if (i >= cuts.length - 2) tail += performance.now() - t;
  }
  const u = process.cpuUsage(u0);
  o.ts.push(Number(process.hrtime.bigint() - t0) / 1e3 / d.header.splitCount);
  o.cs.push((u.user + u.system) / d.header.splitCount);
  o.tails.push(tail);
  o.d = d;
}
const med = (x) => { const q = [...x].sort((a, c) => a - c); return q[q.length >> 1]; };
const name = file.split('/').pop();
if (!flags.against) {
  const { ts, cs, tails, d } = res[0];
  const last = flags.slices ? ` last two pushes median ${med(tails).toFixed(2)} ms` : '';
  console.log(`${name} splits ${d.header.splitCount} us/split ${ts.map((t) => t.toFixed(2)).join(' ')} min ${Math.min(...ts).toFixed(2)} cpu ${cs.map((t) => t.toFixed(2)).join(' ')}${last} sig ${signature(d)}`);
} else {
  const skip = Math.floor(runs / 5), cpu = res.map((o) => med(o.cs.slice(skip)) * o.d.header.splitCount / 1e3);
  const tails = res.map((o) => med(o.tails.slice(skip)));
  console.log(`${name} splits ${res[1].d.header.splitCount}, ${runs} runs each alternating${flags.slices ? ', 8 KiB slices' : ''}: CPU ms per decode ` +
    `${cpu[0].toFixed(2)} (${flags.against}) -> ${cpu[1].toFixed(2)} (${decArg || 'lgpm.js'}): ${(cpu[1] / cpu[0]).toFixed(3)}x` +
    `${flags.slices ? `; last two pushes ${tails[0].toFixed(2)} -> ${tails[1].toFixed(2)} ms` : ''}; signatures ${signature(res[0].d) === signature(res[1].d) ? 'equal' : `DIFFER: ${signature(res[0].d)} / ${signature(res[1].d)}`}`);
}
