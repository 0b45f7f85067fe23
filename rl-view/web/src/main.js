// rl view's page: wires the connection to the view, the panel and the test hooks.
//
// Every `hello` replaces the scene (models, environment, panel, path, plot); every `state`
// poses the bodies, colours collisions, draws the distance, updates panel, IK and plot.

import { Connection, socketUrl } from './connection.js';
import { View } from './scene.js';
import { ModelView } from './models.js';
import { EnvView } from './env.js';
import { JointPanel } from './panel.js';
import { IkTarget } from './ik.js';
import { DistanceView } from './distance.js';
import { PathPlayer } from './path.js';
import { LivePlot } from './plot.js';
import { StatusLine } from './status.js';
import { PlanView } from './plan.js';
import * as THREE from 'three';

const $ = (id) => document.getElementById(id);

const view = new View($('view'));
const status = new StatusLine($('status'));
let conn = null;
const send = (msg) => {
  const ok = conn.send(msg);
  if (!ok) status.setServerError('not connected: the command was not sent');
  return ok;
};
const sendQ = (model, q) => send({ type: 'set_q', model, q });
const panel = new JointPanel($('models'), sendQ);
const ik = new IkTarget(view, $('ik'), send);
const distance = new DistanceView(view, $('labels'));
const player = new PathPlayer($('path'), (model, q) => send({ type: 'set_q', model, q, source: 'path' }));
const plot = new LivePlot($('plot'), $('plot-caption'));
const plan = new PlanView(view);

let scene = null;
let state = null;
let models = [];
let env = null;
let framed = false;
let hellos = 0;

function meshTotals() {
  const t = { pending: 0, loaded: 0, failed: 0, errors: [] };
  for (const m of [...models, env].filter(Boolean)) {
    t.pending += m.meshes.pending;
    t.loaded += m.meshes.loaded;
    t.failed += m.meshes.failed;
    t.errors.push(...m.meshes.errors);
  }
  return t;
}

function changed(what) {
  status.setMeshes(meshTotals());
  // Point the camera once per page load, when every model is drawn at the state's poses.
  if (what.framed && !framed && state && models.length && models.every((m) => m.ready)) {
    framed = true;
    const box = new THREE.Box3();
    view.scene.updateMatrixWorld(true); // Box3 reads world matrices; poses changed since the last render
    for (const m of models) box.expandByObject(m.root);
    box.expandByObject(plan.root);
    if (env) box.expandByObject(env.root);
    view.frame(box);
  }
  if (state) ik.followTool();
  view.requestRender();
}

function onHello(msg) {
  for (const m of models) m.dispose();
  if (env) env.dispose();
  scene = msg.scene;
  hellos += 1;
  models = scene.models.map((d) => new ModelView(view, d, changed));
  env = new EnvView(view, scene.env, changed);
  panel.build(scene);
  ik.build(scene, models);
  player.build(scene);
  plan.build(scene);
  plot.build(scene);
  status.setServerError(null);
  if (msg.state) onState(msg.state);
  changed({});
}

function onState(msg) {
  state = msg;
  for (const sm of msg.models || []) {
    const mv = models.find((m) => m.desc.index === sm.index);
    if (mv && Array.isArray(sm.bodies)) mv.setPoses(sm.bodies);
    if (mv) mv.setShapePoses(sm.shapes);
  }
  const hits = new Map(models.map((m) => [m.desc.index, []]));
  for (const [mi, body] of msg.colliding || []) if (hits.has(mi)) hits.get(mi).push(body);
  for (const m of models) m.setColliding(hits.get(m.desc.index));
  distance.update(msg.distance);
  panel.update(msg);
  ik.update(msg);
  plot.push(msg);
  status.setState(msg);
  view.requestRender();
}

conn = new Connection(socketUrl(), {
  onStatus: (s) => {
    status.setConnection(s);
    plot.setLive(s.connected);
  },
  onMessage: (msg) => {
    switch (msg.type) {
      case 'hello': onHello(msg); break;
      case 'state': onState(msg); break;
      case 'error': status.setServerError(msg.message); break;
      case 'pong': break;
      default: console.warn('rl view: unknown message', msg.type);
    }
  },
});

// Test hooks (the browser test reads and drives the page through these).
window.rlView = {
  get connected() { return conn.connected; },
  get scene() { return scene; },
  get state() { return state; },
  get frames() { return view.frames; },
  /** [[model, body], ...] whose meshes currently carry the collision red. */
  redBodies() {
    return models.flatMap((m) => m.redBodies().map((b) => [m.desc.index, b]));
  },
  /** Moves a joint slider (value in rad or m) as a user would; returns the value sent. */
  setSlider(model, joint, value) { return panel.setSlider(model, joint, value); },
  /** Drags the IK target to [x,y,z,qx,qy,qz,qw]; resolves with the server's IK answer. */
  dragTarget(model, pose) { return ik.drag(model, pose); },
  /** The live plot's tracking-error strip: {shown, max} (max |q_cmd − q|, degrees or mm). */
  plotTracking() { return plot.trackingShown(); },
  /** What the plan shows: bodies per ghost (start, goal) and the trail's points. */
  planShown() { return plan.shown(); },
  /** Joint rows shown beyond their limits: [[model, joint, text], ...]. */
  beyondLimits() { return panel.beyondLimits(); },
  /** Meshes drawn per model, and mesh file loading counts. */
  meshCounts() { return models.map((m) => m.meshCount()); },
  meshLoading() { return meshTotals(); },
  /** The distance label as shown, or null when no distance is drawn. */
  distanceLabel() { return distance.label.hidden ? null : distance.text; },
  statusText() { return $('status').textContent; },
  /** How many `hello`s replaced the scene (1 + reconnects). */
  get hellos() { return hellos; },
  /** World position of a body as drawn (its three.js group), or null. */
  bodyPosition(model, name) {
    const m = models.find((x) => x.desc.index === model);
    const f = m && m.frameOf(name);
    return f ? new THREE.Vector3().setFromMatrixPosition(f).toArray() : null;
  },
  envMeshCount() { return env ? env.root.children.reduce((n, g) => n + (g.children.length ? 1 : 0), 0) : 0; },
  /** Screen rectangle (CSS px, page coordinates) of model `model` as drawn, or null. */
  screenBox(model) {
    const m = models.find((x) => x.desc.index === model);
    if (!m) return null;
    view.scene.updateMatrixWorld(true);
    const box = new THREE.Box3().expandByObject(m.root);
    if (box.isEmpty()) return null;
    const r = $('view').getBoundingClientRect();
    let x0 = Infinity; let y0 = Infinity; let x1 = -Infinity; let y1 = -Infinity;
    for (let i = 0; i < 8; i++) {
      const p = new THREE.Vector3(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z);
      const s = view.toScreen(p);
      if (!s) continue;
      x0 = Math.min(x0, s.x); y0 = Math.min(y0, s.y); x1 = Math.max(x1, s.x); y1 = Math.max(y1, s.y);
    }
    if (!Number.isFinite(x0)) return null;
    const cx = (v) => Math.min(r.width, Math.max(0, v));
    const bottom = r.height - $('status').getBoundingClientRect().height; // not the status line
    const cy = (v) => Math.min(bottom, Math.max(0, v));
    return { x: r.left + cx(x0), y: r.top + cy(y0), width: cx(x1) - cx(x0), height: cy(y1) - cy(y0) };
  },
};
