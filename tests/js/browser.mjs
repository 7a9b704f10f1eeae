// Shared by the browser checks (babylon-lod.mjs, viewer.mjs, three-lod.mjs,
// stream-bench.mjs): headless Chromium through playwright-core, a local HTTP
// server with Range support (optionally throttled), and esbuild bundling of
// a page from node_modules (cached in node_modules/.cache/lodgen).

import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

export const HERE = path.dirname(fileURLToPath(import.meta.url));
export const CHROMIUM = process.env.LODGEN_CHROMIUM || '/usr/bin/chromium';
export const CHROMIUM_ARGS = [
  '--headless',
  '--no-sandbox',
  '--disable-gpu',
  '--no-first-run',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
  '--disable-quic',
  // WebGL through SwiftShader (software) since the GPU is disabled.
  '--use-angle=swiftshader',
  '--enable-unsafe-swiftshader',
];
/** Luminance variance below which a screenshot counts as blank. */
export const MIN_VARIANCE = 20;

/**
 * Start Chromium with a fresh profile; resolves to {context, page, close}.
 * `pageErrors` collects page errors, console errors, failed requests and
 * HTTP errors.
 */
export async function launch(pageErrors, { viewport = { width: 640, height: 480 } } = {}) {
  if (!fs.existsSync(CHROMIUM)) throw new Error(`${CHROMIUM} not found (install Debian's chromium or set LODGEN_CHROMIUM)`);
  const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'lodgen-chromium-'));
  const context = await chromium.launchPersistentContext(userDataDir, {
    executablePath: CHROMIUM,
    headless: true,
    args: CHROMIUM_ARGS,
    viewport,
    timeout: 60_000,
  });
  const page = context.pages()[0] ?? (await context.newPage());
  page.on('pageerror', (e) => pageErrors.push(`page error: ${e.message}`));
  page.on('console', (msg) => {
    const text = msg.text();
    if (msg.type() === 'warning' && text.includes('GL Driver Message')) return; // SwiftShader chatter
    if (msg.type() === 'error') pageErrors.push(`console error: ${text}`);
  });
  // net::ERR_ABORTED is the page cancelling its own request (a navigation
  // or a reader let go while a range was in flight), not a failed one
  page.on('requestfailed', (req) => req.failure()?.errorText === 'net::ERR_ABORTED' || pageErrors.push(`request failed: ${req.url()} ${req.headers().range || ''} (${req.failure()?.errorText})`));
  page.on('response', (res) => {
    if (res.status() >= 400) pageErrors.push(`HTTP ${res.status()} for ${res.url()}`);
  });
  const close = async () => {
    await context.close();
    fs.rmSync(userDataDir, { recursive: true, force: true });
  };
  return { context, page, close };
}

/**
 * Serve `routes` ({path: {type, body}}) on 127.0.0.1 (a free port) with
 * single-range support. With `throttle` ({bitsPerSecond, latencyMs}) every
 * response waits `latencyMs` after its request, then its body goes out in
 * slices at `bitsPerSecond` (a client reading the body as it arrives sees
 * the bytes come in), responses sharing the link one after another (as on
 * one slow line); a response the client closes early stops there and frees
 * the line. A route's own `throttle` applies to it instead (routes without
 * one are then sent at once when `throttle` is null). A route with `cache:
 * true` may be kept in the browser's HTTP cache (else no-store). Each request is
 * logged into `requests`, with `sent`: the body bytes written before the end
 * or the client's close.
 */
export function startServer(routes, requests = [], throttle = null) {
  const queue = []; // throttled responses waiting for the line
  let busy = false;
  const SLICE = 8192;
  const serveNext = () => {
    if (busy || !queue.length) return;
    busy = true;
    const { res, status, headers, body, log, ready, line } = queue.shift();
    let closed = false;
    res.on('close', () => { closed = true; });
    const begin = () => {
      if (closed) { busy = false; serveNext(); return; }
      res.writeHead(status, headers);
      const bytes = body ? body.length : 0;
      const t0 = Date.now();
      let pos = 0;
      const step = () => {
        if (closed || pos >= bytes) {
          if (!closed) res.end();
          busy = false;
          serveNext();
          return;
        }
        const n = Math.min(SLICE, bytes - pos);
        res.write(body.subarray(pos, pos + n));
        pos += n;
        log.sent = pos;
        // the slice's last byte leaves the line at t0 + pos bits / rate
        setTimeout(step, Math.max(0, t0 + (pos * 8 * 1000) / line.bitsPerSecond - Date.now()));
      };
      step();
    };
    setTimeout(begin, Math.max(0, ready - Date.now()));
  };
  const send = (res, status, headers, body, log, line) => {
    if (!line) {
      log.sent = body ? body.length : 0;
      res.writeHead(status, headers).end(body);
      return;
    }
    queue.push({ res, status, headers, body, log, line, ready: Date.now() + line.latencyMs });
    serveNext();
  };
  const server = http.createServer((req, res) => {
    const u = new URL(req.url, 'http://127.0.0.1');
    const route = routes[u.pathname];
    const log = { method: req.method, path: u.pathname, range: req.headers.range ?? null, status: 0, sent: 0, t: Date.now() };
    requests.push(log);
    if (!route) {
      log.status = u.pathname === '/favicon.ico' ? 204 : 404;
      res.writeHead(log.status).end();
      return;
    }
    const body = route.body;
    const headers = { 'Content-Type': route.type, 'Cache-Control': route.cache ? 'max-age=3600' : 'no-store', 'Accept-Ranges': 'bytes' };
    const m = /^bytes=(\d*)-(\d*)$/.exec(req.headers.range ?? '');
    if (m && (m[1] !== '' || m[2] !== '')) {
      let start;
      let end;
      if (m[1] === '') {
        start = Math.max(0, body.length - Number(m[2]));
        end = body.length - 1;
      } else {
        start = Number(m[1]);
        end = m[2] === '' ? body.length - 1 : Math.min(Number(m[2]), body.length - 1);
      }
      if (start > end || start >= body.length) {
        log.status = 416;
        res.writeHead(416, { 'Content-Range': `bytes */${body.length}` }).end();
        return;
      }
      log.status = 206;
      const part = req.method === 'HEAD' ? undefined : body.subarray(start, end + 1);
      send(res, 206, { ...headers, 'Content-Range': `bytes ${start}-${end}/${body.length}`, 'Content-Length': end - start + 1 }, part, log, route.throttle || throttle);
      return;
    }
    log.status = 200;
    send(res, 200, { ...headers, 'Content-Length': body.length }, req.method === 'HEAD' ? undefined : body, log, route.throttle || throttle);
  });
  return new Promise((resolve, reject) => {
    server.once('error', reject);
    server.listen(0, '127.0.0.1', () => resolve(server));
  });
}

/**
 * Bundle `entry` (a path relative to tests/js) with esbuild into one ES
 * module, cached in node_modules/.cache/lodgen keyed by the sources
 * (`extra` files too) and package-lock.json.
 */
export async function bundle(entry, extra = []) {
  const esbuild = await import('esbuild');
  const file = path.resolve(HERE, entry);
  const hash = crypto.createHash('sha256');
  for (const f of [file, ...extra.map((e) => path.resolve(HERE, e)), path.join(HERE, 'package-lock.json')]) {
    hash.update(fs.readFileSync(f));
  }
  const key = hash.digest('hex').slice(0, 16);
  const cached = path.join(HERE, 'node_modules', '.cache', 'lodgen', `${path.basename(entry, '.js')}-${key}.js`);
  if (fs.existsSync(cached)) return fs.readFileSync(cached);
  const r = await esbuild.build({
    entryPoints: [file],
    absWorkingDir: HERE,
    nodePaths: [path.join(HERE, 'node_modules')],
    bundle: true,
    format: 'esm',
    target: 'es2020',
    write: false,
    logLevel: 'silent',
  });
  const js = Buffer.from(r.outputFiles[0].contents);
  fs.mkdirSync(path.dirname(cached), { recursive: true });
  fs.writeFileSync(`${cached}.tmp${process.pid}`, js);
  fs.renameSync(`${cached}.tmp${process.pid}`, cached);
  return js;
}

/** A check list: `check(cond, what)` prints and records; `failures` lists the failed ones. */
export function checker() {
  const failures = [];
  const check = (cond, what) => {
    if (!cond) failures.push(what);
    console.log(`${cond ? 'ok  ' : 'FAIL'} ${what}`);
  };
  return { check, failures };
}
