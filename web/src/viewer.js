// hapticd's viewer: polls /api/state at display rate, /api/stats twice a second and /api/scene
// whenever the scene's generation moves on (docs/viewer.md). Those are read-only; only when given
// the server's HTTP API (Move objects) does the page change anything, through that API, as any
// client of it would (control.js).
import { SceneView, TOOL_COLORS, caseOf, OBJECT_KINDS, FIELD_KINDS, vec } from './scene_view.js';
import { drawHistogram, drawSeries } from './plots.js';
import { Control } from './control.js';

const TOKEN_KEY = 'hapticd-viewer-token';
const API_KEY = 'hapticd-viewer-api';
const STATE_PERIOD_MS = 16;   // at most ~60 requests a second, one at a time
const SCENE_MIN_PERIOD_MS = 500;  // the scene is fetched again at most this often
const STATS_PERIOD_MS = 500;
const HISTORY_S = 60;

const $ = (id) => document.getElementById(id);

// What the page shows, for a person and for tests (read-only; the page never reads it back).
const shown = {
  objects: [],          // [{id, session, kind}]
  fields: [],           // [{id, session, kind}]
  tools: [],            // per device port: {position: [x, y, z], force: [...], contacts}
  toolPosition: null,   // port 0's [x, y, z] (m)
  tick: '0',
  sceneGeneration: null,
  frames: 0,            // frames rendered
  fps: 0,
  statePolls: 0,
  statsPolls: 0,
  latenessSamples: '0', // ticks in the statistics' lateness window
  rateNowHz: null,      // the loop's rate over the last two statistics (the server's clock)
  error: null,          // the latest problem shown to the user
  webgl: true,
  // Move objects: the page's session, moves taken, and moves asked for and not yet answered
  control: { session: null, moves: 0, error: null, underway: 0 },
};
window.hapticViewer = shown;

// A token from the URL's fragment (#token=…) goes to this tab's storage and out of the address bar,
// and so does the HTTP API's address (#api=…, for Move objects). Returns whether there was a token.
function takeTokenFromUrl() {
  const token = /(?:^#|&)token=([^&]*)/.exec(window.location.hash);
  const api = /(?:^#|&)api=([^&]*)/.exec(window.location.hash);
  if (!token && !api) return false;
  if (token) sessionStorage.setItem(TOKEN_KEY, decodeURIComponent(token[1]));
  if (api) sessionStorage.setItem(API_KEY, decodeURIComponent(api[1]));
  history.replaceState(null, '', window.location.pathname + window.location.search);
  return Boolean(token);
}

class Unauthorized extends Error {}

/// GETs `path` with the stored token; throws Unauthorized on 401 and Error naming the status else.
async function getJson(path) {
  const token = sessionStorage.getItem(TOKEN_KEY);
  const response = await fetch(path, {
    cache: 'no-store',
    headers: token ? { Authorization: `Bearer ${token}` } : {},
  });
  if (response.ok) return response.json();
  const text = (await response.text()).trim();
  if (response.status === 401) throw new Unauthorized(text);
  const error = new Error(text || `${path}: HTTP ${response.status}`);
  error.status = response.status;
  throw error;
}

function setStatus(text, kind) {
  const status = $('status');
  status.textContent = text;
  status.className = `status ${kind ?? ''}`;
  if (kind === 'error') shown.error = text;
}

function askForToken(why) {
  $('token-form').hidden = false;
  $('token-why').textContent = why;
  setStatus('needs a token', 'error');
}

function mm(v) {
  return `${(1000 * v.x).toFixed(1)}, ${(1000 * v.y).toFixed(1)}, ${(1000 * v.z).toFixed(1)}`;
}

/// A session id (a JSON string of a uint64) as the log writes it: 16 hex digits; 0 is the server.
function sessionName(id) {
  if (id === undefined || id === '0' || id === 0) return 'server';
  return BigInt(id).toString(16).padStart(16, '0');
}

function cells(row, values) {
  row.replaceChildren(...values.map((value) => {
    const cell = document.createElement('td');
    if (value instanceof Node) cell.append(value); else cell.textContent = value;
    return cell;
  }));
  return row;
}

function fillTable(tbody, rows) {
  tbody.replaceChildren(...rows.map((values) => cells(document.createElement('tr'), values)));
}

function swatch(color) {
  const span = document.createElement('span');
  span.className = 'swatch';
  span.style.background = `#${color.toString(16).padStart(6, '0')}`;
  return span;
}

/// Where an item is, in a few characters (mm).
function whereOf(item, kind) {
  const body = item[kind] ?? {};
  // An object's pose; a field's anchor (a point, or a distance's origin), origin or centre.
  const point = item.pose?.position ?? body.anchor?.origin ?? body.anchor ?? body.distance?.origin ??
                body.origin ?? body.center;
  return point ? mm(vec(point)) : '';
}

class Viewer {
  constructor() {
    this.devices = [];
    this.generation = null;
    this.history = [];  // [t_s, rate_hz, p99_us]
    this.lastStats = null;
    this.started = performance.now();
    this.control = new Control();
    try {
      this.view = new SceneView($('scene'));
    } catch (error) {
      shown.webgl = false;
      this.view = null;
      $('view-message').hidden = false;
      $('view-message').textContent = `This browser gives no WebGL, so the scene cannot be drawn (${error.message}); the tables still update.`;
    }
  }

  start() {
    $('token-form').addEventListener('submit', (event) => {
      event.preventDefault();
      sessionStorage.setItem(TOKEN_KEY, $('token').value.trim());
      $('token').value = '';
      this.useNewToken();
    });
    window.addEventListener('hashchange', () => {
      if (takeTokenFromUrl()) this.useNewToken();
      else if (sessionStorage.getItem(API_KEY)) this.connectControl();
    });
    $('control-form').addEventListener('submit', (event) => {
      event.preventDefault();
      sessionStorage.setItem(API_KEY, $('control-api').value.trim());
      this.connectControl();
    });
    $('move-id').addEventListener('change', () => this.fillMoveForm());
    $('move-form').addEventListener('submit', (event) => {
      event.preventDefault();
      const mm = ['x', 'y', 'z'].map((axis) => Number($(`move-${axis}`).value) / 1000);
      this.moveObject($('move-id').value, { x: mm[0], y: mm[1], z: mm[2] });
    });
    this.view?.enableDragging((id) => this.control.movable(id),
                              (id, p, done) => this.moveObject(id, { x: p.x, y: p.y, z: p.z }, done));
    if (sessionStorage.getItem(API_KEY)) this.connectControl();
    this.pollState();
    this.pollStats();
    this.frame();
  }

  /// Starts over with the token just stored: the scene, the state and the statistics again.
  useNewToken() {
    $('token-form').hidden = true;
    this.generation = null;
    this.pollState();
    if (!this.statsPolling) this.pollStats();
    if (sessionStorage.getItem(API_KEY)) this.connectControl();
  }

  /// Move objects: a session on the HTTP API (the stored address), with the tab's token.
  async connectControl() {
    const api = sessionStorage.getItem(API_KEY);
    $('control-api').value = api;
    $('control-status').textContent = `connecting to ${api}…`;
    try {
      const client = await this.control.connect(api, sessionStorage.getItem(TOKEN_KEY));
      shown.control.session = client.sessionId;
      $('control-status').textContent = `session ${sessionName(client.sessionId)}: shared objects move`;
      this.showControlError(null);
    } catch (error) {
      shown.control.session = null;
      $('control-status').textContent = 'off';
      this.showControlError(error.message);
    }
    this.fillMoveForm();
  }

  showControlError(text) {
    shown.control.error = text;
    $('control-why').hidden = !text;
    $('control-why').textContent = text ?? '';
  }

  /// The move form: the objects this page may move, the chosen one's position (mm).
  fillMoveForm() {
    const ids = this.control.movableIds();
    $('move-form').hidden = ids.length === 0;
    const select = $('move-id');
    const chosen = ids.includes(select.value) ? select.value : ids[0];
    if (select.options.length !== ids.length || [...select.options].some((o, i) => o.value !== ids[i])) {
      select.replaceChildren(...ids.map((id) => {
        const option = document.createElement('option');
        option.value = id;
        option.textContent = `${id} ${caseOf(this.control.objects.get(id).object, OBJECT_KINDS)}`;
        return option;
      }));
    }
    if (chosen === undefined) return;
    select.value = chosen;
    const p = vec(this.control.objects.get(chosen).object.pose?.position);
    $('move-x').value = (1000 * p.x).toFixed(1);
    $('move-y').value = (1000 * p.y).toFixed(1);
    $('move-z').value = (1000 * p.z).toFixed(1);
  }

  /// Moves object `id` to `position` (m, in W) through the HTTP API; a drag's last step (done)
  /// has the scene fetched again.
  async moveObject(id, position, done = true) {
    shown.control.underway += 1;
    try {
      await this.control.move(id, position);
      shown.control.moves = this.control.moves;
      this.showControlError(null);
      if (done && $('move-id').value === id) this.fillMoveForm();
    } catch (error) {
      this.showControlError(`object ${id}: ${error.message}`);
    } finally {
      shown.control.underway -= 1;
    }
    if (done) this.generation = null;  // the scene again at the next poll, the view put right
  }

  /// Each display frame: draws the scene when the state, the scene or the camera changed.
  frame() {
    const now = performance.now();
    if (this.view?.render()) {
      shown.frames += 1;
      this.frameTimes = (this.frameTimes ?? []).filter((t) => now - t < 1000);
      this.frameTimes.push(now);
    }
    shown.fps = (this.frameTimes ?? []).filter((t) => now - t < 1000).length;
    requestAnimationFrame(() => this.frame());
  }

  async loadScene() {
    const scene = await getJson('/api/scene');
    this.generation = scene.generation;
    shown.sceneGeneration = scene.generation;
    if (JSON.stringify(scene.devices) !== JSON.stringify(this.devices)) {
      this.devices = scene.devices ?? [];
      this.view?.setDevices(this.devices);
    }
    const contents = scene.contents ?? {};
    this.view?.setScene(contents);
    this.control.setScene(contents);
    if (document.activeElement?.closest?.('#move-form') == null) this.fillMoveForm();
    this.drawnKey = null;  // the rebuilt scene takes the next state, whatever its tick
    const objects = contents.scene?.objects ?? [];
    const fields = contents.scene?.fields ?? [];
    shown.objects = objects.map((o, i) => ({ id: contents.object_ids[i], session: contents.object_sessions[i], kind: caseOf(o, OBJECT_KINDS) }));
    shown.fields = fields.map((f, i) => ({ id: contents.field_ids[i], session: contents.field_sessions[i], kind: caseOf(f, FIELD_KINDS) }));
    $('scene-counts').textContent = `${objects.length} objects, ${fields.length} fields`;
    fillTable($('items').tBodies[0], [
      ...objects.map((o, i) => [contents.object_ids[i], sessionName(contents.object_sessions[i]), shown.objects[i].kind + (o.dynamics?.mass > 0 ? ' (movable)' : ''), whereOf(o, shown.objects[i].kind)]),
      ...fields.map((f, i) => [contents.field_ids[i], sessionName(contents.field_sessions[i]), `${shown.fields[i].kind} field`, whereOf(f, shown.fields[i].kind)]),
    ]);
  }

  async pollState() {
    if (this.statePolling) return;
    this.statePolling = true;
    try {
      const state = await getJson('/api/state');
      // A changed scene is fetched again, at most twice a second: a client updating an object at
      // its own rate must not make the page rebuild the scene at every poll.
      const sinceLoad = performance.now() - (this.sceneLoadedAt ?? -Infinity);
      // Not while an object is dragged: the rebuilt scene would take it from under the pointer.
      if (state.scene_generation !== this.generation && sinceLoad >= SCENE_MIN_PERIOD_MS && !this.view?.dragging) {
        this.sceneLoadedAt = performance.now();
        await this.loadScene();
      }
      this.showState(state);
      setStatus('live', 'ok');
      shown.error = null;
      this.statePolling = false;
      setTimeout(() => this.pollState(), STATE_PERIOD_MS);
    } catch (error) {
      this.statePolling = false;
      if (error instanceof Unauthorized) {
        askForToken(error.message);  // polling resumes when a token is given
        return;
      }
      setStatus(`no answer: ${error.message}`, 'error');
      setTimeout(() => this.pollState(), 1000);
    }
  }

  showState(state) {
    shown.statePolls += 1;
    shown.tick = state.tick;
    shown.tools = (state.tools ?? []).map((tool) => ({
      position: [vec(tool.position).x, vec(tool.position).y, vec(tool.position).z],
      force: [vec(tool.force).x, vec(tool.force).y, vec(tool.force).z],
      contacts: tool.contact_count ?? 0,
    }));
    shown.toolPosition = shown.tools[0]?.position ?? null;
    // The view redraws only when it has something new to show: another tick, or a scene just
    // rebuilt (polling an idle lockstep server draws nothing).
    const drawnKey = `${state.tick}/${this.generation}`;
    if (drawnKey !== this.drawnKey) {
      this.drawnKey = drawnKey;
      this.view?.setState(state);
    }
    $('clock').textContent = `tick ${state.tick} · t = ${(state.server_time_s ?? 0).toFixed(3)} s · ${shown.fps} fps`;
    fillTable($('tools').tBodies[0], (state.tools ?? []).map((tool, port) => [
      swatch(TOOL_COLORS[port % TOOL_COLORS.length]), this.devices[port]?.model ?? '', mm(vec(tool.position)),
      (() => { const f = vec(tool.force); return `${f.x.toFixed(2)}, ${f.y.toFixed(2)}, ${f.z.toFixed(2)}`; })(),
      (1000 * vec(tool.velocity).length()).toFixed(1), String(tool.contact_count ?? 0),
    ]));
  }

  async pollStats() {
    this.statsPolling = true;
    try {
      const { stats, lateness, read_at_s: readAtS } = await getJson('/api/stats');
      $('stats-why').hidden = true;
      this.showStats(stats, lateness, readAtS);
    } catch (error) {
      const refused = error instanceof Unauthorized || error.status === 403;
      if (!(error instanceof Unauthorized)) {  // pollState asks for the token
        $('stats-why').hidden = false;
        $('stats-why').textContent = error.status === 403
          ? `The statistics need an ADMIN token, as GetStats does: ${error.message}`
          : `No statistics: ${error.message}`;
      }
      if (refused) {  // until another token is given
        this.statsPolling = false;
        return;
      }
    }
    setTimeout(() => this.pollStats(), STATS_PERIOD_MS);
  }

  showStats(stats, lateness, readAtS) {
    shown.statsPolls += 1;
    shown.latenessSamples = lateness?.samples ?? '0';
    const t = (performance.now() - this.started) / 1000;
    // The rate over the last poll (GetStats' own is the mean since start), timed by the server's
    // clock at each reading: the browser's time between polls also holds the network's and the
    // page's delays, which once showed a 1 kHz loop at 1.2-1.56 kHz.
    const ticks = Number(stats.ticks);
    const readAt = Number(readAtS ?? 0);
    const rate = this.lastStats && readAt > this.lastStats.readAt
      ? (ticks - this.lastStats.ticks) / (readAt - this.lastStats.readAt)
      : stats.achieved_rate_hz;
    this.lastStats = { ticks, readAt };
    shown.rateNowHz = rate;
    this.history.push([t, rate, stats.lateness_p99_us]);
    this.history = this.history.filter(([at]) => t - at <= HISTORY_S);
    $('window-s').textContent = String(stats.window_s ?? 10);
    $('loop-figures').textContent =
      `${ticks} ticks · ${rate.toFixed(1)} Hz now (${(stats.achieved_rate_hz ?? 0).toFixed(1)} mean) · ` +
      `lateness p50 ${stats.lateness_p50_us.toFixed(0)} / p99 ${stats.lateness_p99_us.toFixed(0)} / ` +
      `p99.9 ${stats.lateness_p999_us.toFixed(0)} / max ${stats.lateness_max_us.toFixed(0)} µs · ` +
      `overruns ${stats.overruns} · sessions ${stats.sessions} · ` +
      `force faults ${stats.force_faults} · saturations ${stats.force_saturations}`;
    drawHistogram($('lateness-plot'), lateness);
    drawSeries($('rate-plot'), [
      { name: 'rate', unit: 'Hz', color: '#7ddc7d', points: this.history.map(([at, r]) => [at, r]) },
      { name: 'p99', unit: 'µs', color: '#ffb347', points: this.history.map(([at, , p]) => [at, p]) },
    ], HISTORY_S);
    fillTable($('clients').tBodies[0], (stats.clients ?? []).map((c) => [
      sessionName(c.session_id), c.client_name, c.peer, String(c.device_index),
      c.decimation ? `${c.decimation}` : 'off', c.datagrams_sent, c.states_lost,
      c.last_heartbeat_age_s < 0 ? 'none' : `${(1000 * c.last_heartbeat_age_s).toFixed(0)} ms`,
      c.round_trip_samples > 0 ? `${c.round_trip_p50_us.toFixed(0)} / ${c.round_trip_p99_us.toFixed(0)}` : '–',
    ]));
  }
}

takeTokenFromUrl();
const viewer = new Viewer();
// Where object `id` is drawn (client pixels), for tests that drag it; null without WebGL.
window.hapticViewerScreenOf = (id) => viewer.view?.screenOf(id) ?? null;
viewer.start();
