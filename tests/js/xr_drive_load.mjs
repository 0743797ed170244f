// How many headsets one telegrasp-view --drive serves: N synthetic WebSocket clients speaking the
// controller-input contract (what /xr sends), each driving a right hand at 90 Hz along a slow
// circle, against a live telegrasp-server (--relay xr-) over loopback DDS. Per N it reports the
// round trip from a sample's sending to the arrival of the late-latched skeleton reflecting it
// (p50, p99; page -> bridge -> server -> bridge -> page, no browser), the share of samples the
// bridge forwarded, and the bridge's CPU per driven hand (its --stats).
// Usage: BUILD/bin/telegrasp-test-domains node xr_drive_load.mjs --bin BUILD/bin --out DIR
//          [--connections 1,8,32,64] [--duration-s 10]
// Prints one JSON line per N, and a table.
import fs from "node:fs";
import path from "node:path";
import { fatal, need, options, sleep, start, stop, testDomain, until } from "./view_common.mjs";

const { WebSocket } = await need("ws");
const { bin, out } = options();
const args = process.argv.slice(2);
const arg = (flag, fallback) => (args.includes(flag) ? args[args.indexOf(flag) + 1] : fallback);
const counts = arg("--connections", "1,8,32,64").split(",").map(Number);
const seconds = Number(arg("--duration-s", "10"));
if (counts.some((n) => !(n >= 1 && n <= 256)) || !(seconds > 0)) fatal("--connections N,N.. in 1..256, --duration-s > 0");
const domain = testDomain();

const server = start(path.join(bin, "telegrasp-server"), ["--domain", String(domain), "--profile", "loopback",
  "--empty-scene", "--relay", "xr-:256"], { log: path.join(out, "load-server.log") });
let port = null;
const stats = [];
const view = start(path.join(bin, "telegrasp-view"), ["--domain", String(domain), "--profile", "loopback", "--port", "0",
  "--address", "127.0.0.1", "--drive", "--stats", "1"], {
  log: path.join(out, "load-view.stdout.log"),
  onLine: (line) => {
    const m = line.match(/http:\/\/127\.0\.0\.1:(\d+)\/ \(page\)/);
    if (m) port = Number(m[1]);
  },
});
// --stats lines arrive on stderr: follow the log file.
const statsLog = path.join(out, "load-view.stderr.log");
view.stderr.on("data", (d) => {
  fs.appendFileSync(statsLog, d);
  for (const line of d.toString().split("\n")) if (line.startsWith("{")) stats.push({ at: Date.now(), ...JSON.parse(line) });
});
if (!(await until(() => port !== null, 20000, "telegrasp-view"))) fatal("telegrasp-view did not start");
await sleep(2000);  // the server claims its scene
if (server.exitCode !== null) fatal(`telegrasp-server stopped: ${fs.readFileSync(path.join(out, "load-server.log"), "utf8")}`);

function client(index) {
  const c = { sent: new Map(), rtts: [], seq: 0, ready: false, skeletons: 0, latched: 0 };
  c.ws = new WebSocket(`ws://127.0.0.1:${port}/`, ["foxglove.websocket.v1"]);
  c.ws.on("message", (data, binary) => {
    if (!binary) {
      const m = JSON.parse(data.toString());
      if (m.op === "advertise" && m.channels.some((ch) => ch.topic === "/xr/hands")) {
        const hands = m.channels.find((ch) => ch.topic === "/xr/hands");
        c.ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 1, channelId: hands.id }] }));
        c.ws.send(JSON.stringify({ op: "advertise", channels: [{ id: 9, topic: "/controller_state", encoding: "json",
          schemaName: "telegrasp.ControllerInput" }] }));
        c.ready = true;
      }
    } else if (data.length > 13) {
      const h = JSON.parse(data.subarray(13).toString());
      ++c.skeletons;
      if (h.late_latched) ++c.latched;
      const t = c.sent.get(h.input_seq);
      if (h.late_latched && t !== undefined) {
        c.rtts.push(performance.now() - t);
        c.sent.delete(h.input_seq);
      }
    }
  });
  c.send = (time) => {
    const a = time / 2000 + index;
    const seq = ++c.seq;
    const body = Buffer.from(JSON.stringify({ side: "right", pose: { position: { x: 0.3 * Math.cos(a) + (index % 16) * 0.05,
      y: 0.3 * Math.sin(a) + Math.floor(index / 16) * 0.05, z: 0.3 }, orientation: { x: 0, y: 0, z: 0, w: 1 } },
    trigger: 0, seq }));
    const frame = Buffer.alloc(5 + body.length);
    frame[0] = 1;
    frame.writeUInt32LE(9, 1);
    body.copy(frame, 5);
    c.sent.set(seq, performance.now());
    if (c.sent.size > 512) c.sent.delete(c.sent.keys().next().value);
    c.ws.send(frame);
  };
  return c;
}

const percentile = (v, q) => (v.length ? [...v].sort((a, b) => a - b)[Math.min(v.length - 1, Math.floor(q * v.length))] : null);
const rows = [];
for (const n of counts) {
  const clients = Array.from({ length: n }, (_, i) => client(i));
  await until(() => clients.every((c) => c.ready), 20000, `${n} connections`);
  // Warm up a second (hands join the scene), then measure.
  const period = 1000 / 90;
  let next = performance.now();
  const warmUntil = next + 1000, endAt = warmUntil + seconds * 1000;
  let sentMeasured = 0;
  let statsFrom = null;
  while (performance.now() < endAt) {
    const now = performance.now();
    if (now >= warmUntil && statsFrom === null) {
      for (const c of clients) c.rtts = [];
      statsFrom = Date.now();
    }
    for (const c of clients) c.send(now);
    if (statsFrom !== null) sentMeasured += n;
    next += period;
    await sleep(Math.max(0, next - performance.now()));
  }
  const endWall = Date.now();
  await sleep(1500);
  const window = stats.filter((s) => s.at > statsFrom + 1000 && s.at <= endWall + 500);
  const forwarded = window.length >= 2 ? window.at(-1).drive.samples_forwarded - window[0].drive.samples_forwarded : 0;
  const windowS = window.length >= 2 ? window.length - 1 : 1;
  const cpu = window.length ? window.reduce((a, s) => a + s.cpu_percent, 0) / window.length : null;
  const rtts = clients.flatMap((c) => c.rtts);
  const row = { connections: n, samples_per_s_sent: n * 90, forwarded_per_s: forwarded / windowS,
    forwarded_share: forwarded / windowS / (n * 90), rtt_ms_p50: percentile(rtts, 0.5), rtt_ms_p99: percentile(rtts, 0.99),
    matched: rtts.length, skeletons: clients.reduce((a, c) => a + c.skeletons, 0), latched: clients.reduce((a, c) => a + c.latched, 0), bridge_cpu_percent: cpu, bridge_cpu_us_per_hand_sample: cpu === null ? null : (cpu / 100) * 1e6 / (n * 90) };
  rows.push(row);
  console.log(JSON.stringify(row));
  for (const c of clients) c.ws.close();
  await sleep(1500);
}
console.log("connections  forwarded  rtt p50 ms  rtt p99 ms  bridge CPU %  us CPU/sample");
for (const r of rows)
  console.log(`${String(r.connections).padStart(11)}  ${(100 * r.forwarded_share).toFixed(1).padStart(8)}%  ${r.rtt_ms_p50?.toFixed(2).padStart(10)}  ` +
    `${r.rtt_ms_p99?.toFixed(2).padStart(10)}  ${r.bridge_cpu_percent?.toFixed(1).padStart(12)}  ${r.bridge_cpu_us_per_hand_sample?.toFixed(1).padStart(13)}`);
await Promise.all([stop(view), stop(server)]);
process.exit(0);
