// The viewer in headless Chromium (ctest browser.viewer; tests/browser/CMakeLists.txt sets the
// environment): a lockstep hapticd with --http 0, a client registering one object of every shape
// and one field of every kind (tests/browser/viewer_driver), the page loaded by playwright-core
// driving Debian's chromium. Checks what the page shows against what was registered, that the
// tool follows the simulated operator, and the token prompt; that a CONTROLLER token and the HTTP
// API's address let the page move a shared object (the form, and shift-drag in the view), and an
// OBSERVER token does not; writes screenshots into $SCREENSHOTS.
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import { once } from 'node:events';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import readline from 'node:readline';
import { chromium } from 'playwright-core';
import { CHROMIUM, CHROMIUM_ARGS, WAIT_MS, startServer as startHapticd } from './support.mjs';

const DRIVER = process.env.VIEWER_DRIVER;
const SCREENSHOTS = process.env.SCREENSHOTS ?? path.join(os.tmpdir(), 'viewer-screenshots');

/// A hapticd on ephemeral loopback ports (support.mjs), the viewer at `viewer` (a port; 0, any)
/// and, with httpApi, the HTTP API on any port; `url` is the viewer's page.
async function startServer(config, { viewer = 0, httpApi = false } = {}) {
  const server = await startHapticd(config, ['--http', String(viewer), ...(httpApi ? ['--http-api', '0'] : [])]);
  return { ...server, url: `http://127.0.0.1:${server.ports.viewer_port}/` };
}

/// The SDK client: registers every kind at start (its first line says what), then takes commands.
async function startDriver(grpcAddress) {
  const driver = spawn(DRIVER, [grpcAddress], { stdio: ['pipe', 'pipe', 'inherit'] });
  const lines = readline.createInterface({ input: driver.stdout })[Symbol.asyncIterator]();
  const next = async () => JSON.parse((await lines.next()).value);
  return {
    registered: await next(),
    async command(line) {
      driver.stdin.write(`${line}\n`);
      return next();
    },
    async stop() {
      driver.stdin.end('quit\n');
      if (driver.exitCode === null) await once(driver, 'exit');
    },
  };
}

const shown = (page) => page.evaluate(() => window.hapticViewer);

/// A loopback port free a moment ago: the viewer's, which the HTTP API must allow as an origin
/// before the server starts.
async function freePort() {
  const probe = net.createServer().listen(0, '127.0.0.1');
  await once(probe, 'listening');
  const { port } = probe.address();
  probe.close();
  await once(probe, 'close');
  return port;
}
const byId = (a, b) => Number(a.id) - Number(b.id);

describe('the viewer of a lockstep server', () => {
  let server;
  let driver;
  let browser;
  let page;
  const consoleErrors = [];

  before(async () => {
    fs.mkdirSync(SCREENSHOTS, { recursive: true });
    server = await startServer({ time_mode: 'LOCKSTEP', status_period_s: 0, real_time: { use_fifo: false } });
    driver = await startDriver(server.ports.grpc_address);
    await driver.command('move 0 0 0.02 50');  // let the new items ramp in
    browser = await chromium.launch({ executablePath: CHROMIUM, args: CHROMIUM_ARGS });
    page = await browser.newPage({ viewport: { width: 1400, height: 860 } });
    page.on('console', (message) => { if (message.type() === 'error') consoleErrors.push(message.text()); });
    page.on('pageerror', (error) => consoleErrors.push(error.message));
    await page.goto(server.url);
  });

  after(async () => {
    await browser?.close();
    await driver?.stop();
    await server?.stop();
  });

  test('shows every object and field the client registered, with its kind', async () => {
    const expected = driver.registered;
    await page.waitForFunction((n) => window.hapticViewer?.objects.length === n, expected.objects.length,
                               { timeout: WAIT_MS });
    const viewer = await shown(page);
    assert.deepEqual(viewer.objects.map(({ id, kind }) => ({ id, kind })).sort(byId), expected.objects);
    assert.deepEqual(viewer.fields.map(({ id, kind }) => ({ id, kind })).sort(byId), expected.fields);
    assert.ok(viewer.objects.every((o) => o.session === expected.session));
    assert.ok(viewer.webgl, 'the page could not get WebGL');
    // The table lists them too, one row each.
    assert.equal(await page.locator('#items tbody tr').count(), expected.objects.length + expected.fields.length);
    await page.waitForFunction(() => window.hapticViewer.frames > 0, null, { timeout: WAIT_MS });
    await page.screenshot({ path: path.join(SCREENSHOTS, 'viewer-scene.png') });
  });

  test('the tool moves when the simulated operator moves it', async () => {
    const before = (await shown(page)).toolPosition;
    // Into the pushable sphere at x = 50 mm: in contact, pushing it away, 100 ms on.
    const moved = await driver.command('move 0.05 0 0 100');
    await page.waitForFunction((tick) => window.hapticViewer.tick === tick, moved.tick, { timeout: WAIT_MS });
    const viewer = await shown(page);
    viewer.toolPosition.forEach((value, axis) => assert.ok(Math.abs(value - moved.position[axis]) < 1e-12,
      `axis ${axis}: the page shows ${value} m, the client stepped to ${moved.position[axis]} m`));
    assert.ok(Math.hypot(...viewer.toolPosition.map((v, axis) => v - before[axis])) > 0.02,
              `the tool moved only from ${before} to ${viewer.toolPosition}`);
    assert.equal(viewer.tools[0].contacts, 1);
    assert.ok(viewer.tools[0].force[0] < 0, 'the sphere pushes back along −x');
    // The statistics of the same tick in the picture too.
    await page.waitForFunction((n) => window.hapticViewer.statsPolls > n, viewer.statsPolls, { timeout: WAIT_MS });
    await page.screenshot({ path: path.join(SCREENSHOTS, 'viewer-contact.png') });
    assert.deepEqual(consoleErrors, []);
  });
});

describe('the viewer of a real-time server', () => {
  let server;
  let driver;
  let browser;

  before(async () => {
    server = await startServer({ status_period_s: 0, real_time: { use_fifo: false } });
    driver = await startDriver(server.ports.grpc_address);
    await driver.command('sway');
    browser = await chromium.launch({ executablePath: CHROMIUM, args: CHROMIUM_ARGS });
  });

  after(async () => {
    await browser?.close();
    await driver?.stop();
    await server?.stop();
  });

  test('the tool follows the swaying hand and the lateness histogram fills', async () => {
    const page = await browser.newPage({ viewport: { width: 1400, height: 860 } });
    await page.goto(server.url);
    await page.waitForFunction(() => window.hapticViewer?.toolPosition !== null, null, { timeout: WAIT_MS });
    const first = (await shown(page)).toolPosition;
    await page.waitForFunction((x) => Math.abs(window.hapticViewer.toolPosition[0] - x) > 0.005, first[0],
                               { timeout: WAIT_MS });
    // A few seconds of statistics for the plots, then the picture.
    await page.waitForFunction(() => window.hapticViewer.statsPolls >= 8, null, { timeout: WAIT_MS });
    const viewer = await shown(page);
    assert.ok(Number(viewer.latenessSamples) > 0, 'a real-time loop records its lateness');
    // The rate now is timed by the server's clock: a 1 kHz loop cannot show more than 1 kHz (and
    // one tick over the half second between polls). Timed by the browser's, it showed up to 1.56 kHz.
    assert.ok(viewer.rateNowHz > 0 && viewer.rateNowHz <= 1005, `rate now ${viewer.rateNowHz} Hz`);
    assert.equal(viewer.objects.length, driver.registered.objects.length);
    console.log(`viewer in headless chromium: ${viewer.fps} frames/s drawn, ${viewer.statePolls} states and ` +
                `${viewer.statsPolls} statistics polled`);
    await page.screenshot({ path: path.join(SCREENSHOTS, 'viewer-realtime.png') });
    await page.close();
  });
});

describe('the viewer of a server with tokens', () => {
  let server;
  let browser;
  const tokens = [
    { name: 'visitor', token: 'observer-token-0123456789', role: 'OBSERVER' },
    { name: 'lab-admin', token: 'admin-token-0123456789ab', role: 'ADMIN' },
  ];

  before(async () => {
    server = await startServer({ time_mode: 'LOCKSTEP', status_period_s: 0, real_time: { use_fifo: false },
      security: { tokens } });
    browser = await chromium.launch({ executablePath: CHROMIUM, args: CHROMIUM_ARGS });
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  test('asks for a token, and an OBSERVER token shows the scene but not the statistics', async () => {
    const page = await browser.newPage();
    await page.goto(server.url);
    await page.locator('#token-form').waitFor({ state: 'visible', timeout: WAIT_MS });
    assert.match(await page.locator('#token-why').textContent(), /needs a bearer token/);
    // A token in the fragment is taken into the tab's storage and out of the address bar.
    await page.goto(`${server.url}#token=${tokens[0].token}`);
    await page.waitForFunction(() => window.hapticViewer?.statePolls > 0, null, { timeout: WAIT_MS });
    assert.equal(new URL(page.url()).hash, '');
    await page.locator('#stats-why').waitFor({ state: 'visible', timeout: WAIT_MS });
    assert.match(await page.locator('#stats-why').textContent(), /needs role ADMIN or above; token 'visitor' has role OBSERVER/);
    // The prompt takes an ADMIN token: the statistics follow.
    await page.goto(server.url);
    await page.evaluate(() => sessionStorage.clear());
    await page.reload();
    await page.locator('#token').fill(tokens[1].token);
    await page.locator('#token-form button').click();
    await page.waitForFunction(() => document.getElementById('loop-figures').textContent.includes('ticks'), null,
                               { timeout: WAIT_MS });
    await page.close();
  });
});

describe('the viewer moving objects through the HTTP API', () => {
  let server;
  let browser;
  const tokens = [
    { name: 'lab', token: 'controller-token-0123456789', role: 'CONTROLLER' },
    { name: 'visitor', token: 'observer-token-0123456789', role: 'OBSERVER' },
  ];
  // The server's own objects: a shared sphere any CONTROLLER may move, and a box no one else may.
  const scene = { objects: [
    { sphere: { radius: 0.015 }, pose: { position: { x: 0.03, y: 0, z: 0.01 } }, impedance: { stiffness: 300 }, shared: true },
    { box: { half_extents: { x: 0.01, y: 0.01, z: 0.01 } }, pose: { position: { x: -0.04, y: 0, z: 0.01 } },
      impedance: { stiffness: 300 } },
  ] };
  /// The objects' positions as the server has them (m), by id.
  const positions = async () => {
    const response = await fetch(`${server.url}api/scene`, { headers: { Authorization: `Bearer ${tokens[0].token}` } });
    const { contents } = await response.json();
    return Object.fromEntries(contents.object_ids.map((id, i) => {
      const p = contents.scene.objects[i].pose?.position ?? {};
      return [id, [p.x ?? 0, p.y ?? 0, p.z ?? 0]];
    }));
  };

  before(async () => {
    const viewer = await freePort();
    server = await startServer({ time_mode: 'LOCKSTEP', status_period_s: 0, real_time: { use_fifo: false },
      security: { tokens }, initial_scene: scene, http_allowed_origins: [`http://127.0.0.1:${viewer}`] },
    { viewer, httpApi: true });
    browser = await chromium.launch({ executablePath: CHROMIUM, args: CHROMIUM_ARGS });
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  test('a CONTROLLER token moves the shared sphere, by the form and by shift-drag, and not the box', async () => {
    const page = await browser.newPage({ viewport: { width: 1400, height: 860 } });
    const errors = [];
    page.on('pageerror', (error) => errors.push(error.message));
    await page.goto(`${server.url}#token=${tokens[0].token}&api=${server.api}`);
    await page.waitForFunction(() => window.hapticViewer?.control.session !== null && window.hapticViewer.objects.length === 2,
                               null, { timeout: WAIT_MS });
    const [sphere, box] = (await shown(page)).objects.map((o) => o.id);
    // Only the shared sphere is offered.
    assert.deepEqual(await page.locator('#move-id option').evaluateAll((options) => options.map((o) => o.value)), [sphere]);
    assert.equal(await page.locator('#move-x').inputValue(), '30.0');

    await page.locator('#move-x').fill('10');
    await page.locator('#move-y').fill('20');
    await page.locator('#move-z').fill('30');
    await page.locator('#move-form button').click();
    await page.waitForFunction(() => window.hapticViewer.control.moves === 1, null, { timeout: WAIT_MS });
    assert.deepEqual((await positions())[sphere], [0.01, 0.02, 0.03]);
    // The page shows it where it is now.
    await page.locator('#items tbody tr', { hasText: '10.0, 20.0, 30.0' }).waitFor({ timeout: WAIT_MS });

    // Shift-drag it 100 px to the right in the view: it follows, in the plane facing the camera.
    await page.waitForFunction(() => window.hapticViewer.frames > 0, null, { timeout: WAIT_MS });
    const from = await page.evaluate((id) => window.hapticViewerScreenOf(id), sphere);
    assert.ok(from, 'the sphere is drawn');
    await page.keyboard.down('Shift');
    await page.mouse.move(from.x, from.y);
    await page.mouse.down();
    await page.mouse.move(from.x + 100, from.y, { steps: 10 });
    await page.mouse.up();
    await page.keyboard.up('Shift');
    // Every move the drag asked for answered (none in flight, none waiting): a later answer would
    // count against the pan on the box below.
    await page.waitForFunction(() => {
      const control = window.hapticViewer.control;
      return control.moves > 1 && control.underway === 0 && !document.getElementById('control-why').textContent;
    }, null, { timeout: WAIT_MS });
    const moved = await positions();
    const distance = Math.hypot(...moved[sphere].map((v, axis) => v - [0.01, 0.02, 0.03][axis]));
    assert.ok(distance > 0.005, `the sphere moved ${distance} m`);
    assert.deepEqual(moved[box], [-0.04, 0, 0.01], 'the box stays where it was');
    // Shift-drag on the box: the view pans instead, and nothing is sent.
    const moves = (await shown(page)).control.moves;
    const onBox = await page.evaluate((id) => window.hapticViewerScreenOf(id), box);
    await page.keyboard.down('Shift');
    await page.mouse.move(onBox.x, onBox.y);
    await page.mouse.down();
    await page.mouse.move(onBox.x + 60, onBox.y, { steps: 5 });
    await page.mouse.up();
    await page.keyboard.up('Shift');
    assert.equal((await shown(page)).control.moves, moves);
    assert.deepEqual((await positions())[box], [-0.04, 0, 0.01]);
    await page.screenshot({ path: path.join(SCREENSHOTS, 'viewer-moved.png') });
    assert.deepEqual(errors, []);
    await page.close();
  });

  test('an OBSERVER token is refused the move, as the server says', async () => {
    const page = await browser.newPage();
    await page.goto(`${server.url}#token=${tokens[1].token}&api=${server.api}`);
    await page.waitForFunction(() => window.hapticViewer?.control.session !== null && window.hapticViewer.objects.length === 2,
                               null, { timeout: WAIT_MS });
    const before = await positions();
    await page.locator('#move-x').fill('0');
    await page.locator('#move-form button').click();
    await page.waitForFunction(() => window.hapticViewer.control.error !== null, null, { timeout: WAIT_MS });
    assert.match(await page.locator('#control-why').textContent(),
                 /^object \d+: needs role CONTROLLER or above; token 'visitor' has role OBSERVER$/);
    assert.deepEqual(await positions(), before);
    await page.close();
  });
});
