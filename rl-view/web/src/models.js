// One robot model in the view: its bodies posed from the state, drawn from its URDF (with
// urdf-loader, meshes from the server's /files/) or, for RL models, from the scene's shapes.
// Colliding bodies get a red material; the original comes back when they no longer collide.
//
// Every body of the scene JSON is a flat group whose world pose is set from `state.bodies`
// (the server's kinematics, including Coach body overrides). A URDF link that is not one of
// those bodies (a link merged by a fixed joint) is attached to the nearest ancestor that is,
// with its fixed offset from the URDF at load.

import * as THREE from 'three';
import URDFLoader from 'urdf-loader';
import { buildShape, loadMesh, meshFormat, meshesOf } from './shapes.js';
import { setPose } from './scene.js';

const RED = new THREE.MeshStandardMaterial({ color: 0xe0302a, emissive: 0x3a0000, roughness: 0.6 });
// Body colours far from the collision red, so red means colliding and nothing else.
const BODY_COLORS = [0x4f86c6, 0xb4bbc4];

/** True if the material is drawn in the collision red (what redBodies() reads back). */
export function isRed(material) {
  const c = material && material.color;
  if (!c) return false;
  const srgb = c.clone().convertLinearToSRGB();
  return srgb.r > 0.7 && srgb.g < 0.35 && srgb.b < 0.35;
}

export class ModelView {
  /**
   * @param {View} view
   * @param {object} desc one entry of scene.models
   * @param {function} changed called when meshes arrive or fail (status and re-render)
   */
  constructor(view, desc, changed) {
    this.view = view;
    this.desc = desc;
    this.changed = changed;
    this.root = new THREE.Group();
    this.root.name = `model ${desc.index} ${desc.name}`;
    view.scene.add(this.root);
    this.bodies = desc.bodies.map((b) => {
      const g = new THREE.Group();
      g.name = b.name;
      this.root.add(g);
      return g;
    });
    this.byName = new Map(desc.bodies.map((b, i) => [b.name, this.bodies[i]]));
    this.shapes = desc.bodies.map(() => []); // per body: the shape holders, in scene order
    this.shapeOverrides = new Map(); // "b/s" -> holder moved by a Coach shape command
    this.links = new Map(); // URDF link name -> {anchor: body group, rel: Matrix4}
    this.meshes = { pending: 0, loaded: 0, failed: 0, errors: [] };
    this.colliding = new Set();
    this.ready = false;
    // Everything loaded: reported from a task of its own, so never before the constructor
    // has returned (shape models finish synchronously).
    this.manager = new THREE.LoadingManager(() => setTimeout(() => {
      this.ready = true;
      this.#update();
      this.changed({ framed: true });
    }, 0));
    if (desc.urdf) {
      this.#loadUrdf();
    } else {
      this.#buildShapes();
    }
  }

  dispose() {
    this.view.scene.remove(this.root);
    this.root.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
    });
  }

  /** World poses of the bodies, in scene order (state.models[i].bodies). */
  setPoses(poses) {
    const n = Math.min(poses.length, this.bodies.length);
    for (let i = 0; i < n; i++) setPose(this.bodies[i], poses[i]);
  }

  /**
   * Shape poses set by Coach `1` commands: [[body, shape, pose7], ...] (state.models[i].shapes).
   * A shape that no longer has an override goes back to its pose from the scene.
   */
  setShapePoses(list) {
    const now = new Map();
    for (const [b, s, pose] of list || []) {
      const h = this.shapes[b] && this.shapes[b][s];
      if (!h || !Array.isArray(pose)) continue;
      if (!h.userData.rlHome) h.userData.rlHome = { p: h.position.clone(), q: h.quaternion.clone() };
      setPose(h, pose);
      now.set(`${b}/${s}`, h);
    }
    for (const [k, h] of this.shapeOverrides) {
      if (!now.has(k)) {
        h.position.copy(h.userData.rlHome.p);
        h.quaternion.copy(h.userData.rlHome.q);
      }
    }
    this.shapeOverrides = now;
  }

  /** World pose (Matrix4) of body or URDF link `name`, from the current body poses; or null. */
  frameOf(name) {
    const g = this.byName.get(name);
    if (g) {
      g.updateMatrixWorld(true);
      return g.matrixWorld.clone();
    }
    const link = this.links.get(name);
    if (!link) return null;
    link.anchor.updateMatrixWorld(true);
    return link.anchor.matrixWorld.clone().multiply(link.rel);
  }

  /** Marks the named bodies as colliding (red) and restores all others. */
  setColliding(names) {
    this.colliding = new Set(names);
    this.#recolor();
  }

  /** Names of bodies drawn with the collision red, read from their meshes' materials. */
  redBodies() {
    const out = [];
    this.desc.bodies.forEach((b, i) => {
      const red = meshesOf(this.bodies[i]).some((m) =>
        (Array.isArray(m.material) ? m.material : [m.material]).some(isRed));
      if (red) out.push(b.name);
    });
    return out;
  }

  meshCount() {
    return meshesOf(this.root).length;
  }

  #recolor() {
    this.desc.bodies.forEach((b, i) => {
      const hit = this.colliding.has(b.name);
      for (const m of meshesOf(this.bodies[i])) {
        if (hit && m.userData.rlMaterial === undefined) {
          m.userData.rlMaterial = m.material;
          m.material = RED;
        } else if (!hit && m.userData.rlMaterial !== undefined) {
          m.material = m.userData.rlMaterial;
          delete m.userData.rlMaterial;
        }
      }
    });
  }

  #update() {
    this.#recolor();
    this.changed({});
  }

  #meshDone(url, err) {
    this.meshes.pending -= 1;
    if (err) {
      this.meshes.failed += 1;
      this.meshes.errors.push(`${url}: ${err.message || err}`);
      console.error(`rl view: mesh ${url} did not load:`, err);
    } else {
      this.meshes.loaded += 1;
    }
    this.#update();
  }

  #buildShapes() {
    this.manager.itemStart('shapes');
    this.desc.bodies.forEach((b, i) => {
      const material = new THREE.MeshStandardMaterial({
        color: BODY_COLORS[i % BODY_COLORS.length], roughness: 0.55, metalness: 0.1,
      });
      for (const shape of b.shapes || []) {
        if (shape.kind === 'mesh') this.meshes.pending += 1;
        const h = buildShape(shape, material, this.manager, (err) => this.#meshDone(shape.url, err));
        this.shapes[i].push(h);
        this.bodies[i].add(h);
      }
    });
    this.manager.itemEnd('shapes');
  }

  async #loadUrdf() {
    const url = new URL(this.desc.urdf, window.location.href);
    this.manager.itemStart(url.href);
    try {
      const res = await fetch(url);
      if (!res.ok) throw new Error(`GET ${url.pathname}: HTTP ${res.status}`);
      const text = await res.text();
      const loader = new URDFLoader(this.manager);
      // Mesh file names are resolved against the URDF's own URL here (the server rewrites
      // them to /files/... paths), not by urdf-loader's string concatenation.
      loader.loadMeshCb = (path, manager, material, done) => {
        const meshUrl = new URL(path, url).href;
        this.meshes.pending += 1;
        loadMesh(meshUrl, meshFormat(meshUrl), manager, material, (obj, err) => {
          done(obj, err);
          this.#meshDone(meshUrl, err);
        });
      };
      const robot = loader.parse(text, '');
      this.#flatten(robot);
    } catch (err) {
      this.meshes.failed += 1;
      this.meshes.errors.push(`${url.pathname}: ${err.message || err}`);
      console.error('rl view: URDF did not load:', err);
      this.changed({});
    } finally {
      this.manager.itemEnd(url.href);
    }
  }

  /** Moves every link's visuals into the flat body group it belongs to (see the file head). */
  #flatten(robot) {
    robot.updateMatrixWorld(true);
    const inv = new THREE.Matrix4();
    const visit = (link, anchorLink) => {
      let anchor = anchorLink;
      if (this.byName.has(link.name)) anchor = link;
      let target;
      let rel;
      if (anchor) {
        rel = inv.copy(anchor.matrixWorld).invert().multiply(link.matrixWorld).clone();
        target = this.byName.get(anchor.name);
      } else {
        rel = link.matrixWorld.clone();
        target = this.root;
      }
      this.links.set(link.name, { anchor: target, rel });
      const visuals = link.children.filter((c) => c.isURDFVisual);
      if (visuals.length) {
        const holder = new THREE.Group();
        holder.name = `${link.name} visuals`;
        rel.decompose(holder.position, holder.quaternion, holder.scale);
        for (const v of visuals) holder.add(v);
        target.add(holder);
        const bi = this.bodies.indexOf(target);
        if (bi >= 0) this.shapes[bi].push(...visuals);
      }
      for (const j of link.children.filter((c) => c.isURDFJoint)) {
        for (const child of j.children.filter((c) => c.isURDFLink)) visit(child, anchor);
      }
    };
    visit(robot, null);
    // Bodies the server draws but whose URDF link has no <visual> (it stands in the collision
    // geometry where a link has no visual): drawn from the scene's shapes.
    const material = new THREE.MeshStandardMaterial({ color: 0x9aa1aa, roughness: 0.6 });
    this.desc.bodies.forEach((b, i) => {
      if (this.shapes[i].length || !(b.shapes || []).length) return;
      for (const shape of b.shapes) {
        if (shape.kind === 'mesh') this.meshes.pending += 1;
        const h = buildShape(shape, material, this.manager, (err) => this.#meshDone(shape.url, err));
        this.shapes[i].push(h);
        this.bodies[i].add(h);
      }
    });
    this.#update();
  }
}
