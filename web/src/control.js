// The viewer's control (optional; docs/viewer.md, "Moving objects"): given the address of the
// server's HTTP face, the page opens a session of its own there with the tab's token and moves
// objects by UpdateObject, each with its pose's position changed and the rest as its client gave it.
// The server decides, as for any client: UpdateObject needs a CONTROLLER token (on a server with
// tokens), and another session's object (the server's own included) may be moved only when it is
// shared. The viewer's own endpoints (/api/*) stay read-only; the HTTP face must list the viewer's
// origin in http_allowed_origins.
import { HapticClient, HapticError } from './hapticd.js';

export class Control {
  constructor() {
    /** @type {HapticClient|null} */
    this.client = null;
    this.api = null;
    this.token = null;
    this.objects = new Map();  // object id -> {object (scene.proto's Object, JSON), session}
    this.moves = 0;            // UpdateObject calls the server accepted
    this.pending = null;       // the newest position asked for while a move is under way
    this.inFlight = null;
  }

  /**
   * Opens a session on the HTTP face at `api` (closing any other first).
   * @param {string} api 'http://127.0.0.1:8081'
   * @param {string|null} token The bearer token, if any (the tab's, as for /api/*).
   */
  async connect(api, token) {
    await this.disconnect();
    this.api = api;
    this.token = token;
    this.client = await HapticClient.open(api, { token: token || undefined, clientName: 'viewer' });
    return this.client;
  }

  async disconnect() {
    const client = this.client;
    this.client = null;
    await client?.close().catch(() => {});
  }

  /** The scene as /api/scene gave it: which objects there are, whose, and as given. */
  setScene(contents) {
    const objects = contents?.scene?.objects ?? [];
    this.objects = new Map(objects.map((object, i) => [contents.object_ids[i],
      { object, session: contents.object_sessions[i] }]));
  }

  /** Whether the server lets this page's session move object `id`: its own, or a shared one. */
  movable(id) {
    const item = this.objects.get(id);
    return Boolean(this.client && item && (item.object.shared || item.session === this.client.sessionId));
  }

  /** The ids movable() allows, in the scene's order. */
  movableIds() {
    return [...this.objects.keys()].filter((id) => this.movable(id));
  }

  /**
   * Moves object `id` to `position` (its pose's position, in W; Unit: m). While one move is under
   * way, a newer one waits and replaces any that waited before it (a drag sends its newest only).
   * Resolves once the server took it; throws HapticError as the server refused it.
   * @param {string} id
   * @param {{x: number, y: number, z: number}} position
   */
  async move(id, position) {
    this.pending = { id, position };
    while (this.inFlight) await this.inFlight.catch(() => {});
    if (!this.pending) return;  // a later call sent it
    const next = this.pending;
    this.pending = null;
    this.inFlight = this.send(next.id, next.position);
    try {
      await this.inFlight;
    } finally {
      this.inFlight = null;
    }
  }

  async send(id, position) {
    const item = this.objects.get(id);
    if (!item) throw new HapticError('not_found', `object ${id} is no longer in the scene`);
    if (!this.client) throw new HapticError('failed_precondition', 'not connected to the HTTP API');
    const moved = { ...item.object, pose: { ...(item.object.pose ?? {}), position } };
    try {
      await this.client.updateObject(id, moved);
    } catch (error) {
      // A session that lapsed (a hidden tab's timers throttled past its lease): open another, once.
      if (!(error instanceof HapticError && error.code === 'not_found' && /^session_id/.test(error.message))) throw error;
      await this.connect(this.api, this.token);
      await this.client.updateObject(id, moved);
    }
    item.object = moved;
    this.moves += 1;
  }
}
