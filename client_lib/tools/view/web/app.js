// telegrasp-view's built-in page: the scene in three.js from the same Foxglove WebSocket channels
// Foxglove uses (/scene, /tf), plus the hand list, the selected hand's grasp state with ND per
// phalanx, and a time line of grasp events (/grasp_state, /grasp_events, /server_status).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { FoxgloveConnection } from "./protocol.js";
import { FoxgloveScene, metadata } from "./scene.js";
import { SkinnedHands } from "./skinned_hand.js";

// Every JavaScript error the page meets, for the people and the tests that look at it.
const errors = [];
window.addEventListener("error", (e) => errors.push(String(e.message ?? e)));
window.addEventListener("unhandledrejection", (e) => errors.push(String(e.reason)));

const $ = (id) => document.getElementById(id);
const canvas = $("canvas");
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
const scene3d = new THREE.Scene();
scene3d.background = new THREE.Color(0x2a2f37);
const world = new THREE.Group();
scene3d.add(world);
const hemi = new THREE.HemisphereLight(0xffffff, 0x555560, 1.6);
hemi.position.set(0, 0, 1);
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(1, -1.5, 2.5);
scene3d.add(hemi, sun);
// The table top at z = 0, with a 10 cm grid.
const table = new THREE.Mesh(new THREE.PlaneGeometry(3, 3), new THREE.MeshStandardMaterial({ color: 0x3b414b, roughness: 0.9 }));
const grid = new THREE.GridHelper(3, 30, 0x59606c, 0x474d57);
grid.rotateX(Math.PI / 2);
grid.position.z = 0.0005;
scene3d.add(table, grid);

const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 50);
camera.up.set(0, 0, 1);  // +z up, as the server's world
camera.position.set(0.72, -0.42, 0.24);
const controls = new OrbitControls(camera, canvas);
controls.target.set(0.45, 0, 0.1);
controls.enableDamping = true;
controls.update();

const fox = new FoxgloveScene(world);
// Human hands as a skinned hand mesh; their capsules and palm box as an overlay (the checkbox).
const skinned = new SkinnedHands(fox, world);
$("capsules-box").checked = localStorage.getItem("telegrasp.capsules") === "true";
$("capsules-box").addEventListener("change", () => localStorage.setItem("telegrasp.capsules", String($("capsules-box").checked)));
const hands = new Map();        // "client/side" -> { key, client_id, side, colour, rig }
const objects = new Map();      // object id -> { id, name, held, holder }
const graspStates = new Map();  // hand key -> latest /grasp_state
const lastGrasp = new Map();    // hand key -> latest grasp event
const events = [];              // /grasp_events, oldest first
let status = null;
let selected = null;
let jump = false;  // the camera moves to a newly selected hand at once, then follows it smoothly
let connected = false;
let messages = 0;
let dirty = true;

const handKey = (hand) => `${hand.client_id}/${hand.side}`;
const css = (rgb) => `rgb(${rgb.map((c) => Math.round(255 * c)).join(",")})`;

function onScene(update) {
  fox.applySceneUpdate(update);
  for (const d of update.deletions ?? []) {
    if (d.id.startsWith("hand/") && hands.has(d.id.slice(5))) hands.delete(d.id.slice(5));
    if (d.id.startsWith("object/")) objects.delete(Number(d.id.slice(7)));
  }
  for (const entity of update.entities ?? []) {
    const m = metadata(entity);
    if (m.kind === "hand") {
      const key = `${m.client_id}/${m.side}`;
      hands.set(key, { key, client_id: m.client_id, side: m.side, rig: m.rig, colour: JSON.parse(m.colour ?? "[1,1,1]") });
      if (selected === null) selected = key;
    } else if (m.kind === "object") {
      const id = Number(entity.id.slice(7));
      objects.set(id, { id, name: m.name, held: m.held === "true", holder: m.holder ?? null, geometry: m.geometry });
    }
  }
  if (selected !== null && !hands.has(selected)) selected = hands.keys().next().value ?? null;
}

function onMessage(topic, message) {
  ++messages;
  if (topic === "/tf") {
    fox.applyTransforms(message);
    return;  // the render loop shows it; lists do not change
  }
  if (topic === "/scene") onScene(message);
  else if (topic === "/grasp_state") graspStates.set(handKey(message.hand), message);
  else if (topic === "/grasp_events") {
    events.push(message);
    if (events.length > 1000) events.splice(0, events.length - 1000);
    if (message.kind === "grasp") lastGrasp.set(handKey(message.hand), message);
  } else if (topic === "/server_status") status = message;
  dirty = true;
}

// The headset page keeps this page's query (a --drive-token's ?token=).
$("enter-xr").href = `xr${location.search}`;

const url = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}`;
new FoxgloveConnection(url, ["/scene", "/tf", "/grasp_state", "/grasp_events", "/server_status"], {
  onMessage,
  onState: (text, on) => {
    connected = on;
    $("connection").textContent = on ? "live" : "offline";
    $("connection").className = on ? "on" : "off";
    $("connection").title = text;
  },
});

// ---------------------------------------------------------------------------------------------
// Side panel and time line, redrawn at most 5 times a second.

const escape = (s) => String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
const objectName = (id) => (id < 0 ? "none" : objects.get(id)?.name ?? `object ${id}`);
const mm = (v, digits = 2) => (v === null || v === undefined || Number.isNaN(v) ? "n/a" : v.toFixed(digits));

function drawLists() {
  $("hands").innerHTML = [...hands.values()]
    .map((h) => {
      const s = graspStates.get(h.key);
      const what = s ? (s.grasped_object >= 0 ? `holds ${escape(objectName(s.grasped_object))}` : s.selected_object >= 0 ? `at ${escape(objectName(s.selected_object))}` : "free") : "";
      return `<li data-key="${escape(h.key)}" class="${h.key === selected ? "selected" : ""}"><span class="swatch" style="background:${css(h.colour)}"></span>${escape(h.key)} <span class="muted">${what}</span></li>`;
    })
    .join("") || `<li class="muted">no hand yet</li>`;
  $("objects").innerHTML = [...objects.values()]
    .map((o) => {
      const holder = o.held ? hands.get(o.holder) : null;
      const swatch = o.held ? css(holder?.colour ?? [1, 1, 1]) : "#9ea3ad";
      return `<li><span class="swatch" style="background:${swatch}"></span>${escape(o.name)} <span class="muted">#${o.id}${o.held ? ` held by ${escape(o.holder)}` : ""}</span></li>`;
    })
    .join("") || `<li class="muted">no object</li>`;
}

function drawDetail() {
  if (selected === null) {
    $("detail").innerHTML = `<span class="muted">no hand yet</span>`;
    return;
  }
  const s = graspStates.get(selected);
  const g = lastGrasp.get(selected);
  const capsule = new Map((g?.capsules ?? []).map((c) => [c.phalanx_name, c]));
  let html = `<table>
    <tr><th>hand</th><td>${escape(selected)}</td></tr>
    <tr><th>selected</th><td>${s ? escape(objectName(s.selected_object)) : "-"}</td></tr>
    <tr><th>grasped</th><td>${s ? escape(objectName(s.grasped_object)) : "-"}</td></tr>
    <tr><th>trigger</th><td>${s ? s.trigger.toFixed(2) : "-"}</td></tr>
    <tr><th>palm contact</th><td>${s ? (s.palm_contact ? "yes" : "no") : "-"}</td></tr>
    <tr><th>grasp type</th><td>${s && s.grasp_type ? escape(s.grasp_type.replace("_", " ")) : "-"}</td></tr>
    <tr><th>last grasp</th><td>${g ? `${escape(g.object_name)} at ${g.time_s.toFixed(2)} s` : "none yet"}</td></tr>
    <tr><th>HandError</th><td>${g ? `${mm(g.hand_error_mm)} mm` : "n/a"}</td></tr>
    <tr><th>epsilon</th><td>${g && g.epsilon !== undefined && g.epsilon !== null ? g.epsilon.toFixed(4) : "n/a"}</td></tr>
    <tr><th>palm distance</th><td>${g && typeof g.palm_signed_distance_mm === "number" ? `${mm(g.palm_signed_distance_mm)} mm` : "n/a"}</td></tr>
  </table>`;
  if (s) {
    html += `<h2>Phalanges (ND of the last grasp)</h2><table><tr><th>phalanx</th><th>state</th><th class="num">ND mid-length mm</th><th class="num">ND contact mm</th><th class="num">dist mm</th></tr>`;
    for (const p of s.phalanges) {
      const c = capsule.get(p.name);
      html += `<tr><td>${escape(p.name)}</td><td class="${p.blocked ? "blocked" : ""}">${p.blocked ? "blocked" : "free"}</td>` +
        `<td class="num">${c ? (c.hit ? mm(c.nd_midlength_mm ?? c.nd_mm) : "no hit") : ""}</td>` +
        `<td class="num">${c ? (c.contact_hit ? mm(c.nd_contact_mm) : "-") : ""}</td>` +
        `<td class="num">${c ? mm(c.signed_distance_mm) : ""}</td></tr>`;
    }
    html += `</table>`;
  }
  $("detail").innerHTML = html;
}

function drawStatus() {
  $("status").innerHTML = status
    ? `tick ${status.tick} · ${status.time_s.toFixed(1)} s · ${status.hands} hands · ${status.objects} objects<br>` +
      `tick ${status.tick_us_p50.toFixed(0)} µs p50, ${status.tick_us_max.toFixed(0)} µs max · missed ${status.missed_ticks}`
    : `<span class="muted">no status yet</span>`;
}

function drawTimeline() {
  const strip = $("strip");
  const width = strip.clientWidth || 800;
  const now = Math.max(status?.time_s ?? 0, events.length ? events[events.length - 1].time_s : 0);
  const span = 120;  // seconds shown
  const x = (t) => width - ((now - t) / span) * (width - 20) - 10;
  let svg = `<line x1="0" y1="18" x2="${width}" y2="18" stroke="#474d57"/>`;
  for (let t = Math.ceil((now - span) / 10) * 10; t <= now; t += 10)
    svg += `<line x1="${x(t)}" y1="13" x2="${x(t)}" y2="23" stroke="#474d57"/><text x="${x(t) + 2}" y="33" fill="#7c8595" font-size="9">${t}s</text>`;
  for (const e of events) {
    if (e.time_s < now - span) continue;
    const colour = css(hands.get(handKey(e.hand))?.colour ?? [0.8, 0.8, 0.8]);
    const fill = e.kind === "grasp" ? colour : "none";
    svg += `<circle cx="${x(e.time_s)}" cy="18" r="5" fill="${fill}" stroke="${colour}" stroke-width="2"><title>${escape(`${e.kind} ${handKey(e.hand)} ${e.object_name} at ${e.time_s.toFixed(2)} s`)}</title></circle>`;
  }
  strip.setAttribute("viewBox", `0 0 ${width} 36`);
  strip.innerHTML = svg;
  $("events").innerHTML = events
    .slice(-60)
    .reverse()
    .map((e) => `<li>${e.time_s.toFixed(2).padStart(8)} s · <b>${e.kind}</b> · ${escape(handKey(e.hand))} · ${escape(e.object_name)}` +
      (e.kind === "grasp" ? ` · HandError ${mm(e.hand_error_mm)} mm · ${e.capsules_without_hit} capsules without hit` : "") + `</li>`)
    .join("");
}

function select(key) {
  selected = key;
  jump = true;
  dirty = true;
}

$("hands").addEventListener("click", (e) => {
  const li = e.target.closest("li[data-key]");
  if (li) select(li.dataset.key);
});

setInterval(() => {
  if (!dirty) return;
  dirty = false;
  drawLists();
  drawDetail();
  drawStatus();
  drawTimeline();
}, 200);

// ---------------------------------------------------------------------------------------------
// Render loop: the camera follows the selected hand (when asked), keeping its offset.

function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) || canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
  }
}

let frames = 0;
function render() {
  resize();
  if ($("follow-box").checked && selected !== null) {
    const palm = fox.worldPosition(`${selected}/palm`);
    if (palm) {
      const step = palm.clone().sub(controls.target).multiplyScalar(jump ? 1 : 0.15);
      jump = false;
      controls.target.add(step);
      camera.position.add(step);
    }
  }
  controls.update();
  skinned.update([...hands.values()], $("capsules-box").checked);
  renderer.render(scene3d, camera);
  ++frames;
  requestAnimationFrame(render);
}
requestAnimationFrame(render);

// For tests and debugging: what the page shows, and where a frame appears on screen.
window.telegraspView = {
  errors,
  summary: () => ({
    connected,
    messages,
    frames,
    entities: fox.entities.size,
    hands: [...hands.values()].map((h) => ({ ...h, skinned: skinned.skinned(h.key) })),
    objects: [...objects.values()],
    events: events.length,
    selected,
  }),
  screenPoint: (frameId) => {
    const p = fox.worldPosition(frameId);
    if (!p) return null;
    p.project(camera);
    const rect = canvas.getBoundingClientRect();
    return { x: rect.left + ((p.x + 1) / 2) * rect.width, y: rect.top + ((1 - p.y) / 2) * rect.height };
  },
  select,
};
