// The browser client (web/src/hapticd.js) in headless Chromium (ctest browser.touch_wall;
// tests/browser/CMakeLists.txt sets the environment): web/examples/touch_wall.html against a
// lockstep hapticd prints what the C++ touch_wall prints, character for character; with tokens
// it passes the token on, and is refused as the server says; a page from an origin the server does
// not allow is refused; the events, the state stream's refusals, tags and close() in the page;
// the tour's block of docs/http.md as written. Last, over a real-time server, the sample age a page
// sees on the state stream, printed (not asserted: docs/performance.md keeps the figures).
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { CHROMIUM, CHROMIUM_ARGS, WAIT_MS, startServer, startStaticServer } from './support.mjs';

const TOUCH_WALL = process.env.TOUCH_WALL;
const WEB = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const ROOT = path.resolve(WEB, '..');
const RUN_MS = 120000;  // for a whole touch_wall run in the page, under load
const LOCKSTEP = { time_mode: 'LOCKSTEP', status_period_s: 0, real_time: { use_fifo: false } };
const TOKENS = [
  { name: 'watcher', token: 'observer-token-0123456789', role: 'OBSERVER' },
  { name: 'lab', token: 'controller-token-0123456789', role: 'CONTROLLER' },
];
const BLANK = '/blank.html';

/** Runs a program to its end: its exit code and what it printed on stdout. */
function run(program, args) {
  return new Promise((resolve, reject) => {
    const child = spawn(program, args, { stdio: ['ignore', 'pipe', 'inherit'] });
    let stdout = '';
    child.stdout.on('data', (chunk) => { stdout += chunk; });
    child.on('error', reject);
    child.on('close', (code) => resolve({ code, stdout }));
  });
}

/** The C++ touch_wall's output with `options` against a fresh lockstep server. */
async function cppTouchWall(options) {
  const server = await startServer(LOCKSTEP);
  try {
    const { code, stdout } = await run(TOUCH_WALL, [server.ports.grpc_address, ...options]);
    assert.equal(code, 0, stdout);
    return stdout;
  } finally {
    await server.stop();
  }
}

/** web/examples/touch_wall.html run in `page` to its end: {done, output, error}. */
async function pageTouchWall(page, url) {
  await page.goto('about:blank');  // a new document even where only the fragment differs
  await page.goto(url);
  await page.waitForFunction(() => window.touchWall?.done, null, { timeout: RUN_MS });
  return page.evaluate(() => window.touchWall);
}

describe('the browser client against a lockstep server', () => {
  let files;
  let server;
  let browser;
  let page;
  const pageErrors = [];

  before(async () => {
    files = await startStaticServer(WEB, { [BLANK]: '<!doctype html><title>blank</title>' });
    server = await startServer({ ...LOCKSTEP, http_allowed_origins: [files.origin] }, ['--http-api', '0']);
    browser = await chromium.launch({ executablePath: CHROMIUM, args: CHROMIUM_ARGS });
    page = await browser.newPage();
    page.on('pageerror', (error) => pageErrors.push(error.message));
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
    await files?.stop();
  });

  test('touch_wall.html prints exactly what the C++ touch_wall prints', async () => {
    const expected = await cppTouchWall(['--lockstep']);
    assert.ok(expected.split('\n').length > 60, expected);
    const shown = await pageTouchWall(page, `${files.origin}/examples/touch_wall.html?api=${server.api}&lockstep`);
    assert.equal(shown.error, null, shown.output);
    assert.equal(shown.output, expected);
    assert.equal(await page.locator('#out').textContent(), expected);
    assert.deepEqual(pageErrors, []);
  });

  test("the client in a page: events, a refusal as HapticError, the stream's tags and refusals, close()",
       async () => {
    await page.goto(files.origin + BLANK);
    const seen = await page.evaluate(async (api) => {
      const { HapticClient, HapticError } = await import('/src/hapticd.js');
      const out = {};
      const described = (error) => ({ isHapticError: error instanceof HapticError, name: error.name,
        code: error.code, grpcCode: error.grpcCode, call: error.call, httpStatus: error.httpStatus,
        message: error.message });
      const watcher = await HapticClient.open(api, { clientName: 'watcher' });
      const events = [];
      const watch = watcher.watchEvents({ onEvent: (event) => events.push(event) });
      out.started = (await watch.started).kind;

      const client = await HapticClient.open(api, { clientName: 'stepper' });
      out.sessions = [watcher.sessionId, client.sessionId];
      out.key = client.udpKey.length;
      out.objectId = await client.createObject({ sphere: { radius: 0.01 }, impedance: { stiffness: 100 } });
      try {
        await client.createObject({ sphere: { radius: -0.01 }, impedance: { stiffness: 100 } });
      } catch (error) {
        out.invalid = described(error);
      }
      const badRate = client.streamState({ rateHz: 5000 });
      out.badRate = await badRate.waitFor(() => true).then(() => null, described);
      out.badRateClosed = await badRate.closed;

      const stream = client.streamState({ rateHz: 1000 });
      await client.setOperator({ mode: 'APPLY_FORCE', force: { x: 0.5 } });
      const step = await client.step(25);
      const sample = await stream.waitFor((s) => s.tick >= Number(step.tick));
      out.sample = { tick: sample.tick, stepTick: Number(step.tick), type: sample.type,
        sameSession: sample.sessionId === client.sessionId, position: sample.position,
        stepPosition: step.state.position, serverTimeS: sample.serverTimeS, stepTimeS: step.state.server_time_s,
        received: stream.received, rejected: stream.rejected };

      // A stream closed while it opens says nothing; a wait on one that ends is told so.
      const early = client.streamState({ rateHz: 10, onError: (error) => { out.earlyError = error.message; } });
      early.close();
      out.earlyClosed = (await early.closed).code;
      const waiting = stream.waitFor(() => false, 60000).then(() => null, (error) => error.code);
      await client.close();
      out.streamAfterClose = await stream.closed;
      out.waitingAfterClose = await waiting;
      out.waitAfterEnd = await stream.waitFor(() => false).then(() => null, (error) => error.code);
      try {
        await client.step(1);
      } catch (error) {
        out.afterClose = described(error);
      }
      // The closing as the other session sees it.
      const deadline = performance.now() + 10000;
      while (!events.some((e) => e.kind === 'SESSION_CLOSED') && performance.now() < deadline) {
        await new Promise((resolve) => setTimeout(resolve, 20));
      }
      out.events = events.map(({ kind, session_id: session, item_id: item }) => ({ kind, session, item }));
      await watcher.close();
      out.watchClosed = await watch.closed;
      return out;
    }, server.api);

    assert.equal(seen.started, 'WATCH_STARTED');
    assert.equal(seen.key, 16);
    assert.deepEqual(seen.invalid, { isHapticError: true, name: 'HapticError', code: 'invalid_argument', grpcCode: 3,
      call: 'CreateObject', httpStatus: 400, message: 'object.sphere.radius: must be finite and in (0, 10], got -0.01' });
    assert.equal(seen.badRate.code, 'invalid_argument');
    assert.equal(seen.badRate.call, 'StreamState');
    assert.match(seen.badRate.message, /^rate_hz: must be 1 to 1000/);
    assert.equal(seen.badRateClosed.code, 1008);
    // The datagram's tick and values are the Step reply's, and its tag verified in the page.
    assert.equal(seen.sample.tick, seen.sample.stepTick);
    assert.equal(seen.sample.type, 'State');
    assert.ok(seen.sample.sameSession);
    assert.deepEqual(seen.sample.position, seen.sample.stepPosition);
    assert.ok(seen.sample.position.x > 0, 'the hand pushed the tool along +x');
    assert.equal(seen.sample.serverTimeS, seen.sample.stepTimeS);
    assert.ok(seen.sample.received >= 1);
    assert.equal(seen.sample.rejected, 0);
    assert.equal(seen.streamAfterClose.code, 1000);
    assert.equal(seen.earlyError, undefined);
    assert.equal(typeof seen.earlyClosed, 'number');
    assert.equal(seen.waitingAfterClose, 'cancelled');
    assert.equal(seen.waitAfterEnd, 'cancelled');
    assert.equal(seen.afterClose.code, 'failed_precondition');
    const [watcherId, clientId] = seen.sessions;
    assert.deepEqual(seen.events.filter((e) => e.session === clientId && e.kind !== 'SESSION_OPENED'), [
      { kind: 'SCENE_CHANGED', session: clientId, item: seen.objectId },
      { kind: 'SESSION_CLOSED', session: clientId, item: '0' },
    ]);
    assert.equal(seen.events[0].session, watcherId);
    assert.equal(seen.watchClosed.code, 1000);
    assert.deepEqual(pageErrors, []);
  });

  test("docs/http.md's browser tour runs as written and logs what the page says", async () => {
    const doc = fs.readFileSync(path.join(ROOT, 'docs/http.md'), 'utf8');
    const block = /<!-- snippet: browser-tour [^\n]*-->\n```js\n([\s\S]*?)```/.exec(doc)?.[1];
    assert.ok(block, 'docs/http.md has the browser-tour block');
    const expected = [...block.matchAll(/^\/\/ (.*)$/gm)].map((m) => m[1]);
    assert.equal(expected.length, 2);
    const source = block.replace("'./hapticd.js'", "'/src/hapticd.js'").replace('http://127.0.0.1:8081', server.api);
    await page.goto(files.origin + BLANK);
    const logged = [];
    page.on('console', (message) => { if (message.type() === 'log') logged.push(message.text()); });
    await page.addScriptTag({ type: 'module', content: `${source}\nwindow.tourDone = true;\n` });
    await page.waitForFunction(() => window.tourDone, null, { timeout: WAIT_MS });
    assert.deepEqual(logged, expected);
    assert.deepEqual(pageErrors, []);
  });

  test('a page from an origin the server does not allow is refused', async () => {
    // The same page by another name: http://localhost:PORT is another origin.
    const shown = await pageTouchWall(page, `http://localhost:${files.port}/examples/touch_wall.html?api=${server.api}&lockstep`);
    assert.equal(shown.error?.code, 'unavailable', shown.output);
    assert.match(shown.error.message, /OpenSession: cannot reach hapticd at http:\/\/127\.0\.0\.1:\d+: nothing answers \(or this page's origin, http:\/\/localhost:\d+, is not in its http_allowed_origins\)/);
  });
});

describe('the browser client against a lockstep server with tokens', () => {
  let files;
  let server;
  let browser;
  let page;

  before(async () => {
    files = await startStaticServer(WEB);
    server = await startServer({ ...LOCKSTEP, http_allowed_origins: [files.origin], security: { tokens: TOKENS } },
                               ['--http-api', '0']);
    browser = await chromium.launch({ executablePath: CHROMIUM, args: CHROMIUM_ARGS });
    page = await browser.newPage();
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
    await files?.stop();
  });

  const pageUrl = (token) => `${files.origin}/examples/touch_wall.html?api=${server.api}&lockstep` +
                             (token ? `#token=${token}` : '');

  test('a CONTROLLER token is carried on every call and stream: the same rows', async () => {
    const expected = await cppTouchWall(['--lockstep']);
    const rows = (text) => text.split('\n').filter((line) => /^ *\d+\.\d{3} /.test(line)).join('\n');
    const shown = await pageTouchWall(page, pageUrl(TOKENS[1].token));
    assert.equal(shown.error, null, shown.output);
    assert.ok(rows(expected).length > 1000);
    assert.equal(rows(shown.output), rows(expected));
  });

  test('no token, or an OBSERVER one, is refused as the server says', async () => {
    const none = await pageTouchWall(page, pageUrl());
    assert.equal(none.error?.code, 'unauthenticated', none.output);
    assert.match(none.error.message, /token/);
    const observer = await pageTouchWall(page, pageUrl(TOKENS[0].token));
    assert.equal(observer.error?.code, 'permission_denied', observer.output);
    assert.equal(observer.error.message, "needs role CONTROLLER or above; token 'watcher' has role OBSERVER");
  });
});

describe('the sample age a page sees on a real-time server', () => {
  let files;
  let server;
  let browser;

  before(async () => {
    files = await startStaticServer(WEB, { [BLANK]: '<!doctype html><title>blank</title>' });
    server = await startServer({ status_period_s: 0, real_time: { use_fifo: false }, http_allowed_origins: [files.origin] },
                               ['--http-api', '0']);
    browser = await chromium.launch({ executablePath: CHROMIUM, args: CHROMIUM_ARGS });
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
    await files?.stop();
  });

  // Age: the time a message's 'message' event ran in the page (performance.now()) less its tick's
  // server time, both on CLOCK_MONOTONIC: the server's time 0 is its ready file's time_origin_ns,
  // and the page's clock is set against this process's (process.hrtime, CLOCK_MONOTONIC too) by
  // reading performance.now() 50 times between two readings of it here, which bounds the offset;
  // the bounds together leave an interval, whose middle is taken (± half of it, printed).
  // OpenSession's server_time_s, read between a call's sending and its reply, must agree. Beside
  // it, the age at Chromium's network service: DevTools' Network.webSocketFrameReceived time stamp
  // (CLOCK_MONOTONIC) of the frame less the server time in its header, which parts the server's
  // and the network's share from the page's own.
  async function pageClock(page) {
    const coarse = 0.1;  // performance.now() is coarsened to 100 us in a page not cross-origin isolated
    let low = -Infinity;
    let high = Infinity;
    for (let i = 0; i < 50; ++i) {
      const before = Number(process.hrtime.bigint()) / 1e6;
      const now = await page.evaluate(() => performance.now());
      const after = Number(process.hrtime.bigint()) / 1e6;
      low = Math.max(low, before - now - coarse);
      high = Math.min(high, after - now + coarse);
    }
    assert.ok(low <= high, `the page's clock is not CLOCK_MONOTONIC: ${low} > ${high}`);
    return { monotonicMinusPageMs: (low + high) / 2, uncertaintyMs: (high - low) / 2 };
  }

  for (const rateHz of [60, 250]) {
    test(`prints the p50 and p99 of the sample age at ${rateHz} Hz`, async () => {
      const page = await browser.newPage();
      await page.goto(files.origin + BLANK);
      const clock = await pageClock(page);
      const devtools = await page.context().newCDPSession(page);
      await devtools.send('Network.enable');
      const atNetwork = [];  // [monotonic time received (ms), server time (ns)]
      devtools.on('Network.webSocketFrameReceived', ({ timestamp, response }) => {
        if (response.opcode !== 2) return;
        const bytes = Buffer.from(response.payloadData, 'base64');
        if (bytes.length >= 32) atNetwork.push([timestamp * 1e3, Number(bytes.readBigInt64LE(24))]);
      });
      const seen = await page.evaluate(async ({ api, rate, seconds }) => {
        const { HapticClient } = await import('/src/hapticd.js');
        const client = await HapticClient.open(api, { clientName: 'sample age' });
        const samples = [];  // [page time received (ms), server time (s)]
        let gaps = 0;
        let last = 0;
        const stream = client.streamState({ rateHz: rate, onState: (sample, receivedAt) => {
          samples.push([receivedAt, sample.serverTimeS]);
          if (last && sample.sequence !== last + 1) gaps += sample.sequence - last - 1;
          last = sample.sequence;
        } });
        await stream.waitFor(() => true);
        samples.length = 0;  // from the first message on: the stream's start is not its steady state
        await new Promise((resolve) => setTimeout(resolve, seconds * 1000));
        const { received, rejected } = stream;
        await client.close();
        return { samples, received, rejected, gaps, serverClock: client.serverClock };
      }, { api: server.api, rate: rateHz, seconds: 3 });
      const originMs = server.ports.time_origin_ns / 1e6;
      const toMonotonic = (pageMs) => pageMs + clock.monotonicMinusPageMs;
      const ages = seen.samples.map(([received, serverS]) => toMonotonic(received) - (originMs + serverS * 1e3))
        .sort((a, b) => a - b);
      const at = (q) => ages[Math.min(ages.length - 1, Math.floor(q * ages.length))];
      const figures = { p50: at(0.5), p99: at(0.99), min: ages[0], max: ages[ages.length - 1], n: ages.length };
      // The same span of the stream at the network service: the frames of the page's samples.
      const first = seen.samples[0]?.[1] * 1e9;
      const network = atNetwork.filter(([, serverNs]) => serverNs >= first - 1e3)
        .map(([received, serverNs]) => received - (originMs + serverNs / 1e6)).sort((a, b) => a - b);
      const q = (list, p) => list[Math.min(list.length - 1, Math.floor(p * list.length))];
      console.log(`sample age in headless chromium, ${rateHz} Hz for 3 s: p50 ${figures.p50.toFixed(2)} ms, ` +
                  `p99 ${figures.p99.toFixed(2)} ms (min ${figures.min.toFixed(2)}, max ${figures.max.toFixed(2)}; ` +
                  `clocks ± ${clock.uncertaintyMs.toFixed(2)} ms), ${figures.n} samples, ${seen.gaps} sequence gaps; ` +
                  `at the network service p50 ${q(network, 0.5)?.toFixed(2)} ms, p99 ${q(network, 0.99)?.toFixed(2)} ms ` +
                  `(${network.length} frames)`);
      await devtools.detach();
      // The client's own estimate of the server's clock, from OpenSession's round trip, holds the truth.
      const truthMs = originMs - clock.monotonicMinusPageMs;  // page time of server time 0
      const { offsetMs, uncertaintyMs } = seen.serverClock;
      assert.ok(Math.abs(offsetMs - truthMs) <= uncertaintyMs + clock.uncertaintyMs + 0.1,
                `serverClock ${offsetMs} ± ${uncertaintyMs} ms, CLOCK_MONOTONIC says ${truthMs} ms`);
      assert.ok(figures.min > -clock.uncertaintyMs - 0.1, 'no sample arrives before its tick');
      assert.equal(seen.rejected, 0);
      assert.ok(figures.n > 0, `no samples in 3 s at ${rateHz} Hz`);
      await page.close();
    });
  }
});
