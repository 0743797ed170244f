// Load for telegrasp-view measurements: N Foxglove clients (@foxglove/ws-protocol over ws) that
// subscribe to every channel for S seconds, then print one JSON line with what each received
// (messages and payload bytes per channel). --slow K makes the first K clients stop reading their
// socket for 2 s of every 3 (a viewer on a bad link), to show the bridge drops their frames
// (newest wins) instead of slowing down.
// Usage: node view_viewers.mjs --url ws://127.0.0.1:8765 [--clients 4] [--duration-s 20] [--slow 0]
import { need } from "./view_common.mjs";

const ws = await need("ws");
const protocol = await need("@foxglove/ws-protocol");
const WebSocket = ws.WebSocket ?? ws.default;
const FoxgloveClient = protocol.FoxgloveClient ?? protocol.default?.FoxgloveClient;

const args = process.argv.slice(2);
const get = (flag, fallback) => (args.includes(flag) ? args[args.indexOf(flag) + 1] : fallback);
const url = get("--url", "ws://127.0.0.1:8765");
const clients = Number(get("--clients", 4));
const seconds = Number(get("--duration-s", 20));
const slow = Number(get("--slow", 0));

const results = [];
for (let i = 0; i < clients; ++i) {
  const socket = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  const client = new FoxgloveClient({ ws: socket });
  const r = { client: i, slow: i < slow, channels: {} };
  results.push(r);
  const topicOf = new Map();
  client.on("advertise", (channels) => {
    for (const c of channels) topicOf.set(client.subscribe(c.id), c.topic);
  });
  client.on("message", ({ subscriptionId, data }) => {
    const topic = topicOf.get(subscriptionId);
    const c = (r.channels[topic] ??= { messages: 0, kb: 0 });
    ++c.messages;
    c.kb += data.byteLength / 1024;
  });
  if (i < slow)
    setInterval(() => {
      socket._socket?.pause();
      setTimeout(() => socket._socket?.resume(), 2000);
    }, 3000);
  setTimeout(() => client.close(), seconds * 1000);
}
setTimeout(() => {
  for (const r of results) for (const c of Object.values(r.channels)) c.kb = Math.round(c.kb);
  console.log(JSON.stringify({ seconds, results }));
  process.exit(0);
}, seconds * 1000 + 500);
