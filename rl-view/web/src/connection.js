// The WebSocket to the server's /ws: JSON messages both ways, reconnect with backoff.
//
// A `hello` (sent by the server on every connect) replaces the whole scene; `state` messages
// follow. After a close the page retries after 250 ms, doubling up to 5 s, with a little
// jitter so several tabs do not retry in step. A connection that hears nothing for 15 s
// (the page pings every 5 s) is closed and retried: a silent server counts as gone.

const FIRST_DELAY_MS = 250;
const MAX_DELAY_MS = 5000;
const PING_MS = 5000;
const SILENT_MS = 15000;

export class Connection {
  /**
   * @param {string} url ws:// or wss:// address of the server's /ws
   * @param {object} handlers onMessage(msg), onStatus({connected, attempt, retryInMs, error})
   */
  constructor(url, handlers) {
    this.url = url;
    this.handlers = handlers;
    this.ws = null;
    this.connected = false;
    this.attempt = 0;
    this.lastHeard = 0;
    this.received = 0;
    this.badMessages = 0;
    this.retryTimer = null;
    this.pingTimer = setInterval(() => this.#keepAlive(), PING_MS);
    this.#open();
  }

  /** Sends one message; false when the socket is not open (the caller shows it). */
  send(msg) {
    if (!this.ws || this.ws.readyState !== WebSocket.OPEN) return false;
    this.ws.send(JSON.stringify(msg));
    return true;
  }

  #open() {
    this.retryTimer = null;
    let ws;
    try {
      ws = new WebSocket(this.url);
    } catch (e) {
      this.#retry(String(e));
      return;
    }
    this.ws = ws;
    ws.onopen = () => {
      this.connected = true;
      this.attempt = 0;
      this.lastHeard = performance.now();
      this.handlers.onStatus({ connected: true, attempt: 0 });
    };
    ws.onmessage = (ev) => {
      this.lastHeard = performance.now();
      this.received += 1;
      let msg;
      try {
        msg = JSON.parse(ev.data);
      } catch (e) {
        this.badMessages += 1;
        console.error('rl view: message is not JSON', e);
        return;
      }
      this.handlers.onMessage(msg);
    };
    ws.onclose = (ev) => {
      if (this.ws !== ws) return;
      this.ws = null;
      this.connected = false;
      this.#retry(ev.reason || `closed (code ${ev.code})`);
    };
    // onerror is always followed by onclose, which schedules the retry.
    ws.onerror = () => {};
  }

  #retry(error) {
    if (this.retryTimer !== null) return;
    const base = Math.min(MAX_DELAY_MS, FIRST_DELAY_MS * 2 ** this.attempt);
    const delay = Math.round(base * (0.8 + 0.4 * Math.random()));
    this.attempt += 1;
    this.handlers.onStatus({ connected: false, attempt: this.attempt, retryInMs: delay, error });
    this.retryTimer = setTimeout(() => this.#open(), delay);
  }

  #keepAlive() {
    if (!this.connected || !this.ws) return;
    if (performance.now() - this.lastHeard > SILENT_MS) {
      const ws = this.ws;
      this.ws = null;
      this.connected = false;
      ws.close();
      this.#retry('server silent for 15 s');
      return;
    }
    this.send({ type: 'ping' });
  }
}

/** The /ws address of the server that served this page. */
export function socketUrl(loc = window.location) {
  const scheme = loc.protocol === 'https:' ? 'wss:' : 'ws:';
  return `${scheme}//${loc.host}/ws`;
}
