// The joint panel: one slider and one number field per joint, within the joint's limits,
// in degrees (revolute, continuous) or millimetres (prismatic). Moving either sends the
// model's whole q as `set_q`; the server's state then moves the model (forward kinematics).

const DEG = 180 / Math.PI;

/** Display unit of a joint: factor from SI (rad, m), label, step. */
export function unitOf(joint) {
  if (joint.kind === 'prismatic' || joint.unit === 'm') return { k: 1000, label: 'mm', step: 0.1 };
  // A floating base's quaternion coordinates: plain numbers.
  if (joint.kind === 'quaternion') return { k: 1, label: '', step: 0.001 };
  return { k: DEG, label: '°', step: 0.1 };
}

/** Whether the joint has real limits (else the slider spans a default range). */
function limited(joint) {
  const lo = Number(joint.min);
  const hi = Number(joint.max);
  return joint.min !== null && joint.max !== null && Number.isFinite(lo) && Number.isFinite(hi) && hi > lo;
}

function limits(joint) {
  if (limited(joint)) return [Number(joint.min), Number(joint.max)];
  if (joint.kind === 'quaternion') return [-1, 1];
  if (joint.kind === 'prismatic' || joint.unit === 'm') return [-1, 1];
  return [-Math.PI, Math.PI];
}

/** Tolerance of the limit test: a value the server clamped to a limit is within it. */
const LIMIT_EPS = 1e-9;

export class JointPanel {
  /**
   * @param {HTMLElement} root container
   * @param {function} sendQ (model index, q array) => bool sent
   */
  constructor(root, sendQ) {
    this.root = root;
    this.sendQ = sendQ;
    this.models = [];
  }

  build(scene) {
    this.root.replaceChildren();
    this.models = scene.models.map((m) => {
      const box = document.createElement('div');
      box.className = 'model';
      const h = document.createElement('h2');
      h.textContent = `${m.name} `;
      const small = document.createElement('small');
      small.textContent = `model ${m.index}${m.urdf ? '' : ' · RL model'}`;
      h.appendChild(small);
      box.appendChild(h);
      if (Array.isArray(m.warnings) && m.warnings.length) {
        const w = document.createElement('details');
        w.className = 'warnings';
        const sum = document.createElement('summary');
        sum.textContent = `${m.warnings.length} warning${m.warnings.length === 1 ? '' : 's'} from loading`;
        const ul = document.createElement('ul');
        for (const text of m.warnings) {
          const li = document.createElement('li');
          li.textContent = text;
          ul.appendChild(li);
        }
        w.append(sum, ul);
        box.appendChild(w);
      }
      if (m.initial_source) {
        const init = document.createElement('div');
        init.className = 'initial';
        const from = m.initial_source.startsWith('srdf:')
          ? `the SRDF's state "${m.initial_source.slice(5)}"`
          : { start: 'the given start', home: "the model's home", neutral: 'zero (neutral)' }[m.initial_source] || m.initial_source;
        init.textContent = `starts at ${from}`;
        box.appendChild(init);
      }
      const source = document.createElement('div');
      source.className = 'source';
      box.appendChild(source);
      const entry = { desc: m, q: m.joints.map(() => 0), rows: [], source };
      m.joints.forEach((j, ji) => entry.rows.push(this.#row(box, entry, j, ji)));
      const zero = document.createElement('button');
      zero.textContent = 'zero';
      zero.title = 'all joints to 0 (clamped to the limits)';
      zero.onclick = () => {
        const q = m.joints.map((j) => { const [lo, hi] = limits(j); return Math.min(hi, Math.max(lo, 0)); });
        entry.q = q;
        this.sendQ(m.index, q.slice());
      };
      box.appendChild(zero);
      this.root.appendChild(box);
      return entry;
    });
  }

  #row(box, entry, joint, ji) {
    const u = unitOf(joint);
    const [lo, hi] = limits(joint);
    const row = document.createElement('label');
    row.className = 'joint';
    const name = document.createElement('span');
    name.className = 'name';
    name.textContent = joint.name;
    name.title = `${joint.name} (${joint.kind}) ${(lo * u.k).toFixed(1)} … ${(hi * u.k).toFixed(1)} ${u.label}`;
    const range = document.createElement('input');
    range.type = 'range';
    range.min = String(lo * u.k);
    range.max = String(hi * u.k);
    range.step = String(u.step);
    range.value = '0';
    const num = document.createElement('input');
    num.type = 'number';
    num.step = String(u.step);
    num.min = range.min;
    num.max = range.max;
    const unit = document.createElement('span');
    unit.className = 'unit';
    unit.textContent = u.label;
    row.append(name, range, num, unit);
    box.appendChild(row);
    const r = { joint, u, lo, hi, range, num, row, name, active: false, beyond: false, limited: limited(joint) };
    const send = (display) => {
      const v = Math.min(hi, Math.max(lo, Number(display) / u.k));
      if (!Number.isFinite(v)) return;
      entry.q[ji] = v;
      this.sendQ(entry.desc.index, entry.q.slice());
    };
    range.addEventListener('pointerdown', () => { r.active = true; });
    range.addEventListener('pointerup', () => { r.active = false; });
    range.addEventListener('change', () => { r.active = false; }); // released outside the slider
    range.addEventListener('input', () => {
      num.value = Number(range.value).toFixed(1);
      send(range.value);
    });
    num.addEventListener('focus', () => { r.active = true; });
    num.addEventListener('blur', () => { r.active = false; });
    num.addEventListener('change', () => {
      range.value = num.value;
      send(num.value);
    });
    return r;
  }

  /** Shows the state's q (rows the user is moving are left alone). */
  update(state) {
    for (const sm of state.models || []) {
      const entry = this.models.find((e) => e.desc.index === sm.index);
      if (!entry || !Array.isArray(sm.q)) continue;
      entry.q = sm.q.slice(0, entry.rows.length);
      entry.source.textContent = `source: ${sm.source || '?'}`;
      entry.rows.forEach((r, i) => {
        if (i >= sm.q.length) return;
        this.#markLimit(r, sm.q[i]);
        if (r.active) return;
        const d = sm.q[i] * r.u.k;
        r.range.value = String(d);
        r.num.value = d.toFixed(r.u.k === 1 ? 3 : 1);
      });
    }
  }

  /**
   * A value beyond the joint's limit (sent by Coach, a path or a run: the slider cannot show
   * it) is shown as such: the row turns red, the field keeps the true value and says which
   * limit it passes and by how much.
   */
  #markLimit(r, v) {
    const over = r.limited && (v > r.hi + LIMIT_EPS || v < r.lo - LIMIT_EPS);
    r.beyond = over;
    r.row.classList.toggle('beyond', over);
    if (over) {
      const [which, lim] = v > r.hi ? ['upper', r.hi] : ['lower', r.lo];
      const text = `${r.joint.name}: ${(v * r.u.k).toFixed(1)} ${r.u.label} is beyond its ${which} limit `
        + `${(lim * r.u.k).toFixed(1)} ${r.u.label} by ${(Math.abs(v - lim) * r.u.k).toFixed(1)} ${r.u.label}`;
      r.num.title = text;
      r.name.title = text;
      r.beyondText = text;
    } else {
      r.num.title = '';
      r.name.title = `${r.joint.name} (${r.joint.kind}) ${(r.lo * r.u.k).toFixed(1)} … ${(r.hi * r.u.k).toFixed(1)} ${r.u.label}`;
      r.beyondText = null;
    }
  }

  /** Test hook: [[model, joint, text], ...] of the rows shown beyond their limits. */
  beyondLimits() {
    return this.models.flatMap((e) => e.rows.flatMap((r, i) => (r.beyond ? [[e.desc.index, i, r.beyondText]] : [])));
  }

  /** Test hook: moves slider `joint` of model `model` to `value` (SI: rad or m), as a user would. */
  setSlider(model, joint, value) {
    const entry = this.models.find((e) => e.desc.index === model);
    if (!entry) throw new Error(`no model ${model}`);
    const r = entry.rows[joint];
    if (!r) throw new Error(`model ${model} has no joint ${joint}`);
    r.range.value = String(value * r.u.k);
    r.range.dispatchEvent(new Event('input', { bubbles: true }));
    return Number(r.range.value) / r.u.k;
  }
}
