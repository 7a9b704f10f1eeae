#!/usr/bin/env node
// Decode speed of the LODGEN_progressive stream decoder in node: decodes the
// whole stream of a progressive GLB `runs` times (64 KiB pushes), prints
// wall and CPU microseconds per split for each run, and a signature of the
// decoded records, their wedges included (to check two decoders agree).
//
//   node decode-bench.mjs FILE.glb [runs] [DECODER.js]
//
// DECODER.js (an absolute path) defaults to crates/lodgen/web/three/lgpm.js;
// e.g. `git show REV:crates/lodgen/web/three/lgpm.js > /tmp/old.mjs` to
// compare against an older decoder, alternating runs.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { MeshoptDecoder } from 'meshoptimizer';
const here = path.dirname(fileURLToPath(import.meta.url));
const [file, runsArg, decArg] = process.argv.slice(2);
if (!file) { console.error('decode-bench.mjs: needs FILE.glb [runs] [DECODER.js]'); process.exit(2); }
const dec = decArg || path.join(here, '../../crates/lodgen/web/three/lgpm.js');
const { StreamDecoder } = await import(pathToFileURL(dec).href);
await MeshoptDecoder.ready;
const b = fs.readFileSync(file);
const jl = b.readUInt32LE(12);
const json = JSON.parse(b.subarray(20, 20 + jl).toString());
const binStart = 20 + jl + 8;
let ext = null;
for (const m of json.meshes) for (const p of m.primitives) if (p.extensions && p.extensions.LODGEN_progressive) ext = p.extensions.LODGEN_progressive;
const bv = json.bufferViews[ext.bufferView];
const s = new Uint8Array(b.buffer, b.byteOffset + binStart + (bv.byteOffset || 0), bv.byteLength);
const runs = Number(runsArg || 5);
const ts = [], cs = [];
let d;
for (let r = 0; r < runs; r++) {
  const t0 = process.hrtime.bigint(), u0 = process.cpuUsage();
  d = new StreamDecoder(MeshoptDecoder);
  for (let at = 0; at < s.length; at += 65536) d.push(s.subarray(at, Math.min(s.length, at + 65536)));
  ts.push(Number(process.hrtime.bigint() - t0) / 1e3 / d.header.splitCount);
  const u = process.cpuUsage(u0); cs.push((u.user + u.system) / d.header.splitCount);
}
// hash of final output for identity check
const mix = (arr) => { let x = 0; for (let i = 0; i < arr.length; i++) x = (Math.imul(x, 31) + (arr[i] >>> 0)) | 0; return x >>> 0; };
const sig = [mix(d.faces0), mix(d.corners.a.subarray(0, d.corners.n)), mix(new Uint32Array(d.p0.buffer)), mix(new Uint32Array(d.p1.buffer)), mix(new Uint32Array(d.pm.buffer)), mix(d.v1), mix(d.cStart),
  // with wedges: the faces' and edited corners' wedges, each wedge's values and group
  ...(d.wfaces0 ? [mix(d.wfaces0), mix(d.wafter.a.subarray(0, d.wafter.n)), mix(d.wbefore.a.subarray(0, d.wbefore.n)), mix(new Uint32Array(d.wvals.buffer)), mix(d.wgroups)] : [])].join(',');
console.log(`${file.split('/').pop()} splits ${d.header.splitCount} us/split ${ts.map((t) => t.toFixed(2)).join(' ')} min ${Math.min(...ts).toFixed(2)} cpu ${cs.map((t) => t.toFixed(2)).join(' ')} sig ${sig}`);
