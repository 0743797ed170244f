// SceneServer: the simulation thread's state: the World, the hands of every client, the objects,
// and what is published after each input and each tick. Knows nothing of DDS entities.
#pragma once

#include "conversions.h"
#include "input_mailbox.h"
#include "output_sink.h"
#include "server_config.h"
#include "telegrasp/sim/world.h"

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::server {

/// Where the default scene puts each model: rows along +y from x = 0.35 m, footprints apart by
/// at least `gap`, all on a table of half extent `table_half_extent`.
std::vector<SceneObjectSpec> default_layout(const std::vector<sim::ObjectModelPtr>& models, double gap,
                                            double table_half_extent);

/// Timing of the loop that drives the SceneServer and the process's memory, for ServerStatus.
struct LoopStats {
  double tick_us_p50 = 0, tick_us_p99 = 0, tick_us_max = 0;
  std::uint64_t missed_ticks = 0;
  std::uint64_t rss_kib = 0, heap_kib = 0;
};

class SceneServer {
 public:
  /// Builds the scene: settings.restored_objects at their poses if set, else settings.objects or
  /// default_layout of every model. SceneState and ServerStatus carry settings.incarnation. Throws
  /// std::runtime_error naming a scene object whose model is unknown.
  SceneServer(const ServerSettings& settings, std::vector<sim::ObjectModelPtr> models,
              std::shared_ptr<const sim::HandRig> right_rig, std::shared_ptr<const sim::HandRig> left_rig,
              InputMailbox& mailbox, OutputSink& sink);

  /// Takes accepted samples: a new hand joins; the hand's input for the next tick is replaced;
  /// with late latching its skeleton is published at once, re-posed at the sample's palm.
  void on_inputs(std::vector<InputSample> samples, std::int64_t now_ns);
  /// One fixed tick: silent hands frozen or removed, physics and hands stepped, outputs published.
  void tick(std::int64_t now_ns);
  /// Applies a scene command; returns "" or why it was rejected (counted in the status per reason,
  /// logged once per client and reason, and told to its client in a ClientNotice). Any client may
  /// spawn (up to max_objects_per_client objects at once; an object spawned on the table where it
  /// would overlap another goes to the nearest free spot within kFreeSpotSearch, else is refused)
  /// and remove the objects it spawned or holds; operators may also remove any object and reset.
  std::string apply_command(const msg::SceneCommand& command);
  /// Lockstep: true when some hand is live (not frozen) and every live one has answered the current tick
  /// (ControllerState.lockstep_tick) and every command its client sent before that answer has
  /// been applied. Frozen hands are not waited for.
  bool lockstep_ready() const;
  /// The status message for the current state.
  msg::ServerStatus status(const LoopStats& loop) const;
  /// GraspEvents held for their grasp quality (at most quality_delay_ticks ticks' worth); a stop
  /// does not publish them.
  std::size_t held_events() const { return held_events_.size(); }

  const sim::World& world() const { return *world_; }
  std::size_t hand_count() const { return hands_.size(); }
  /// The hand of a client, if present.
  std::optional<sim::HandId> hand_id(const HandAddress& hand) const;
  static constexpr double kTableHalfExtent = 2.0;
  /// Objects set down on the table keep their centre this far inside its edge, m.
  static constexpr double kTableMargin = 0.05;
  /// An object below this height fell off the table: it is put back where it was spawned, or at
  /// the nearest free spot when another object now stands there.
  static constexpr double kFallenHeight = -1.0;
  /// How far from the requested spot a spawn on the table may be moved to a free one, m.
  static constexpr double kFreeSpotSearch = 0.5;

 private:
  struct Hand {
    sim::HandId id;
    InputStamp stamp;
    std::int64_t last_received_ns = 0;
    bool frozen = false;
    std::uint64_t answered_tick = 0;  // lockstep: ControllerState.lockstep_tick of the newest sample
    std::uint32_t commands_sent = 0;  // ... and its commands_sent
    std::optional<msg::GraspState> published_state;  // last GraspState sent (on change only)
  };
  struct Object {
    std::string name;
    std::string owner;  // the client that spawned it ("": the configured scene)
    double spawn_time = 0;
    Eigen::Isometry3d X_WorldSpawn = Eigen::Isometry3d::Identity();  // where it goes back if it falls off the table
  };
  void spawn_initial_scene();
  void spawn_restored_objects();  // settings_.restored_objects, at their poses
  sim::ObjectId spawn(const sim::ObjectModelPtr& model, const Eigen::Isometry3d& X_WorldObject,
                      const std::string& owner = "");
  /// The command's outcome: {"", ""} or {reason, detail}.
  std::pair<std::string, std::string> try_command(const msg::SceneCommand& command);
  std::pair<std::string, std::string> try_spawn(const msg::SceneCommand& command, bool is_operator);
  /// The nearest spot on the table to (x, y) where `model` overlaps no object (but `ignored`), if
  /// one is within kFreeSpotSearch.
  std::optional<Eigen::Vector2d> free_spot(const sim::ObjectModel& model, double x, double y,
                                           sim::ObjectId ignored = {}) const;
  /// Puts the objects that fell off the table back (kFallenHeight).
  void put_back_fallen();
  bool is_operator(const std::string& client_id) const;
  void remove_hand(std::map<HandAddress, Hand>::iterator it);
  void remove_object(sim::ObjectId id);
  // Builds the GraspEvents of the World's last step and holds them quality_delay_ticks ticks,
  // fills in each grasp's metrics and quality when the World delivers them, and publishes those
  // due, in order.
  void publish_events();
  msg::SceneState scene_state() const;

  struct HeldEvent {
    std::uint64_t due_tick = 0;  // published on this tick
    std::uint64_t quality_job = 0;  // grasp events: sim::GraspEvent::quality_job
    msg::GraspEvent message;
  };
  std::deque<HeldEvent> held_events_;

  ServerSettings settings_;
  std::map<std::string, sim::ObjectModelPtr> models_;
  std::vector<std::string> model_names_;  // in the order given
  std::shared_ptr<const sim::HandRig> rigs_[2];  // by side
  InputMailbox& mailbox_;
  OutputSink& sink_;
  std::unique_ptr<sim::World> world_;
  std::map<HandAddress, Hand> hands_;
  std::map<int, HandAddress> address_of_;  // by HandId; kept one tick after removal for its events
  std::map<int, Object> objects_;  // by ObjectId; likewise
  std::vector<int> retired_hands_, retired_objects_;  // removed since the last tick's events
  std::uint64_t next_event_id_ = 1;
  std::uint64_t commands_accepted_ = 0, commands_rejected_ = 0, notices_ = 0;
  std::map<std::string, std::uint64_t> commands_rejected_by_reason_;
  std::map<std::pair<std::string, std::string>, std::uint64_t> command_refusals_;  // per (client, reason), bounded
  std::map<std::string, std::uint64_t> commands_seen_;  // per client: its highest command_id applied
};

}  // namespace telegrasp::server
