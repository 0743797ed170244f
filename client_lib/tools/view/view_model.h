// ViewModel: telegrasp-view's picture of the scene, fed with what the client library holds (the
// newest sample of every output) and turned into Foxglove messages. No I/O and no threads: the
// web server's thread owns it. Geometry lives in each entity's own frame (a phalanx's capsule in
// the phalanx frame, an object's shape in the object frame), so motion travels on /tf alone and
// /scene changes only when something looks different (blocked, held, added, removed).
#pragma once

#include "foxglove_json.h"
#include "telegrasp/client/types.h"
#include "telegrasp/sim/hand_rig.h"

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::view {

/// One poll of the client: the newest sample of each output (per hand for per-hand outputs),
/// and the grasp events that arrived since the last poll.
struct ClientSnapshot {
  std::vector<client::HandSkeleton> skeletons;
  std::map<client::HandKey, client::GraspState> grasp_states;
  std::map<client::HandKey, client::ContactSet> contact_sets;
  std::optional<client::SceneState> scene;
  std::optional<client::ServerStatus> status;
  std::vector<client::GraspEvent> events;
  /// Object meshes by model name, as the server publishes them (client::Client::object_geometries()).
  std::map<std::string, std::shared_ptr<const client::ObjectGeometry>> geometries;
};

/// An object's mesh as the view draws it: decimated for the wire (a 10k-triangle YCB scan would be
/// about 1.4 MB of JSON per viewer), in the object's frame.
struct ObjectMesh {
  std::uint64_t content_hash = 0;  ///< Of the ObjectGeometry it came from.
  std::vector<Eigen::Vector3d> points;
  std::vector<std::uint32_t> indices;  ///< Three per triangle, counter-clockwise seen from outside.
};

/// The triangles of `geometry`, decimated to at most `max_triangles` (vertex clustering, as the
/// report's pictures do); empty when the server omitted the mesh.
ObjectMesh view_mesh(const client::ObjectGeometry& geometry, int max_triangles);

/// What one update produced, each ready to send on its channel.
struct ViewUpdate {
  std::optional<Json> scene;  ///< /scene: changed entities and deletions (absent: nothing changed).
  /// /tf: the frames that moved since the last update, and every frame every kFullTransformsEvery
  /// (absent: none moved). `transforms_full` is then every frame, for a viewer that missed one.
  std::optional<Json> transforms;
  bool transforms_complete = false;  ///< `transforms` holds every frame.
  std::vector<Json> grasp_states;  ///< /grasp_state: one per hand whose state changed.
  std::vector<Json> grasp_events;  ///< /grasp_events: in arrival order.
  std::optional<Json> server_status;  ///< /server_status: when a new one arrived.
};

class ViewModel {
 public:
  /// A rig by the name HandSkeleton carries, or nullptr when unknown (the hand is then drawn as
  /// spheres at its joints). Called once per name.
  using RigLookup = std::function<const sim::HandRig*(const std::string& rig_name)>;

  explicit ViewModel(RigLookup rigs);

  /// Takes in a poll of the client; `stamp_ns` (wall clock) stamps every message it builds.
  ViewUpdate update(const ClientSnapshot& snapshot, std::uint64_t stamp_ns);

  /// For a viewer that subscribes now: the whole scene as one SceneUpdate.
  Json scene_full(std::uint64_t stamp_ns) const;
  /// Every frame as one FrameTransforms; absent before anything arrived.
  std::optional<Json> transforms_full(std::uint64_t stamp_ns) const;
  /// The newest grasp state of every hand.
  std::vector<Json> grasp_states_full() const;
  /// The last `kEventHistory` grasp events, oldest first.
  const std::deque<Json>& event_history() const { return event_history_; }
  /// The newest server status, if any.
  const std::optional<Json>& server_status() const { return server_status_; }

  static constexpr std::size_t kEventHistory = 256;
  /// How often /tf carries every frame even if none moved (for viewers' transform buffers).
  static constexpr std::uint64_t kFullTransformsEveryNs = 2'000'000'000;

  std::size_t hand_count() const { return hands_.size(); }
  std::size_t object_count() const { return objects_.size(); }

 private:
  struct Hand {
    client::HandSkeleton skeleton;
    std::vector<Eigen::Isometry3d> sent_X_PalmPhalanx;  ///< On /tf last.
    std::optional<Eigen::Isometry3d> sent_X_WorldPalm;
    const sim::HandRig* rig = nullptr;
    std::size_t colour = 0;
    std::optional<client::GraspState> state;
    std::optional<client::ContactSet> contacts;  ///< Shown while the hand holds their object.
  };
  struct Object {
    client::ObjectState state;
    Eigen::Vector3d half_extent{0.02, 0.02, 0.02};  ///< Of the placeholder box.
    std::optional<Eigen::Isometry3d> sent_X_WorldObject;  ///< On /tf last.
  };

  const sim::HandRig* rig(const std::string& name);
  bool blocked(const Hand& hand, std::size_t phalanx) const;
  bool shows_contacts(const Hand& hand) const;
  Rgba holder_colour(const client::ObjectState& object) const;
  void grow_placeholder(int object_id, const std::vector<client::ContactPoint>& contacts);

  Json hand_entity(const client::HandKey& key, const Hand& hand, std::uint64_t stamp_ns) const;
  Json phalanx_entity(const client::HandKey& key, const Hand& hand, std::size_t phalanx, std::uint64_t stamp_ns) const;
  Json object_entity(const Object& object, std::uint64_t stamp_ns) const;
  Json contacts_entity(const client::HandKey& key, const Hand& hand, std::uint64_t stamp_ns) const;
  /// An entity: what it draws (a hand's palm, one of its phalanges, its contacts, an object) and
  /// a key of how it looks: an entity is re-sent when its key changes.
  struct Look {
    enum class Kind { kPalm, kPhalanx, kContacts, kObject } kind;
    const client::HandKey* hand = nullptr;  ///< Into hands_, valid until it changes.
    std::size_t phalanx = 0;
    int object_id = -1;
    std::string key;
  };
  std::map<std::string, Look> appearance() const;
  Json build(const Look& look, std::uint64_t stamp_ns) const;
  /// The frames that moved since they were last on /tf (all if `all`), marked as sent.
  Json moved_transforms(bool all, std::uint64_t stamp_ns);

  RigLookup rig_lookup_;
  std::map<std::string, const sim::HandRig*> rigs_;
  std::map<client::HandKey, Hand> hands_;
  std::map<int, Object> objects_;
  std::map<std::string, ObjectMesh> meshes_;  ///< By model name, once its geometry arrived.
  std::size_t next_colour_ = 0;
  std::map<std::string, std::string> sent_;  ///< Entity id -> appearance key last sent.
  std::uint64_t last_scene_tick_ = 0;
  std::optional<std::uint64_t> last_status_tick_;
  std::uint64_t last_full_transforms_ns_ = 0;
  std::deque<Json> event_history_;
  std::optional<Json> server_status_;
};

/// Adds to `entity` (in the object's own frame) the primitives that draw an object: its mesh as a
/// foxglove TriangleListPrimitive when the server published it (`mesh` not null; sent once per
/// object and to each viewer that subscribes later, and again only when its colour changes), else
/// a placeholder box of `half_extent` (grown to enclose every contact point seen on the object, at
/// least 2 cm); and the object's name.
void add_object_geometry(Json& entity, const client::ObjectState& object, const Eigen::Vector3d& half_extent,
                         const Rgba& colour, const ObjectMesh* mesh);

}  // namespace telegrasp::view
