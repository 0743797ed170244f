// A three.js scene driven by foxglove.FrameTransforms (a tree of frames) and foxglove.SceneUpdate
// (entities drawn in those frames), as Foxglove's 3D panel draws them. World frame: "world", +z up.
import * as THREE from "three";

const unitBox = new THREE.BoxGeometry(1, 1, 1);
const unitSphere = new THREE.SphereGeometry(0.5, 24, 16);
// Foxglove's cylinders and arrows run along local z and x; three's along y.
const unitCylinder = new THREE.CylinderGeometry(0.5, 0.5, 1, 24).rotateX(Math.PI / 2);
const unitCone = new THREE.ConeGeometry(0.5, 1, 20).rotateZ(-Math.PI / 2);
const unitShaft = new THREE.CylinderGeometry(0.5, 0.5, 1, 12).rotateZ(-Math.PI / 2);

function applyPose(object, pose) {
  if (!pose) return;
  const p = pose.position ?? {};
  const q = pose.orientation ?? {};
  object.position.set(p.x ?? 0, p.y ?? 0, p.z ?? 0);
  object.quaternion.set(q.x ?? 0, q.y ?? 0, q.z ?? 0, q.w ?? 1);
}

export class FoxgloveScene {
  constructor(root) {
    this.root = root;                 // the "world" frame
    this.frames = new Map([["world", root]]);
    this.entities = new Map();        // id -> { group, entity }
    this.materials = new Map();
  }

  material(color) {
    const c = color ?? { r: 1, g: 1, b: 1, a: 1 };
    const key = `${c.r},${c.g},${c.b},${c.a}`;
    let m = this.materials.get(key);
    if (!m) {
      m = new THREE.MeshStandardMaterial({ roughness: 0.6, metalness: 0.0 });
      m.color.setRGB(c.r, c.g, c.b, THREE.SRGBColorSpace);
      if (c.a < 1) Object.assign(m, { transparent: true, opacity: c.a, depthWrite: false });
      this.materials.set(key, m);
    }
    return m;
  }

  // A frame's group; a frame no transform named yet hangs off the world, hidden.
  frame(id) {
    let group = this.frames.get(id);
    if (!group) {
      group = new THREE.Group();
      group.name = id;
      group.visible = false;
      this.root.add(group);
      this.frames.set(id, group);
    }
    return group;
  }

  applyTransforms(message) {
    for (const t of message.transforms ?? []) {
      const parent = this.frame(t.parent_frame_id);
      const child = this.frame(t.child_frame_id);
      if (child.parent !== parent) parent.add(child);
      child.position.set(t.translation.x, t.translation.y, t.translation.z);
      child.quaternion.set(t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w);
      child.visible = true;
    }
  }

  applySceneUpdate(message) {
    for (const d of message.deletions ?? []) {
      if (d.type === 1) for (const id of [...this.entities.keys()]) this.remove(id);
      else this.remove(d.id);
    }
    for (const entity of message.entities ?? []) {
      this.remove(entity.id);
      const group = this.build(entity);
      this.frame(entity.frame_id).add(group);
      this.entities.set(entity.id, { group, entity });
    }
  }

  remove(id) {
    const e = this.entities.get(id);
    if (!e) return;
    e.group.removeFromParent();
    e.group.traverse((o) => {
      if (o.geometry && o.userData.ownGeometry) o.geometry.dispose();
    });
    this.entities.delete(id);
  }

  build(entity) {
    const group = new THREE.Group();
    group.name = entity.id;
    const add = (geometry, primitive, scale) => {
      const mesh = new THREE.Mesh(geometry, this.material(primitive.color));
      applyPose(mesh, primitive.pose);
      if (scale) mesh.scale.set(scale.x, scale.y, scale.z);
      group.add(mesh);
      return mesh;
    };
    for (const c of entity.cubes ?? []) add(unitBox, c, c.size);
    for (const s of entity.spheres ?? []) add(unitSphere, s, s.size);
    for (const c of entity.cylinders ?? []) {
      if ((c.top_scale ?? 1) === 1 && (c.bottom_scale ?? 1) === 1) {
        add(unitCylinder, c, c.size);
      } else {
        const g = new THREE.CylinderGeometry(0.5 * c.top_scale, 0.5 * c.bottom_scale, 1, 24).rotateX(Math.PI / 2);
        add(g, c, c.size).userData.ownGeometry = true;
      }
    }
    for (const a of entity.arrows ?? []) {
      const arrow = new THREE.Group();
      applyPose(arrow, a.pose);
      const shaft = new THREE.Mesh(unitShaft, this.material(a.color));
      shaft.scale.set(a.shaft_length, a.shaft_diameter, a.shaft_diameter);
      shaft.position.x = a.shaft_length / 2;
      const head = new THREE.Mesh(unitCone, this.material(a.color));
      head.scale.set(a.head_length, a.head_diameter, a.head_diameter);
      head.position.x = a.shaft_length + a.head_length / 2;
      arrow.add(shaft, head);
      group.add(arrow);
    }
    for (const t of entity.triangles ?? []) {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.Float32BufferAttribute(t.points.flatMap((p) => [p.x, p.y, p.z]), 3));
      if (t.indices?.length) g.setIndex(t.indices);
      g.computeVertexNormals();
      add(g, t).userData.ownGeometry = true;
    }
    for (const l of entity.lines ?? []) {
      const g = new THREE.BufferGeometry().setFromPoints(l.points.map((p) => new THREE.Vector3(p.x, p.y, p.z)));
      if (l.indices?.length) g.setIndex(l.indices);
      const m = new THREE.LineBasicMaterial();
      m.color.setRGB(l.color?.r ?? 1, l.color?.g ?? 1, l.color?.b ?? 1, THREE.SRGBColorSpace);
      const line = l.type === 2 ? new THREE.LineSegments(g, m) : l.type === 1 ? new THREE.LineLoop(g, m) : new THREE.Line(g, m);
      applyPose(line, l.pose);
      line.userData.ownGeometry = true;
      group.add(line);
    }
    return group;
  }

  // A frame's origin in world coordinates, or null when no transform named it yet.
  worldPosition(frameId) {
    const f = this.frames.get(frameId);
    if (!f || !f.visible) return null;
    f.updateWorldMatrix(true, false);
    return new THREE.Vector3().setFromMatrixPosition(f.matrixWorld);
  }
}

export function metadata(entity) {
  return Object.fromEntries((entity.metadata ?? []).map((kv) => [kv.key, kv.value]));
}
