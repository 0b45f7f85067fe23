// The IK target: a TransformControls gizmo at the tool. Dragging it sends `ik` with the
// target pose; the server answers with a state whose `ik` says ok or why not, shown here.
// While nobody drags, the target follows the tool frame (drawn as axes) of the state.

import * as THREE from 'three';
import { TransformControls } from 'three/examples/jsm/controls/TransformControls.js';

const SEND_EVERY_MS = 40;

function poseOf(obj) {
  const p = obj.position;
  const q = obj.quaternion;
  return [p.x, p.y, p.z, q.x, q.y, q.z, q.w];
}

export class IkTarget {
  constructor(view, root, send) {
    this.view = view;
    this.root = root;
    this.send = send;
    this.models = [];
    this.model = null; // index into this.models
    this.dragging = false;
    this.held = false; // the target stays where it was dragged until the robot moves otherwise
    this.lastSent = 0;
    this.waiters = [];
    this.lastIk = null; // JSON of the last IK answer seen, to tell a new answer from it

    this.target = new THREE.Group();
    this.target.name = 'ik target';
    const ball = new THREE.Mesh(
      new THREE.SphereGeometry(0.018, 20, 12),
      new THREE.MeshStandardMaterial({ color: 0x1e88e5, transparent: true, opacity: 0.6 }),
    );
    this.target.add(ball);
    view.scene.add(this.target);

    this.toolAxes = new THREE.AxesHelper(0.12);
    this.toolAxes.name = 'tool frame';
    this.toolAxes.material.depthTest = false;
    this.toolAxes.renderOrder = 2;
    view.scene.add(this.toolAxes);

    this.gizmo = new TransformControls(view.camera, view.renderer.domElement);
    this.gizmo.setSize(0.8);
    this.gizmo.attach(this.target);
    view.scene.add(this.gizmo.getHelper());
    this.gizmo.addEventListener('change', () => view.requestRender());
    this.gizmo.addEventListener('dragging-changed', (e) => {
      this.dragging = e.value;
      if (e.value) this.held = true;
      view.controls.enabled = !e.value;
      if (!e.value) this.#sendTarget(true);
    });
    this.gizmo.addEventListener('objectChange', () => { if (this.dragging) this.#sendTarget(false); });
    window.addEventListener('keydown', (e) => {
      if (e.target instanceof HTMLInputElement) return;
      if (e.key === 't') this.setMode('translate');
      if (e.key === 'r') this.setMode('rotate');
    });

    this.status = document.createElement('div');
    this.status.className = 'ik-status';
    this.status.textContent = 'IK: drag the blue target at the tool';
  }

  build(scene, modelViews) {
    this.models = modelViews;
    this.lastQ = null;
    this.model = modelViews.findIndex((m) => m.desc.joints.length > 0 && m.desc.tool);
    this.root.replaceChildren();
    const h = document.createElement('h2');
    h.textContent = 'Tool target (IK)';
    this.root.appendChild(h);
    const bar = document.createElement('div');
    bar.className = 'bar';
    if (modelViews.length > 1) {
      const sel = document.createElement('select');
      modelViews.forEach((m, i) => {
        const o = document.createElement('option');
        o.value = String(i);
        o.textContent = `${m.desc.name} (${m.desc.tool})`;
        sel.appendChild(o);
      });
      sel.value = String(this.model);
      sel.onchange = () => { this.model = Number(sel.value); this.followTool(); };
      bar.appendChild(sel);
    }
    for (const [mode, label] of [['translate', 'move (t)'], ['rotate', 'turn (r)']]) {
      const b = document.createElement('button');
      b.textContent = label;
      b.onclick = () => this.setMode(mode);
      bar.appendChild(b);
    }
    const reset = document.createElement('button');
    reset.textContent = 'to tool';
    reset.title = 'put the target back on the tool frame';
    reset.onclick = () => { this.held = false; this.followTool(); };
    bar.appendChild(reset);
    this.root.appendChild(bar);
    this.root.appendChild(this.status);
    this.target.visible = this.model >= 0;
    this.gizmo.enabled = this.model >= 0;
    this.gizmo.getHelper().visible = this.model >= 0;
    this.toolAxes.visible = this.model >= 0;
  }

  setMode(mode) {
    this.gizmo.setMode(mode);
    this.view.requestRender();
  }

  /** Moves the target and the tool axes onto the tool frame of the current state. */
  followTool() {
    const mv = this.models[this.model];
    if (!mv) return;
    // The tool's frame where the page knows it (a URDF link or body of that name), else the
    // body the tool is attached to.
    const m = (mv.desc.tool && mv.frameOf(mv.desc.tool))
      || (mv.desc.tool_body && mv.frameOf(mv.desc.tool_body))
      || (mv.bodies.length ? mv.frameOf(mv.desc.bodies.at(-1).name) : null);
    if (!m) return;
    m.decompose(this.toolAxes.position, this.toolAxes.quaternion, new THREE.Vector3());
    if (!this.dragging && !this.held) {
      this.target.position.copy(this.toolAxes.position);
      this.target.quaternion.copy(this.toolAxes.quaternion);
    }
    this.view.requestRender();
  }

  update(state) {
    const mine = (state.models || []).find((m) => this.models[this.model] && m.index === this.models[this.model].desc.index);
    // A motion not made by IK (Coach, sliders, path) gives the target back to the tool.
    if (mine && Array.isArray(mine.q)) {
      const moved = !this.lastQ || mine.q.some((v, i) => v !== this.lastQ[i]);
      if (moved && mine.source !== 'ik' && !this.dragging) this.held = false;
      this.lastQ = mine.q.slice();
    }
    this.followTool();
    const ik = state.ik;
    if (ik) {
      if (ik.ok) {
        const err = Number.isFinite(ik.position_error) ? ` · error ${ik.position_error.toExponential(1)} m` : '';
        const it = Number.isFinite(ik.iterations) ? ` · ${ik.iterations} iterations` : '';
        this.status.textContent = `IK ok${err}${it}`;
        this.status.className = 'ik-status ok';
      } else {
        this.status.textContent = `IK failed: ${ik.reason || 'no reason given'}`;
        this.status.className = 'ik-status fail';
      }
      // The state keeps the last IK answer: a state sent before the server saw the request
      // still carries the previous one. A different answer is the reply; the same answer is
      // taken only if nothing different follows within 1.5 s (the same request twice).
      const text = JSON.stringify(ik);
      this.lastIk = text;
      for (const w of this.waiters) {
        if (text !== w.before) w.done(ik);
        else w.same = ik;
      }
    }
  }

  #sendTarget(force) {
    const now = performance.now();
    if (!force && now - this.lastSent < SEND_EVERY_MS) return;
    const mv = this.models[this.model];
    if (!mv) return;
    this.lastSent = now;
    this.send({ type: 'ik', model: mv.desc.index, target: poseOf(this.target) });
  }

  /** Test hook: drags the target of model `model` to `pose` and resolves with the IK answer. */
  drag(model, pose, timeoutMs = 10000) {
    const i = this.models.findIndex((m) => m.desc.index === model);
    if (i < 0) return Promise.reject(new Error(`no model ${model}`));
    this.model = i;
    this.held = true;
    this.target.position.set(pose[0], pose[1], pose[2]);
    this.target.quaternion.set(pose[3], pose[4], pose[5], pose[6]).normalize();
    this.view.requestRender();
    return new Promise((resolve, reject) => {
      const timers = [];
      const w = { before: this.lastIk, same: null };
      const finish = () => {
        this.waiters = this.waiters.filter((x) => x !== w);
        timers.forEach(clearTimeout);
      };
      w.done = (ik) => { finish(); resolve(ik); };
      this.waiters.push(w);
      timers.push(setTimeout(() => { if (w.same) w.done(w.same); }, 1500));
      timers.push(setTimeout(() => { finish(); reject(new Error('no IK answer within the timeout')); }, timeoutMs));
      this.#sendTarget(true);
    });
  }
}
