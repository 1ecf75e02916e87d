// The scene drawn with three.js: every object as its shape, every field as wireframe and markers,
// each device port's workspace, tool, proxy and force arrow. World frame W, z up, metres.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

// The colour of each device port's tool and force (port 0 first).
export const TOOL_COLORS = [0xffd24f, 0x4fb3ff, 0xff6f91, 0x7ddc7d, 0xc58cff, 0xff9f4f, 0x4fffd2, 0xffffff];
const FORCE_SCALE_M_PER_N = 0.03;  // the force arrow's length per newton
const MAX_ARROW_M = 0.08;
const OBJECT_COLORS = {
  half_space: 0x5a6b85, sphere: 0x4fb3ff, box: 0xff9f4f, capsule: 0x7ddc7d,
  mesh: 0xc58cff, tangent_plane: 0xff6f91,
};
const FIELD_COLOR = 0x4fffd2;

/// A haptic.v1.Vec3 in protobuf's JSON (zero fields may be absent) as a THREE.Vector3.
export function vec(v) {
  return new THREE.Vector3(v?.x ?? 0, v?.y ?? 0, v?.z ?? 0);
}

/// A haptic.v1.Quaternion (w, x, y, z); unset or zero is the identity.
function quat(q) {
  if (!q) return new THREE.Quaternion();
  const out = new THREE.Quaternion(q.x ?? 0, q.y ?? 0, q.z ?? 0, q.w ?? 0);
  return out.lengthSq() > 0 ? out.normalize() : new THREE.Quaternion();
}

/// The oneof case set in `message` among `names`, or 'unknown'.
export function caseOf(message, names) {
  return names.find((name) => message[name] !== undefined) ?? 'unknown';
}
export const OBJECT_KINDS = ['half_space', 'sphere', 'box', 'capsule', 'mesh', 'tangent_plane'];
export const FIELD_KINDS = ['spring_to_point', 'spring', 'potential', 'linear', 'viscous', 'detent'];

/// Rotation taking +z to `normal` (the planes' geometry faces +z).
function facing(normal) {
  const n = normal.lengthSq() > 0 ? normal.clone().normalize() : new THREE.Vector3(0, 0, 1);
  return new THREE.Quaternion().setFromUnitVectors(new THREE.Vector3(0, 0, 1), n);
}

function solid(color, opacity = 0.55) {
  return new THREE.MeshStandardMaterial({
    color, transparent: opacity < 1, opacity, roughness: 0.6, metalness: 0.05, side: THREE.DoubleSide,
    depthWrite: opacity >= 1,
  });
}

function wire(color, opacity = 0.6) {
  return new THREE.LineBasicMaterial({ color, transparent: true, opacity });
}

function wireSphere(radius, color) {
  return new THREE.LineSegments(new THREE.WireframeGeometry(new THREE.SphereGeometry(radius, 16, 10)),
                                wire(color, 0.35));
}

function marker(color, size = 0.004) {
  return new THREE.Mesh(new THREE.OctahedronGeometry(size), new THREE.MeshBasicMaterial({ color }));
}

function line(from, to, color, opacity = 0.6) {
  return new THREE.Line(new THREE.BufferGeometry().setFromPoints([from, to]), wire(color, opacity));
}

export class SceneView {
  /// Draws into `canvas`; throws when the browser has no WebGL.
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x14171c);
    this.camera = new THREE.PerspectiveCamera(45, 1, 0.001, 10);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(0.22, -0.28, 0.18);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.target.set(0, 0, 0);
    this.controls.update();
    // Drawn only when something changed (a software renderer spends tens of ms a frame).
    this.dirty = true;
    this.controls.addEventListener('change', () => { this.dirty = true; });
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x30343c, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.4);
    sun.position.set(0.3, -0.2, 0.6);
    this.scene.add(sun);
    this.scene.add(new THREE.AxesHelper(0.03));
    this.items = new THREE.Group();      // objects and fields, remade with each scene
    this.workspace = new THREE.Group();  // each port's box, remade when the devices change
    this.scene.add(this.items, this.workspace);
    this.tools = [];                     // per device port: {sphere, proxy, arrow}
    this.movable = new Map();            // object id -> its mesh, for the virtual masses
    this.springs = [];                   // spring_to_point anchors: a line to port 0's tool each frame
    this.extent = 0.1;                   // half the workspace's largest side, for the walls' size
    this.dragging = false;               // an object is being dragged (enableDragging)
    this.resize();
    window.addEventListener('resize', () => this.resize());
  }

  resize() {
    const { clientWidth: width, clientHeight: height } = this.canvas;
    if (width === 0 || height === 0) return;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    this.dirty = true;
  }

  /// Each port's workspace box and a tool for each; the view frames port 0's workspace.
  setDevices(devices) {
    this.dirty = true;
    this.workspace.clear();
    for (const tool of this.tools) this.scene.remove(tool.group);
    this.tools = [];
    devices.forEach((device, port) => {
      const box = new THREE.Box3(vec(device.workspace_min), vec(device.workspace_max));
      this.workspace.add(new THREE.Box3Helper(box, new THREE.Color(0x3a4350)));
      if (port === 0) {
        const size = box.getSize(new THREE.Vector3());
        this.extent = Math.max(size.x, size.y, size.z) / 2;
        const grid = new THREE.GridHelper(size.x, 10, 0x2d333d, 0x22272f);
        grid.rotation.x = Math.PI / 2;
        grid.position.set(box.getCenter(new THREE.Vector3()).x, box.getCenter(new THREE.Vector3()).y, box.min.z);
        this.workspace.add(grid);
        this.controls.target.copy(box.getCenter(new THREE.Vector3()));
        this.camera.position.copy(this.controls.target).add(new THREE.Vector3(1.1, -1.4, 0.9).multiplyScalar(this.extent * 2));
        this.controls.update();
      }
      const color = TOOL_COLORS[port % TOOL_COLORS.length];
      const group = new THREE.Group();
      const sphere = new THREE.Mesh(new THREE.SphereGeometry(0.004, 20, 14), new THREE.MeshStandardMaterial({ color, emissive: color, emissiveIntensity: 0.35 }));
      const proxy = new THREE.Mesh(new THREE.SphereGeometry(0.0045, 12, 8), new THREE.MeshBasicMaterial({ color, wireframe: true }));
      const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.001, color, 0.008, 0.005);
      group.add(sphere, proxy, arrow);
      this.scene.add(group);
      this.tools.push({ group, sphere, proxy, arrow });
    });
  }

  /// Replaces the drawn items with `contents` (a haptic.v1.SceneContents).
  setScene(contents) {
    this.dirty = true;
    // The GPU's copies go with the items: geometries, and materials (one or several per mesh).
    this.items.traverse((node) => {
      node.geometry?.dispose();
      for (const material of [node.material ?? []].flat()) material.dispose();
    });
    this.items.clear();
    this.movable.clear();
    this.springs = [];
    const objects = contents?.scene?.objects ?? [];
    objects.forEach((object, i) => {
      const drawn = this.objectNode(object);
      drawn.userData.id = contents.object_ids[i];
      this.items.add(drawn);
      if (object.dynamics && (object.dynamics.mass ?? 0) > 0) this.movable.set(contents.object_ids[i], drawn);
    });
    for (const field of contents?.scene?.fields ?? []) this.items.add(this.fieldNode(field));
  }

  objectNode(object) {
    const kind = caseOf(object, OBJECT_KINDS);
    const color = OBJECT_COLORS[kind] ?? 0xaaaaaa;
    const group = new THREE.Group();
    group.position.copy(vec(object.pose?.position));
    group.quaternion.copy(quat(object.pose?.orientation));
    switch (kind) {
      case 'half_space': {
        // A large translucent square on the surface, and the outward normal.
        const size = this.extent * 3;
        const normal = vec(object.half_space.normal);
        const plane = new THREE.Mesh(new THREE.PlaneGeometry(size, size), solid(color, 0.22));
        plane.quaternion.copy(facing(normal));
        const edges = new THREE.LineSegments(new THREE.EdgesGeometry(plane.geometry), wire(color, 0.7));
        edges.quaternion.copy(plane.quaternion);
        group.add(plane, edges, new THREE.ArrowHelper(normal.clone().normalize(), new THREE.Vector3(), 0.02, color));
        break;
      }
      case 'sphere':
        group.add(new THREE.Mesh(new THREE.SphereGeometry(object.sphere.radius, 32, 20), solid(color)));
        break;
      case 'box': {
        const h = vec(object.box.half_extents);
        group.add(new THREE.Mesh(new THREE.BoxGeometry(2 * h.x, 2 * h.y, 2 * h.z), solid(color)));
        break;
      }
      case 'capsule': {
        // three's capsule lies along y; hapticd's along the object's z.
        const geometry = new THREE.CapsuleGeometry(object.capsule.radius, 2 * (object.capsule.half_length ?? 0), 8, 20);
        geometry.rotateX(Math.PI / 2);
        group.add(new THREE.Mesh(geometry, solid(color)));
        break;
      }
      case 'mesh': {
        const geometry = new THREE.BufferGeometry();
        geometry.setAttribute('position', new THREE.Float32BufferAttribute(
          (object.mesh.vertices ?? []).flatMap((v) => [v.x ?? 0, v.y ?? 0, v.z ?? 0]), 3));
        geometry.setIndex(object.mesh.indices ?? []);
        geometry.computeVertexNormals();
        group.add(new THREE.Mesh(geometry, solid(color, 0.7)),
                  new THREE.LineSegments(new THREE.EdgesGeometry(geometry), wire(color, 0.9)));
        break;
      }
      case 'tangent_plane': {
        const normal = vec(object.tangent_plane.normal);
        const size = 0.04;
        const plane = new THREE.Mesh(new THREE.PlaneGeometry(size, size), solid(color, 0.35));
        plane.quaternion.copy(facing(normal));
        const reference = marker(color, 0.003);
        reference.position.copy(vec(object.tangent_plane.reference));
        group.add(plane, reference, new THREE.ArrowHelper(normal.clone().normalize(), new THREE.Vector3(), 0.015, color));
        break;
      }
      default:
        break;
    }
    return group;
  }

  /// A distance's zero set: a point, a line, a plane or a sphere.
  distanceNode(distance, color) {
    const origin = vec(distance?.origin);
    const axis = vec(distance?.axis ?? { z: 1 });
    const direction = axis.lengthSq() > 0 ? axis.clone().normalize() : new THREE.Vector3(0, 0, 1);
    switch (distance?.kind ?? 'POINT') {
      case 'LINE':
        return line(origin.clone().addScaledVector(direction, -this.extent * 1.5),
                    origin.clone().addScaledVector(direction, this.extent * 1.5), color);
      case 'PLANE': {
        const grid = new THREE.GridHelper(this.extent * 2, 8, color, color);
        grid.material.transparent = true;
        grid.material.opacity = 0.35;
        grid.quaternion.copy(facing(direction)).multiply(new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(1, 0, 0), Math.PI / 2));
        grid.position.copy(origin);
        return grid;
      }
      case 'SPHERE': {
        const sphere = wireSphere(distance.radius ?? 0, color);
        sphere.position.copy(origin);
        return sphere;
      }
      default: {
        const point = marker(color);
        point.position.copy(origin);
        return point;
      }
    }
  }

  fieldNode(field) {
    const kind = caseOf(field, FIELD_KINDS);
    const group = new THREE.Group();
    const around = (center, radius) => {
      if (!(radius > 0)) return;
      const sphere = wireSphere(radius, FIELD_COLOR);
      sphere.position.copy(center);
      group.add(sphere);
    };
    switch (kind) {
      case 'spring_to_point': {
        const anchor = marker(FIELD_COLOR);
        anchor.position.copy(vec(field.spring_to_point.anchor));
        const tie = line(anchor.position, anchor.position, FIELD_COLOR, 0.8);
        this.springs.push({ anchor: anchor.position.clone(), tie });
        group.add(anchor, tie);
        break;
      }
      case 'spring':
        group.add(this.distanceNode(field.spring.anchor, FIELD_COLOR));
        break;
      case 'potential': {
        const p = field.potential;
        group.add(this.distanceNode(p.distance, FIELD_COLOR));
        if ((p.distance?.kind ?? 'POINT') === 'POINT') {
          around(vec(p.distance?.origin), p.kind === 'KHATIB' ? p.influence_distance : p.offset);
        }
        break;
      }
      case 'linear': {
        const l = field.linear;
        around(vec(l.origin), l.radius);
        const f = vec(l.force);
        if (f.lengthSq() > 0) {
          group.add(new THREE.ArrowHelper(f.clone().normalize(), vec(l.origin),
                                          Math.min(MAX_ARROW_M, f.length() * FORCE_SCALE_M_PER_N), FIELD_COLOR));
        }
        break;
      }
      case 'viscous':
        around(vec(field.viscous.center), field.viscous.radius);  // radius 0: everywhere, nothing to draw
        break;
      case 'detent': {
        const d = field.detent;
        group.add(this.distanceNode(d.distance, FIELD_COLOR));
        if ((d.distance?.kind ?? 'POINT') === 'POINT') around(vec(d.distance?.origin), d.radius);
        break;
      }
      default:
        break;
    }
    return group;
  }

  /// Moves the tools and the virtual masses to `state` (a haptic.v1.ViewerState).
  setState(state) {
    this.dirty = true;
    (state.tools ?? []).forEach((tool, port) => {
      const drawn = this.tools[port];
      if (!drawn) return;
      const p = vec(tool.position);
      drawn.sphere.position.copy(p);
      drawn.proxy.position.copy(vec(tool.proxy));
      drawn.proxy.visible = (tool.contact_count ?? 0) > 0;
      const force = vec(tool.force);
      const length = Math.min(MAX_ARROW_M, force.length() * FORCE_SCALE_M_PER_N);
      drawn.arrow.visible = length > 1e-4;
      if (drawn.arrow.visible) {
        drawn.arrow.position.copy(p);
        drawn.arrow.setDirection(force.clone().normalize());
        drawn.arrow.setLength(length, Math.min(0.008, length * 0.4), Math.min(0.005, length * 0.25));
      }
      if (port === 0) {
        for (const spring of this.springs) {
          spring.tie.geometry.setFromPoints([spring.anchor, p]);
        }
      }
    });
    for (const object of state.objects ?? []) {
      this.movable.get(object.id)?.position.copy(vec(object.position));
    }
  }

  /// Shift-drag moves an object for which canDrag(id) holds, in the plane through it that faces the
  /// camera: onMove(id, position, done) with its new pose position (THREE.Vector3, m, in W) at each
  /// step and done at the end. The orbit controls do not see such a drag. `dragging` is true
  /// while one is under way.
  enableDragging(canDrag, onMove) {
    const raycaster = new THREE.Raycaster();
    const ray = (event) => {
      const rect = this.canvas.getBoundingClientRect();
      raycaster.setFromCamera(new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
                                                -((event.clientY - rect.top) / rect.height) * 2 + 1), this.camera);
      return raycaster.ray;
    };
    let drag = null;
    const end = (event) => {
      if (!drag || event.pointerId !== drag.pointerId) return;
      const { id, node } = drag;
      drag = null;
      this.dragging = false;
      this.controls.enabled = true;
      onMove(id, node.position.clone(), true);
    };
    // Capturing, on the canvas: before the orbit controls' own listeners there.
    this.canvas.addEventListener('pointerdown', (event) => {
      if (!event.shiftKey || event.button !== 0) return;
      ray(event);
      for (const hit of raycaster.intersectObjects(this.items.children, true)) {
        let node = hit.object;
        while (node && node.userData.id === undefined) node = node.parent;
        if (!node || !canDrag(node.userData.id)) continue;
        const facingCamera = this.camera.getWorldDirection(new THREE.Vector3());
        drag = { id: node.userData.id, node, pointerId: event.pointerId,
                 plane: new THREE.Plane().setFromNormalAndCoplanarPoint(facingCamera, hit.point),
                 offset: node.position.clone().sub(hit.point) };
        this.dragging = true;
        this.controls.enabled = false;
        this.canvas.setPointerCapture(event.pointerId);
        event.stopImmediatePropagation();
        event.preventDefault();
        return;
      }
    }, { capture: true });
    this.canvas.addEventListener('pointermove', (event) => {
      if (!drag || event.pointerId !== drag.pointerId) return;
      const point = ray(event).intersectPlane(drag.plane, new THREE.Vector3());
      if (!point) return;
      drag.node.position.copy(point.add(drag.offset));
      this.dirty = true;
      event.stopImmediatePropagation();
      onMove(drag.id, drag.node.position.clone(), false);
    }, { capture: true });
    this.canvas.addEventListener('pointerup', end, { capture: true });
    this.canvas.addEventListener('pointercancel', end, { capture: true });
  }

  /// Where object `id`'s origin is drawn on the page (client pixels), or null.
  screenOf(id) {
    const node = this.items.children.find((child) => child.userData.id === id);
    if (!node) return null;
    const p = node.getWorldPosition(new THREE.Vector3()).project(this.camera);
    const rect = this.canvas.getBoundingClientRect();
    return { x: rect.left + ((p.x + 1) / 2) * rect.width, y: rect.top + ((1 - p.y) / 2) * rect.height };
  }

  /// Draws the scene if anything changed since the last time; returns whether it drew.
  render() {
    if (!this.dirty) return false;
    this.dirty = false;
    this.renderer.render(this.scene, this.camera);
    return true;
  }
}
