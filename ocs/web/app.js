// The operator page: draws the track, the car, its trail, the plan and the sampled rollouts on
// a canvas, strip charts with uPlot, the chassis status, and sends the operator's controls.
// Live mode reads server-sent events from /api/stream; replay mode reads /api/recording once.
'use strict';

const CHART_SECONDS = 30;
const TRAIL_POINTS = 4000;
const query = new URLSearchParams(location.search);
const testMode = query.has('test');
// The server's per-launch secret, from the URL it printed (?token=...): without it the page
// shows everything but can change nothing (docs/SECURITY.md).
const token = query.get('token') || '';
// ?frames=N: stop streaming after N frames (the browser test: 15)
const holdAfter = +(new URLSearchParams(location.search).get('frames') || (testMode ? 15 : 0));
const $ = (id) => document.getElementById(id);

// ---- colours (distinct families, so a test can find each in the pixels) ----
const CAR = 'rgb(255,0,255)';
const PLAN = 'rgb(255,255,255)';
const lerp = (a, b, s) => a.map((v, i) => Math.round(v + (b[i] - v) * s));
const ROLLOUT_LOW = [0, 200, 255], ROLLOUT_HIGH = [255, 230, 0];
const TRAIL_SLOW = [0, 180, 0], TRAIL_FAST = [230, 0, 0];
const rgb = (c) => `rgb(${c[0]},${c[1]},${c[2]})`;

// ---- the map: world metres -> canvas pixels, y up ----
const canvas = $('map');
const ctx = canvas.getContext('2d');
const background = document.createElement('canvas');
background.width = canvas.width;
background.height = canvas.height;
let view = { x0: -10, y0: -10, scale: 10 };
const px = (x, y) => [(x - view.x0) * view.scale, canvas.height - (y - view.y0) * view.scale];

function fitView(xmin, xmax, ymin, ymax) {
  const margin = 2;
  const w = xmax - xmin + 2 * margin, h = ymax - ymin + 2 * margin;
  const scale = Math.min(canvas.width / w, canvas.height / h);
  view = { scale, x0: xmin - margin - (canvas.width / scale - w) / 2, y0: ymin - margin - (canvas.height / scale - h) / 2 };
}

function strokeFlat(g, flat, closed) {
  if (!flat || flat.length < 4) return;
  g.beginPath();
  let [x, y] = px(flat[0], flat[1]);
  g.moveTo(x, y);
  for (let i = 2; i < flat.length; i += 2) {
    [x, y] = px(flat[i], flat[i + 1]);
    g.lineTo(x, y);
  }
  if (closed) g.closePath();
  g.stroke();
}

function drawBackground(track) {
  const g = background.getContext('2d');
  g.fillStyle = '#000';
  g.fillRect(0, 0, background.width, background.height);
  if (!track) return;
  const m = track.costmap;
  // The cost map in grey: dark on the racing line, light off the track.
  const img = document.createElement('canvas');
  img.width = m.cols;
  img.height = m.rows;
  const ig = img.getContext('2d');
  const data = ig.createImageData(m.cols, m.rows);
  for (let r = 0; r < m.rows; ++r)
    for (let c = 0; c < m.cols; ++c) {
      const v = 25 + Math.round(m.cells[r * m.cols + c] * 0.45);
      const o = ((m.rows - 1 - r) * m.cols + c) * 4;  // row 0 is y_min: the bottom
      data.data[o] = data.data[o + 1] = data.data[o + 2] = v;
      data.data[o + 3] = 255;
    }
  ig.putImageData(data, 0, 0);
  const [x0, y1] = px(m.x_min, m.y_max), [x1, y0] = px(m.x_max, m.y_min);
  g.imageSmoothingEnabled = true;
  g.drawImage(img, x0, y1, x1 - x0, y0 - y1);
  g.lineWidth = 1;
  g.strokeStyle = 'rgb(150,150,150)';
  strokeFlat(g, track.inner, true);
  strokeFlat(g, track.outer, true);
  g.strokeStyle = 'rgb(70,70,70)';
  g.setLineDash([4, 6]);
  strokeFlat(g, track.centreline, true);
  g.setLineDash([]);
  g.strokeStyle = 'rgb(200,200,200)';
  for (const b of track.barriers) {
    g.lineWidth = Math.max(1, 2 * b.radius_m * view.scale);
    strokeFlat(g, b.centre, true);
  }
}

// ---- what is drawn each frame ----
const trail = [];  // {x, y, speed}
let maxSpeed = 8;

// The trail is drawn once per segment onto its own layer (a live page adds one segment a frame).
const trailLayer = document.createElement('canvas');
trailLayer.width = canvas.width;
trailLayer.height = canvas.height;
const trailCtx = trailLayer.getContext('2d');
let trailDrawn = 0;  // segments of `trail` already on the layer

function drawTrail() {
  if (trailDrawn > trail.length) {  // the trail was cut (replay moved back): start again
    trailCtx.clearRect(0, 0, trailLayer.width, trailLayer.height);
    trailDrawn = 0;
  }
  trailCtx.lineWidth = 2.5;
  for (let i = Math.max(1, trailDrawn); i < trail.length; ++i) {
    const a = trail[i - 1], b = trail[i];
    if (Math.hypot(b.x - a.x, b.y - a.y) > 3) continue;  // a respawn: no line across the map
    trailCtx.strokeStyle = rgb(lerp(TRAIL_SLOW, TRAIL_FAST, Math.min(1, b.speed / maxSpeed)));
    trailCtx.beginPath();
    trailCtx.moveTo(...px(a.x, a.y));
    trailCtx.lineTo(...px(b.x, b.y));
    trailCtx.stroke();
  }
  trailDrawn = trail.length;
}

function clearTrail() {
  trail.length = 0;
  trailDrawn = 0;
  trailCtx.clearRect(0, 0, trailLayer.width, trailLayer.height);
}

function drawScene(frame) {
  ctx.drawImage(background, 0, 0);
  drawTrail();
  ctx.drawImage(trailLayer, 0, 0);
  if (!frame) return;
  // rollouts coloured by weight (log scale over three decades), the heaviest drawn last
  const rollouts = frame.rollouts || [], weights = frame.weights || [];
  const wmax = Math.max(1e-30, ...weights);
  const order = weights.map((w, i) => i).sort((i, j) => weights[i] - weights[j]);
  ctx.lineWidth = 1.5;
  for (const i of order) {
    const s = Math.min(1, Math.max(0, 1 + Math.log10(Math.max(weights[i], 1e-30) / wmax) / 3));
    ctx.strokeStyle = rgb(lerp(ROLLOUT_LOW, ROLLOUT_HIGH, s));
    strokeFlat(ctx, rollouts[i], false);
  }
  if (frame.plan && frame.plan.length) {
    ctx.lineWidth = 3;
    ctx.strokeStyle = PLAN;
    strokeFlat(ctx, frame.plan, false);
  }
  drawCar(frame.x, frame.y, frame.yaw);
}

function drawCar(x, y, yaw) {
  const [cx, cy] = px(x, y);
  const length = Math.max(16, 0.9 * view.scale), width = Math.max(9, 0.45 * view.scale);
  ctx.save();
  ctx.translate(cx, cy);
  ctx.rotate(-yaw);
  ctx.fillStyle = CAR;
  ctx.fillRect(-length / 2, -width / 2, length, width);
  ctx.restore();
}

// ---- strip charts ----
const chartSpecs = [
  { key: 'speed', title: 'speed [m/s]', series: [['speed', '#4fc3f7'], ['target', '#888']] },
  { key: 'slip', title: 'slip angle [deg]', series: [['slip', '#ffb74d']] },
  { key: 'steer', title: 'steering [-1, 1]', series: [['command', '#81c784'], ['applied', '#388e3c']] },
  { key: 'throttle', title: 'throttle [-1, 1]', series: [['command', '#e57373'], ['applied', '#b71c1c']] },
  { key: 'opt', title: 'optimizer time [ms]', series: [['optimizer', '#ba68c8']] },
  { key: 'ess', title: 'effective sample size', series: [['ESS', '#fff176']] },
];
const charts = {};
let cursorTime = null;

function makeCharts() {
  const box = $('charts');
  const width = Math.max(300, Math.floor((box.clientWidth || 1200) / 3) - 16);
  for (const spec of chartSpecs) {
    const div = document.createElement('div');
    box.appendChild(div);
    const opts = {
      title: spec.title, width, height: 150,
      scales: { x: { time: false } },
      axes: [{ stroke: '#aaa', grid: { stroke: '#333' }, label: 't [s]' }, { stroke: '#aaa', grid: { stroke: '#333' } }],
      series: [{ label: 't' }, ...spec.series.map(([label, stroke]) => ({ label, stroke, width: 1.5 }))],
      hooks: { draw: [(u) => drawCursor(u)] },
    };
    const data = [[], ...spec.series.map(() => [])];
    charts[spec.key] = { plot: new uPlot(opts, data, div), data };
  }
}

function drawCursor(u) {
  if (cursorTime === null) return;
  const x = u.valToPos(cursorTime, 'x', true);
  const g = u.ctx;
  g.save();
  g.strokeStyle = '#ff00ff';
  g.lineWidth = 1;
  g.beginPath();
  g.moveTo(x, u.bbox.top);
  g.lineTo(x, u.bbox.top + u.bbox.height);
  g.stroke();
  g.restore();
}

const slipDeg = (vx, vy) => (Math.hypot(vx, vy) > 0.5 ? Math.atan2(vy, Math.abs(vx)) * 180 / Math.PI : 0);

function pushChart(key, t, values) {
  const c = charts[key];
  c.data[0].push(t);
  values.forEach((v, i) => c.data[i + 1].push(v));
  while (c.data[0].length > 2 && c.data[0][0] < t - CHART_SECONDS) c.data.forEach((col) => col.shift());
}

function redrawCharts() {
  for (const c of Object.values(charts)) c.plot.setData(c.data);
}

// ---- status panel ----
function setText(id, text, cls) {
  const el = $(id);
  el.textContent = text;
  el.className = cls || '';
}

function showStatus(f) {
  const c = f.chassis;
  if (c && c.present) {
    setText('st-runstop', c.motion_enabled ? 'motion enabled' : 'RUNSTOP', c.motion_enabled ? 'ok' : 'bad');
    setText('st-watchdog', c.watchdog_tripped ? 'TRIPPED' : 'ok', c.watchdog_tripped ? 'bad' : 'ok');
    setText('st-steering', c.steering);
    setText('st-throttle', c.throttle);
    setText('st-brake', c.front_brake);
  } else {
    setText('st-runstop', 'no chassis (direct)');
  }
  setText('st-speed', `${f.speed.toFixed(2)} m/s`);
  setText('st-target', `${f.target_speed.toFixed(1)} m/s`);
  setText('st-opt', `${f.optimizer_ms.toFixed(2)} ms`);
  setText('st-ess', `${f.ess.toFixed(1)} of ${f.samples}`);
  setText('st-laps', `${f.laps} / ${f.crashes}`);
  $('clock').textContent = `t = ${f.t.toFixed(2)} s${f.paused ? ' (paused)' : ''}`;
  $('pause').classList.toggle('active', !!f.paused);
  $('runstop').textContent = c && c.present && !c.motion_enabled ? 'release runstop' : 'RUNSTOP';
}

// ---- live mode ----
let frames = 0, lastFrame = null, chartsDrawnAt = 0;
const controlReplies = [];  // {status, error} of each control sent (the browser test reads them)
let controlsPending = 0;
const whenControlsDone = (f) => (controlsPending ? setTimeout(() => whenControlsDone(f), 20) : f());

function startLive(info) {
  $('mode').textContent = info.can_pause ? 'live simulation' : 'live vehicle';
  $('pause').hidden = !info.can_pause;
  $('st-priorities').textContent = info.priorities.map((p) => `${p.sender} (${p.priority})`).join(', ') || '–';
  if (!token) $('control-error').textContent = 'view only: open the URL the server printed (with ?token=...) to use the controls';
  let source = new EventSource('/api/stream');
  const cycle = +new URLSearchParams(location.search).get('cycle');
  if (cycle > 0)  // the timing measurement: connected for `cycle` seconds, then not, and so on
    setInterval(() => {
      if (source.readyState === EventSource.CLOSED) {
        source = new EventSource('/api/stream');
        source.onmessage = onFrame;
      } else source.close();
    }, cycle * 1000);
  const onFrame = (event) => {
    const f = JSON.parse(event.data);
    ++frames;
    lastFrame = f;
    if (trail.length >= TRAIL_POINTS) clearTrail();
    trail.push({ x: f.x, y: f.y, speed: f.speed });
    maxSpeed = Math.max(maxSpeed, f.speed, f.target_speed * 1.2);
    pushChart('speed', f.t, [f.speed, f.target_speed]);
    pushChart('slip', f.t, [f.slip * 180 / Math.PI]);
    pushChart('steer', f.t, [f.steer, f.applied_steer]);
    pushChart('throttle', f.t, [f.throttle, f.applied_throttle]);
    pushChart('opt', f.t, [f.optimizer_ms]);
    pushChart('ess', f.t, [f.ess]);
    if (performance.now() - chartsDrawnAt > 200 || frames === holdAfter) {  // charts at 5 Hz
      chartsDrawnAt = performance.now();
      redrawCharts();
    }
    drawScene(f);
    showStatus(f);
    // ?press=ID[,ID]: the browser test presses these buttons once (with ?target=V for set-target)
    if (testMode && frames === 1 && query.get('press')) {
      if (query.has('target')) $('target').value = query.get('target');
      for (const id of query.get('press').split(',')) $(id).click();
    }
    if (frames === holdAfter) {  // a screenshot or the browser test: hold the picture still
      source.close();
      if (testMode) {
        const extra = { mode: 'live', frames, t: f.t, rollouts_in_frame: f.rollouts.length };
        whenControlsDone(() => report({ ...extra, controls: controlReplies }));
      }
    }
  };
  source.onmessage = onFrame;
  source.onerror = () => { $('mode').textContent = 'live simulation (disconnected)'; };
  const post = async (params) => {
    ++controlsPending;
    try {
      const r = await fetch('/api/control', { method: 'POST', body: new URLSearchParams(params),
                                              headers: { 'X-MPPI-Token': token } });
      const body = await r.json();
      controlReplies.push({ status: r.status, error: body.error || '' });
      $('control-error').textContent = r.ok ? '' : body.error;
    } catch (e) {
      controlReplies.push({ status: 0, error: String(e) });
      $('control-error').textContent = `control not sent: ${e}`;
    } finally {
      --controlsPending;
    }
  };
  $('pause').onclick = () => post({ pause: lastFrame && lastFrame.paused ? '0' : '1' });
  $('runstop').onclick = () => post({ runstop: lastFrame && lastFrame.chassis.present && !lastFrame.chassis.motion_enabled ? '0' : '1' });
  $('set-target').onclick = () => post({ target_speed: $('target').value });
}

// ---- replay mode ----
function startReplay(rec) {
  $('mode').textContent = `replay: ${rec.source} (${rec.rows} rows${rec.stride > 1 ? `, every ${rec.stride}th shown` : ''})`;
  $('controls').hidden = true;
  $('replay-controls').hidden = false;
  const col = rec.columns, n = col.t.length;
  const at = (name, i) => (col[name] ? col[name][i] : null);
  const speed = col.vx.map((vx, i) => Math.hypot(vx || 0, col.vy[i] || 0));
  maxSpeed = Math.max(1, ...speed);
  const fill = (key, series) => {
    const c = charts[key];
    c.data[0] = col.t;
    series.forEach((s, i) => { c.data[i + 1] = s; });
  };
  fill('speed', [speed, col.t.map(() => null)]);
  fill('slip', [col.vx.map((vx, i) => slipDeg(vx, col.vy[i]))]);
  fill('steer', [col.steer, col.t.map(() => null)]);
  fill('throttle', [col.throttle, col.t.map(() => null)]);
  fill('opt', [col.optimizer_ms || col.t.map(() => null)]);
  fill('ess', [col.effective_sample_size || col.t.map(() => null)]);
  const slider = $('slider');
  slider.max = n - 1;
  const show = (i) => {
    if (i + 1 < trail.length) clearTrail();
    for (let k = trail.length; k <= i; ++k) trail.push({ x: col.x[k], y: col.y[k], speed: speed[k] });
    cursorTime = col.t[i];
    redrawCharts();
    const f = { x: col.x[i], y: col.y[i], yaw: col.yaw[i] };
    drawScene(f);
    $('slider-time').textContent = `t = ${col.t[i].toFixed(2)} s`;
    $('clock').textContent = `t = ${col.t[i].toFixed(2)} s, v = ${speed[i].toFixed(2)} m/s`;
    setText('st-speed', `${speed[i].toFixed(2)} m/s`);
    setText('st-opt', at('optimizer_ms', i) === null ? 'not recorded' : `${at('optimizer_ms', i).toFixed(2)} ms`);
    setText('st-ess', at('effective_sample_size', i) === null ? 'not recorded' : at('effective_sample_size', i).toFixed(1));
    setText('st-laps', at('lap', i) === null ? '–' : `${at('lap', i)}`);
    setText('st-runstop', 'not recorded');
  };
  slider.oninput = () => show(+slider.value);
  let timer = null;
  $('play').onclick = () => {
    if (timer) { clearInterval(timer); timer = null; $('play').textContent = '▶ play'; return; }
    $('play').textContent = '❚❚ pause';
    let i = +slider.value;
    const t0 = performance.now(), start = col.t[i];
    timer = setInterval(() => {
      const t = start + (performance.now() - t0) / 1000;
      while (i + 1 < n && col.t[i + 1] <= t) ++i;
      slider.value = i;
      show(i);
      if (i + 1 >= n) $('play').onclick();
    }, 50);
  };
  const startAt = testMode ? Math.floor(n * 0.6) : n - 1;
  slider.value = startAt;
  show(startAt);
  if (testMode) report({ mode: 'replay', frames: 1, t: col.t[startAt], rows: rec.rows });
}

// ---- the browser test's hook: counts pixels of each colour family on the map canvas ----
function near(p, c, tol) { return Math.abs(p[0] - c[0]) + Math.abs(p[1] - c[1]) + Math.abs(p[2] - c[2]) <= tol; }

function report(extra) {
  const img = ctx.getImageData(0, 0, canvas.width, canvas.height).data;
  const rolloutRamp = [], trailRamp = [];
  for (let s = 0; s <= 1.0001; s += 0.05) {
    rolloutRamp.push(lerp(ROLLOUT_LOW, ROLLOUT_HIGH, s));
    trailRamp.push(lerp(TRAIL_SLOW, TRAIL_FAST, s));
  }
  let car = 0, rollout = 0, plan = 0, trailPx = 0;
  for (let o = 0; o < img.length; o += 4) {
    const p = [img[o], img[o + 1], img[o + 2]];
    if (near(p, [255, 0, 255], 10)) ++car;
    else if (near(p, [255, 255, 255], 6)) ++plan;
    else if (rolloutRamp.some((c) => near(p, c, 12))) ++rollout;
    else if (trailRamp.some((c) => near(p, c, 12))) ++trailPx;
  }
  const result = { ...extra, car_pixels: car, rollout_pixels: rollout, plan_pixels: plan, trail_pixels: trailPx,
                   charts: Object.keys(charts).length, uplot: typeof uPlot === 'function' };
  document.title = 'OCS-TEST ' + JSON.stringify(result);
  const el = $('test-report');  // with the map's pixels, for a check independent of these counts
  el.textContent = JSON.stringify({ ...result, canvas_png: canvas.toDataURL('image/png') });
  el.hidden = false;
}

// ---- start ----
(async () => {
  makeCharts();
  const info = await (await fetch('/api/info')).json();
  const track = info.has_track ? await (await fetch('/api/track')).json() : null;
  let rec = null;
  if (info.mode === 'replay') rec = await (await fetch('/api/recording')).json();
  if (track) fitView(...track.bounds);
  else if (rec) {
    const xs = rec.columns.x.filter((v) => v !== null), ys = rec.columns.y.filter((v) => v !== null);
    fitView(Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys));
  }
  drawBackground(track);
  drawScene(null);
  if (info.mode === 'live') startLive(info);
  else startReplay(rec);
})();
