// The status line: connection (connected / reconnecting), the Coach listener's counters,
// mesh loading, a controller run (running; ended, and how), and the last error the server
// reported for a page message.

export class StatusLine {
  constructor(el) {
    this.el = el;
    this.conn = { connected: false, attempt: 0 };
    this.coach = null;
    this.seq = null;
    this.meshes = null;
    this.run = null;
    this.serverError = null;
    this.render();
  }

  setConnection(s) { this.conn = s; this.render(); }

  setState(state) {
    this.coach = state.coach || null;
    this.run = state.run || null;
    this.seq = state.seq;
    this.render();
  }

  setMeshes(m) { this.meshes = m; this.render(); }

  setServerError(message) { this.serverError = message; this.render(); }

  render() {
    const parts = [];
    const c = this.conn;
    if (c.connected) {
      parts.push(['conn ok', '● connected']);
    } else if (c.attempt > 0) {
      const wait = c.retryInMs !== undefined ? `, next try in ${(c.retryInMs / 1000).toFixed(1)} s` : '';
      parts.push(['conn bad', `○ reconnecting (attempt ${c.attempt}${wait})${c.error ? `: ${c.error}` : ''}`]);
    } else {
      parts.push(['conn', '○ connecting…']);
    }
    if (this.coach) {
      const k = this.coach;
      const n = (v, one, many) => `${v} ${v === 1 ? one : many}`;
      parts.push(['coach', `coach: ${n(k.clients, 'client', 'clients')}, ${n(k.lines, 'line', 'lines')}, ${k.rejected} rejected`]);
      if (k.last_error) parts.push(['err', `coach error: ${k.last_error}`]);
    }
    if (this.meshes && (this.meshes.loaded || this.meshes.failed || this.meshes.pending)) {
      const m = this.meshes;
      const pend = m.pending > 0 ? `, ${m.pending} loading` : '';
      parts.push([m.failed ? 'err' : '', `meshes: ${m.loaded} loaded${pend}${m.failed ? `, ${m.failed} failed` : ''}`]);
    }
    if (this.run) {
      const r = this.run;
      const head = r.ended ? 'run ended' : 'run';
      parts.push([r.ok ? 'ok' : 'bad', `${head}: ${r.summary}`]);
    }
    if (this.seq !== null && this.seq !== undefined) parts.push(['', `state #${this.seq}`]);
    if (this.serverError) parts.push(['err', `server: ${this.serverError}`]);
    this.el.replaceChildren(...parts.map(([cls, text]) => {
      const s = document.createElement('span');
      if (cls) s.className = cls;
      s.textContent = text;
      return s;
    }));
    if (this.meshes && this.meshes.errors.length) this.el.title = this.meshes.errors.join('\n');
  }
}
