// SPDX-License-Identifier: Apache-2.0
// tacse3 web view: live (tacse3d --http) it reads /api/stream (Server-Sent Events), /api/fields
// and the pads' JPEGs (docs/viewer.md) and draws them; its only write is POST /api/command, from
// the control buttons, which are greyed out unless the board enables the controls. On a
// recording (tacse3-replay --view, /api/info has "recording") it shows the frame the scrubber or
// play picks, with the recording's truth when it has one.
'use strict';

const WINDOW_S = 10;       // rolling plots
const IMAGE_PERIOD_MS = 200;  // images and fields at 5 Hz; the scalars at the stream's rate
const PADS = ['left', 'right'];
const $ = (id) => document.getElementById(id);
const fmt = (x, d) => (x === null || x === undefined || !isFinite(x) ? '-' : x.toFixed(d));

// --- pose: angle and axis of the unit quaternion [w, x, y, z], in degrees ---
function angleAxis(q) {
  let [w, x, y, z] = q;
  if (w < 0) { w = -w; x = -x; y = -y; z = -z; }  // the short way round
  const s = Math.hypot(x, y, z);
  const angle = 2 * Math.atan2(s, w) * 180 / Math.PI;
  return s < 1e-12 ? { angle: 0, axis: [0, 0, 1] } : { angle, axis: [x / s, y / s, z / s] };
}

// --- 3D view: G's axes and the object's frame, a fixed orthographic oblique projection ---
// The view looks at G's origin from the direction EYE (in G), with G's x axis (along the fingers)
// pointing up the screen. The object's frame is G's moved by the pose: axes R(q) e_i from the
// origin p (docs/recording-format.md: g(t) = R(q) g0 + p), p magnified POSE_P_SCALE times.
const POSE_AXIS_MM = 10;      // every drawn axis is 10 mm long
const POSE_P_SCALE = 5;       // the displacement p is drawn 5x
const POSE_PX_PER_MM = 9;     // canvas pixels per (drawn) millimetre
const EYE = [-0.3, -0.4, 0.87];  // near G z: a turn about the grasp axis shows in the plane
const UP = [1, 0, 0];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                         a[0] * b[1] - a[1] * b[0]];
const unit = (a) => { const n = Math.hypot(...a); return a.map((x) => x / n); };
// The screen's right and up directions in G: right = up x eye, up' = eye x right.
function viewBasis(eye, up) {
  const e = unit(eye);
  const right = unit(cross(up, e));
  return { right, up: cross(e, right) };
}
// R(q) v for a unit quaternion [w, x, y, z] (Hamilton): v + 2w (u x v) + 2 u x (u x v).
function rotate(q, v) {
  const u = [q[1], q[2], q[3]];
  const t = cross(u, v).map((c) => 2 * c);
  const ut = cross(u, t);
  return [0, 1, 2].map((i) => v[i] + q[0] * t[i] + ut[i]);
}
// A point of G in mm to canvas pixels (centre cx, cy; the canvas y axis points down).
function project(basis, cx, cy, g) {
  return [cx + POSE_PX_PER_MM * dot(basis.right, g), cy - POSE_PX_PER_MM * dot(basis.up, g)];
}
// The end points to draw: G's origin and axis tips, the object's origin and axis tips, in pixels.
function poseAxes(q, p, cx, cy) {
  const basis = viewBasis(EYE, UP);
  const e = [[POSE_AXIS_MM, 0, 0], [0, POSE_AXIS_MM, 0], [0, 0, POSE_AXIS_MM]];
  const o = p.map((x) => (x === null ? 0 : x * 1e3 * POSE_P_SCALE));
  const at = (g) => project(basis, cx, cy, g);
  return {
    g: { origin: at([0, 0, 0]), axes: e.map(at) },
    object: { origin: at(o), axes: e.map((v) => at(rotate(q, v).map((c, i) => c + o[i]))) },
  };
}
const AXIS_COLOURS = ['#d62728', '#2ca02c', '#1f77b4'];  // x red, y green, z blue
function drawFrame(g, f, width, dash, label) {
  g.lineWidth = width;
  g.setLineDash(dash);
  f.axes.forEach((tip, i) => {
    g.strokeStyle = AXIS_COLOURS[i];
    g.beginPath();
    g.moveTo(f.origin[0], f.origin[1]);
    g.lineTo(tip[0], tip[1]);
    g.stroke();
    g.fillStyle = AXIS_COLOURS[i];
    g.fillText(label + 'xyz'[i], tip[0] + 3, tip[1] - 3);
  });
  g.setLineDash([]);
}
let drawnPose = null;  // what the 3D view drew last (the browser test reads it)
function drawPose3d(q, p, truth) {
  const canvas = $('pose3d');
  const g = canvas.getContext('2d');
  g.clearRect(0, 0, canvas.width, canvas.height);
  g.font = '12px sans-serif';
  const cx = canvas.width / 2, cy = canvas.height / 2;
  const a = poseAxes(q, p, cx, cy);
  drawFrame(g, a.g, 1, [2, 3], 'G ');
  if (truth) drawFrame(g, poseAxes(truth.q, truth.p, cx, cy).object, 1.5, [6, 4], 'truth ');
  drawFrame(g, a.object, 3, [], '');
  drawnPose = { q, p, basis: viewBasis(EYE, UP), cx, cy, axis_mm: POSE_AXIS_MM,
                p_scale: POSE_P_SCALE, px_per_mm: POSE_PX_PER_MM, ...a };
}

// --- plots ---
const series = { t: [], w: [[], [], []], v: [[], [], []], rot: [[], [], []], area: [[], []],
                 conf: [], dsp: [], latency: [], truth: [[], [], []] };
const plots = [];
function makePlot(el, title, labels, columns, unit) {
  if (typeof uPlot === 'undefined') return;
  const colours = ['#c0392b', '#27ae60', '#2471a3'];
  const opts = {
    title, width: 460, height: 180,
    scales: { x: { time: false } },
    axes: [{ label: 's' }, { label: unit }],
    // A truth series is dashed, in its estimate's colour.
    series: [{}].concat(labels.map((l, i) => ({ label: l, stroke: colours[i % 3], width: 1.5,
                                                 dash: l.startsWith('truth') ? [6, 4] : [] }))),
  };
  plots.push({ plot: new uPlot(opts, [[]].concat(labels.map(() => [])), el), columns });
}
function setupPlots(withTruth) {
  if (typeof uPlot === 'undefined') { $('plots-missing').hidden = false; return; }
  makePlot($('plot-w'), 'angular twist ω', ['x', 'y', 'z'], () => series.w, 'deg/s');
  makePlot($('plot-v'), 'linear twist v', ['x', 'y', 'z'], () => series.v, 'mm/s');
  if (withTruth) {
    makePlot($('plot-angles'), 'pose rotation vector, truth dashed',
             ['x', 'y', 'z', 'truth x', 'truth y', 'truth z'],
             () => series.rot.concat(series.truth), 'deg');
  } else {
    makePlot($('plot-angles'), 'pose rotation vector', ['x', 'y', 'z'], () => series.rot, 'deg');
  }
  makePlot($('plot-area'), 'contact area', ['left', 'right'], () => series.area, 'mm²');
  makePlot($('plot-conf'), 'confidence', ['confidence'], () => [series.conf], '');
  makePlot($('plot-timing'), 'timing', ['dsp', 'latency'], () => [series.dsp, series.latency],
           'µs');
}
let t0_us = null;  // the plots' time axis: seconds since the page's first snapshot
// Appends snapshot s to the plots' series; live, only the last WINDOW_S seconds are kept.
function record(s, keepAll) {
  if (t0_us === null) t0_us = s.t_us;
  const t = (s.t_us - t0_us) / 1e6;
  const deg = 180 / Math.PI;
  const aa = angleAxis(s.pose.q);
  const push = (arr, v) => arr.push(v === null ? null : v);
  series.t.push(t);
  for (let i = 0; i < 3; i++) {
    push(series.w[i], s.twist.w[i] === null ? null : s.twist.w[i] * deg);
    push(series.v[i], s.twist.v[i] === null ? null : s.twist.v[i] * 1e3);
    series.rot[i].push(aa.angle * aa.axis[i]);
  }
  if (s.truth) {
    const ta = angleAxis(s.truth.q);
    for (let i = 0; i < 3; i++) series.truth[i].push(ta.angle * ta.axis[i]);
  }
  PADS.forEach((p, i) => series.area[i].push(s.sensors[p].contact_area_m2 * 1e6));
  push(series.conf, s.confidence);
  series.dsp.push(s.dsp_us < 0 ? null : s.dsp_us);
  series.latency.push(s.latency_us < 0 ? null : s.latency_us);
  if (keepAll) return;
  let drop = 0;
  while (drop < series.t.length && series.t[drop] < t - WINDOW_S) drop++;
  if (drop > 0) {
    const cut = (a) => a.splice(0, drop);
    cut(series.t); series.w.forEach(cut); series.v.forEach(cut); series.rot.forEach(cut);
    series.area.forEach(cut); cut(series.conf); cut(series.dsp); cut(series.latency);
  }
}
function redrawPlots() {
  for (const p of plots) p.plot.setData([series.t].concat(p.columns()));
}

// --- scalars ---
let last = null;
function show(s) {
  showScalars(s);
  record(s, false);
}
function showScalars(s) {
  last = s;
  const st = $('state');
  st.textContent = s.state;
  st.className = 'badge ' + ({ TRACKING: 'ok', NO_CONTACT: 'ok', FAULT: 'bad' }[s.state] || 'warn');
  $('calibrated').hidden = s.calibrated;
  $('cycle').textContent = s.cycle;
  $('t').textContent = fmt(s.t_us / 1e6, 3);
  $('confidence').textContent = fmt(s.confidence, 2);
  $('dsp').textContent = s.dsp_us;
  $('latency').textContent = s.latency_us;
  const aa = angleAxis(s.pose.q);
  $('angle').textContent = fmt(aa.angle, 2);
  $('axis').textContent = '(' + aa.axis.map((a) => fmt(a, 3)).join(', ') + ')';
  $('position').textContent = '(' + s.pose.p.map((a) => fmt(a * 1e3, 2)).join(', ') + ')';
  drawPose3d(s.pose.q, s.pose.p, s.truth);
  $('truth-caption').hidden = !s.truth;
  const c = s.counters;
  $('counters').textContent = `cycles sent ${c.cycles_sent}, CAN send failures ${c.can_send_failures}, ` +
    `CAN tx dropped ${c.can_tx_dropped}, commands ${c.commands} (${c.rejected_commands} rejected)`;
  for (const p of PADS) {
    const d = s.sensors[p];
    const el = document.querySelector('#pad-' + p + ' .padstate');
    el.textContent = !d.configured ? 'not on this board'
      : `${d.health}  ${d.contact ? (d.slipping ? 'SLIP' : 'STICK') : 'no contact'}  ` +
        `area ${fmt(d.contact_area_m2 * 1e6, 1)} mm²  tracked ${fmt(d.tracked_fraction * 100, 0)} %  ` +
        `frames ${d.frames} (${d.dropped} dropped)`;
  }
}

// --- images and overlays ---
const images = {};
const shearScale = { left: 0, right: 0 };
const SHEAR_SCALE_DECAY = 0.98;  // per drawing at 5 Hz: the scale halves in about 7 s
let fields = null;
function drawPad(p) {
  const canvas = document.querySelector('#pad-' + p + ' canvas');
  const g = canvas.getContext('2d');
  g.clearRect(0, 0, canvas.width, canvas.height);
  if (images[p]) g.drawImage(images[p], 0, 0, canvas.width, canvas.height);
  if (!fields || !fields[p]) return;
  const gw = fields.grid.width, gh = fields.grid.height;
  const cw = canvas.width / gw, ch = canvas.height / gh;
  const f = fields[p];
  if ($('show-fz').checked) {
    let max = 0;
    for (const v of f.fz) max = Math.max(max, Math.abs(v));
    if (max > 0) {
      for (let i = 0; i < f.fz.length; i++) {
        const a = Math.max(0, f.fz[i]) / max;
        if (a <= 0.02) continue;
        g.fillStyle = `rgba(255, ${Math.round(200 * (1 - a))}, 0, ${0.6 * a})`;
        g.fillRect((i % gw) * cw, Math.floor(i / gw) * ch, cw, ch);
      }
    }
  }
  if ($('show-contact').checked) {
    // The outline of Ω: every cell edge between a contact cell and a non-contact one.
    g.strokeStyle = '#00e5ff';
    g.lineWidth = 2;
    g.beginPath();
    const at = (x, y) => x >= 0 && y >= 0 && x < gw && y < gh && f.mask[y * gw + x] === 1;
    for (let y = 0; y < gh; y++) {
      for (let x = 0; x < gw; x++) {
        if (!at(x, y)) continue;
        const x0 = x * cw, y0 = y * ch;
        if (!at(x, y - 1)) { g.moveTo(x0, y0); g.lineTo(x0 + cw, y0); }
        if (!at(x, y + 1)) { g.moveTo(x0, y0 + ch); g.lineTo(x0 + cw, y0 + ch); }
        if (!at(x - 1, y)) { g.moveTo(x0, y0); g.lineTo(x0, y0 + ch); }
        if (!at(x + 1, y)) { g.moveTo(x0 + cw, y0); g.lineTo(x0 + cw, y0 + ch); }
      }
    }
    g.stroke();
  }
  if ($('show-shear').checked) {
    // Every second grid point; the largest shear of the last seconds spans two grid cells (a
    // decaying maximum: after a release the gel's noise is not blown up to full length).
    let max = 0;
    for (let i = 0; i < f.shear_x.length; i++) max = Math.max(max, Math.hypot(f.shear_x[i], f.shear_y[i]));
    max = shearScale[p] = Math.max(max, shearScale[p] * SHEAR_SCALE_DECAY);
    if (max > 0) {
      const k = 2 * cw / max;
      g.strokeStyle = '#ffeb3b';
      g.lineWidth = 1.2;
      g.beginPath();
      for (let y = 0; y < gh; y += 2) {
        for (let x = 0; x < gw; x += 2) {
          const i = y * gw + x;
          const dx = f.shear_x[i] * k, dy = f.shear_y[i] * k;
          if (Math.hypot(dx, dy) < 1.5) continue;
          const x0 = (x + 0.5) * cw, y0 = (y + 0.5) * ch;
          g.moveTo(x0, y0);
          g.lineTo(x0 + dx, y0 + dy);
          const a = Math.atan2(dy, dx);
          g.lineTo(x0 + dx - 4 * Math.cos(a - 0.5), y0 + dy - 4 * Math.sin(a - 0.5));
        }
      }
      g.stroke();
    }
  }
}
async function refreshImages() {
  try {
    const r = await fetch('api/fields', { cache: 'no-store' });
    if (r.ok) fields = await r.json();
    for (const p of PADS) {
      if (last && !last.sensors[p].configured) continue;
      const ir = await fetch('api/image/' + p + '.jpg', { cache: 'no-store' });
      if (ir.ok) images[p] = await createImageBitmap(await ir.blob());
    }
  } catch (e) { /* the daemon went away: the stream badge says so */ }
  PADS.forEach(drawPad);
  setTimeout(refreshImages, IMAGE_PERIOD_MS);
}

// --- stream ---
function connect() {
  const es = new EventSource('api/stream');
  es.addEventListener('state', (ev) => {
    $('link').textContent = 'live';
    $('link').className = 'badge ok';
    show(JSON.parse(ev.data));
  });
  es.onerror = () => {
    $('link').textContent = 'stream lost, retrying';
    $('link').className = 'badge bad';
  };
}

async function showInfo() {
  try {
    const r = await fetch('api/info');
    const i = await r.json();
    const cal = `calibration ${i.calibration === null ? 'built-in defaults' : i.calibration}`;
    $('info').textContent = i.recording
      ? `recording ${i.recording}, ${cal}, tacse3-replay ${i.version}`
      : `board ${i.board} (${i.board_file}), ${cal}, tacse3d ${i.version}`;
    if (!i.recording) setupControls(i);
    return i;
  } catch (e) { return null; /* shown as "-" */ }
}

// --- controls: each button posts one command; the daemon's ACK/NACK is shown as it came ---
const COMMANDS = {
  'cmd-tare': { command: 'tare' },
  'cmd-reset-pose': { command: 'reset_pose' },
  'cmd-stream-on': { command: 'stream', on: true },
  'cmd-stream-off': { command: 'stream', on: false },
};

function setupControls(info) {
  if (!info.controls) {
    $('controls-off').textContent = 'Controls disabled: ' + info.controls_off;
    $('controls-off').hidden = false;
    return;
  }
  for (const [id, body] of Object.entries(COMMANDS)) {
    $(id).disabled = false;
    $(id).addEventListener('click', () => send(body));
  }
}

async function send(body) {
  const ack = $('ack');
  ack.textContent = `${body.command}: sent`;
  ack.className = '';
  try {
    const r = await fetch('api/command', {
      method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify(body),
    });
    const a = await r.json();
    if (a.result !== undefined) {
      ack.textContent = `${a.command}: ${a.ack ? 'ACK' : 'NACK ' + a.result} (code ${a.code}, ` +
        `sequence ${a.sequence})`;
      ack.className = a.ack ? 'ack-ok' : 'ack-bad';
    } else {
      ack.textContent = `${body.command}: HTTP ${r.status}: ${a.error}`;
      ack.className = 'ack-bad';
    }
  } catch (e) {
    ack.textContent = `${body.command}: no answer (${e})`;
    ack.className = 'ack-bad';
  }
}

// --- a recording: the scrubber and play pick the frame; every frame is in the plots ---
const rec = { states: [], index: 0, shown: -1, playing: false, wall0: 0, t0: 0, asked: 0 };

async function getJson(url) {
  const r = await fetch(url, { cache: 'no-store' });
  return r.ok ? r.json() : null;
}

async function getImage(url) {
  const r = await fetch(url, { cache: 'no-store' });
  return r.ok ? createImageBitmap(await r.blob()) : null;
}

// Fetches frame i's state, fields and images and shows them (unless a later frame was asked for
// meanwhile).
async function showFrame(i) {
  rec.index = i;
  const ticket = ++rec.asked;
  $('frame').value = i;
  const q = '?frame=' + i;
  const [s, f] = await Promise.all([getJson('api/state' + q), getJson('api/fields' + q)]);
  if (!s) return;
  const imgs = await Promise.all(PADS.map((p) => (s.sensors[p].configured
    ? getImage('api/image/' + p + '.jpg' + q) : null)));
  if (ticket !== rec.asked) return;
  fields = f;
  PADS.forEach((p, k) => { images[p] = imgs[k]; });
  showScalars(s);
  PADS.forEach(drawPad);
  $('frame-index').textContent = i;
  rec.shown = i;
}

// Play at the recording's rate: each tick shows the last frame whose time has come.
async function tick() {
  if (!rec.playing) return;
  const n = rec.states.length;
  const target = rec.t0 + (performance.now() - rec.wall0) * 1000;
  let i = rec.index;
  while (i + 1 < n && rec.states[i + 1].t_us <= target) i++;
  if (i !== rec.shown) await showFrame(i);
  if (i >= n - 1) { setPlaying(false); return; }
  setTimeout(tick, 1000 / 30);
}

function setPlaying(on) {
  rec.playing = on;
  $('play').textContent = on ? 'pause' : 'play';
  if (!on) return;
  if (rec.index >= rec.states.length - 1) rec.index = 0;
  rec.wall0 = performance.now();
  rec.t0 = rec.states[rec.index].t_us;
  tick();
}

async function startRecording(info) {
  document.title = 'tacse3-replay: ' + info.recording;
  $('title').textContent = 'tacse3-replay';
  $('link').hidden = true;
  document.querySelector('section.controls').hidden = true;
  $('recording').hidden = false;
  $('plots-title').textContent = 'the recording';
  // A replay has no DSP timing, latency or CAN counters.
  for (const el of [$('dsp').parentElement, $('latency').parentElement, $('counters'),
                    $('plot-timing')]) el.hidden = true;
  const r = await getJson('api/frames');
  rec.states = r.states;
  setupPlots(r.states.some((s) => s.truth !== undefined));
  for (const s of r.states) record(s, true);
  redrawPlots();
  $('frame').max = r.frames - 1;
  $('frame-count').textContent = r.frames;
  $('frame').addEventListener('input', () => { setPlaying(false); showFrame(+$('frame').value); });
  $('play').addEventListener('click', () => setPlaying(!rec.playing));
  await showFrame(0);
}

async function start() {
  const info = await showInfo();
  if (info && info.recording) return startRecording(info);
  setupPlots(false);
  connect();
  refreshImages();
  setInterval(redrawPlots, 100);
}

for (const id of ['show-shear', 'show-contact', 'show-fz'])
  $(id).addEventListener('change', () => PADS.forEach(drawPad));
start();
// For the browser tests.
window.tacse3 = { series, last: () => last, plots: () => plots.length, pose3d: () => drawnPose,
                   poseAxes, plotData: (k) => plots[k].plot.data,
                   recording: () => ({ index: rec.index, shown: rec.shown,
                                       frames: rec.states.length, playing: rec.playing }) };
