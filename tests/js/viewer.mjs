#!/usr/bin/env node
// The `lodgen view` page in a real browser: headless Chromium (Debian's
// /usr/bin/chromium, override with env LODGEN_CHROMIUM) driven by
// playwright-core.
//
//   node viewer.mjs --url http://127.0.0.1:PORT/ --expect EXPECT.json [--out DIR] [--chunk BYTES]
//   node viewer.mjs --lodgen BIN FILE [--out DIR] [--chunk BYTES]     (or env LODGEN_BIN)
//
// With --lodgen, runs `BIN view --print-levels FILE` for the expectations and
// serves `BIN view FILE --port 0` itself. EXPECT.json is that output:
// {"splits":N,"streamBytes":B,"levels":[{"records":k,"triangles":t,"indexHash":h},...finest first]}.
//
// Checks: the page decodes the stream from several Range chunks and shows
// records before the last chunk has arrived; after k records (each level's
// count, refining and coarsening) the viewer's triangle count and index-buffer
// hash equal the expected ones, and with attributes (EXPECT's "channels" and
// each level's "attributeHash") so does the hash of every corner's streamed
// attribute values; the screen-coverage mode picks a coarser level
// when the camera moves away; no page or console errors. Writes
// DIR/viewer-<level>.png for the finest, a middle and the coarsest level
// (default DIR: target/test-out) and checks each is not blank (luminance
// variance of the rendered canvas). Exit 0 on success, 1 on failure, 2 on
// bad usage.

import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { HERE, MIN_VARIANCE, checker, launch } from './browser.mjs';

function usage(msg) {
  console.error(
    `viewer.mjs: ${msg}\nusage: node viewer.mjs --url URL --expect EXPECT.json [--out DIR] [--chunk BYTES]\n` +
      '       node viewer.mjs --lodgen BIN FILE [--out DIR] [--chunk BYTES]',
  );
  process.exit(2);
}

function parseArgs(argv) {
  const o = { out: path.resolve(HERE, '../../target/test-out'), chunk: 4096, lodgen: process.env.LODGEN_BIN, files: [] };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const next = () => {
      if (i + 1 >= argv.length) usage(`${a} needs a value`);
      return argv[++i];
    };
    if (a === '--url') o.url = next();
    else if (a === '--expect') o.expect = next();
    else if (a === '--out') o.out = path.resolve(next());
    else if (a === '--chunk') o.chunk = Number(next());
    else if (a === '--lodgen') o.lodgen = next();
    else if (a.startsWith('-')) usage(`unknown option ${a}`);
    else o.files.push(a);
  }
  if (!(o.chunk > 0)) usage('--chunk needs a positive byte count');
  if (o.url) {
    if (!o.expect) usage('--url needs --expect');
  } else {
    if (!o.lodgen || o.files.length !== 1) usage('expected --url URL --expect FILE, or --lodgen BIN FILE');
  }
  return o;
}

/// Start `BIN view FILE --port 0`; resolves to {url, child} once it prints its URL.
function startServer(bin, file) {
  return new Promise((resolve, reject) => {
    const child = spawn(bin, ['view', file, '--port', '0'], { stdio: ['ignore', 'ignore', 'pipe'] });
    let err = '';
    const timer = setTimeout(() => reject(new Error(`lodgen view did not start: ${err}`)), 120000);
    child.stderr.on('data', (d) => {
      err += d;
      const m = err.match(/http:\/\/127\.0\.0\.1:\d+\//);
      if (m) {
        clearTimeout(timer);
        resolve({ url: m[0], child });
      }
    });
    child.on('exit', (code) => reject(new Error(`lodgen view exited with ${code}: ${err}`)));
  });
}

const { check, failures } = checker();

async function main() {
  const o = parseArgs(process.argv.slice(2));
  let expect;
  let server = null;
  if (o.url) {
    expect = JSON.parse(fs.readFileSync(o.expect, 'utf8'));
  } else {
    expect = JSON.parse(execFileSync(o.lodgen, ['view', '--print-levels', o.files[0]], { encoding: 'utf8' }));
    server = await startServer(o.lodgen, o.files[0]);
    o.url = server.url;
  }
  fs.mkdirSync(o.out, { recursive: true });
  const errors = [];
  const browser = await launch(errors, { viewport: { width: 800, height: 600 } });
  try {
    const page = browser.page;
    const rangeRequests = [];
    page.on('request', (r) => { if (r.url().includes('stream.bin')) rangeRequests.push(r.headers()['range']); });

    const url = new URL(o.url);
    url.searchParams.set('chunk', String(o.chunk));
    await page.goto(url.toString());
    await page.waitForFunction(() => window.lodgen && (window.lodgen.complete() || window.lodgen.error()), null, {
      timeout: 120000,
    });
    const pageError = await page.evaluate(() => window.lodgen.error());
    check(!pageError, `page loads the stream${pageError ? ': ' + pageError : ''}`);
    if (pageError) return;

    // streamed in chunks, records applied before the end
    const history = await page.evaluate(() => window.lodgen.history());
    check(rangeRequests.length >= 3 && rangeRequests.every((r) => /^bytes=\d+-\d+$/.test(r || '')),
      `stream fetched in ${rangeRequests.length} Range requests`);
    const early = history.filter((h) => h.bytes < expect.streamBytes && h.applied > 0);
    check(early.length > 0, `records shown before the last chunk (${early.length} of ${history.length} chunks)`);
    const mono = history.every((h, i) => i === 0 || h.decoded >= history[i - 1].decoded);
    check(mono, 'decoded record count grows chunk by chunk');
    const decoded = await page.evaluate(() => window.lodgen.decoded());
    check(decoded === expect.splits, `all ${expect.splits} records decoded (${decoded})`);

    // each level, refining then coarsening then refining again
    const order = [...expect.levels].reverse().concat(expect.levels, [...expect.levels].reverse());
    for (const lv of order) {
      const got = await page.evaluate((k) => {
        const applied = window.lodgen.refineTo(k);
        return {
          applied, triangles: window.lodgen.triangles(), hash: window.lodgen.indexHash(),
          attr: window.lodgen.attributeHash(),
        };
      }, lv.records);
      check(got.applied === lv.records && got.triangles === lv.triangles && got.hash === lv.indexHash,
        `after ${lv.records} records: ${got.triangles} triangles, hash ${got.hash} ` +
          `(expected ${lv.triangles}, ${lv.indexHash})`);
      if (lv.attributeHash !== undefined) {
        check(got.attr === lv.attributeHash,
          `after ${lv.records} records: corner attribute hash ${got.attr} (expected ${lv.attributeHash})`);
      }
    }
    const channels = await page.evaluate(() => window.lodgen.channels());
    const want = expect.channels || [];
    check(JSON.stringify(channels) === JSON.stringify(want),
      `streamed attributes: [${channels.join(', ')}] (expected [${want.join(', ')}])`);
    if (want.includes('TEXCOORD_0')) {
      const modes = await page.evaluate(() => window.lodgen.shadingModes());
      check(modes.includes('uv checker'), `UV checker shading offered (${modes.join(', ')})`);
    }

    // screen-coverage mode: far away → a coarser level (or culled) than near
    const near = await page.evaluate(() => { window.lodgen.setCamera(0.6, 0.25, 1.5); return window.lodgen.setAuto(true); });
    const far = await page.evaluate(() => { window.lodgen.setCamera(0.6, 0.25, 400); window.lodgen.setAuto(true); return { a: window.lodgen.applied(), culled: window.lodgen.culled() }; });
    const records = expect.levels.map((l) => l.records);
    check(records.includes(near) && (far.culled || (records.includes(far.a) && far.a < near)),
      `coverage mode: near shows ${near} records, far ${far.culled ? 'culls' : 'shows ' + far.a}`);

    // screenshots at three levels
    const n = expect.levels.length;
    const picks = [...new Set([0, Math.floor((n - 1) / 2), n - 1])];
    for (const i of picks) {
      const lv = expect.levels[i];
      const stats = await page.evaluate((k) => {
        window.lodgen.setAuto(false);
        window.lodgen.setCamera(0.6, 0.25, 2.6);
        window.lodgen.refineTo(k);
        return window.lodgen.pixelStats();
      }, lv.records);
      const file = path.join(o.out, `viewer-L${i}-${lv.triangles}.png`);
      await page.screenshot({ path: file });
      check(stats.variance > MIN_VARIANCE,
        `level ${i} (${lv.triangles} triangles) not blank: luminance variance ${stats.variance.toFixed(1)} → ${file}`);
    }
    check(errors.length === 0, `no page errors${errors.length ? ': ' + errors.join('; ') : ''}`);
  } finally {
    await browser.close();
    if (server) server.child.kill();
  }
}

main().then(
  () => {
    if (failures.length) {
      console.error(`viewer.mjs: ${failures.length} check(s) failed`);
      process.exit(1);
    }
  },
  (e) => {
    console.error(`viewer.mjs: ${e.stack || e}`);
    process.exit(1);
  },
);
