// A small live plot of one model's joint positions over the last 10 s of server time
// (state.t), in degrees or mm like the panel. When the state carries the commanded positions
// with the measured ones (`q_cmd`: a controller in the same process, `rl run --view`), a second
// strip below shows the tracking error q_cmd − q per joint, the difference the run's report is
// made of. Without q_cmd (Coach lines, sliders, IK, paths) only q is drawn, and the caption
// says why: the page does not plot a number it cannot know.

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
    this.unitLabel = units;
    this.tracking = null;
    this.#caption();
    this.#draw();
  }

  /** Whether the tracking-error strip is drawn, and the largest |q_cmd − q| it shows (in
   * the panel's units: degrees or mm) — for the browser test. */
  trackingShown() {
    return { shown: this.#hasError(), max: this.#errorMax() };
  }

  #hasError() {
    return this.samples.some((x) => x.e);
  }

  #errorMax() {
    let m = 0;
    for (const x of this.samples) if (x.e) for (const v of x.e) m = Math.max(m, Math.abs(v));
    return m;
  }

  #caption() {
    const tracking = this.#hasError();
    if (this.tracking === tracking && this.model) return;
    this.tracking = tracking;
    const head = this.model
      ? `${this.model.name}: joint positions q [${this.unitLabel}], last ${WINDOW_S} s of server time. `
      : '';
    this.caption.textContent = !this.model
      ? 'no model with joints'
      : tracking
        ? head + 'Below: tracking error q_cmd − q (commanded minus measured, from the controller).'
        : head + 'Tracking error is not shown: the state carries the displayed q, not a ' +
          'commanded/measured pair (a controller sends both with rl run --view).';
  }

  push(state) {
    if (!this.model || !Number.isFinite(state.t)) return;
    const m = (state.models || []).find((x) => x.index === this.model.index);
    if (!m || !Array.isArray(m.q)) return;
    const last = this.samples.at(-1);
    if (last && state.t < last.t) this.samples = []; // server restarted: its clock began again
    this.lastLocal = performance.now();
    const k = (i) => (this.units[i] ? this.units[i].k : 1);
    const e = Array.isArray(m.q_cmd) && m.q_cmd.length === m.q.length
      ? m.q_cmd.map((c, i) => (c - m.q[i]) * k(i))
      : null;
    this.samples.push({ t: state.t, q: m.q.map((v, i) => v * k(i)), e });
    while (this.samples.length > 2 && this.samples[1].t < state.t - WINDOW_S) this.samples.shift();
    this.#caption();
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
    const left = 34;
    const X = (t) => left + ((t - t0) / WINDOW_S) * (w - left - 4);
    const tracking = this.#hasError();
    // q on top; with q_cmd the tracking error below, 40 % of the height.
    const qBottom = tracking ? Math.round(h * 0.58) : h - 12;
    this.#strip(g, s, (x) => x.q, X, t0, t1, 4, qBottom, left, w, 1);
    if (tracking) {
      g.fillStyle = '#667';
      this.#strip(g, s, (x) => x.e, X, t0, t1, qBottom + 8, h - 12, left, w, 0.001);
      g.fillStyle = '#445';
      g.fillText(`q_cmd − q [${this.unitLabel}]`, left + 2, qBottom + 17);
    }
    g.fillStyle = '#667';
    g.fillText(`-${WINDOW_S} s`, left, h - 2);
    g.fillText('now', w - 24, h - 2);
    let x = left;
    this.model.joints.forEach((jt, j) => {
      g.fillStyle = COLORS[j % COLORS.length];
      const label = `q${j + 1}`;
      g.fillText(label, x, 12);
      x += g.measureText(label).width + 6;
    });
  }

  /** Draws one strip between y0 and y1: the series `pick(sample)` per joint, sample and hold
   * (states only come when something changed), with a three-line axis; `minSpan` is the
   * smallest value range shown. Samples without the series leave gaps. */
  #strip(g, s, pick, X, t0, t1, y0, y1, left, w, minSpan) {
    let lo = Infinity;
    let hi = -Infinity;
    for (const x of s) for (const v of pick(x) || []) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (!Number.isFinite(lo)) return;
    if (hi - lo < minSpan) { const mid = (hi + lo) / 2; lo = mid - minSpan / 2; hi = mid + minSpan / 2; }
    const pad = (hi - lo) * 0.08;
    lo -= pad;
    hi += pad;
    const Y = (v) => y0 + (1 - (v - lo) / (hi - lo)) * (y1 - y0);
    const span = hi - lo;
    const digits = span < 0.1 ? 3 : span < 10 ? 1 : 0;
    g.strokeStyle = '#d5dbe2';
    g.fillStyle = '#667';
    g.lineWidth = 1;
    for (const v of [lo + pad, (lo + hi) / 2, hi - pad]) {
      g.beginPath();
      g.moveTo(left, Y(v));
      g.lineTo(w - 4, Y(v));
      g.stroke();
      g.fillText((Math.abs(v) < span * 0.01 ? 0 : v).toFixed(digits), 2, Y(v) + 3);
    }
    const n = this.model.joints.length;
    for (let j = 0; j < n; j++) {
      g.strokeStyle = COLORS[j % COLORS.length];
      g.lineWidth = 1.5;
      g.beginPath();
      let prev = null;
      for (const x of s) {
        const v = pick(x);
        if (!v) { prev = null; continue; }
        const px = X(Math.max(t0, x.t));
        if (prev === null) g.moveTo(px, Y(v[j]));
        else {
          g.lineTo(px, Y(prev));
          g.lineTo(px, Y(v[j]));
        }
        prev = v[j];
      }
      // Hold the last value up to now.
      if (prev !== null && pick(s.at(-1))) g.lineTo(X(t1), Y(prev));
      g.stroke();
    }
  }
}
