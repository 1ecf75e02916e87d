// hapticd.js: a browser client for hapticd's control plane over HTTP (docs/http.md). A plain ES
// module, no build step: `import { HapticClient } from './hapticd.js'` in a <script type="module">
// (the viewer serves it beside its page, at /hapticd.js). It also runs under Node.js 22 or later,
// where fetch and WebSocket are global (20: with --experimental-websocket).
//
//   const client = await HapticClient.open('http://127.0.0.1:8081', { clientName: 'my page' });
//   await client.createObject({ half_space: { normal: { z: 1 } }, impedance: { stiffness: 1000 } });
//   const stream = client.streamState({ rateHz: 60, onState: (s) => draw(s.position) });
//   ...
//   await client.close();
//
// Requests and replies of the unary calls are protobuf's JSON mapping as the server speaks it
// (field names as in proto/haptic/v1/*.proto, snake_case; 64-bit integers as decimal strings).
// The state stream's datagrams are decoded here (docs/protocol.md, "Data plane") into plain
// objects with camelCase names; each one's SipHash-2-4 tag is checked with the session's udp_key.
//
// Frames and units throughout: W is the device's world frame (the scene's frame), T the tool. SI
// units: m, m/s, N, N·m, s (server times also as ns, BigInt).

/** The API version this module speaks (proto/haptic/v1/service.proto, API_VERSION_CURRENT). */
export const API_VERSION = 5;
/** The datagram wire version the state stream's messages carry (docs/protocol.md). */
export const WIRE_VERSION = 5;

const CALL_PREFIX = '/haptic.v1.Haptic/';
const MAGIC = 0x43545048;  // "HPTC" read as a little-endian u32
const HEADER_SIZE = 40;
const TAG_SIZE = 8;
const TYPE_STATE = 1;
const TYPE_STATE_ORIENTED = 5;
const STATE_PAYLOAD_SIZE = 116;
const STATE_ORIENTED_PAYLOAD_SIZE = 172;

/** gRPC's status codes by their Connect names (what an error body's "code" says). */
export const GRPC_CODES = Object.freeze({
  ok: 0, cancelled: 1, unknown: 2, invalid_argument: 3, deadline_exceeded: 4, not_found: 5,
  already_exists: 6, permission_denied: 7, resource_exhausted: 8, failed_precondition: 9,
  aborted: 10, out_of_range: 11, unimplemented: 12, internal: 13, unavailable: 14, data_loss: 15,
  unauthenticated: 16,
});

// A body that is not the server's JSON error (the HTTP layer's plain-text refusals: 413, 415, 431):
// the code its status stands for.
const CODE_OF_HTTP_STATUS = {
  400: 'invalid_argument', 401: 'unauthenticated', 403: 'permission_denied', 404: 'not_found',
  405: 'unimplemented', 413: 'resource_exhausted', 415: 'invalid_argument', 429: 'resource_exhausted',
  431: 'resource_exhausted', 501: 'unimplemented', 503: 'unavailable', 504: 'deadline_exceeded',
};

/**
 * A call or stream the server refused, or that could not reach it. `code` is gRPC's status code in
 * Connect's spelling ('invalid_argument', 'permission_denied', ...), `grpcCode` the same as its
 * number (3, 7, ...); `message` is the server's own words (it names the offending field).
 */
export class HapticError extends Error {
  /**
   * @param {string} code Connect's name of the gRPC code.
   * @param {string} message
   * @param {{call?: string, httpStatus?: number, cause?: unknown}} [details]
   */
  constructor(code, message, { call, httpStatus, cause } = {}) {
    super(message, cause === undefined ? undefined : { cause });
    this.name = 'HapticError';
    /** @type {string} */
    this.code = code;
    /** @type {number} gRPC's number for `code` (2, unknown, for a code this module does not know). */
    this.grpcCode = GRPC_CODES[code] ?? GRPC_CODES.unknown;
    /** @type {string|undefined} The call ('CreateObject') or stream ('StreamState') refused. */
    this.call = call;
    /** @type {number|undefined} The HTTP status of the reply, where there was one. */
    this.httpStatus = httpStatus;
  }
}

/** A state stream's message that is not a valid State datagram for the session; `reason` says why. */
export class DatagramError extends Error {
  constructor(reason) {
    super(`state datagram dropped: ${reason}`);
    this.name = 'DatagramError';
    this.reason = reason;
  }
}

// ---------------------------------------------------------------------------------------------
// SipHash-2-4 (Aumasson & Bernstein 2012), as proto/haptic/wire/siphash.cpp computes it.

const MASK64 = (1n << 64n) - 1n;
const rotl64 = (x, b) => ((x << b) | (x >> (64n - b))) & MASK64;

/**
 * SipHash-2-4 of `message` under the 16-byte `key`: the 64-bit tag, as the datagrams carry it
 * (little-endian in their last 8 bytes).
 * @param {Uint8Array} key 16 bytes.
 * @param {Uint8Array} message
 * @returns {bigint} 0 ... 2^64 − 1
 */
export function siphash24(key, message) {
  if (key.length !== 16) throw new RangeError(`siphash24: the key is 16 bytes, got ${key.length}`);
  const keyView = new DataView(key.buffer, key.byteOffset, 16);
  const k0 = keyView.getBigUint64(0, true);
  const k1 = keyView.getBigUint64(8, true);
  // "somepseudorandomlygeneratedbytes"
  let v0 = k0 ^ 0x736f6d6570736575n;
  let v1 = k1 ^ 0x646f72616e646f6dn;
  let v2 = k0 ^ 0x6c7967656e657261n;
  let v3 = k1 ^ 0x7465646279746573n;
  const sipRound = () => {
    v0 = (v0 + v1) & MASK64; v1 = rotl64(v1, 13n); v1 ^= v0; v0 = rotl64(v0, 32n);
    v2 = (v2 + v3) & MASK64; v3 = rotl64(v3, 16n); v3 ^= v2;
    v0 = (v0 + v3) & MASK64; v3 = rotl64(v3, 21n); v3 ^= v0;
    v2 = (v2 + v1) & MASK64; v1 = rotl64(v1, 17n); v1 ^= v2; v2 = rotl64(v2, 32n);
  };
  const compress = (m) => {
    v3 ^= m;
    sipRound();
    sipRound();
    v0 ^= m;
  };
  const view = new DataView(message.buffer, message.byteOffset, message.length);
  const full = message.length - (message.length % 8);
  for (let i = 0; i < full; i += 8) compress(view.getBigUint64(i, true));
  // The last word: the 0 to 7 bytes left, the length (mod 256) in its top byte.
  let last = BigInt(message.length & 0xff) << 56n;
  for (let i = full; i < message.length; ++i) last |= BigInt(message[i]) << BigInt(8 * (i - full));
  compress(last);
  v2 ^= 0xffn;
  for (let i = 0; i < 4; ++i) sipRound();
  return v0 ^ v1 ^ v2 ^ v3;
}

// ---------------------------------------------------------------------------------------------
// The State datagram (docs/protocol.md).

/**
 * @typedef {{x: number, y: number, z: number}} Vec3
 * @typedef {{w: number, x: number, y: number, z: number}} Quaternion
 */

/**
 * One tick's sample of the tool, as a State or StateOriented datagram carries it.
 * @typedef {object} ToolSample
 * @property {'State'|'StateOriented'} type
 * @property {string} sessionId    The session, as a decimal string (as the JSON calls write it).
 * @property {number} sequence     The stream's number for this sample, from 1; a gap is a sample not sent.
 * @property {bigint} serverTimeNs The tick's server time (since the server started; in lockstep,
 *                                 ticks × period). Unit: ns.
 * @property {number} serverTimeS  The same. Unit: s.
 * @property {number} tick         The tick's index.
 * @property {Vec3} position       p_WT, the tool in W. Unit: m.
 * @property {Vec3} velocity       v_WT. Unit: m/s.
 * @property {Vec3} force          F_T_W, the force commanded on the tool after the safety stage, in W. Unit: N.
 * @property {Vec3} proxy          p_WP, the proxy (god object) in W. Unit: m.
 * @property {number} contactCount Objects in contact.
 * @property {number} flags        1 force saturated, 2 force fault replaced by zero, 4 some force
 *                                 ramping out, 8 device fault (docs/protocol.md).
 * @property {number} buttons      Bit i: the device's button i pressed.
 * @property {Quaternion|null} orientation R_WT (StateOriented only; else null).
 * @property {Vec3|null} torque    tau_T_W, the torque on the tool in W (StateOriented only). Unit: N·m.
 */

/**
 * Decodes one State or StateOriented datagram, checking its header and, when `key` is given, its
 * SipHash-2-4 tag. Throws DatagramError naming what was wrong (as the UDP receiver drops it).
 * @param {ArrayBuffer|Uint8Array} datagram
 * @param {Uint8Array|null} key The session's 16-byte udp_key; null skips the tag's check.
 * @returns {ToolSample}
 */
export function decodeState(datagram, key) {
  const bytes = datagram instanceof Uint8Array ? datagram : new Uint8Array(datagram);
  if (bytes.length < HEADER_SIZE + TAG_SIZE) throw new DatagramError(`too short (${bytes.length} bytes)`);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.length);
  if (view.getUint32(0, true) !== MAGIC) throw new DatagramError('not a hapticd datagram (magic)');
  const version = view.getUint16(4, true);
  if (version !== WIRE_VERSION) throw new DatagramError(`wire version ${version}, this client speaks ${WIRE_VERSION}`);
  const type = view.getUint16(6, true);
  const expected = type === TYPE_STATE ? STATE_PAYLOAD_SIZE : type === TYPE_STATE_ORIENTED ? STATE_ORIENTED_PAYLOAD_SIZE : -1;
  if (expected < 0) throw new DatagramError(`type ${type} is not State or StateOriented`);
  const payloadSize = view.getUint32(32, true);
  if (payloadSize !== expected) throw new DatagramError(`payload size ${payloadSize} for type ${type}`);
  if (bytes.length !== HEADER_SIZE + payloadSize + TAG_SIZE) throw new DatagramError(`length ${bytes.length} for payload ${payloadSize}`);
  if (view.getUint32(36, true) !== 0) throw new DatagramError('reserved field not 0');
  if (key) {
    const body = bytes.length - TAG_SIZE;
    if (siphash24(key, bytes.subarray(0, body)) !== view.getBigUint64(body, true)) {
      throw new DatagramError("tag does not verify under the session's key");
    }
  }
  const f64 = (offset) => view.getFloat64(offset, true);
  const vec3 = (offset) => ({ x: f64(offset), y: f64(offset + 8), z: f64(offset + 16) });
  const p = HEADER_SIZE;
  const serverTimeNs = view.getBigInt64(24, true);
  const oriented = type === TYPE_STATE_ORIENTED;
  return {
    type: oriented ? 'StateOriented' : 'State',
    sessionId: view.getBigUint64(8, true).toString(),
    sequence: Number(view.getBigUint64(16, true)),
    serverTimeNs,
    serverTimeS: Number(serverTimeNs) * 1e-9,
    tick: Number(view.getBigUint64(p, true)),
    position: vec3(p + 8),
    velocity: vec3(p + 32),
    force: vec3(p + 56),
    proxy: vec3(p + 80),
    contactCount: view.getUint32(p + 104, true),
    flags: view.getUint32(p + 108, true),
    buttons: view.getUint32(p + 112, true),
    orientation: oriented ? { w: f64(p + 116), x: f64(p + 124), y: f64(p + 132), z: f64(p + 140) } : null,
    torque: oriented ? vec3(p + 148) : null,
  };
}

// ---------------------------------------------------------------------------------------------

const now = () => performance.now();

function base64Bytes(text) {
  return Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
}

/** `url` without a trailing slash or call prefix: 'http://127.0.0.1:8081'. */
function baseOf(url) {
  let base = String(url).replace(/\/+$/, '');
  if (base.endsWith('/haptic.v1.Haptic')) base = base.slice(0, -'/haptic.v1.Haptic'.length);
  if (!/^https?:\/\//.test(base)) throw new TypeError(`hapticd: '${url}' is not an http:// or https:// address`);
  return base;
}

function unreachable(base, call, cause) {
  const origin = globalThis.location?.origin;
  const page = origin && origin !== 'null' ? ` (or this page's origin, ${origin}, is not in its http_allowed_origins)` : '';
  return new HapticError('unavailable', `${call}: cannot reach hapticd at ${base}: nothing answers${page}`,
                         { call, cause });
}

/** POSTs one call; the reply's JSON, or throws HapticError. */
async function post(base, call, request, { token, secret, timeoutMs, fetchImpl }) {
  const headers = { 'Content-Type': 'application/json' };
  if (token) headers.Authorization = `Bearer ${token}`;
  if (secret) headers['haptic-session-secret-bin'] = secret;
  let response;
  try {
    response = await fetchImpl(base + CALL_PREFIX + call, {
      method: 'POST', headers, body: JSON.stringify(request), cache: 'no-store', credentials: 'omit',
      signal: timeoutMs > 0 ? AbortSignal.timeout(timeoutMs) : undefined,
    });
  } catch (error) {
    if (error?.name === 'TimeoutError') {
      throw new HapticError('deadline_exceeded', `${call}: no reply within ${timeoutMs} ms`, { call, cause: error });
    }
    throw unreachable(base, call, error);
  }
  const text = await response.text();
  if (response.ok) return text ? JSON.parse(text) : {};
  let body = null;
  try {
    body = JSON.parse(text);
  } catch {
    // the HTTP layer's plain-text refusals
  }
  if (body && typeof body.code === 'string') {
    throw new HapticError(body.code, body.message ?? '', { call, httpStatus: response.status });
  }
  throw new HapticError(CODE_OF_HTTP_STATUS[response.status] ?? 'unknown',
                        text.trim() || `${call}: HTTP ${response.status}`, { call, httpStatus: response.status });
}

/**
 * One session on a hapticd, over its HTTP face. Make one with HapticClient.open(); close() it when
 * done (its objects and fields then fade out). Every call for the session carries its secret and
 * the bearer token, if any, as headers; the streams carry them in their opening message.
 *
 * The session's lease (leaseTimeoutMs, 1 s by default) runs out when the client goes quiet: every
 * call renews it, and so does an open state stream; with keepAlive (the default) the client calls
 * GetDeviceInfo when it has said nothing for a quarter of the lease. A browser throttles the timers
 * of a hidden tab (to once a second or less): a page that must keep its session while hidden keeps
 * a state stream open.
 */
export class HapticClient {
  /**
   * Opens a session.
   * @param {string} url The HTTP face: 'http://127.0.0.1:8081' (or https://; a trailing
   *                     /haptic.v1.Haptic/ is taken off).
   * @param {object} [options]
   * @param {string} [options.token]        Bearer token (docs/deployment.md), for a server with tokens.
   * @param {string} [options.clientName]   1 to 64 printable characters; the server's log and ListSessions show it.
   * @param {number} [options.deviceIndex]  The device port: 0, the configured device; 1.., extra_devices.
   * @param {number} [options.timeoutMs]    Each call's deadline (Step's is longer by its ticks' real
   *                                        time); 0: none. Default 10000. Unit: ms.
   * @param {boolean} [options.keepAlive]   Renew the lease while idle (default true).
   * @param {typeof fetch} [options.fetch]  In place of the global fetch.
   * @returns {Promise<HapticClient>}
   */
  static async open(url, { token, clientName = 'browser', deviceIndex = 0, timeoutMs = 10000, keepAlive = true,
                           fetch: fetchImpl = globalThis.fetch.bind(globalThis) } = {}) {
    const base = baseOf(url);
    const sent = now();
    const reply = await post(base, 'OpenSession',
                             { client_name: clientName, api_version: API_VERSION, device_index: deviceIndex },
                             { token, timeoutMs, fetchImpl });
    const received = now();
    return new HapticClient(base, reply, { token, timeoutMs, keepAlive, fetchImpl, sent, received });
  }

  /** @private Use HapticClient.open(). */
  constructor(base, reply, { token, timeoutMs, keepAlive, fetchImpl, sent, received }) {
    /** The HTTP face's address, 'http://127.0.0.1:8081'. */
    this.url = base;
    /** @type {string} The session's id (a handle others see), a decimal string. */
    this.sessionId = reply.session_id;
    /** @type {object} The device's DeviceInfo (proto/haptic/v1/device.proto), as the JSON has it. */
    this.device = reply.device;
    /** @type {number} Unit: ms. */
    this.leaseTimeoutMs = reply.lease_timeout_ms;
    /** @type {Uint8Array} The 16-byte SipHash-2-4 key of the session's datagrams. */
    this.udpKey = base64Bytes(reply.udp_key);
    /**
     * The server's clock against this page's performance.now(), from OpenSession's round trip:
     * server time s is page time s × 1000 + offsetMs, within ± uncertaintyMs (half the round trip).
     * (In lockstep the server's time is its ticks', and this says nothing.)
     */
    this.serverClock = {
      offsetMs: (sent + received) / 2 - reply.server_time_s * 1000,
      uncertaintyMs: (received - sent) / 2,
    };
    this._secret = reply.session_secret;
    this._token = token;
    this._timeoutMs = timeoutMs;
    this._fetch = fetchImpl;
    this._streams = new Set();
    this._closed = false;
    this._lastCall = received;
    this._keepAlive = null;
    if (keepAlive && this.leaseTimeoutMs > 0) {
      const quarter = Math.max(10, this.leaseTimeoutMs / 4);
      this._keepAlive = setInterval(() => {
        const streaming = [...this._streams].some((s) => s instanceof StateStream && s.isOpen);
        if (!streaming && now() - this._lastCall >= quarter) this.call('GetDeviceInfo').catch(() => {});
      }, quarter);
      this._keepAlive.unref?.();  // Node.js: the timer alone keeps no process running
    }
  }

  /**
   * Page time (performance.now()'s clock, ms) of a server time, by serverClock.
   * @param {number} serverTimeS Unit: s.
   * @returns {number} Unit: ms.
   */
  pageTimeOf(serverTimeS) {
    return serverTimeS * 1000 + this.serverClock.offsetMs;
  }

  /**
   * One unary call of haptic.v1.Haptic for this session: `request` in protobuf's JSON mapping,
   * with session_id filled in where it has none. Resolves to the reply's JSON; throws HapticError.
   * @param {string} call 'CreateObject', 'Step', ... (proto/haptic/v1/service.proto).
   * @param {object} [request]
   * @param {{timeoutMs?: number}} [options]
   * @returns {Promise<object>}
   */
  async call(call, request = {}, { timeoutMs = this._timeoutMs } = {}) {
    if (this._closed) throw new HapticError('failed_precondition', `${call}: the client is closed`, { call });
    const body = 'session_id' in request ? request : { session_id: this.sessionId, ...request };
    const reply = await post(this.url, call, body,
                             { token: this._token, secret: this._secret, timeoutMs, fetchImpl: this._fetch });
    this._lastCall = now();
    return reply;
  }

  /**
   * Registers an object (scene.proto's Object: shape, pose in W (m), impedance). Its id, a string.
   * @param {object} object
   * @returns {Promise<string>}
   */
  async createObject(object) {
    return (await this.call('CreateObject', { object })).id;
  }

  /**
   * Replaces object `id` by `object` (cross-faded in). Another session's object only when it is
   * shared (object.shared stays true). Resolves to the reply (id and StabilityReport).
   * @param {string} id
   * @param {object} object
   */
  updateObject(id, object) {
    return this.call('UpdateObject', { object_id: id, object });
  }

  /** Deletes one of this session's objects. @param {string} id */
  deleteObject(id) {
    return this.call('DeleteObject', { id });
  }

  /**
   * Registers a field (scene.proto's Field). Its id, a string.
   * @param {object} field
   * @returns {Promise<string>}
   */
  async createField(field) {
    return (await this.call('CreateField', { field })).id;
  }

  /**
   * What the simulated operator's hand does (device.proto's OperatorInput: FOLLOW_TARGET with a
   * target in W (m), stiffness (N/m), damping (N·s/m); APPLY_FORCE with a force in W (N); NONE).
   * @param {object} input
   */
  setOperator(input) {
    return this.call('SetOperator', { input });
  }

  /**
   * Lockstep only: runs `ticks` ticks (1 ... 1,000,000). Resolves to the StepResponse: tick (a
   * decimal string), server_time_s, state (ToolState, the last tick's), run.
   * @param {number} ticks
   */
  step(ticks) {
    const rate = this.device?.loop_rate_hz > 0 ? this.device.loop_rate_hz : 1000;
    const timeoutMs = this._timeoutMs > 0 ? this._timeoutMs + Math.ceil((ticks * 1000) / rate) : 0;
    return this.call('Step', { ticks }, { timeoutMs });
  }

  /**
   * The state stream over WebSocket: the session port's newest sample, `rateHz` times a second,
   * each tick once at most, decoded and tag-checked. A message that fails the checks is dropped
   * and counted (stream.rejected; stream.lastRejection says why).
   * @param {object} [options]
   * @param {number} [options.rateHz]  1 ... 1000, and at most the loop's rate. Default 60. Unit: Hz.
   * @param {(sample: ToolSample, receivedAtMs: number) => void} [options.onState] Each sample, and
   *        when it arrived (performance.now(), ms).
   * @param {(error: HapticError) => void} [options.onError] The server's refusal, or a stream lost.
   * @returns {StateStream}
   */
  streamState({ rateHz = 60, onState, onError } = {}) {
    return this._track(new StateStream(this, { session_id: this.sessionId, rate_hz: rateHz }, { onState, onError }));
  }

  /**
   * The server's events over WebSocket, as WatchEvents gives them over gRPC: every session's
   * (service.proto's Event, as JSON: kind, session_id, server_time_s (s), message, item_id),
   * WATCH_STARTED first (stream.started resolves on it). The stream ends with this session.
   * @param {object} [options]
   * @param {(event: object) => void} [options.onEvent]
   * @param {(error: HapticError) => void} [options.onError]
   * @returns {EventStream}
   */
  watchEvents({ onEvent, onError } = {}) {
    return this._track(new EventStream(this, { session_id: this.sessionId }, { onEvent, onError }));
  }

  /** Closes the streams and the session (its items fade out). Safe to call twice. */
  async close() {
    if (this._closed) return;
    clearInterval(this._keepAlive);
    for (const stream of this._streams) stream.close();
    try {
      await this.call('CloseSession');
    } finally {
      this._closed = true;
    }
  }

  _track(stream) {
    this._streams.add(stream);
    stream.closed.then(() => this._streams.delete(stream));
    return stream;
  }

  /** @private The opening message of a stream. */
  _opening(request) {
    const opening = { request, session_secret: this._secret };
    if (this._token) opening.authorization = `Bearer ${this._token}`;
    return JSON.stringify(opening);
  }
}

/** What StateStream and EventStream share: the WebSocket, its opening, its errors and its end. */
class Stream {
  constructor(client, name, request, onError) {
    this._name = name;
    this._onError = onError;
    this._error = null;
    this._closing = false;
    /** Resolves to {code, reason} of the WebSocket's close frame once the stream has ended. */
    this.closed = new Promise((resolve) => { this._resolveClosed = resolve; });
    const url = client.url.replace(/^http/, 'ws') + CALL_PREFIX + name;
    this._socket = new WebSocket(url);
    this._socket.binaryType = 'arraybuffer';
    this._socket.addEventListener('open', () => this._socket.send(client._opening(request)));
    this._socket.addEventListener('message', (message) => {
      if (typeof message.data === 'string') {
        const body = JSON.parse(message.data);
        if (body.error) this._fail(new HapticError(body.error.code, body.error.message, { call: name }));
        else this._text(body);
      } else {
        this._binary(message.data);
      }
    });
    this._socket.addEventListener('close', (event) => {
      if (event.code !== 1000 && event.code !== 1005 && !this._error && !this._closing) {
        this._fail(event.code === 1006
          ? unreachable(client.url, name)
          : new HapticError(event.code === 1008 ? 'permission_denied' : 'unavailable',
                            `${name}: the server closed the stream (${event.code}${event.reason ? `: ${event.reason}` : ''})`,
                            { call: name }));
      }
      // Whatever still waits on the stream learns that it has ended.
      if (!this._error) this._failed(new HapticError('cancelled', `${name}: the stream has ended`, { call: name }));
      this._resolveClosed({ code: event.code, reason: event.reason });
    });
  }

  /** Whether the stream is still open (or opening). */
  get isOpen() {
    return this._socket.readyState <= 1;
  }

  /** Why the stream failed (a HapticError), or null. */
  get error() {
    return this._error;
  }

  /** Ends the stream (no error follows, whatever the state it was in). */
  close() {
    this._closing = true;
    if (this.isOpen) this._socket.close(1000);
  }

  _fail(error) {
    if (this._error) return;
    this._error = error;
    this._onError?.(error);
    this._failed(error);
  }

  _text() {}
  _binary() {}
  _failed() {}
}

/**
 * A state stream (HapticClient.streamState). `latest` is the newest sample; waitFor() waits for one
 * that passes a test; `received` and `rejected` count the messages taken and dropped.
 */
export class StateStream extends Stream {
  constructor(client, request, { onState, onError }) {
    super(client, 'StreamState', request, onError);
    this._key = client.udpKey;
    this._onState = onState;
    this._waiters = [];
    /** @type {ToolSample|null} */
    this.latest = null;
    /** Unit: ms, performance.now()'s clock: when `latest` arrived. */
    this.latestReceivedAtMs = null;
    this.received = 0;
    this.rejected = 0;
    /** @type {string|null} */
    this.lastRejection = null;
  }

  /**
   * The first sample (the latest included) for which `test` holds.
   * @param {(sample: ToolSample) => boolean} test
   * @param {number} [timeoutMs] Default 10000; rejects with a deadline_exceeded HapticError after it.
   * @returns {Promise<ToolSample>}
   */
  waitFor(test, timeoutMs = 10000) {
    if (this.latest && test(this.latest)) return Promise.resolve(this.latest);
    if (this.error) return Promise.reject(this.error);
    if (!this.isOpen) {
      return Promise.reject(new HapticError('cancelled', 'StreamState: the stream has ended', { call: 'StreamState' }));
    }
    return new Promise((resolve, reject) => {
      const waiter = { test, resolve, reject };
      waiter.timer = setTimeout(() => {
        this._waiters = this._waiters.filter((w) => w !== waiter);
        reject(new HapticError('deadline_exceeded', `StreamState: no such sample within ${timeoutMs} ms` +
                                 (this.rejected ? ` (${this.rejected} dropped: ${this.lastRejection})` : ''),
                               { call: 'StreamState' }));
      }, timeoutMs);
      this._waiters.push(waiter);
    });
  }

  _binary(data) {
    const receivedAt = now();
    let sample;
    try {
      sample = decodeState(data, this._key);
    } catch (error) {
      if (!(error instanceof DatagramError)) throw error;
      this.rejected += 1;
      this.lastRejection = error.reason;
      return;
    }
    this.received += 1;
    this.latest = sample;
    this.latestReceivedAtMs = receivedAt;
    this._onState?.(sample, receivedAt);
    const waiting = this._waiters;
    this._waiters = [];
    for (const waiter of waiting) {
      if (waiter.test(sample)) {
        clearTimeout(waiter.timer);
        waiter.resolve(sample);
      } else {
        this._waiters.push(waiter);
      }
    }
  }

  _failed(error) {
    for (const waiter of this._waiters) {
      clearTimeout(waiter.timer);
      waiter.reject(error);
    }
    this._waiters = [];
  }
}

/** An event stream (HapticClient.watchEvents); `started` resolves on WATCH_STARTED. */
export class EventStream extends Stream {
  constructor(client, request, { onEvent, onError }) {
    super(client, 'WatchEvents', request, onError);
    this._onEvent = onEvent;
    /** @type {Promise<object>} The WATCH_STARTED event; rejects if the stream is refused. */
    this.started = new Promise((resolve, reject) => { this._started = { resolve, reject }; });
    this.started.catch(() => {});
  }

  _text(body) {
    if (!body.event) return;
    if (body.event.kind === 'WATCH_STARTED') this._started.resolve(body.event);
    this._onEvent?.(body.event);
  }

  _failed(error) {
    this._started.reject(error);
  }
}
