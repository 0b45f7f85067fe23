// A small live plot of one model's joint positions over the last 10 s of server time
// (state.t), in degrees or mm like the panel. The state carries the displayed q only (and
// qd when a client sends it), not a commanded/measured pair, so no tracking error is drawn:
// the caption says so rather than plotting a number the page cannot know.

import { unitOf } from './panel.js';

const WINDOW_S = 10;
const COLORS = ['#e53935', '#43a047', '#1e88e5', '#fb8c00', '#8e24aa', '#00897b', '#6d4c41', '#3949ab'];

export class LivePlot {
  constructor(canvas, caption) {
    this.canvas = canvas;
    this.caption = caption;
    this.samples = [];
    this.model = null;
    this.dirty = false;
    this.lastDraw = 0;
    this.lastLocal = 0;
    this.live = false;
    // Scroll with time between states (they only come when something changed).
    setInterval(() => { if (this.live && this.samples.length) this.#draw(); }, 250);
  }

  /** Whether the connection is up: a plot without a server stops scrolling. */
  setLive(live) {
    this.live = live;
  }

  build(scene) {
    this.samples = [];
    this.model = scene.models.find((m) => m.joints.length > 0) || null;
    this.units = this.model ? this.model.joints.map(unitOf) : [];
    const units = [...new Set(this.units.map((u) => u.label))].join(', ');
    this.caption.textContent = this.model
      ? `${this.model.name}: joint positions q [${units}], last ${WINDOW_S} s of server time. ` +
        'Tracking error is not shown: the state carries the displayed q, not a commanded/measured pair.'
      : 'no model with joints';
    this.#draw();
  }

  push(state) {
    if (!this.model || !Number.isFinite(state.t)) return;
    const m = (state.models || []).find((x) => x.index === this.model.index);
    if (!m || !Array.isArray(m.q)) return;
    const last = this.samples.at(-1);
    if (last && state.t < last.t) this.samples = []; // server restarted: its clock began again
    this.lastLocal = performance.now();
    this.samples.push({ t: state.t, q: m.q.map((v, i) => v * (this.units[i] ? this.units[i].k : 1)) });
    while (this.samples.length > 2 && this.samples[1].t < state.t - WINDOW_S) this.samples.shift();
    const now = performance.now();
    if (now - this.lastDraw > 100) this.#draw();
    else if (!this.dirty) {
      this.dirty = true;
      setTimeout(() => this.#draw(), 110);
    }
  }

  #draw() {
    this.dirty = false;
    this.lastDraw = performance.now();
    const c = this.canvas;
    const dpr = window.devicePixelRatio || 1;
    const w = c.clientWidth;
    const h = c.clientHeight;
    if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    const g = c.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    g.font = '10px system-ui, sans-serif';
    const s = this.samples;
    if (!this.model || s.length === 0) {
      g.fillStyle = '#889';
      g.fillText('waiting for states…', 8, h / 2);
      return;
    }
    const t1 = s.at(-1).t + (this.live ? (performance.now() - this.lastLocal) / 1000 : 0);
    const t0 = t1 - WINDOW_S;
    let lo = Infinity;
    let hi = -Infinity;
    for (const x of s) for (const v of x.q) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (hi - lo < 1) { lo -= 0.5; hi += 0.5; }
    const pad = (hi - lo) * 0.08;
    lo -= pad;
    hi += pad;
    const left = 34;
    const X = (t) => left + ((t - t0) / WINDOW_S) * (w - left - 4);
    const Y = (v) => 4 + (1 - (v - lo) / (hi - lo)) * (h - 16);
    g.strokeStyle = '#d5dbe2';
    g.fillStyle = '#667';
    g.lineWidth = 1;
    for (const v of [lo + pad, (lo + hi) / 2, hi - pad]) {
      g.beginPath();
      g.moveTo(left, Y(v));
      g.lineTo(w - 4, Y(v));
      g.stroke();
      g.fillText((Math.abs(v) < 0.05 ? 0 : v).toFixed(hi - lo < 10 ? 1 : 0), 2, Y(v) + 3);
    }
    g.fillText(`-${WINDOW_S} s`, left, h - 2);
    g.fillText('now', w - 24, h - 2);
    const n = s[0].q.length;
    for (let j = 0; j < n; j++) {
      g.strokeStyle = COLORS[j % COLORS.length];
      g.lineWidth = 1.5;
      g.beginPath();
      // Sample and hold: a state's q holds until the next state (Coach lines are steps).
      s.forEach((x, i) => {
        const px = X(Math.max(t0, x.t));
        const py = Y(x.q[j]);
        if (i === 0) g.moveTo(px, py);
        else {
          g.lineTo(px, Y(s[i - 1].q[j]));
          g.lineTo(px, py);
        }
      });
      // Hold the last value up to now (states only come when something changed).
      g.lineTo(X(t1), Y(s.at(-1).q[j]));
      g.stroke();
    }
    let x = left;
    this.model.joints.forEach((jt, j) => {
      g.fillStyle = COLORS[j % COLORS.length];
      const label = `q${j + 1}`;
      g.fillText(label, x, 12);
      x += g.measureText(label).width + 6;
    });
  }
}
