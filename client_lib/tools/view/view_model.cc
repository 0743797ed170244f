#include "view_model.h"

#include "grasp_svg.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

namespace telegrasp::view {
namespace {

constexpr double kMinHalfExtent = 0.02;  // m, the smallest placeholder box
constexpr int kMeshTriangles = 2000;  // an object's mesh is decimated to this for the wire
constexpr double kJointSphereRadius = 0.006;  // m, a phalanx of an unknown rig
constexpr double kContactArrowLength = 0.025;  // m
constexpr double kContactDotRadius = 0.0025;  // m

// Rounds for appearance keys, so float noise does not re-send an entity.
std::string rounded(double v, double step) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.0f,", std::round(v / step));
  return buffer;
}

std::string phalanx_name(const sim::HandRig* rig, std::size_t i) {
  if (rig != nullptr && i < rig->phalanges().size()) return rig->phalanges()[i].name;
  return "phalanx" + std::to_string(i);
}

}  // namespace

ObjectMesh view_mesh(const client::ObjectGeometry& geometry, int max_triangles) {
  ObjectMesh out;
  out.content_hash = geometry.content_hash;
  if (geometry.mesh_omitted || geometry.triangles.empty()) return out;
  sim::TriangleMesh mesh;
  mesh.vertices.reserve(geometry.vertices.size());
  for (const Eigen::Vector3f& v : geometry.vertices) mesh.vertices.push_back(v.cast<double>());
  mesh.triangles = geometry.triangles;
  const sim::DrawingMesh drawn = sim::decimate_for_drawing(mesh, max_triangles);
  out.points = drawn.mesh.vertices;
  for (const auto& t : drawn.mesh.triangles) out.indices.insert(out.indices.end(), t.begin(), t.end());
  return out;
}

void add_object_geometry(Json& entity, const client::ObjectState& object, const Eigen::Vector3d& half_extent,
                         const Rgba& colour, const ObjectMesh* mesh) {
  double top = half_extent.z();
  if (mesh != nullptr && !mesh->indices.empty()) {
    add_triangles(entity, mesh->points, mesh->indices, colour);
    for (const Eigen::Vector3d& p : mesh->points) top = std::max(top, p.z());
    add_metadata(entity, "geometry", "mesh");
  } else {
    add_box(entity, Eigen::Isometry3d::Identity(), 2 * half_extent, colour);
    add_metadata(entity, "geometry", "placeholder");
  }
  add_text(entity, Eigen::Vector3d(0, 0, top + 0.03), object.name, Rgba{1, 1, 1, 1});
}

ViewModel::ViewModel(RigLookup rigs) : rig_lookup_(std::move(rigs)) {}

const sim::HandRig* ViewModel::rig(const std::string& name) {
  const auto it = rigs_.find(name);
  if (it != rigs_.end()) return it->second;
  const sim::HandRig* r = rig_lookup_ ? rig_lookup_(name) : nullptr;
  rigs_.emplace(name, r);
  return r;
}

bool ViewModel::blocked(const Hand& hand, std::size_t phalanx) const {
  return hand.state && phalanx < hand.state->blocked.size() && hand.state->blocked[phalanx];
}

bool ViewModel::shows_contacts(const Hand& hand) const {
  return hand.state && hand.state->grasped_object >= 0 && hand.contacts &&
         hand.contacts->object_id == hand.state->grasped_object && objects_.contains(hand.contacts->object_id) &&
         !hand.contacts->contacts.empty();
}

Rgba ViewModel::holder_colour(const client::ObjectState& object) const {
  const auto it = hands_.find(object.holder);
  return colours::hand_colour(it == hands_.end() ? 0 : it->second.colour);
}

void ViewModel::grow_placeholder(int object_id, const std::vector<client::ContactPoint>& contacts) {
  const auto it = objects_.find(object_id);
  if (it == objects_.end()) return;
  for (const client::ContactPoint& c : contacts)
    if (c.p_ObjectContact.allFinite() && c.p_ObjectContact.norm() < 1.0)  // ignore nonsense
      it->second.half_extent = it->second.half_extent.cwiseMax(c.p_ObjectContact.cwiseAbs());
}

ViewUpdate ViewModel::update(const ClientSnapshot& snap, std::uint64_t stamp_ns) {
  ViewUpdate out;

  // Hands: one per skeleton the client holds; a hand the server removed is gone from it.
  std::set<client::HandKey> present;
  for (const client::HandSkeleton& s : snap.skeletons) {
    present.insert(s.hand);
    auto [it, added] = hands_.try_emplace(s.hand);
    Hand& hand = it->second;
    if (added) hand.colour = next_colour_++;
    if (added || hand.skeleton.rig != s.rig) hand.rig = rig(s.rig);
    hand.skeleton = s;
  }
  std::erase_if(hands_, [&](const auto& entry) { return !present.contains(entry.first); });

  // Object meshes: decimated once per model and content.
  for (const auto& [model, geometry] : snap.geometries) {
    const auto it = meshes_.find(model);
    if (geometry && (it == meshes_.end() || it->second.content_hash != geometry->content_hash))
      meshes_[model] = view_mesh(*geometry, kMeshTriangles);
  }

  // Objects: those of the newest scene state.
  if (snap.scene && (objects_.empty() || snap.scene->tick != last_scene_tick_)) {
    last_scene_tick_ = snap.scene->tick;
    std::set<int> ids;
    for (const client::ObjectState& o : snap.scene->objects) {
      ids.insert(o.id);
      objects_[o.id].state = o;
    }
    std::erase_if(objects_, [&](const auto& entry) { return !ids.contains(entry.first); });
  }

  // Grasp states (sent on change) and contact sets (shown while holding).
  for (auto& [key, hand] : hands_) {
    if (const auto it = snap.grasp_states.find(key); it != snap.grasp_states.end()) {
      const client::GraspState& s = it->second;
      if (!hand.state || hand.state->tick != s.tick || hand.state->blocked != s.blocked ||
          hand.state->grasped_object != s.grasped_object || hand.state->selected_object != s.selected_object) {
        hand.state = s;
        std::vector<std::string> names;
        for (std::size_t i = 0; i < s.blocked.size(); ++i) names.push_back(phalanx_name(hand.rig, i));
        out.grasp_states.push_back(grasp_state_message(s, names));
      }
    }
    if (const auto it = snap.contact_sets.find(key); it != snap.contact_sets.end()) {
      hand.contacts = it->second;
      grow_placeholder(it->second.object_id, it->second.contacts);
    }
  }

  for (const client::GraspEvent& e : snap.events) {
    grow_placeholder(e.object_id, e.contacts);
    Json message = grasp_event_message(e);
    event_history_.push_back(message);
    if (event_history_.size() > kEventHistory) event_history_.pop_front();
    out.grasp_events.push_back(std::move(message));
  }

  if (snap.status && snap.status->tick != last_status_tick_) {
    last_status_tick_ = snap.status->tick;
    server_status_ = server_status_message(*snap.status);
    out.server_status = server_status_;
  }

  // /scene: the entities whose appearance changed, and the deletions of those gone.
  const std::map<std::string, Look> now = appearance();
  std::vector<Json> entities;
  std::vector<std::string> deleted;
  for (const auto& [id, look] : now) {
    const auto it = sent_.find(id);
    if (it == sent_.end() || it->second != look.key) entities.push_back(build(look, stamp_ns));
  }
  for (const auto& [id, key] : sent_)
    if (!now.contains(id)) deleted.push_back(id);
  if (!entities.empty() || !deleted.empty()) out.scene = scene_update(std::move(entities), deleted, stamp_ns);
  sent_.clear();
  for (const auto& [id, look] : now) sent_.emplace(id, look.key);

  const bool all = stamp_ns >= last_full_transforms_ns_ + kFullTransformsEveryNs;
  Json moved = moved_transforms(all, stamp_ns);
  if (all) last_full_transforms_ns_ = stamp_ns;
  if (!moved["transforms"].empty()) {
    out.transforms = std::move(moved);
    out.transforms_complete = all;
  }
  return out;
}

std::map<std::string, ViewModel::Look> ViewModel::appearance() const {
  using Kind = Look::Kind;
  std::map<std::string, Look> looks;
  for (const auto& [key, hand] : hands_) {
    const std::string& rig_name = hand.skeleton.rig;
    looks[hand_entity_id(key)] = Look{Kind::kPalm, &key, 0, -1,
                                      rig_name + (hand.state && hand.state->palm_contact ? "|palm|" : "|") +
                                          std::to_string(hand.colour) + (hand.rig ? "" : "|unknown")};
    for (std::size_t i = 0; i < hand.skeleton.X_WorldPhalanx.size(); ++i) {
      if (hand.rig != nullptr && (i >= hand.rig->phalanges().size() || !hand.rig->phalanges()[i].capsule)) continue;
      looks[phalanx_entity_id(key, phalanx_name(hand.rig, i))] =
          Look{Kind::kPhalanx, &key, i, -1, rig_name + (blocked(hand, i) ? "|blocked" : "|free")};
    }
    if (shows_contacts(hand)) {
      std::string look = std::to_string(hand.contacts->object_id) + ":";
      for (const client::ContactPoint& c : hand.contacts->contacts) {
        look += std::to_string(c.phalanx) + ";";
        for (int k = 0; k < 3; ++k) look += rounded(c.p_ObjectContact[k], 1e-4) + rounded(c.n_Object[k], 1e-2);
      }
      looks[contacts_entity_id(key)] = Look{Kind::kContacts, &key, 0, -1, std::move(look)};
    }
  }
  for (const auto& [id, object] : objects_) {
    const client::ObjectState& o = object.state;
    std::string look = o.name + "|";
    if (o.held) {
      const auto holder = hands_.find(o.holder);
      look += "held|" + std::to_string(holder == hands_.end() ? 0 : holder->second.colour) + "|";
    }
    if (const auto mesh = meshes_.find(o.name); mesh != meshes_.end())
      look += "mesh|" + std::to_string(mesh->second.content_hash);
    else
      for (int k = 0; k < 3; ++k) look += rounded(object.half_extent[k], 1e-3);
    looks[object_entity_id(id)] = Look{Kind::kObject, nullptr, 0, id, std::move(look)};
  }
  return looks;
}

Json ViewModel::build(const Look& look, std::uint64_t stamp_ns) const {
  switch (look.kind) {
    case Look::Kind::kPalm:
      return hand_entity(*look.hand, hands_.at(*look.hand), stamp_ns);
    case Look::Kind::kPhalanx:
      return phalanx_entity(*look.hand, hands_.at(*look.hand), look.phalanx, stamp_ns);
    case Look::Kind::kContacts:
      return contacts_entity(*look.hand, hands_.at(*look.hand), stamp_ns);
    case Look::Kind::kObject:
      return object_entity(objects_.at(look.object_id), stamp_ns);
  }
  return Json();
}

Json ViewModel::hand_entity(const client::HandKey& key, const Hand& hand, std::uint64_t stamp_ns) const {
  Json e = scene_entity(hand_entity_id(key), palm_frame(key), stamp_ns);
  add_metadata(e, "kind", "hand");
  add_metadata(e, "client_id", key.client_id);
  add_metadata(e, "side", client::to_string(key.side));
  add_metadata(e, "rig", hand.skeleton.rig);
  const bool palm_contact = hand.state && hand.state->palm_contact;
  const Rgba identity = colours::hand_colour(hand.colour);
  add_metadata(e, "colour", Json::array({identity.r, identity.g, identity.b}).dump());
  if (hand.rig != nullptr) {
    add_box(e, Eigen::Isometry3d::Identity(), 2 * hand.rig->palm_half_extent(), colours::kSkin);
    // The palm sphere: the palm contact volume, in the hand's identity colour (red on contact).
    add_sphere(e, hand.rig->palm_contact().p_PalmCenter, hand.rig->palm_contact().radius,
               palm_contact ? colours::kBlocked : identity);
  } else {
    add_sphere(e, Eigen::Vector3d::Zero(), 0.02, identity);
  }
  return e;
}

Json ViewModel::phalanx_entity(const client::HandKey& key, const Hand& hand, std::size_t i,
                               std::uint64_t stamp_ns) const {
  const std::string name = phalanx_name(hand.rig, i);
  Json e = scene_entity(phalanx_entity_id(key, name), phalanx_frame(key, name), stamp_ns);
  add_metadata(e, "kind", "phalanx");
  add_metadata(e, "blocked", blocked(hand, i) ? "true" : "false");
  const Rgba c = blocked(hand, i) ? colours::kBlocked : colours::kSkin;
  if (hand.rig != nullptr && i < hand.rig->phalanges().size() && hand.rig->phalanges()[i].capsule) {
    const sim::CapsuleSpec& capsule = *hand.rig->phalanges()[i].capsule;
    add_capsule(e, capsule.p_PhalanxA, capsule.p_PhalanxB, capsule.radius, c);
  } else {
    add_sphere(e, Eigen::Vector3d::Zero(), kJointSphereRadius, c);
  }
  return e;
}

Json ViewModel::object_entity(const Object& object, std::uint64_t stamp_ns) const {
  const client::ObjectState& o = object.state;
  Json e = scene_entity(object_entity_id(o.id), object_frame(o.id), stamp_ns);
  add_metadata(e, "kind", "object");
  add_metadata(e, "name", o.name);
  add_metadata(e, "held", o.held ? "true" : "false");
  if (o.held) add_metadata(e, "holder", o.holder.client_id + "/" + client::to_string(o.holder.side));
  const auto mesh = meshes_.find(o.name);
  add_object_geometry(e, o, object.half_extent.cwiseMax(Eigen::Vector3d::Constant(kMinHalfExtent)),
                      o.held ? holder_colour(o) : colours::kFreeObject,
                      mesh == meshes_.end() ? nullptr : &mesh->second);
  return e;
}

Json ViewModel::contacts_entity(const client::HandKey& key, const Hand& hand, std::uint64_t stamp_ns) const {
  // In the object's frame: contacts stay put while the hand holds it.
  Json e = scene_entity(contacts_entity_id(key), object_frame(hand.contacts->object_id), stamp_ns);
  add_metadata(e, "kind", "contacts");
  for (const client::ContactPoint& c : hand.contacts->contacts) {
    add_arrow(e, c.p_ObjectContact, c.n_Object, kContactArrowLength, colours::kContact);
    add_sphere(e, c.p_ObjectContact, kContactDotRadius, colours::kContact);
  }
  return e;
}

Json ViewModel::scene_full(std::uint64_t stamp_ns) const {
  std::vector<Json> entities;
  for (const auto& [id, look] : appearance()) entities.push_back(build(look, stamp_ns));
  return scene_update(std::move(entities), {}, stamp_ns);
}

std::optional<Json> ViewModel::transforms_full(std::uint64_t stamp_ns) const {
  if (hands_.empty() && objects_.empty()) return std::nullopt;
  Json transforms = Json::array();
  for (const auto& [key, hand] : hands_) {
    const Eigen::Isometry3d& X_WorldPalm = hand.skeleton.X_WorldPalm;
    transforms.push_back(frame_transform("world", palm_frame(key), X_WorldPalm, stamp_ns));
    const Eigen::Isometry3d X_PalmWorld = X_WorldPalm.inverse();
    for (std::size_t i = 0; i < hand.skeleton.X_WorldPhalanx.size(); ++i)
      transforms.push_back(frame_transform(palm_frame(key), phalanx_frame(key, phalanx_name(hand.rig, i)),
                                           X_PalmWorld * hand.skeleton.X_WorldPhalanx[i], stamp_ns));
  }
  for (const auto& [id, object] : objects_)
    transforms.push_back(frame_transform("world", object_frame(id), object.state.X_WorldObject, stamp_ns));
  return Json{{"transforms", std::move(transforms)}};
}

Json ViewModel::moved_transforms(bool all, std::uint64_t stamp_ns) {
  // Exact comparison: a frame is re-sent when any bit of its pose changed.
  const auto moved = [all](const std::optional<Eigen::Isometry3d>& sent, const Eigen::Isometry3d& X) {
    return all || !sent || !(sent->matrix() == X.matrix());
  };
  Json transforms = Json::array();
  for (auto& [key, hand] : hands_) {
    const Eigen::Isometry3d& X_WorldPalm = hand.skeleton.X_WorldPalm;
    if (moved(hand.sent_X_WorldPalm, X_WorldPalm)) {
      transforms.push_back(frame_transform("world", palm_frame(key), X_WorldPalm, stamp_ns));
      hand.sent_X_WorldPalm = X_WorldPalm;
    }
    const Eigen::Isometry3d X_PalmWorld = X_WorldPalm.inverse();
    const std::size_t n = hand.skeleton.X_WorldPhalanx.size();
    const bool resend = all || hand.sent_X_PalmPhalanx.size() != n;
    hand.sent_X_PalmPhalanx.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Isometry3d X_PalmPhalanx = X_PalmWorld * hand.skeleton.X_WorldPhalanx[i];
      // Re-posing the hand leaves X_PalmPhalanx equal up to rounding: compare at 1e-9.
      if (resend || !X_PalmPhalanx.matrix().isApprox(hand.sent_X_PalmPhalanx[i].matrix(), 1e-9)) {
        transforms.push_back(
            frame_transform(palm_frame(key), phalanx_frame(key, phalanx_name(hand.rig, i)), X_PalmPhalanx, stamp_ns));
        hand.sent_X_PalmPhalanx[i] = X_PalmPhalanx;
      }
    }
  }
  for (auto& [id, object] : objects_) {
    if (moved(object.sent_X_WorldObject, object.state.X_WorldObject)) {
      transforms.push_back(frame_transform("world", object_frame(id), object.state.X_WorldObject, stamp_ns));
      object.sent_X_WorldObject = object.state.X_WorldObject;
    }
  }
  return Json{{"transforms", std::move(transforms)}};
}

std::vector<Json> ViewModel::grasp_states_full() const {
  std::vector<Json> out;
  for (const auto& [key, hand] : hands_) {
    if (!hand.state) continue;
    std::vector<std::string> names;
    for (std::size_t i = 0; i < hand.state->blocked.size(); ++i) names.push_back(phalanx_name(hand.rig, i));
    out.push_back(grasp_state_message(*hand.state, names));
  }
  return out;
}

}  // namespace telegrasp::view
