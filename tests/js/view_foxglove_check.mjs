// telegrasp-view as Foxglove sees it: the npm client @foxglove/ws-protocol (FoxgloveClient over the
// `ws` package) connects to telegrasp-view while a bot grasps over loopback DDS, and telegrasp-echo
// records what the DDS side published at the same time. Checks:
//   1. the advertised channels (/scene, /tf, /grasp_state, /grasp_events, /server_status) with JSON
//      schemas (foxglove.SceneUpdate and foxglove.FrameTransforms as @foxglove/schemas defines them);
//   2. /scene decodes: an entity per hand in its palm frame, capsules (cylinders with sphere caps)
//      in its phalanx frames, one per object of the scene in the object's frame;
//   3. every palm pose on /tf is one the server published for that hand (echo's HandSkeleton,
//      within 1e-6 m and 1e-6 in the quaternion);
//   4. after each grasp, the grasped object's entity is held by that hand, and its /tf poses (sent
//      when it moves: /tf carries the frames that moved) are poses the server published (echo's
//      SceneState), within 20 cm of the holding palm;
//   5. /grasp_events carries the events echo saw (same ids, objects, HandError).
// Usage: BUILD/bin/telegrasp-test-domains node view_foxglove_check.mjs --bin BUILD/bin --out DIR
//   (ctest: client_lib.view.foxglove_client; the wrapper leases the DDS domain)
import path from "node:path";
import { Checks, fatal, need, options, start, startBot, startServerAndView, stop, testDomain, until, sleep } from "./view_common.mjs";

const kPositionTolerance = 1e-6;  // m: the same doubles, printed by two programs
const kQuaternionTolerance = 1e-6;
const kHeldDistance = 0.2;        // m: a held object's origin from its hand's palm, at most

const ws = await need("ws");
const protocol = await need("@foxglove/ws-protocol");
const WebSocket = ws.WebSocket ?? ws.default;
const FoxgloveClient = protocol.FoxgloveClient ?? protocol.default?.FoxgloveClient;
if (!WebSocket || !FoxgloveClient) fatal("ws or @foxglove/ws-protocol lacks WebSocket / FoxgloveClient");

const { bin, out } = options();
const domain = testDomain();
const checks = new Checks("view.foxglove_client");
console.log(`DDS domain ${domain}, artefacts in ${out}`);

// What the DDS side published, from telegrasp-echo.
const echoSkeletons = new Map();   // "client/side" -> [{p, q}]
const echoObjects = new Map();     // object id -> [{p, q}]
const echoEvents = new Map();      // event id -> event
let echoScene = null;              // the newest SceneState
const { server, view, port } = await startServerAndView(bin, out, domain);
const echo = start(path.join(bin, "telegrasp-echo"), ["--domain", String(domain), "--profile", "loopback",
  "--topics", "HandSkeleton,SceneState,GraspEvent"], {
  log: path.join(out, "echo.log"),
  onLine: (line) => {
    const m = JSON.parse(line);
    if (m.topic === "HandSkeleton") {
      const key = `${m.hand.client_id}/${m.hand.side}`;
      if (!echoSkeletons.has(key)) echoSkeletons.set(key, []);
      echoSkeletons.get(key).push(echoPose(m.X_WorldPalm));
    } else if (m.topic === "SceneState") {
      echoScene = m;
      for (const o of m.objects) {
        if (!echoObjects.has(o.id)) echoObjects.set(o.id, []);
        const poses = echoObjects.get(o.id);
        const last = poses[poses.length - 1];
        const pose = echoPose(o.X_WorldObject);
        if (!last || !samePose(last, pose)) poses.push(pose);  // objects at rest: once
      }
    } else if (m.topic === "GraspEvent") {
      echoEvents.set(m.event_id, m);
    }
  },
});

// What the viewer received.
const channels = new Map();        // topic -> advertised channel
const entities = new Map();        // id -> entity
const tfMessages = [];             // [{ frames: Map(child -> {parent, p, q}), world, heldBy: Map(objectId -> hand) }]
const world = new Map();           // every frame as the /tf messages so far leave it (they carry what moved)
const viewEvents = [];
let statusCount = 0;
let graspStateCount = 0;

// telegrasp-echo's pose {p_m, q_wxyz} in the form the checks compare: {p: [x, y, z], q: [w, x, y, z]}.
function echoPose(x) {
  return { p: x.p_m, q: x.q_wxyz };
}

function samePose(a, b) {
  // a, b: {p: [x, y, z], q: [w, x, y, z]}; q and -q are the same rotation.
  const dp = Math.hypot(a.p[0] - b.p[0], a.p[1] - b.p[1], a.p[2] - b.p[2]);
  const dq = (s) => Math.max(...a.q.map((v, i) => Math.abs(v - s * b.q[i])));
  return dp <= kPositionTolerance && Math.min(dq(1), dq(-1)) <= kQuaternionTolerance;
}
const fromTransform = (t) => ({ p: [t.translation.x, t.translation.y, t.translation.z], q: [t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z] });
const meta = (entity) => Object.fromEntries(entity.metadata.map((kv) => [kv.key, kv.value]));

const client = new FoxgloveClient({ ws: new WebSocket(`ws://127.0.0.1:${port}`, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
const topicOf = new Map();
const decoder = new TextDecoder();
client.on("error", (e) => console.error(`FoxgloveClient error: ${e}`));
client.on("advertise", (advertised) => {
  for (const c of advertised) {
    channels.set(c.topic, c);
    topicOf.set(client.subscribe(c.id), c.topic);
  }
});
client.on("message", ({ subscriptionId, data }) => {
  const topic = topicOf.get(subscriptionId);
  const message = JSON.parse(decoder.decode(new Uint8Array(data.buffer, data.byteOffset, data.byteLength)));
  if (topic === "/scene") {
    for (const d of message.deletions) entities.delete(d.id);
    for (const e of message.entities) entities.set(e.id, e);
  } else if (topic === "/tf") {
    const frames = new Map(message.transforms.map((t) => [t.child_frame_id, { parent: t.parent_frame_id, ...fromTransform(t) }]));
    for (const [child, t] of frames) world.set(child, t);
    const heldBy = new Map();
    for (const e of entities.values()) {
      const m = meta(e);
      if (m.kind === "object" && m.held === "true") heldBy.set(Number(e.id.slice(7)), m.holder);
    }
    tfMessages.push({ frames, world: new Map(world), heldBy });
  } else if (topic === "/grasp_events") {
    viewEvents.push(message);
  } else if (topic === "/server_status") {
    ++statusCount;
  } else if (topic === "/grasp_state") {
    ++graspStateCount;
  }
});

// The bot grasps; wait for a grasp by each hand (or the first grasp and 40 s), plus 1.5 s of holding.
const clientId = `viewtest-${process.pid}`;
const bot = startBot(bin, out, domain, clientId);
const graspsBy = () => new Set(viewEvents.filter((e) => e.kind === "grasp").map((e) => e.hand.side));
await until(() => graspsBy().size >= 2 || bot.exitCode !== null, 60000, "a grasp by each hand");
await sleep(1500);
const scene = new Map(entities);  // before the bot goes and the server removes its hands
await stop(bot);
await sleep(500);
client.close();
await stop(echo);
await Promise.all([stop(view), stop(server)]);

// 1. Channels.
const expected = {
  "/scene": "foxglove.SceneUpdate",
  "/tf": "foxglove.FrameTransforms",
  "/grasp_state": "telegrasp.GraspState",
  "/grasp_events": "telegrasp.GraspEvent",
  "/server_status": "telegrasp.ServerStatus",
};
for (const [topic, schemaName] of Object.entries(expected)) {
  const c = channels.get(topic);
  let schema = null;
  try {
    schema = JSON.parse(c?.schema ?? "null");
  } catch {}
  checks.check(c && c.encoding === "json" && c.schemaName === schemaName && c.schemaEncoding === "jsonschema" && schema?.type === "object",
    `channel ${topic} advertised as ${schemaName}, JSON with a jsonschema`);
}
checks.check(JSON.parse(channels.get("/scene")?.schema ?? "{}").title === "foxglove.SceneUpdate" &&
  JSON.parse(channels.get("/tf")?.schema ?? "{}").title === "foxglove.FrameTransforms",
  "/scene and /tf carry the schemas of @foxglove/schemas (titles foxglove.SceneUpdate, foxglove.FrameTransforms)");
checks.check(statusCount > 0 && graspStateCount > 0, `/server_status (${statusCount}) and /grasp_state (${graspStateCount}) messages arrived`);

// 2. Entities.
const hands = [...echoSkeletons.keys()].filter((k) => k.startsWith(clientId + "/"));
checks.check(hands.length === 2, `echo saw both bot hands (${hands.join(", ")})`);
for (const key of hands) {
  const palm = scene.get(`hand/${key}`);
  checks.check(palm && palm.frame_id === `${key}/palm` && meta(palm).kind === "hand" && palm.frame_locked === true,
    `hand ${key}: an entity in frame ${key}/palm`);
  const phalanges = [...scene.values()].filter((e) => e.id.startsWith(`hand/${key}/`));
  checks.check(phalanges.length >= 10 && phalanges.every((e) => e.cylinders.length === 1 && e.spheres.length === 2 &&
    e.frame_id === e.id.slice(5)), `hand ${key}: ${phalanges.length} capsules (a cylinder and two sphere caps each) in their phalanx frames`);
}
const sceneIds = (echoScene?.objects ?? []).map((o) => o.id);
checks.check(sceneIds.length > 0 && sceneIds.every((id) => scene.get(`object/${id}`)?.frame_id === `object/${id}` &&
  world.get(`object/${id}`)?.parent === "world"),
  `every object of the scene (${sceneIds.length}) has an entity and a /tf frame`);

// echo's best-effort reader may miss samples the view got (2 of 14 held poses once, on a fresh
// clone's loaded test run): allow 5 %, or 2 samples when that is more.
const enough = (n) => Math.min(0.95 * n, n - 2);

// 3. Palm poses.
for (const key of hands) {
  const published = echoSkeletons.get(key);
  let seen = 0, matched = 0;
  for (const tf of tfMessages) {
    const palm = tf.frames.get(`${key}/palm`);
    if (!palm) continue;
    ++seen;
    if (published.some((p) => samePose(p, palm))) ++matched;
  }
  checks.check(seen >= 15 && matched >= enough(seen), `hand ${key}: ${matched} of ${seen} palm poses on /tf are poses the server published`);
}

// 4. Grasped objects.
const grasps = viewEvents.filter((e) => e.kind === "grasp" && e.hand.client_id === clientId);
checks.check(grasps.length >= 1, `${grasps.length} grasp events on /grasp_events`);
for (const g of grasps) {
  const key = `${g.hand.client_id}/${g.hand.side}`;
  const frame = `object/${g.object_id}`;
  const held = tfMessages.filter((tf) => tf.heldBy.get(g.object_id) === key && tf.frames.has(frame) && tf.world.has(`${key}/palm`));
  const published = echoObjects.get(g.object_id) ?? [];
  const matched = held.filter((tf) => published.some((p) => samePose(p, tf.frames.get(frame))));
  const near = held.filter((tf) => {
    const o = tf.frames.get(frame).p, p = tf.world.get(`${key}/palm`).p;
    return Math.hypot(o[0] - p[0], o[1] - p[1], o[2] - p[2]) <= kHeldDistance;
  });
  checks.check(held.length >= 3, `${g.object_name} (#${g.object_id}): held by ${key} and moving in ${held.length} /tf messages`);
  checks.check(matched.length >= enough(held.length) && near.length === held.length,
    `${g.object_name}: ${matched.length} of ${held.length} held poses are poses the server published, all within ${kHeldDistance} m of the palm`);
}

// 5. Events.
const sameEvents = viewEvents.filter((e) => {
  const d = echoEvents.get(e.event_id);
  return d && d.kind === e.kind && d.object_id === e.object_id && (e.kind !== "grasp" || d.hand_error_mm === e.hand_error_mm);
});
checks.check(viewEvents.length > 0 && sameEvents.length === viewEvents.length,
  `${sameEvents.length} of ${viewEvents.length} events on /grasp_events match echo's (id, kind, object, HandError)`);

process.exit(checks.finish());
