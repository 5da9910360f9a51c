// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: decodes a candump -L log through the DBC with candied (an independent decoder).
//
// usage: node decode_log.mjs LOG DBC [DBC...]   (one DBC per node id, from tacse3-dbcgen --node)
// Every signal position, width, sign, factor and value name comes from the DBC as candied parses
// it; this script adds only what a DBC cannot say and docs/can-protocol.md specifies: the CRC-8
// check and the cycle reassembly rule. Output: JSON lines with tacse3-canmon's keys.
import fs from 'node:fs';
import candied from 'candied';

const { Dbc, Can } = candied;
const [logPath, ...dbcPaths] = process.argv.slice(2);
if (!logPath || dbcPaths.length === 0) {
  console.error('usage: node decode_log.mjs LOG DBC [DBC...]');
  process.exit(2);
}
const decoders = dbcPaths.map((path) => {
  const dbcText = fs.readFileSync(path, 'utf8');
  const data = new Dbc().load(dbcText);
  // candied 2.2.0 reads a message size as a single digit ("BO_ 38 CycleFd: 64" -> 6); take the
  // sizes from the BO_ lines so CAN FD messages decode.
  for (const m of dbcText.matchAll(/^BO_ (\d+) (\w+): (\d+) /gm)) {
    const msg = data.messages.get(m[2]);
    if (msg) msg.dlc = Number(m[3]);
  }
  const can = new Can();
  can.database = data;
  return can;
});
function decodeFrame(frame) {
  for (const can of decoders) {
    const bound = can.decode(frame);
    if (bound) return bound;
  }
  return undefined;
}

function crc8(bytes) {
  let c = 0xff;
  for (const b of bytes) {
    c ^= b;
    for (let i = 0; i < 8; i++) c = c & 0x80 ? ((c << 1) ^ 0x1d) & 0xff : (c << 1) & 0xff;
  }
  return c ^ 0xff;
}

// Signal value as the DBC defines it: a VAL_ name "INVALID" -> null, other VAL_ names -> the
// name, otherwise the scaled value (candied's `value`).
function signalValue(sig) {
  const table = sig.boundData.signal.valueTable;
  if (table && table.has(sig.rawValue)) {
    const name = table.get(sig.rawValue);
    return name === 'INVALID' ? null : name;
  }
  if (table && sig.boundData.signal.valueTable.size > 1) return sig.rawValue;  // unknown enum
  return sig.value;
}

// Signals of a decoded message, honouring the multiplexor (candied decodes all of them).
function signals(bound) {
  const out = {};
  let mux = null;
  for (const [name, s] of bound.boundSignals) {
    if (s.boundData.signal.multiplexer) mux = s.rawValue;
  }
  for (const [name, s] of bound.boundSignals) {
    const m = s.boundData.signal.multiplex;
    if (m && m.startsWith('m') && Number(m.slice(1)) !== mux) continue;
    out[name] = signalValue(s);
  }
  return out;
}

const CYCLE_PARTS = ['Timestamp', 'TwistAngular', 'TwistLinear', 'PoseOrientation', 'PosePosition'];
const nodes = new Map();
let crcErrors = 0;
const emit = (o) => process.stdout.write(JSON.stringify(o) + '\n');

function nodeState(node) {
  if (!nodes.has(node)) {
    nodes.set(node, { counter: null, complete: false, parts: {}, lastT: null, cycles: 0 });
  }
  return nodes.get(node);
}

function emitCycle(node, counter, p) {
  const ts = p.Timestamp;
  const b = (v) => v === 1;
  return {
    type: 'cycle', node, counter, t_us: ts.SampleTime,
    valid: b(ts.EstimateValid), single_sensor: b(ts.SingleSensor),
    pose_reset: b(ts.PoseReset), saturated: b(ts.Saturated),
    wx: p.TwistAngular.AngVelX, wy: p.TwistAngular.AngVelY, wz: p.TwistAngular.AngVelZ,
    vx: p.TwistLinear.LinVelX, vy: p.TwistLinear.LinVelY, vz: p.TwistLinear.LinVelZ,
    qw: p.PoseOrientation.QuatW, qx: p.PoseOrientation.QuatX,
    qy: p.PoseOrientation.QuatY, qz: p.PoseOrientation.QuatZ,
    px: p.PosePosition.PosX, py: p.PosePosition.PosY, pz: p.PosePosition.PosZ,
    sat_w: [b(p.TwistAngular.AngVelXSat), b(p.TwistAngular.AngVelYSat), b(p.TwistAngular.AngVelZSat)],
    sat_v: [b(p.TwistLinear.LinVelXSat), b(p.TwistLinear.LinVelYSat), b(p.TwistLinear.LinVelZSat)],
    sat_p: [b(p.PosePosition.PosXSat), b(p.PosePosition.PosYSat), b(p.PosePosition.PosZSat)],
  };
}

// The reassembly rule of docs/can-protocol.md ("Cycle reassembly").
function cyclePart(node, counter, parts) {
  const st = nodeState(node);
  if (st.counter === counter) {
    if (st.complete || Object.keys(parts).some((k) => k in st.parts)) return;
  } else if (st.counter !== null) {
    if (((counter - st.counter) & 15) === 15) return;
    st.counter = null;
  }
  if (st.counter === null) Object.assign(st, { counter, complete: false, parts: {} });
  Object.assign(st.parts, parts);
  if (Object.keys(st.parts).length < CYCLE_PARTS.length) return;
  st.complete = true;
  const c = emitCycle(node, counter, st.parts);
  if (c.t_us !== null && st.lastT !== null && c.t_us <= st.lastT) return;
  if (c.t_us !== null) st.lastT = c.t_us;
  st.cycles++;
  emit(c);
}

const lineRe = /^\((\d+)\.(\d+)\)\s+(\S+)\s+([0-9A-Fa-f]+)#(#[0-9A-Fa-f])?([0-9A-Fa-f]*)\s*$/;
for (const line of fs.readFileSync(logPath, 'utf8').split('\n')) {
  const m = lineRe.exec(line);
  if (!m) continue;
  const isExtended = m[4].length === 8;
  const id = parseInt(m[4], 16);
  const payload = (m[6].match(/../g) || []).map((h) => parseInt(h, 16));
  const dbcId = isExtended ? (id | 0x80000000) >>> 0 : id;
  const bound = decodeFrame({ id: dbcId, dlc: payload.length, isExtended, payload });
  if (!bound) continue;  // not in the DBC (or wrong length)
  const word = [dbcId & 0xff, (dbcId >>> 8) & 0xff, (dbcId >>> 16) & 0xff, (dbcId >>> 24) & 0xff];
  if (crc8(word.concat(payload.slice(0, -1))) !== payload[payload.length - 1]) {
    crcErrors++;
    continue;
  }
  const node = (id >> 5) & 0x3f;
  const s = signals(bound);
  const name = bound.name;
  if (CYCLE_PARTS.includes(name)) {
    cyclePart(node, s.Counter, { [name]: s });
  } else if (name === 'CycleFd') {
    const counters = [s.Counter, s.CounterAngular, s.CounterLinear, s.CounterOrientation,
                      s.CounterPosition];
    if (new Set(counters).size !== 1) continue;
    cyclePart(node, s.Counter, Object.fromEntries(CYCLE_PARTS.map((p) => [p, s])));
  } else if (name === 'Status') {
    const b = (v) => v === 1;
    emit({
      type: 'status', node, counter: s.Counter, state: s.State, health_left: s.HealthLeft,
      health_right: s.HealthRight, contact_left: b(s.ContactLeft), contact_right: b(s.ContactRight),
      slip_left: b(s.SlipLeft), slip_right: b(s.SlipRight), stream_enabled: b(s.StreamEnabled),
      fusion: s.FusionMethod, velocity_mode: s.VelocityMode, confidence: s.Confidence,
      rate_divider: s.RateDivider, fault: s.FaultCode, rejected_commands: s.RejectedCommands,
      calibrated: b(s.Calibrated),
    });
  } else if (name === 'StatusContact') {
    emit({ type: 'status_contact', node, counter: s.Counter, area_left: s.AreaLeft,
           area_right: s.AreaRight, confidence_left: s.ConfidenceLeft,
           confidence_right: s.ConfidenceRight });
  } else if (name === 'StatusTiming') {
    emit({ type: 'status_timing', node, counter: s.Counter, dsp_time: s.DspTime,
           latency_p50: s.LatencyP50, latency_p99: s.LatencyP99 });
  } else if (name === 'StatusCounters') {
    emit({ type: 'status_counters', node, counter: s.Counter, dropped_left: s.DroppedLeft,
           dropped_right: s.DroppedRight, can_tx_dropped: s.CanTxDropped });
  } else if (name === 'Ack') {
    emit({ type: 'ack', node, command: s.AckCommand, result: s.AckResult, sequence: s.Sequence });
  } else if (name === 'Command') {
    emit({ type: 'command', node, command: s.CommandCode, target_node: s.TargetNode,
           sequence: s.Sequence });
  }
}
for (const [node, st] of [...nodes].sort((a, b) => a[0] - b[0])) {
  console.error(`decode_log.mjs: node ${node}: ${st.cycles} cycles`);
}
console.error(`decode_log.mjs: ${crcErrors} CRC errors`);
