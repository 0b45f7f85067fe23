// Playback of a planned path (scene.path from `rl view --path`): a time slider and a play
// button. The page interpolates q linearly between the path's samples and sends it as
// `set_q` with source "path"; the server's state moves the model like any other command.

/** q at time t on path {t: [...], q: [[...]]}, linear between samples, clamped at the ends. */
export function sample(path, t) {
  const ts = path.t;
  const n = ts.length;
  if (t <= ts[0]) return path.q[0].slice();
  if (t >= ts[n - 1]) return path.q[n - 1].slice();
  let lo = 0;
  let hi = n - 1;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (ts[mid] <= t) lo = mid; else hi = mid;
  }
  const s = (t - ts[lo]) / (ts[hi] - ts[lo] || 1);
  return path.q[lo].map((a, i) => a + s * (path.q[hi][i] - a));
}

export class PathPlayer {
  constructor(root, sendQ) {
    this.root = root;
    this.sendQ = sendQ;
    this.path = null;
    this.playing = false;
    this.t = 0;
    this.lastFrame = 0;
    this.lastSent = -1;
  }

  build(scene) {
    this.stop();
    const p = scene.path;
    this.root.replaceChildren();
    const ok = p && Array.isArray(p.t) && Array.isArray(p.q) && p.t.length > 0 && p.t.length === p.q.length;
    this.root.hidden = !ok;
    this.path = ok ? p : null;
    if (!ok) return;
    const h = document.createElement('h2');
    h.textContent = `Path (model ${p.model}, ${p.t.length} samples)`;
    const bar = document.createElement('div');
    bar.className = 'bar';
    this.button = document.createElement('button');
    this.button.textContent = '▶ play';
    this.button.onclick = () => (this.playing ? this.stop() : this.play());
    this.slider = document.createElement('input');
    this.slider.type = 'range';
    this.slider.min = String(p.t[0]);
    this.slider.max = String(p.t.at(-1));
    this.slider.step = 'any';
    this.slider.value = String(p.t[0]);
    this.slider.oninput = () => { this.stop(); this.seek(Number(this.slider.value)); };
    this.time = document.createElement('span');
    this.time.className = 'time';
    bar.append(this.button, this.slider, this.time);
    this.root.append(h, bar);
    const tm = p.timing;
    if (tm && tm.from === 'speed_limits') {
      const note = document.createElement('p');
      note.className = 'note';
      const assumed = (tm.assumed_for || []).length
        ? `; no limit for ${tm.assumed_for.join(', ')}: ${tm.assumed_speed} assumed`
        : '';
      note.textContent = `timed at the joints' speed limits (the file has no times)${assumed}`;
      this.root.append(note);
    }
    this.t = p.t[0];
    this.#show();
  }

  seek(t) {
    if (!this.path) return;
    this.t = t;
    this.sendQ(this.path.model, sample(this.path, t));
    this.#show();
  }

  play() {
    if (!this.path) return;
    if (this.t >= this.path.t.at(-1)) this.t = this.path.t[0];
    this.playing = true;
    this.button.textContent = '❚❚ pause';
    this.lastFrame = performance.now();
    const step = (now) => {
      if (!this.playing) return;
      this.t += (now - this.lastFrame) / 1000;
      this.lastFrame = now;
      const end = this.path.t.at(-1);
      if (this.t >= end) {
        this.seek(end);
        this.stop();
        return;
      }
      // At most one set_q every 20 ms: the server coalesces states to 15 ms anyway.
      if (now - this.lastSent >= 20) {
        this.lastSent = now;
        this.seek(this.t);
      }
      requestAnimationFrame(step);
    };
    requestAnimationFrame(step);
  }

  stop() {
    this.playing = false;
    if (this.button) this.button.textContent = '▶ play';
  }

  #show() {
    this.slider.value = String(this.t);
    this.time.textContent = `${this.t.toFixed(2)} / ${this.path.t.at(-1).toFixed(2)} s`;
  }
}
