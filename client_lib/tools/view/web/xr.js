// telegrasp's headset page (/xr on telegrasp-view --drive): WebXR immersive-vr (or -ar with
// passthrough), the server's scene and the server's resolved hands, and each frame's controller or
// tracked-hand input sent to the bridge on /controller_state (telegrasp.ControllerInput; the
// contract is in the view's README, "Driving hands").
//
// Frames. The scene's world is +z up, metres, table top at z = 0. The XR reference space is
// local-floor (+y up, the user looking along -z from the origin at first). X_XR_World, the
// alignment: by default the world's origin is 0.6 m in front of the starting position at 0.8 m
// height, world +x pointing away from the user (XR -z), world +y to the user's left (XR -x). The
// user moves it with "recentre" (A or X on a controller, or the page's button): the table's
// origin goes 0.45 m in front of the headset, 0.45 m below it, turned to face the user. The
// placement is kept in this browser (localStorage) until the next recentre; ?align=default in the
// URL ignores it, so tests and scripts know where the scene is.
import * as THREE from "three";
import { FoxgloveConnection } from "./protocol.js";
import { FoxgloveScene, metadata } from "./scene.js";
import { SkinnedHands } from "./skinned_hand.js";

const errors = [];
window.addEventListener("error", (e) => errors.push(String(e.message ?? e)));
window.addEventListener("unhandledrejection", (e) => errors.push(String(e.reason)));

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const kAlignmentKey = "telegrasp.xr.alignment";
const kDefaultAlignment = { x: 0, y: 0.8, z: -0.6, yaw: 0 };  // world origin in local-floor, yaw about +y

// ---------------------------------------------------------------------------------------------
// Alignment: X_XR_World from {x, y, z, yaw}.

function alignmentMatrix(a) {
  // World axes in XR: x_w -> -z, y_w -> -x, z_w -> +y (Matrix4.set takes rows).
  const base = new THREE.Matrix4().set(0, -1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 0, 0, 0, 0, 1);
  return new THREE.Matrix4().makeTranslation(a.x, a.y, a.z).multiply(new THREE.Matrix4().makeRotationY(a.yaw)).multiply(base);
}

function storedAlignment() {
  if (params.get("align") === "default") return { ...kDefaultAlignment };
  try {
    const a = JSON.parse(localStorage.getItem(kAlignmentKey));
    if (a && ["x", "y", "z", "yaw"].every((k) => Number.isFinite(a[k]))) return a;
  } catch (_) { /* none stored */ }
  return { ...kDefaultAlignment };
}

let alignment = storedAlignment();
const X_XR_World = alignmentMatrix(alignment);
const X_World_XR = X_XR_World.clone().invert();

// ---------------------------------------------------------------------------------------------
// The scene: the world group carries the alignment; the Foxglove scene draws in it.

const canvas = $("canvas");
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.xr.enabled = true;
renderer.xr.setReferenceSpaceType("local-floor");
const scene3d = new THREE.Scene();
scene3d.background = new THREE.Color(0x2a2f37);
const hemi = new THREE.HemisphereLight(0xffffff, 0x555560, 1.6);
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(1, 3, 1);
scene3d.add(hemi, sun);
const floor = new THREE.GridHelper(6, 12, 0x474d57, 0x3b414b);
scene3d.add(floor);

const world = new THREE.Group();
world.matrixAutoUpdate = false;
world.matrix.copy(X_XR_World);
scene3d.add(world);
// The table top (z = 0) under the objects, 1.2 m x 0.8 m around the world's origin.
const table = new THREE.Mesh(new THREE.BoxGeometry(1.2, 0.8, 0.02), new THREE.MeshStandardMaterial({ color: 0x3b414b, roughness: 0.9 }));
table.position.z = -0.0101;
world.add(table);
const fox = new FoxgloveScene(world);
const skinned = new SkinnedHands(fox, world);
const capsulesBox = $("capsules");
capsulesBox.checked = localStorage.getItem("telegrasp.capsules") === "true";
capsulesBox.addEventListener("change", () => localStorage.setItem("telegrasp.capsules", String(capsulesBox.checked)));

// A faint ghost of each tracked controller where the resolved hand differs from it (> 5 mm).
const ghostMaterial = new THREE.MeshStandardMaterial({ color: 0x9fc6ff, transparent: true, opacity: 0.25, depthWrite: false });
const ghosts = new Map();  // side -> mesh (palm-sized box at the tracked palm pose)

// A desktop camera where a standing user's eyes would be, before entering XR.
const camera = new THREE.PerspectiveCamera(60, 1, 0.01, 50);
camera.position.set(0, 1.45, 0.1);
camera.lookAt(new THREE.Vector3(0, 0.8, -0.6));

// ---------------------------------------------------------------------------------------------
// The bridge: the scene's channels, this connection's own hands, and publishing.

let clientId = null;
let resumeToken = sessionStorage.getItem("telegrasp.xr.resume");
let connected = false;
let mayDrive = false;
let lastStatus = "";
const objects = new Map();   // id -> { id, name, held, holder }
const hands = new Map();     // "client/side" -> { client_id, side, rig }
const own = new Map();       // side -> newest /xr/hands message
const latencies = [];        // ms, page frame -> skeleton reflecting it (late latched)
let skeletons = 0;
let graspEvents = [];

function socketUrl() {
  const q = new URLSearchParams();
  if (params.get("token")) q.set("token", params.get("token"));
  if (resumeToken) q.set("resume", resumeToken);
  const query = q.toString();
  return `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/${query ? `?${query}` : ""}`;
}

function onServerInfo(info) {
  mayDrive = (info.capabilities ?? []).includes("clientPublish");
  clientId = info.metadata?.client_id ?? null;
  if (info.metadata?.resume_token) {
    resumeToken = info.metadata.resume_token;
    sessionStorage.setItem("telegrasp.xr.resume", resumeToken);
  }
  showState();
}

// Own hands: the frames follow each skeleton as it arrives, not the view's 30 Hz /tf.
function onOwnHand(m) {
  ++skeletons;
  own.set(m.side, m);
  const prefix = `${m.client_id}/${m.side}`;
  const palm = fox.frame(`${prefix}/palm`);
  if (palm.parent !== world) world.add(palm);
  poseObject(palm, m.palm);
  palm.visible = true;
  const X_WorldPalm_inv = palm.matrix.clone().invert();
  m.phalanges.forEach((pose, i) => {
    const name = m.phalanx_names?.[i];
    if (!name) return;
    const f = fox.frame(`${prefix}/${name}`);
    if (f.parent !== palm) palm.add(f);
    const local = new THREE.Matrix4().compose(vec(pose.position), quat(pose.orientation), new THREE.Vector3(1, 1, 1)).premultiply(X_WorldPalm_inv);
    local.decompose(f.position, f.quaternion, f.scale);
    f.visible = true;
  });
  // The ghost of the controller, where the resolved pose differs from it.
  let ghost = ghosts.get(m.side);
  if (!ghost) {
    ghost = new THREE.Mesh(new THREE.BoxGeometry(0.09, 0.084, 0.026), ghostMaterial);
    world.add(ghost);
    ghosts.set(m.side, ghost);
  }
  poseObject(ghost, m.tracked_palm);
  ghost.visible = Math.hypot(...m.resolve_offset_m) > 0.005 || m.resolve_angle_rad > 0.05;
  if (m.late_latched && m.input_stamp) {
    const ms = nowMs() - (m.input_stamp.sec * 1e3 + m.input_stamp.nsec / 1e6);
    latencies.push(ms);
    if (latencies.length > 5000) latencies.splice(0, latencies.length - 5000);
  }
}

function onMessage(topic, message) {
  if (topic === "/xr/hands") return onOwnHand(message);
  if (topic === "/tf") {
    // Own hands move with /xr/hands; the view's slower /tf would pull them back.
    if (clientId) message = { transforms: (message.transforms ?? []).filter((t) => !t.child_frame_id.startsWith(`${clientId}/`)) };
    fox.applyTransforms(message);
  } else if (topic === "/scene") {
    fox.applySceneUpdate(message);
    for (const d of message.deletions ?? []) {
      if (d.id.startsWith("object/")) objects.delete(Number(d.id.slice(7)));
      if (d.id.startsWith("hand/") && hands.has(d.id.slice(5))) hands.delete(d.id.slice(5));
    }
    for (const entity of message.entities ?? []) {
      const m = metadata(entity);
      if (m.kind === "object") {
        const id = Number(entity.id.slice(7));
        objects.set(id, { id, name: m.name, held: m.held === "true", holder: m.holder ?? null });
      } else if (m.kind === "hand") {
        hands.set(`${m.client_id}/${m.side}`, { client_id: m.client_id, side: m.side, rig: m.rig, colour: JSON.parse(m.colour ?? "[1,1,1]") });
      }
    }
  } else if (topic === "/grasp_events") {
    if (message.hand?.client_id === clientId) {
      graspEvents.push({ kind: message.kind, side: message.hand.side, object: message.object_name });
      if (graspEvents.length > 100) graspEvents = graspEvents.slice(-100);
      pulse(message.hand.side, message.kind === "grasp" ? 0.7 : 0.35);
    }
  }
}

const connection = new FoxgloveConnection(socketUrl, ["/scene", "/tf", "/grasp_events", "/xr/hands"], {
  onMessage,
  onServerInfo,
  onStatus: (s) => {
    lastStatus = s.message;
    showState();
  },
  onState: (text, on) => {
    connected = on;
    if (!on) mayDrive = false;
    showState();
  },
  publish: { topic: "/controller_state", schemaName: "telegrasp.ControllerInput" },
});

// A page that goes away says so (a WebSocket close): its hands leave at once, while a link that
// merely drops keeps them for the resume window.
window.addEventListener("pagehide", () => connection.close());

function showState() {
  $("xr-state").textContent = !connected
    ? "connecting…"
    : mayDrive
      ? `driving as ${clientId}${lastStatus ? ` · ${lastStatus}` : ""}`
      : `viewing only${lastStatus ? `: ${lastStatus}` : ""}`;
}

// ---------------------------------------------------------------------------------------------
// Input: each XR frame, each hand's grip pose (world frame), trigger and curls.

const vec = (p) => new THREE.Vector3(p.x, p.y, p.z);
const quat = (q) => new THREE.Quaternion(q.x, q.y, q.z, q.w);
const nowMs = () => performance.timeOrigin + performance.now();

function poseObject(object, pose) {
  object.position.copy(vec(pose.position));
  object.quaternion.copy(quat(pose.orientation));
  object.updateMatrix();
}

const seq = { left: 0, right: 0 };
const sent = { left: 0, right: 0 };
const lastSent = {};  // side -> the newest message, for tests

// Five curls (thumb first) from a tracked hand's joints: the bends along each finger's chain of
// bones over what a fist bends them, and a pinch closes the whole hand: every curl is at least
// the pinch, 0 with the thumb and index tips 6 cm apart, 1 at 1.5 cm.
const kFingers = [
  ["thumb-metacarpal", "thumb-phalanx-proximal", "thumb-phalanx-distal", "thumb-tip"],
  ...["index-finger", "middle-finger", "ring-finger", "pinky-finger"].map((f) =>
    [`${f}-metacarpal`, `${f}-phalanx-proximal`, `${f}-phalanx-intermediate`, `${f}-phalanx-distal`, `${f}-tip`]),
];
const kFullBend = [Math.PI * 0.45, Math.PI * 1.2, Math.PI * 1.2, Math.PI * 1.2, Math.PI * 1.2];
const kPinchOpen = 0.06, kPinchClosed = 0.015;  // m between the thumb and index tips

function handCurls(frame, hand, space) {
  const chains = [];
  for (const chain of kFingers) {
    const points = [];
    for (const joint of chain) {
      const jointSpace = hand.get(joint);
      const pose = jointSpace && frame.getJointPose?.(jointSpace, space);
      if (!pose) return null;
      points.push(vec(pose.transform.position));
    }
    chains.push(points);
  }
  const pinchGap = chains[0].at(-1).distanceTo(chains[1].at(-1));
  const pinch = Math.min(1, Math.max(0, (kPinchOpen - pinchGap) / (kPinchOpen - kPinchClosed)));
  return chains.map((points, f) => {
    let bend = 0;
    for (let i = 0; i + 2 < points.length; ++i) {
      const a = points[i + 1].clone().sub(points[i]), b = points[i + 2].clone().sub(points[i + 1]);
      if (a.lengthSq() > 0 && b.lengthSq() > 0) bend += a.angleTo(b);
    }
    return Math.min(1, Math.max(pinch, bend / kFullBend[f]));
  });
}

function sample(frame, source, space) {
  const side = source.handedness;
  if (side !== "left" && side !== "right") return;
  const gripSpace = source.gripSpace ?? source.hand?.get("wrist");
  const pose = gripSpace && frame.getPose(gripSpace, space);
  const message = { side, trigger: 0, tracking: Boolean(pose), seq: ++seq[side] };
  if (pose) {
    const X_World_Grip = X_World_XR.clone().multiply(new THREE.Matrix4().fromArray(pose.transform.matrix));
    const p = new THREE.Vector3(), q = new THREE.Quaternion(), s = new THREE.Vector3();
    X_World_Grip.decompose(p, q, s);
    message.pose = { position: { x: p.x, y: p.y, z: p.z }, orientation: { x: q.x, y: q.y, z: q.z, w: q.w } };
  } else if (lastSent[side]?.pose) {
    message.pose = lastSent[side].pose;  // the bridge keeps the last pose while tracking is lost
  } else {
    return;
  }
  if (source.hand) {
    const curls = handCurls(frame, source.hand, space);
    if (curls) message.curls = curls;
  } else if (source.gamepad) {
    const b = source.gamepad.buttons;
    message.trigger = Math.min(1, Math.max(b[0]?.value ?? 0, b[1]?.value ?? 0));  // trigger, or squeeze
    if (b[4]?.pressed && !recentreHeld[side]) recentre();
    recentreHeld[side] = Boolean(b[4]?.pressed);
  }
  const t = nowMs();
  message.stamp = { sec: Math.floor(t / 1e3), nsec: Math.round((t % 1e3) * 1e6) };
  if (connection.send(message)) {
    ++sent[side];
    lastSent[side] = message;
  }
}
const recentreHeld = {};
let pulses = 0;  // haptic pulses asked for (grasps and releases of this connection's hands)

function pulse(side, strength) {
  const session = renderer.xr.getSession();
  for (const source of session?.inputSources ?? []) {
    if (source.handedness !== side) continue;
    const actuator = source.gamepad?.hapticActuators?.[0];
    if (actuator?.pulse) {
      actuator.pulse(strength, 60).catch(() => {});
      ++pulses;
    }
    else source.gamepad?.vibrationActuator?.playEffect?.("dual-rumble", { duration: 60, strongMagnitude: strength }).catch(() => {});
  }
}

// Recentre: the table's origin 0.45 m in front of the headset and 0.45 m below it, facing the user.
function recentre() {
  const head = renderer.xr.isPresenting ? renderer.xr.getCamera() : camera;
  head.updateMatrixWorld();
  const p = new THREE.Vector3().setFromMatrixPosition(head.matrixWorld);
  const forward = new THREE.Vector3(0, 0, -1).transformDirection(head.matrixWorld);
  const yaw = Math.atan2(-forward.x, -forward.z);  // world +x along the headset's horizontal forward
  const across = Math.max(1e-6, Math.hypot(forward.x, forward.z));
  alignment = { x: p.x + (0.45 * forward.x) / across, y: Math.max(0.3, p.y - 0.45), z: p.z + (0.45 * forward.z) / across, yaw };
  localStorage.setItem(kAlignmentKey, JSON.stringify(alignment));
  X_XR_World.copy(alignmentMatrix(alignment));
  X_World_XR.copy(X_XR_World).invert();
  world.matrix.copy(X_XR_World);
}
$("recentre").addEventListener("click", recentre);

// ---------------------------------------------------------------------------------------------
// Sessions and the render loop.

async function enter(mode) {
  const session = await navigator.xr.requestSession(mode, { requiredFeatures: ["local-floor"], optionalFeatures: ["hand-tracking"] });
  await renderer.xr.setSession(session);
  session.addEventListener("end", () => showState());
}

async function offerSessions() {
  if (!navigator.xr) {
    $("xr-state").textContent = "this browser has no WebXR (a headset browser, over HTTPS or localhost, has)";
    return;
  }
  if (await navigator.xr.isSessionSupported("immersive-vr")) {
    $("enter-vr").disabled = false;
    $("enter-vr").addEventListener("click", () => enter("immersive-vr").catch((e) => errors.push(String(e))));
  }
  if (await navigator.xr.isSessionSupported("immersive-ar")) {
    $("enter-ar").hidden = false;
    $("enter-ar").addEventListener("click", () => {
      scene3d.background = null;  // passthrough
      enter("immersive-ar").catch((e) => errors.push(String(e)));
    });
  }
}
offerSessions();

function resize() {
  const w = window.innerWidth, h = window.innerHeight;
  if (renderer.xr.isPresenting) return;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(1, h);
  camera.updateProjectionMatrix();
}
window.addEventListener("resize", resize);
resize();

let frames = 0;
renderer.setAnimationLoop((time, frame) => {
  ++frames;
  if (frame) {
    const space = renderer.xr.getReferenceSpace();
    for (const source of frame.session.inputSources) sample(frame, source, space);
  }
  skinned.update([...hands.entries()].map(([key, h]) => ({ key, side: h.side, rig: h.rig })), capsulesBox.checked);
  renderer.render(scene3d, camera);
});

function percentile(values, q) {
  if (values.length === 0) return null;
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];
}

// For tests and people debugging: what the page knows and sends.
window.telegraspXR = {
  errors,
  alignment: () => ({ ...alignment, X_XR_World: X_XR_World.toArray() }),
  summary: () => ({
    connected,
    mayDrive,
    clientId,
    presenting: renderer.xr.isPresenting,
    frames,
    sent: { ...sent },
    lastSent: { ...lastSent },
    skeletons,
    ownHands: Object.fromEntries([...own].map(([side, m]) => [side, { palm: m.palm, tracked_palm: m.tracked_palm, frozen: m.frozen }])),
    objects: [...objects.values()].map((o) => ({ ...o, position: fox.worldPosition(`object/${o.id}`)?.applyMatrix4(X_World_XR).toArray() ?? null })),
    hands: [...hands.entries()].map(([key, h]) => ({ ...h, skinned: skinned.skinned(key) })),
    graspEvents,
    lastStatus,
    pulses,
    latency: { count: latencies.length, p50: percentile(latencies, 0.5), p99: percentile(latencies, 0.99) },
  }),
  recentre,
};
