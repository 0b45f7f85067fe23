// The page of `rl view` in a real browser: playwright-core drives Debian's headless Chromium
// (WebGL on SwiftShader) against the real `rl view` server, and a Coach client sends joint
// commands over TCP as RL's controllers do. Run by tests/view_browser.rs:
//
//   node rl-view/web/test/browser.mjs --rl target/release/rl [--out DIR] [--chromium PATH]
//
// What it checks (each step prints what it measured):
//   1. ur5 (URDF with STL meshes) loads: connected, frames drawn, every mesh loaded.
//   2. Coach `2 0 q1..q6` moves the model: the page's state reports q (to 1e-4), the drawn
//      bodies sit at the state's poses, and a screenshot of the robot region differs from the
//      one before by more than a threshold measured from two screenshots with no change.
//   3. A slider change moves the model (source "ui"), by the same screenshot measure.
//   4. The IK target dragged to a reachable pose (the tool pose at a known q) gives IK ok and
//      the tool there; a pose out of reach gives a failure with its reason in the panel.
//   5. The server restarts on the same address: the page shows it is reconnecting, then
//      reconnects by itself and shows the new server's current state.
//   6. With an obstacle at the tool (a MoveIt scene written here), the colliding bodies are
//      drawn red (read from the three.js materials) and restored when the arm moves away; the
//      distance line's label shows the state's distance.
//   7. An RL XML model (no meshes) is drawn from its bodies' shapes and follows Coach too.
//   8. The default robot (the RV-6SL with RL's visual VRML meshes): every inline mesh counts
//      as loaded (nothing left "loading"); a Coach value beyond a joint's limit is shown as
//      such; a Coach error is shown, and cleared by the next good line.
//   9. An RL scenario (`rl view SCENARIO.xml --path PLAN.csv`, the path from `rl plan`): the
//      robot at the scenario's start, start and goal ghosts and the tool's trail, shown before
//      and while the path plays; the path's times from the joints' speed limits.
//  10. `rl run --view`: live q and q_cmd, the tracking error plotted, and after the run the
//      page says it has ended and how.
// Screenshots go to --out (default <repo>/target/view-screenshots). Exit 0 when all pass.

import { chromium } from 'playwright-core';
import { spawn } from 'node:child_process';
import net from 'node:net';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const repo = path.resolve(here, '..', '..', '..');

function arg(name, fallback) {
  const i = process.argv.indexOf(name);
  return i >= 0 && i + 1 < process.argv.length ? process.argv[i + 1] : fallback;
}
const rlBin = arg('--rl', null);
const outDir = path.resolve(arg('--out', path.join(repo, 'target', 'view-screenshots')));
const chromiumPath = arg('--chromium', '/usr/bin/chromium');
if (!rlBin) {
  console.error('usage: browser.mjs --rl PATH_TO_RL [--out DIR] [--chromium PATH]');
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const data = (p) => path.join(repo, 'tests', 'data', p);

const WAIT_MS = 30000;
const TOTAL_MS = 360000;
const servers = new Set();
let browser = null;
let passed = 0;

const watchdog = setTimeout(() => {
  console.error(`browser test: still running after ${TOTAL_MS / 1000} s, giving up`);
  cleanup().finally(() => process.exit(1));
}, TOTAL_MS);

async function cleanup() {
  for (const s of servers) s.kill();
  if (browser) await browser.close().catch(() => {});
}

function ok(what) {
  passed += 1;
  console.log(`ok ${passed} - ${what}`);
}

function check(cond, what) {
  if (!cond) throw new Error(`check failed: ${what}`);
}

// ---- the server ------------------------------------------------------------------------

/** `rl view ARGS...`; resolves when it has printed its page and Coach addresses. */
function startServer(args) {
  return new Promise((resolve, reject) => {
    const child = spawn(rlBin, ['view', ...args], { cwd: repo, stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let done = false;
    const server = {
      child,
      http: null,
      coach: null,
      output: () => out,
      /** SIGTERM (rl view shuts down), SIGKILL if it is still there after 5 s. */
      kill() {
        servers.delete(server);
        if (child.exitCode !== null || child.signalCode !== null) return;
        child.kill('SIGTERM');
        const t = setTimeout(() => child.kill('SIGKILL'), 5000);
        child.once('exit', () => clearTimeout(t));
      },
      exited: new Promise((r) => child.once('exit', r)),
    };
    servers.add(server);
    const timer = setTimeout(() => {
      if (!done) { done = true; server.kill(); reject(new Error(`rl view printed no addresses in ${WAIT_MS} ms:\n${out}`)); }
    }, WAIT_MS);
    const scan = (chunk) => {
      out += chunk;
      const http = /(http:\/\/[0-9.]+:\d+)/.exec(out);
      // `rl view: open http://HOST:PORT/` and `rl view: Coach listening on HOST:PORT`.
      const coach = /coach(?: listening on|:)\s*([0-9]+\.[0-9]+\.[0-9]+\.[0-9]+):(\d+)/i.exec(out);
      if (!done && http && coach) {
        done = true;
        clearTimeout(timer);
        server.http = http[1];
        server.coach = { host: coach[1], port: Number(coach[2]) };
        resolve(server);
      }
    };
    child.stdout.on('data', (d) => scan(d.toString()));
    child.stderr.on('data', (d) => scan(d.toString()));
    child.once('exit', (code, sig) => {
      if (!done) { done = true; clearTimeout(timer); reject(new Error(`rl view exited (${code ?? sig}):\n${out}`)); }
    });
  });
}

/** `rl run ARGS... --view 127.0.0.1:0 --view-hold`: a controller with the viewer in its
 * process; resolves when it has printed the page's address. */
function startRun(args) {
  return new Promise((resolve, reject) => {
    const child = spawn(rlBin, ['run', ...args, '--view', '127.0.0.1:0', '--view-hold'],
      { cwd: repo, stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let done = false;
    const server = {
      child,
      http: null,
      output: () => out,
      kill() {
        servers.delete(server);
        if (child.exitCode !== null || child.signalCode !== null) return;
        child.kill('SIGTERM');
        const t = setTimeout(() => child.kill('SIGKILL'), 5000);
        child.once('exit', () => clearTimeout(t));
      },
      exited: new Promise((r) => child.once('exit', r)),
    };
    servers.add(server);
    const timer = setTimeout(() => {
      if (!done) { done = true; server.kill(); reject(new Error(`rl run printed no view address in ${WAIT_MS} ms:\n${out}`)); }
    }, WAIT_MS);
    const scan = (chunk) => {
      out += chunk;
      const http = /view: open (http:\/\/[0-9.]+:\d+)/.exec(out);
      if (!done && http) {
        done = true;
        clearTimeout(timer);
        server.http = http[1];
        resolve(server);
      }
    };
    child.stdout.on('data', (d) => scan(d.toString()));
    child.stderr.on('data', (d) => scan(d.toString()));
    child.once('exit', (code, sig) => {
      if (!done) { done = true; clearTimeout(timer); reject(new Error(`rl run exited (${code ?? sig}):\n${out}`)); }
    });
  });
}

/** A Coach client (RL's protocol: ASCII lines over TCP). */
function coachClient(addr) {
  return new Promise((resolve, reject) => {
    const sock = net.connect(addr.port, addr.host);
    sock.setNoDelay(true);
    sock.once('error', reject);
    sock.once('connect', () => resolve({
      joints(model, q) { sock.write(`2 ${model} ${q.map((v) => v.toPrecision(9)).join(' ')}\n`); },
      raw(line) { sock.write(line); },
      close() { sock.destroy(); },
    }));
  });
}

// ---- the page --------------------------------------------------------------------------

async function openPage(url) {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  page.on('pageerror', (e) => console.log(`page error: ${e.message}`));
  page.on('console', (m) => {
    // Refused connections while the server restarts are expected; everything else is shown.
    if (m.type() === 'error' && !/ERR_CONNECTION_REFUSED/.test(m.text())) console.log(`page console: ${m.text()}`);
  });
  await page.goto(url);
  await page.waitForFunction(() => window.rlView && rlView.connected && rlView.scene && rlView.state
    && rlView.frames > 0 && rlView.meshLoading().pending === 0, null, { timeout: WAIT_MS });
  await settle(page);
  return page;
}

/** Waits until the page has drawn at least two more frames (the last change is on screen). */
async function settle(page) {
  const f0 = await page.evaluate(() => rlView.frames);
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  // Render-on-demand: nudge a render so a frame exists after every state applied so far.
  await page.waitForFunction((f) => rlView.frames >= f, f0, { timeout: WAIT_MS });
  await page.waitForTimeout(150);
}

/** Waits until state.models[model].q equals q to 1e-4; returns the state. */
async function waitQ(page, model, q, source) {
  await page.waitForFunction(([m, want, src]) => {
    const s = rlView.state && rlView.state.models.find((x) => x.index === m);
    return !!s && s.q.length === want.length && s.q.every((v, i) => Math.abs(v - want[i]) <= 1e-4)
      && (!src || s.source === src);
  }, [model, q, source], { timeout: WAIT_MS });
  await settle(page);
  return page.evaluate(() => rlView.state);
}

/** PNG screenshot of `rect` (page CSS px). */
function shot(page, rect, file) {
  return page.screenshot({ clip: rect, path: file ? path.join(outDir, file) : undefined });
}

/**
 * Fraction of the pixels inside `rect` (page CSS px; whole images when null) whose colour
 * differs by more than 24/255 in some channel between two full-page PNG screenshots.
 */
async function changedFraction(page, a, b, rect = null) {
  return page.evaluate(async ([a64, b64, r]) => {
    const load = async (b64x) => {
      const blob = await (await fetch(`data:image/png;base64,${b64x}`)).blob();
      const bmp = await createImageBitmap(blob);
      const c = new OffscreenCanvas(bmp.width, bmp.height);
      const g = c.getContext('2d');
      g.drawImage(bmp, 0, 0);
      return g.getImageData(0, 0, bmp.width, bmp.height);
    };
    const [x, y] = [await load(a64), await load(b64)];
    if (x.width !== y.width || x.height !== y.height) return 1;
    const k = x.width / window.innerWidth; // device pixels per CSS pixel
    const x0 = r ? Math.floor(r.x * k) : 0;
    const y0 = r ? Math.floor(r.y * k) : 0;
    const x1 = r ? Math.min(x.width, Math.ceil((r.x + r.width) * k)) : x.width;
    const y1 = r ? Math.min(x.height, Math.ceil((r.y + r.height) * k)) : x.height;
    let n = 0;
    for (let row = y0; row < y1; row++) {
      for (let col = x0; col < x1; col++) {
        const i = 4 * (row * x.width + col);
        if (Math.abs(x.data[i] - y.data[i]) > 24 || Math.abs(x.data[i + 1] - y.data[i + 1]) > 24
          || Math.abs(x.data[i + 2] - y.data[i + 2]) > 24) n += 1;
      }
    }
    return n / Math.max(1, (x1 - x0) * (y1 - y0));
  }, [a.toString('base64'), b.toString('base64'), rect]);
}

/** Union of two rectangles (either may be null), rounded out to whole pixels. */
function union(r, s) {
  const rs = [r, s].filter(Boolean);
  const x0 = Math.floor(Math.min(...rs.map((t) => t.x)));
  const y0 = Math.floor(Math.min(...rs.map((t) => t.y)));
  const x1 = Math.ceil(Math.max(...rs.map((t) => t.x + t.width)));
  const y1 = Math.ceil(Math.max(...rs.map((t) => t.y + t.height)));
  return { x: x0, y: y0, width: Math.max(1, x1 - x0), height: Math.max(1, y1 - y0) };
}

/**
 * Runs `act` (which changes what the page shows) and measures how much of the robot's screen
 * region changed: the union of the robot's screen box before and after, compared between
 * full-page screenshots before and after. The "after" crop is saved as `file`.
 */
async function measureChange(page, act, file) {
  const before = await page.evaluate(() => rlView.screenBox(0));
  const a = await page.screenshot();
  await act();
  const after = await page.evaluate(() => rlView.screenBox(0));
  const rect = union(before, after);
  const b = await page.screenshot();
  await shot(page, rect, file);
  return { rect, fraction: await changedFraction(page, a, b, rect) };
}

const threshold = { noise: null, value: null };

function angleBetween(q1, q2) {
  const d = Math.abs(q1[0] * q2[0] + q1[1] * q2[1] + q1[2] * q2[2] + q1[3] * q2[3]);
  return 2 * Math.acos(Math.min(1, d));
}

function dist3(a, b) {
  return Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

async function checkDrawnAtState(page, model, what) {
  const r = await page.evaluate((m) => {
    const s = rlView.state.models.find((x) => x.index === m);
    const sc = rlView.scene.models.find((x) => x.index === m);
    let worst = 0;
    sc.bodies.forEach((b, i) => {
      const p = rlView.bodyPosition(m, b.name);
      const w = s.bodies[i];
      worst = Math.max(worst, Math.hypot(p[0] - w[0], p[1] - w[1], p[2] - w[2]));
    });
    return { worst, n: sc.bodies.length };
  }, model);
  check(r.worst < 1e-6, `${what}: drawn bodies at the state's poses (worst ${r.worst} m)`);
  return r;
}

// ---- the steps -------------------------------------------------------------------------

const Q1 = [0.4, -1.2, 1.5, -0.9, -1.4, 0.3];
const Q2 = [-0.3, -1.6, 1.2, -1.1, -1.6, 0.5];
const Q3 = [1.0, -0.8, 0.9, -1.6, 0.7, -0.4];

async function ur5Steps() {
  const urdf = data('mbm/ur5/ur5.urdf');
  let server = await startServer([urdf, '--http', '127.0.0.1:0', '--coach', '127.0.0.1:0']);
  console.log(`# rl view ${path.relative(repo, urdf)}: page ${server.http}/, coach ${server.coach.host}:${server.coach.port}`);
  const page = await openPage(`${server.http}/`);
  const info = await page.evaluate(() => ({
    joints: rlView.scene.models[0].joints.length, meshes: rlView.meshCounts(), loading: rlView.meshLoading(),
    frames: rlView.frames, tool: rlView.scene.models[0].tool, toolBody: rlView.scene.models[0].tool_body,
  }));
  check(info.joints === 6, `ur5 has 6 joints (got ${info.joints})`);
  check(info.meshes[0] > 0 && info.loading.failed === 0, `meshes drawn, none failed (${JSON.stringify(info.loading)})`);
  await page.screenshot({ path: path.join(outDir, '01-ur5-loaded.png') });
  ok(`ur5 page loads: ${info.meshes[0]} meshes drawn, ${info.loading.loaded} mesh files loaded, 0 failed, ${info.frames} frames`);

  // The noise floor: two screenshots of the robot region with nothing changed in between.
  const box0 = union(await page.evaluate(() => rlView.screenBox(0)), null);
  const n1 = await page.screenshot();
  await page.waitForTimeout(400);
  await settle(page);
  const n2 = await page.screenshot();
  threshold.noise = await changedFraction(page, n1, n2, box0);
  threshold.value = Math.max(0.02, 10 * threshold.noise);
  ok(`noise floor: ${(100 * threshold.noise).toFixed(3)} % of ${box0.width}x${box0.height} px changed with no change; threshold ${(100 * threshold.value).toFixed(1)} %`);

  // Coach joint commands move the model.
  const coach = await coachClient(server.coach);
  const m1 = await measureChange(page, async () => { coach.joints(0, Q1); await waitQ(page, 0, Q1, 'coach'); }, '02-coach-q1.png');
  const f1 = m1.fraction;
  await checkDrawnAtState(page, 0, 'after Coach');
  check(f1 > threshold.value, `Coach move changed ${(100 * f1).toFixed(1)} % of the robot region (> ${(100 * threshold.value).toFixed(1)} %)`);
  const coachStatus = await page.evaluate(() => rlView.statusText());
  check(/coach: 1 client/.test(coachStatus), `status line shows the Coach client (${coachStatus})`);
  ok(`Coach "2 0 ${Q1.join(' ')}": state q equal to 1e-4, bodies drawn at the state's poses, ${(100 * f1).toFixed(1)} % of the ${m1.rect.width}x${m1.rect.height} px robot region changed`);

  // A second tab shows the same state and follows the first tab's slider below.
  const page2 = await openPage(`${server.http}/`);
  const q2 = await page2.evaluate(() => rlView.state.models[0].q);
  check(q2.every((v, i) => Math.abs(v - Q1[i]) <= 1e-4), `a second tab opens at the current q (${q2})`);
  ok('a second tab opens showing the current state');

  // A slider moves the model.
  let sent = null;
  const m2 = await measureChange(page, async () => {
    sent = await page.evaluate(() => rlView.setSlider(0, 0, -0.6));
    const want = Q1.slice();
    want[0] = sent;
    await waitQ(page, 0, want, 'ui');
  }, '03-slider.png');
  const f2 = m2.fraction;
  check(f2 > threshold.value, `slider move changed ${(100 * f2).toFixed(1)} % (> ${(100 * threshold.value).toFixed(1)} %)`);
  await checkDrawnAtState(page, 0, 'after the slider');
  ok(`slider joint 1 to ${sent.toFixed(4)} rad: state q follows (source ui), ${(100 * f2).toFixed(1)} % of the robot region changed`);
  const want2 = Q1.slice();
  want2[0] = sent;
  await waitQ(page2, 0, want2, 'ui');
  await checkDrawnAtState(page2, 0, 'second tab');
  await page2.close();
  ok('the second tab follows the first tab\'s slider');

  // IK: the tool pose at Q2 is reachable; drag the target there from Q1.
  const toolName = info.tool;
  const toolIndex = await page.evaluate((t) => {
    const b = rlView.scene.models[0].bodies.findIndex((x) => x.name === t);
    return b >= 0 ? b : rlView.scene.models[0].bodies.findIndex((x) => x.name === rlView.scene.models[0].tool_body);
  }, toolName);
  check(toolIndex >= 0, `the tool ${toolName} is a body of the scene`);
  coach.joints(0, Q2);
  const s2 = await waitQ(page, 0, Q2, 'coach');
  const goal = s2.models[0].bodies[toolIndex];
  coach.joints(0, Q1);
  await waitQ(page, 0, Q1, 'coach');
  const ikOk = await page.evaluate((g) => rlView.dragTarget(0, g), goal);
  check(ikOk.ok === true, `IK to a reachable pose is ok (${JSON.stringify(ikOk)})`);
  await page.waitForFunction(() => rlView.state.models[0].source === 'ik', null, { timeout: WAIT_MS });
  await settle(page);
  const reached = await page.evaluate((i) => rlView.state.models[0].bodies[i], toolIndex);
  const posErr = dist3(reached, goal);
  const angErr = angleBetween(reached.slice(3), goal.slice(3));
  check(posErr < 1e-3 && angErr < 1e-2, `the tool reached the target (${posErr} m, ${angErr} rad)`);
  const ikText = await page.evaluate(() => document.querySelector('.ik-status').textContent);
  check(/IK ok/.test(ikText), `the panel says IK ok (${ikText})`);
  await page.screenshot({ path: path.join(outDir, '04-ik-reached.png') });
  ok(`IK target dragged to the tool pose at q=[${Q2.join(', ')}]: ok, tool ${posErr.toExponential(1)} m and ${angErr.toExponential(1)} rad from it; panel "${ikText}"`);
  const far = [3.0, 0.0, 0.5, 0, 0, 0, 1];
  const ikFail = await page.evaluate((g) => rlView.dragTarget(0, g), far);
  check(ikFail.ok === false && ikFail.reason, `IK to a pose 3 m away fails with a reason (${JSON.stringify(ikFail)})`);
  const failText = await page.evaluate(() => document.querySelector('.ik-status').textContent);
  check(/IK failed: ./.test(failText), `the panel shows the failure (${failText})`);
  ok(`IK target 3 m away: not ok, the panel shows "${failText}"`);

  // Restart the server on the same address: the page reconnects and shows the current state.
  const httpAddr = server.http.replace('http://', '');
  // Where the wrist is at Q1: the obstacle of the collision steps goes there.
  coach.joints(0, Q1);
  const sq1 = await waitQ(page, 0, Q1, 'coach');
  const wrist = await page.evaluate(() => rlView.scene.models[0].bodies.findIndex((b) => b.name === 'wrist_3_link'));
  check(wrist >= 0, 'ur5 has a body wrist_3_link');
  const wristAtQ1 = sq1.models[0].bodies[wrist];
  coach.close();
  server.kill();
  await server.exited;
  await page.waitForFunction(() => !rlView.connected && /reconnecting/.test(rlView.statusText()), null, { timeout: WAIT_MS });
  const downText = await page.evaluate(() => rlView.statusText());
  server = await startServer([urdf, '--http', httpAddr, '--coach', '127.0.0.1:0']);
  const coach2 = await coachClient(server.coach);
  coach2.joints(0, Q3);
  await page.waitForFunction(() => rlView.connected && rlView.hellos >= 2, null, { timeout: WAIT_MS });
  const st = await waitQ(page, 0, Q3, 'coach');
  await checkDrawnAtState(page, 0, 'after the reconnect');
  await page.screenshot({ path: path.join(outDir, '05-reconnected.png') });
  ok(`server restarted on ${httpAddr}: page showed "${downText.slice(0, 60)}…", reconnected by itself (hello #${await page.evaluate(() => rlView.hellos)}), shows the new server's q (state #${st.seq})`);
  coach2.close();
  await page.close();
  server.kill();
  return wristAtQ1;
}

async function collisionSteps(obstacleAt) {
  // A MoveIt planning scene with one box around the wrist's position at Q1.
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'rl-view-browser-'));
  const scene = path.join(dir, 'box.yaml');
  fs.writeFileSync(scene, [
    'name: box at the wrist',
    'world:',
    '  collision_objects:',
    '    - id: box1',
    '      header:',
    '        frame_id: world',
    '      pose:',
    `        position: [${obstacleAt.slice(0, 3).join(', ')}]`,
    '        orientation: [0, 0, 0, 1]',
    '      primitives:',
    '        - type: box',
    '          dimensions: [0.16, 0.16, 0.16]',
    '      primitive_poses:',
    '        - position: [0, 0, 0]',
    '          orientation: [0, 0, 0, 1]',
    '',
  ].join('\n'));
  const server = await startServer([data('mbm/ur5/ur5.urdf'), '--env', scene, '--http', '127.0.0.1:0', '--coach', '127.0.0.1:0']);
  const page = await openPage(`${server.http}/`);
  const envShapes = await page.evaluate(() => rlView.envMeshCount());
  check(envShapes === 1, `the obstacle is drawn (${envShapes} env bodies)`);
  const coach = await coachClient(server.coach);
  coach.joints(0, Q1);
  await waitQ(page, 0, Q1, 'coach');
  const hit = await page.evaluate(() => ({ colliding: rlView.state.colliding, red: rlView.redBodies() }));
  const key = (l) => l.map(([m, b]) => `${m}/${b}`).sort();
  check(hit.colliding.length > 0, `the wrist in the box collides (${JSON.stringify(hit.colliding)})`);
  check(JSON.stringify(key(hit.red)) === JSON.stringify(key(hit.colliding)), `red bodies ${JSON.stringify(hit.red)} = colliding ${JSON.stringify(hit.colliding)}`);
  await page.screenshot({ path: path.join(outDir, '06-collision-red.png') });
  ok(`obstacle at the wrist: ${hit.colliding.length} colliding bodies (${key(hit.colliding).join(', ')}) drawn red`);
  const away = Q1.slice();
  away[0] += Math.PI;
  coach.joints(0, away);
  await waitQ(page, 0, away, 'coach');
  const clear = await page.evaluate(() => ({ colliding: rlView.state.colliding, red: rlView.redBodies(), d: rlView.state.distance, label: rlView.distanceLabel() }));
  check(clear.colliding.length === 0 && clear.red.length === 0, `arm turned away: nothing red (${JSON.stringify(clear)})`);
  check(clear.d && clear.d.value > 0, `a distance to the obstacle is reported (${JSON.stringify(clear.d)})`);
  check(clear.label && clear.label.startsWith(`${(clear.d.value * 1000).toFixed(1)} mm`), `the distance label shows it (${clear.label})`);
  await page.screenshot({ path: path.join(outDir, '07-distance.png') });
  ok(`arm turned away: materials restored, distance line labelled "${clear.label}"`);
  coach.close();
  await page.close();
  server.kill();
  fs.rmSync(dir, { recursive: true, force: true });
}

async function defaultRobotSteps() {
  // `rl view` with no model: the embedded default robot, with RL's visual meshes.
  const server = await startServer(['--http', '127.0.0.1:0', '--coach', '127.0.0.1:0']);
  const page = await openPage(`${server.http}/`);
  const info = await page.evaluate(() => ({
    name: rlView.scene.models[0].name, joints: rlView.scene.models[0].joints.length, meshes: rlView.meshCounts(),
    shapes: rlView.scene.models[0].bodies.reduce((n, b) => n + b.shapes.filter((x) => x.kind === 'mesh').length, 0),
    loading: rlView.meshLoading(), status: rlView.statusText(),
  }));
  check(info.joints === 6 && info.shapes >= 7 && info.meshes[0] >= info.shapes, `the default robot is drawn with its visual meshes (${JSON.stringify(info)})`);
  check(info.loading.pending === 0 && info.loading.loaded === info.shapes && !/loading/.test(info.status),
    `every inline mesh counts as loaded, none left loading (${JSON.stringify(info.loading)}; "${info.status}")`);
  await page.screenshot({ path: path.join(outDir, '12-default-robot.png') });
  const plotted = await page.evaluate(() => rlView.plotTracking());
  check(!plotted.shown, 'no tracking-error strip without q_cmd');
  ok(`rl view with no model: ${info.name}, ${info.joints} joints, ${info.shapes} visual meshes (RL's VRML), ${info.loading.loaded} loaded, none loading; the plot shows q only`);

  // A value beyond a joint's limit (Coach takes what the robot reports) is shown as such.
  const lim = await page.evaluate(() => rlView.scene.models[0].joints.map((j) => [j.min, j.max]));
  const beyond = [lim[0][1] + 0.2, 0.3, 1.2, 0, 0.5, 0];
  const coach = await coachClient(server.coach);
  coach.joints(0, beyond);
  await waitQ(page, 0, beyond, 'coach');
  const marked = await page.evaluate(() => ({ rows: rlView.beyondLimits(), red: document.querySelectorAll('.joint.beyond').length }));
  check(marked.rows.length === 1 && marked.rows[0][1] === 0 && /beyond its upper limit/.test(marked.rows[0][2]) && marked.red === 1,
    `joint 0 at its limit + 0.2 rad is marked beyond it (${JSON.stringify(marked)})`);
  await page.screenshot({ path: path.join(outDir, '16-beyond-limit.png') });
  coach.joints(0, [0, 0.3, 1.2, 0, 0.5, 0]);
  await waitQ(page, 0, [0, 0.3, 1.2, 0, 0.5, 0], 'coach');
  const cleared = await page.evaluate(() => rlView.beyondLimits().length);
  check(cleared === 0, `back within the limits, nothing marked (${cleared})`);
  ok(`a Coach value ${(beyond[0] * 180 / Math.PI).toFixed(1)}° beyond joint 0's ${(lim[0][1] * 180 / Math.PI).toFixed(1)}° limit is shown: "${marked.rows[0][2]}"`);

  // A Coach error is shown while it is the latest word, and a good line clears it.
  coach.raw('2 0 1 2\n');
  await page.waitForFunction(() => /coach error:/.test(rlView.statusText()), null, { timeout: WAIT_MS });
  const errText = await page.evaluate(() => rlView.state.coach.last_error);
  await page.screenshot({ path: path.join(outDir, '17-coach-error.png') });
  coach.joints(0, [0.1, 0.3, 1.2, 0, 0.5, 0]);
  await waitQ(page, 0, [0.1, 0.3, 1.2, 0, 0.5, 0], 'coach');
  const after = await page.evaluate(() => rlView.statusText());
  check(!/coach error/.test(after) && /1 rejected/.test(after), `a good line clears the error shown, the count stays ("${after}")`);
  ok(`Coach error shown ("coach error: ${errText}"), cleared by the next good line`);
  coach.close();
  await page.close();
  server.kill();
}

async function scenarioSteps() {
  // rlPlanDemo's view of RL's Puma scenario: the kinematic world turned 90° about z.
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'rl-view-scenario-'));
  const scenario = data('rlplan/unimation-puma560_boxes_rrtConCon.xml');
  const csv = path.join(dir, 'plan.csv');
  const planned = await new Promise((resolve) => {
    const p = spawn(rlBin, ['plan', scenario, '--plan-time', '20s', '--out', csv], { cwd: repo, stdio: ['ignore', 'ignore', 'pipe'] });
    let err = '';
    p.stderr.on('data', (d) => { err += d; });
    p.once('exit', (code) => resolve({ code, err }));
  });
  check(planned.code === 0, `rl plan solved the Puma scenario (exit ${planned.code}) ${planned.err}`);
  const server = await startServer([scenario, '--path', csv, '--http', '127.0.0.1:0', '--coach', '127.0.0.1:0']);
  const page = await openPage(`${server.http}/`);
  const info = await page.evaluate(() => ({
    plan: rlView.planShown(), loading: rlView.meshLoading(), status: rlView.statusText(),
    start: rlView.scene.plan.start.q, goal: rlView.scene.plan.goal.q, q: rlView.state.models[0].q,
    bodies: rlView.scene.models[0].bodies.length, path: rlView.scene.path,
    joints: rlView.scene.models[0].joints, initial: document.querySelector('.initial')?.textContent,
  }));
  check(info.plan.start === info.bodies && info.plan.goal === info.bodies && info.plan.trail >= 2,
    `start and goal ghosts of all ${info.bodies} bodies and a trail (${JSON.stringify(info.plan)})`);
  check(info.loading.pending === 0 && !/loading/.test(info.status), `the VRML meshes are all in (${JSON.stringify(info.loading)})`);
  check(info.q.every((v, i) => Math.abs(v - info.start[i]) < 1e-12), `the robot starts at the scenario's start (${info.q})`);
  check(/starts at the given start/.test(info.initial || ''), `the panel says where it starts (${info.initial})`);
  await checkDrawnAtState(page, 0, 'scenario at its start');
  // Waypoints without times: each segment as long as its slowest joint needs at its limit.
  const p = info.path;
  check(p.timing && p.timing.from === 'speed_limits', `the path is timed from the speed limits (${JSON.stringify(p.timing)})`);
  let worstDt = 0;
  for (let k = 1; k < p.q.length; k++) {
    const need = Math.max(...p.q[k].map((v, j) => Math.abs(v - p.q[k - 1][j]) / (info.joints[j].max_speed ?? p.timing.assumed_speed)));
    worstDt = Math.max(worstDt, Math.abs((p.t[k] - p.t[k - 1]) - need));
  }
  check(worstDt < 1e-9, `segment times are max |Δq|/v_max (worst difference ${worstDt} s)`);
  await page.screenshot({ path: path.join(outDir, '14-scenario-start.png') });
  // Play: the ghosts and the trail stay while the robot moves along the path.
  await page.click('#path button');
  const half = p.t.at(-1) / 2;
  await page.waitForFunction((h) => rlView.state.models[0].source === 'path' && Number(document.querySelector('#path input[type=range]').value) >= h, half, { timeout: WAIT_MS + 1000 * p.t.at(-1) });
  const during = await page.evaluate(() => rlView.planShown());
  await page.screenshot({ path: path.join(outDir, '15-scenario-playing.png') });
  check(during.start === info.bodies && during.goal === info.bodies && during.trail === info.plan.trail, `ghosts and trail stay while it plays (${JSON.stringify(during)})`);
  // The rest by the time slider (the play's second half adds nothing to check).
  await page.$eval('#path input[type=range]', (el, v) => { el.value = String(v); el.dispatchEvent(new Event('input')); }, p.t.at(-1));
  await waitQ(page, 0, info.goal, 'path');
  await checkDrawnAtState(page, 0, 'scenario at its goal');
  ok(`Puma scenario: start/goal ghosts (${info.bodies} bodies each), a trail of ${info.plan.trail} tool points; the path of ${p.q.length} waypoints takes ${p.t.at(-1).toFixed(2)} s at the speed limits and plays (half of it, then the slider to the goal)`);
  await page.close();
  server.kill();
  fs.rmSync(dir, { recursive: true, force: true });
}

async function runViewSteps() {
  // `rl run --view`: the controller's measured and commanded q reach the page, whose plot
  // draws the tracking error q_cmd − q.
  const run = await startRun(['--duration', '4s']);
  const page = await openPage(`${run.http}/`);
  await page.waitForFunction(() => rlView.state.models[0].source === 'live'
    && Array.isArray(rlView.state.models[0].q_cmd) && rlView.plotTracking().shown
    && rlView.plotTracking().max > 0, null, { timeout: WAIT_MS });
  const caption = await page.$eval('#plot-caption', (el) => el.textContent);
  check(/q_cmd − q/.test(caption), `the caption names the tracking error: ${caption}`);
  await page.waitForTimeout(1000);
  const t = await page.evaluate(() => rlView.plotTracking());
  const box = await page.$('#plot-box');
  await box.screenshot({ path: path.join(outDir, '13-run-view-tracking.png') });
  ok(`rl run --view: live states with q_cmd; the plot draws the tracking error (max ${t.max.toFixed(3)}° so far)`);
  await page.close();
  // The run ends on its own and the page stays (--view-hold) until SIGTERM.
  const until = Date.now() + WAIT_MS;
  while (!/view: still serving/.test(run.output())) {
    check(Date.now() < until, `rl run did not end its run in ${WAIT_MS} ms`);
    await new Promise((r) => setTimeout(r, 50));
  }
  // The page says the run has ended, and how.
  const page2 = await openPage(`${run.http}/`);
  await page2.waitForFunction(() => /run ended: /.test(rlView.statusText()), null, { timeout: WAIT_MS });
  const ended = await page2.evaluate(() => ({ text: rlView.statusText(), run: rlView.state.run }));
  check(ended.run && ended.run.ended && /exit code \d/.test(ended.run.summary), `the state carries the run's end (${JSON.stringify(ended.run)})`);
  await page2.screenshot({ path: path.join(outDir, '18-run-ended.png') });
  ok(`after the run the page says: "${ended.text.match(/run ended: [^●]*?exit code \d+/)[0]}"`);
  await page2.close();
  run.kill();
  const code = await run.exited;
  // SIGTERM ends the hold: the run's own status (0, or 1 if the run faulted: on this 2-core
  // machine the browser's software rendering competes with the in-process fake robot, whose
  // threads are not real-time), never a signal or a crash.
  check(code === 0 || code === 1, `rl run --view-hold ends with its run's status on SIGTERM (got ${code}):\n${run.output()}`);
  if (code === 1) console.log(`# note: the run under the browser's load ended with a fault:\n${run.output().split('\n').filter((l) => /result|fault|fail/i.test(l)).join('\n')}`);
}

async function rlModelSteps() {
  const xml = data('rlmdl/unimation-puma560.xml');
  const server = await startServer([xml, '--http', '127.0.0.1:0', '--coach', '127.0.0.1:0']);
  const page = await openPage(`${server.http}/`);
  const info = await page.evaluate(() => ({
    urdf: rlView.scene.models[0].urdf, joints: rlView.scene.models[0].joints.length,
    shapes: rlView.scene.models[0].bodies.reduce((n, b) => n + b.shapes.length, 0), meshes: rlView.meshCounts(),
  }));
  check(info.urdf === null, 'an RL model has no URDF');
  check(info.shapes > 0 && info.meshes[0] >= info.shapes, `drawn from its ${info.shapes} shapes (${info.meshes[0]} meshes)`);
  await page.screenshot({ path: path.join(outDir, '08-rlmdl-loaded.png') });
  const q = Array.from({ length: info.joints }, (_, i) => [0.5, -0.7, 0.9, 0.4, -0.6, 0.8][i % 6]);
  const coach = await coachClient(server.coach);
  const m = await measureChange(page, async () => { coach.joints(0, q); await waitQ(page, 0, q, 'coach'); }, '09-rlmdl-coach.png');
  const f = m.fraction;
  check(f > threshold.value, `RL model moved: ${(100 * f).toFixed(1)} % changed (> ${(100 * threshold.value).toFixed(1)} %)`);
  await checkDrawnAtState(page, 0, 'RL model after Coach');
  const red = await page.evaluate(() => ({ red: rlView.redBodies().length, colliding: rlView.state.colliding.length }));
  check(red.red === red.colliding, `red bodies = colliding bodies (${JSON.stringify(red)})`);
  ok(`RL model ${path.basename(xml)}: ${info.shapes} shapes drawn, Coach q moves it, ${(100 * f).toFixed(1)} % of the robot region changed (the server reports ${red.colliding} colliding bodies there, ${red.red} drawn red)`);
  coach.close();
  await page.close();
  server.kill();
}

// A unit cube as OBJ and as COLLADA text, and a two-joint URDF that draws one of each.
const CUBE_V = [[-0.5, -0.5, -0.5], [0.5, -0.5, -0.5], [0.5, 0.5, -0.5], [-0.5, 0.5, -0.5],
  [-0.5, -0.5, 0.5], [0.5, -0.5, 0.5], [0.5, 0.5, 0.5], [-0.5, 0.5, 0.5]];
const CUBE_T = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]];
const cubeObj = () => [...CUBE_V.map((v) => `v ${v.join(' ')}`), ...CUBE_T.map((t) => `f ${t.map((i) => i + 1).join(' ')}`), ''].join('\n');
const cubeDae = () => `<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="cube" name="cube"><mesh>
      <source id="cube-pos">
        <float_array id="cube-pos-array" count="24">${CUBE_V.flat().join(' ')}</float_array>
        <technique_common><accessor source="#cube-pos-array" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <vertices id="cube-vtx"><input semantic="POSITION" source="#cube-pos"/></vertices>
      <triangles count="12"><input semantic="VERTEX" source="#cube-vtx" offset="0"/><p>${CUBE_T.flat().join(' ')}</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene"><node id="cube-node" name="cube"><instance_geometry url="#cube"/></node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
`;
const formatsUrdf = () => `<?xml version="1.0"?>
<robot name="formats">
  <link name="base">
    <visual><origin xyz="0 0 0.05"/><geometry><cylinder radius="0.08" length="0.1"/></geometry></visual>
    <collision><origin xyz="0 0 0.05"/><geometry><cylinder radius="0.08" length="0.1"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <link name="arm">
    <visual><origin xyz="0.15 0 0.03"/><geometry><mesh filename="meshes/cube.obj" scale="0.3 0.06 0.06"/></geometry></visual>
    <collision><origin xyz="0.15 0 0.03"/><geometry><box size="0.3 0.06 0.06"/></geometry></collision>
  </link>
  <joint name="j2" type="prismatic">
    <parent link="arm"/><child link="hand"/><origin xyz="0.3 0 0.03"/><axis xyz="0 0 1"/>
    <limit lower="-0.1" upper="0.2" effort="1" velocity="1"/>
  </joint>
  <link name="hand">
    <visual><origin xyz="0.05 0 0"/><geometry><mesh filename="meshes/cube.dae" scale="0.1 0.08 0.08"/></geometry></visual>
    <collision><origin xyz="0.05 0 0"/><geometry><box size="0.1 0.08 0.08"/></geometry></collision>
  </link>
</robot>
`;

async function formatsAndPathSteps() {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'rl-view-formats-'));
  fs.mkdirSync(path.join(dir, 'meshes'));
  fs.writeFileSync(path.join(dir, 'meshes', 'cube.obj'), cubeObj());
  fs.writeFileSync(path.join(dir, 'meshes', 'cube.dae'), cubeDae());
  fs.writeFileSync(path.join(dir, 'formats.urdf'), formatsUrdf());
  // A path as `rl plan --out` writes it: joint names, one waypoint per row (1 s apart).
  const rows = [[0, 0], [1.2, 0.15], [-0.8, 0.05]];
  fs.writeFileSync(path.join(dir, 'path.csv'), ['j1,j2', ...rows.map((r) => r.join(',')), ''].join('\n'));
  const server = await startServer([path.join(dir, 'formats.urdf'), '--path', path.join(dir, 'path.csv'),
    '--http', '127.0.0.1:0', '--coach', '127.0.0.1:0']);
  const page = await openPage(`${server.http}/`);
  const info = await page.evaluate(() => ({
    loading: rlView.meshLoading(), meshes: rlView.meshCounts(),
    formats: rlView.scene.models[0].bodies.flatMap((b) => b.shapes.map((x) => x.format || x.kind)),
    units: [...document.querySelectorAll('.joint .unit')].map((e) => e.textContent),
    path: rlView.scene.path,
  }));
  check(info.loading.failed === 0 && info.loading.loaded === 2, `OBJ and COLLADA meshes loaded (${JSON.stringify(info.loading)})`);
  check(info.meshes[0] >= 3, `cylinder, OBJ and COLLADA drawn (${info.meshes[0]} meshes)`);
  check(JSON.stringify(info.units) === JSON.stringify(['°', 'mm']), `revolute in degrees, prismatic in mm (${info.units})`);
  await page.screenshot({ path: path.join(outDir, '10-obj-dae-loaded.png') });
  ok(`URDF with ${info.formats.join(', ')} visuals: ${info.loading.loaded} mesh files loaded, 0 failed, ${info.meshes[0]} meshes drawn; panel units ${info.units.join(' and ')}`);

  // Coach `0`: a body pose set over Coach overrides the kinematics until the next joint update.
  const coach = await coachClient(server.coach);
  coach.joints(0, [0.3, 0.1]);
  await waitQ(page, 0, [0.3, 0.1], 'coach');
  const handIndex = await page.evaluate(() => rlView.scene.models[0].bodies.findIndex((b) => b.name === 'hand'));
  coach.raw(`0 0 ${handIndex} 0.1 0.4 0.5 0 0 0\n`);
  await page.waitForFunction((i) => {
    const p = rlView.bodyPosition(0, 'hand');
    const w = rlView.state.models[0].bodies[i];
    return Math.hypot(w[0] - 0.1, w[1] - 0.4, w[2] - 0.5) < 1e-6 && Math.hypot(p[0] - 0.1, p[1] - 0.4, p[2] - 0.5) < 1e-6;
  }, handIndex, { timeout: WAIT_MS });
  ok('Coach "0 0 <hand> 0.1 0.4 0.5 0 0 0": the hand is drawn at (0.1, 0.4, 0.5)');

  // Path playback: the play button runs to the end; the time slider gives the interpolated q.
  check(info.path && info.path.t.length === rows.length, `the page has the path (${JSON.stringify(info.path)})`);
  await page.click('#path button');
  const end = await waitQ(page, 0, rows.at(-1), 'path');
  await page.screenshot({ path: path.join(outDir, '11-path-end.png') });
  const t = (info.path.t[0] + info.path.t[1]) / 2 + 0.25 * (info.path.t[1] - info.path.t[0]);
  await page.$eval('#path input[type=range]', (el, v) => { el.value = String(v); el.dispatchEvent(new Event('input')); }, t);
  const s = (t - info.path.t[0]) / (info.path.t[1] - info.path.t[0]);
  const want = rows[0].map((a, i) => a + s * (rows[1][i] - a));
  await waitQ(page, 0, want, 'path');
  ok(`path of ${rows.length} waypoints: play ran to the last one (state #${end.seq}, source path); the time slider at ${t.toFixed(2)} s gives q = [${want.map((v) => v.toFixed(4)).join(', ')}]`);
  coach.close();
  await page.close();
  server.kill();
  fs.rmSync(dir, { recursive: true, force: true });
}

try {
  browser = await chromium.launch({
    executablePath: chromiumPath,
    headless: true,
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--no-sandbox'],
  });
  const obstacle = await ur5Steps();
  await collisionSteps(obstacle);
  await rlModelSteps();
  await formatsAndPathSteps();
  await defaultRobotSteps();
  await scenarioSteps();
  await runViewSteps();
  console.log(`screenshots: ${outDir}`);
  console.log(`${passed} passed, 0 failed`);
  await cleanup();
  clearTimeout(watchdog);
  process.exit(0);
} catch (e) {
  console.error(`not ok ${passed + 1} - ${e.message}`);
  for (const s of servers) console.error(`--- rl view output:\n${s.output()}`);
  await cleanup();
  clearTimeout(watchdog);
  process.exit(1);
}
