// The human rigs' hands drawn as a skinned hand mesh: the generic hand glTF of the WebXR input
// profiles (npm @webxr-input-profiles/assets, served from vendor/generic-hand/), its 25 joints posed
// each frame from the rig's palm and phalanx frames of a FoxgloveScene. The glTF's joints follow
// WebXR's joint spaces (-Z along the bone toward the tip, +Y out of the back of the hand), the
// rig's phalanx frames have +x along the bone and +z out of the back, so a joint's rotation is its
// rig frame's turned by kRigToJoint. Which rig bone drives which joint (by name):
//
//   rig phalanx                      glTF joint
//   thumb_prox, thumb_mid, thumb_dist  thumb-metacarpal, thumb-phalanx-proximal, thumb-phalanx-distal
//   <f>_prox, <f>_mid, <f>_dist        <F>-phalanx-proximal, -intermediate, -distal
//     (f: index, middle, ring, little; F: index-finger, middle-finger, ring-finger, pinky-finger)
//   the palm                          wrist and the four finger metacarpals, placed as in the glTF's
//                                     bind pose relative to the middle finger's proximal joint
//   each distal phalanx               its tip, as in the bind pose relative to the distal joint
//
// The mesh is scaled by the rig's middle finger length over the glTF's (proximal to distal joint).
// Rigs that are not human hands (the gripper) keep their capsules.
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { clone } from "three/addons/utils/SkeletonUtils.js";

const kFingers = [["index", "index-finger"], ["middle", "middle-finger"], ["ring", "ring-finger"], ["little", "pinky-finger"]];
const kDriven = [  // [rig phalanx, glTF joint]
  ["thumb_prox", "thumb-metacarpal"], ["thumb_mid", "thumb-phalanx-proximal"], ["thumb_dist", "thumb-phalanx-distal"],
  ...kFingers.flatMap(([r, g]) => [[`${r}_prox`, `${g}-phalanx-proximal`], [`${r}_mid`, `${g}-phalanx-intermediate`],
    [`${r}_dist`, `${g}-phalanx-distal`]]),
];
// Each driven joint's next joint along its finger.
const kNext = new Map(kDriven.map(([, joint], i) =>
  [joint, joint.endsWith("distal") ? joint.replace(/phalanx-distal$/, "tip") : kDriven[i + 1][1]]));
const kFromPalm = ["wrist", ...kFingers.map(([, g]) => `${g}-metacarpal`)];
const kTips = [["thumb-phalanx-distal", "thumb-tip"], ...kFingers.map(([, g]) => [`${g}-phalanx-distal`, `${g}-tip`])];
// Joint axes in the rig frame: X = -y, Y = +z, Z = -x.
const kRigToJoint = new THREE.Quaternion().setFromRotationMatrix(new THREE.Matrix4().set(
  0, 0, -1, 0,
  -1, 0, 0, 0,
  0, 1, 0, 0,
  0, 0, 0, 1));
const kSkin = new THREE.Color().setRGB(0.88, 0.69, 0.56, THREE.SRGBColorSpace);
const kBlocked = new THREE.MeshStandardMaterial({ color: new THREE.Color().setRGB(0.84, 0.15, 0.16, THREE.SRGBColorSpace) });
const kMarker = new THREE.SphereGeometry(0.005, 12, 8);

export class SkinnedHands {
  // fox: the FoxgloveScene whose frames pose the hands; parent: the group the frames hang in
  // ("world"); base: the page's URL prefix of vendor/ ("./").
  constructor(fox, parent, base = "./") {
    this.fox = fox;
    this.parent = parent;
    this.templates = new Map();  // side -> Promise of the loaded glTF scene
    this.hands = new Map();  // key -> { root, bones, markers, scale }
    this.base = base;
    this.failed = null;
  }

  template(side) {
    if (!this.templates.has(side))
      this.templates.set(side, new GLTFLoader().loadAsync(`${this.base}vendor/generic-hand/${side}.glb`).then((gltf) => gltf.scene,
        (e) => { this.failed = String(e); throw e; }));
    return this.templates.get(side);
  }

  // Whether hand `key` ("client/side") is drawn skinned (its mesh loaded and posed).
  skinned(key) {
    return this.hands.get(key)?.posed ?? false;
  }

  // Poses every hand in `hands` ({key, side, rig}) from its frames and drops the others; the
  // capsules and palm box of a skinned hand are shown only with `capsules`.
  update(hands, capsules = false) {
    const live = new Set();
    for (const h of hands) {
      if (!/^human_(right|left)(_opposable)?$/.test(h.rig)) continue;
      live.add(h.key);
      let hand = this.hands.get(h.key);
      if (!hand) {
        hand = { root: null, posed: false };
        this.hands.set(h.key, hand);
        this.template(h.side).then((scene) => this.build(h.key, hand, scene)).catch(() => {});
      }
      if (hand.root) hand.posed = this.pose(h.key, hand);
      const prefix = `hand/${h.key}`;
      for (const [id, e] of this.fox.entities)
        if (id === prefix || id.startsWith(`${prefix}/`)) e.group.visible = capsules || !hand.posed;
    }
    for (const [key, hand] of this.hands)
      if (!live.has(key)) {
        hand.root?.removeFromParent();
        this.hands.delete(key);
      }
  }

  build(key, hand, template) {
    if (this.hands.get(key) !== hand) return;  // gone meanwhile
    const root = clone(template);
    const bind = new Map();
    root.traverse((o) => {
      if (o.isSkinnedMesh) {
        o.material = new THREE.MeshStandardMaterial({ color: kSkin, roughness: 0.7 });
        o.frustumCulled = false;  // the bones move it far from its bind bounds
      }
      if (o.isBone) bind.set(o.name, { p: o.position.clone(), q: o.quaternion.clone() });
    });
    const middle = bind.get("middle-finger-phalanx-proximal"), inter = bind.get("middle-finger-phalanx-intermediate"),
      distal = bind.get("middle-finger-phalanx-distal");
    hand.glbMiddle = middle.p.distanceTo(inter.p) + inter.p.distanceTo(distal.p);
    // Wrist and metacarpals relative to the middle proximal joint, in its frame; tips in their distal's.
    hand.fromPalm = kFromPalm.map((name) => {
      const b = bind.get(name);
      return { name, p: b.p.clone().sub(middle.p).applyQuaternion(middle.q.clone().invert()), q: middle.q.clone().invert().multiply(b.q) };
    });
    hand.tips = kTips.map(([from, name]) => {
      const a = bind.get(from), b = bind.get(name);
      return { from, name, p: b.p.clone().sub(a.p).applyQuaternion(a.q.clone().invert()), q: a.q.clone().invert().multiply(b.q) };
    });
    hand.bones = new Map();
    root.traverse((o) => { if (o.isBone) hand.bones.set(o.name, o); });
    hand.markers = new Map();  // rig phalanx -> red sphere shown while it is blocked
    for (const [rigName] of kDriven) {
      const m = new THREE.Mesh(kMarker, kBlocked);
      m.visible = false;
      root.add(m);
      hand.markers.set(rigName, m);
    }
    root.visible = false;
    this.parent.add(root);
    hand.root = root;
  }

  // A frame's pose in the parent group: the palm's is its own, a phalanx's goes through the palm.
  framePose(id) {
    const f = this.fox.frames.get(id);
    if (!f || !f.visible) return null;
    const m = new THREE.Matrix4();
    for (let o = f; o && o !== this.parent; o = o.parent) {
      o.updateMatrix();
      m.premultiply(o.matrix);
    }
    const p = new THREE.Vector3(), q = new THREE.Quaternion(), s = new THREE.Vector3();
    m.decompose(p, q, s);
    return { p, q };
  }

  pose(key, hand) {
    const rig = new Map();
    for (const [name] of kDriven) {
      const pose = this.framePose(`${key}/${name}`);
      if (!pose) return false;
      rig.set(name, pose);
    }
    const palm = this.framePose(`${key}/palm`);
    if (!palm) return false;
    const rigMiddle = rig.get("middle_prox").p.distanceTo(rig.get("middle_mid").p) + rig.get("middle_mid").p.distanceTo(rig.get("middle_dist").p);
    const scale = rigMiddle / hand.glbMiddle;
    const set = (name, p, q) => {
      const bone = hand.bones.get(name);
      bone.position.copy(p);
      bone.quaternion.copy(q);
      bone.scale.setScalar(scale);
    };
    const jointQ = new Map();
    for (const [rigName, joint] of kDriven) {
      const q = rig.get(rigName).q.clone().multiply(kRigToJoint);
      jointQ.set(joint, q);
      set(joint, rig.get(rigName).p, q);
    }
    // The palm's joints: placed as in the bind pose around the middle proximal joint, in a frame
    // that gives the wrist the palm's turn.
    const anchor = rig.get("middle_prox").p;
    const knuckleQ = palm.q.clone().multiply(kRigToJoint).multiply(hand.fromPalm[0].q.clone().invert());
    for (const b of hand.fromPalm)
      set(b.name, b.p.clone().multiplyScalar(scale).applyQuaternion(knuckleQ).add(anchor), knuckleQ.clone().multiply(b.q));
    for (const t of hand.tips) {
      const a = jointQ.get(t.from), from = hand.bones.get(t.from).position;
      set(t.name, t.p.clone().multiplyScalar(scale).applyQuaternion(a).add(from), a.clone().multiply(t.q));
    }
    // Blocked phalanges (their capsule entity is drawn red): a red dot on the palmar skin, half way
    // to the next joint.
    for (const [rigName, joint] of kDriven) {
      const marker = hand.markers.get(rigName);
      const c = this.fox.entities.get(`hand/${key}/${rigName}`)?.entity?.cylinders?.[0]?.color;
      marker.visible = Boolean(c && c.r > 0.7 && c.g < 0.3);
      if (!marker.visible) continue;
      const next = hand.bones.get(kNext.get(joint)).position;
      const palmar = new THREE.Vector3(0, -0.009 * scale, 0).applyQuaternion(jointQ.get(joint));
      marker.position.copy(hand.bones.get(joint).position).lerp(next, 0.5).add(palmar);
    }
    hand.root.visible = true;
    return true;
  }
}
