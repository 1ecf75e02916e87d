// What the browser tests share: a hapticd on ephemeral loopback ports, a static file server for
// pages that are not the viewer's, and Chromium's arguments.
import { spawn } from 'node:child_process';
import { once } from 'node:events';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';

export const HAPTICD = process.env.HAPTICD;
export const CHROMIUM = process.env.CHROMIUM ?? '/usr/bin/chromium';
// Chromium as root in a sandbox-less container, on a closed network, drawing WebGL in software.
export const CHROMIUM_ARGS = ['--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
  '--disable-quic', '--no-first-run', '--disable-background-networking', '--disable-component-update',
  '--disable-sync'];
export const WAIT_MS = 20000;  // for anything to show; the tests' own bound (ctest's is longer)

/**
 * A hapticd started from `config` (a ServerConfig) with `args`, on ephemeral loopback ports; ready
 * once its ready file names them (`ports`: grpc_address, http_port, viewer_port, ...).
 */
export async function startServer(config, args = []) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hapticd-browser-'));
  fs.writeFileSync(path.join(dir, 'config.json'), JSON.stringify(config));
  const ready = path.join(dir, 'ready.json');
  const server = spawn(HAPTICD, ['--config', path.join(dir, 'config.json'), '--grpc-address', '127.0.0.1:0',
    '--udp-port', '0', '--ready-file', ready, ...args], { stdio: ['ignore', 'inherit', 'inherit'] });
  const giveUp = Date.now() + WAIT_MS;
  while (!fs.existsSync(ready)) {
    if (server.exitCode !== null) throw new Error(`hapticd exited (${server.exitCode}) before it was ready`);
    if (Date.now() > giveUp) throw new Error('hapticd not ready');
    await new Promise((resolve) => setTimeout(resolve, 20));
  }
  const ports = JSON.parse(fs.readFileSync(ready, 'utf8'));
  return {
    ports,
    api: `http://127.0.0.1:${ports.http_port}`,
    async stop() {
      if (server.exitCode === null) {
        server.kill('SIGTERM');
        await once(server, 'exit');
      }
      fs.rmSync(dir, { recursive: true, force: true });
    },
  };
}

const TYPES = { '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8', '.css': 'text/css; charset=utf-8' };

/**
 * Serves the files under `root` at http://127.0.0.1:PORT/ (GET only), and `pages` (path: HTML) beside
 * them; `origin` is that address.
 */
export async function startStaticServer(root, pages = {}) {
  const server = http.createServer((request, response) => {
    const page = pages[new URL(request.url, 'http://x').pathname];
    if (page !== undefined) {
      response.writeHead(200, { 'Content-Type': TYPES['.html'], 'Cache-Control': 'no-store' }).end(page);
      return;
    }
    const file = path.join(root, path.normalize(decodeURIComponent(new URL(request.url, 'http://x').pathname)));
    if (request.method !== 'GET' || !file.startsWith(root) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      response.writeHead(404).end();
      return;
    }
    response.writeHead(200, { 'Content-Type': TYPES[path.extname(file)] ?? 'application/octet-stream',
      'Cache-Control': 'no-store' });
    fs.createReadStream(file).pipe(response);
  });
  server.listen(0, '127.0.0.1');
  await once(server, 'listening');
  return {
    origin: `http://127.0.0.1:${server.address().port}`,
    port: server.address().port,
    async stop() {
      server.closeAllConnections();
      server.close();
      await once(server, 'close');
    },
  };
}
