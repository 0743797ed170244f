// telegrasp::client::Client: publish controller states and commands to a telegrasp server and
// receive everything it publishes, with callbacks or by polling. No Fast DDS types here.
#pragma once

#include "telegrasp/client/types.h"

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::client {

/// Server outputs a client subscribes to (bits; default all).
enum Topics : unsigned {
  kHandSkeletons = 1u << 0,
  kGraspStates = 1u << 1,
  kContactSets = 1u << 2,
  kGraspEvents = 1u << 3,
  kSceneStates = 1u << 4,
  kServerStatuses = 1u << 5,
  kObjectGeometries = 1u << 6,  ///< Each model's mesh and mass, once per model (late joiners too).
  kNotices = 1u << 7,  ///< Why the server refused this client's inputs or commands (only this client's).
  kAllTopics = (1u << 8) - 1,  ///< Every output of the client's scene.
  /// The scene directory (every scene's servers: Client::scenes()); not in kAllTopics.
  kSceneDirectory = 1u << 8,
};

struct ClientOptions {
  std::string client_id;  ///< Names this client's hands; 1..64 characters.
  int domain = 0;  ///< DDS domain, 0..232.
  /// Participant profile: loopback, lan, wan, or secure (DDS Security: the identity comes from
  /// $TELEGRASP_SECURITY_DIR and $TELEGRASP_IDENTITY).
  std::string profile = "loopback";
  std::string profiles_file;  ///< "": $TELEGRASP_PROFILES, else the shipped file.
  /// The scene (room) to join: only its server's samples arrive (DDS partition
  /// telegrasp/scene/<scene>). 1-64 letters, digits, '-', '_', '.'; "": $TELEGRASP_SCENE, else
  /// "default".
  std::string scene;
  /// Fast DDS discovery servers, "HOST[:PORT]" in server-id order (`fastdds discovery -i 0`, ...);
  /// empty: $TELEGRASP_DISCOVERY_SERVERS, else the profile's discovery.
  std::vector<std::string> discovery_servers;
  unsigned topics = kAllTopics;  ///< Outputs to subscribe to (bits of Topics).
  /// A relay forwarding many users' hands (a server's --relay PREFIX; telegrasp-view --drive):
  /// publish_as() sends as client ids that start with this prefix, and their notices arrive with
  /// this client's. "": not a relay.
  std::string relay_prefix;
};

/// "" when `name` can be a scene name (ClientOptions::scene), else why not.
std::string scene_name_error(const std::string& name);
/// "" when `address` can be a discovery server (ClientOptions::discovery_servers: HOST[:PORT],
/// HOST resolving to an IPv4 address), else why not.
std::string discovery_server_error(const std::string& address);

/// One DDS participant with a writer per input topic and a reader per subscribed output.
/// Thread-safe. Callbacks run on a DDS thread: keep them short, do not call back into the
/// client from them except the poll/take functions, and do not set a callback or destroy the
/// client while holding a lock your callbacks take. No callback runs after the destructor returns.
class Client {
 public:
  /// Throws std::runtime_error naming what is wrong (client id, domain, profiles file, profile).
  explicit Client(ClientOptions options);
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  const std::string& client_id() const;

  /// Publishes one controller sample; returns the sequence number it carries. Invalid values go out
  /// unchanged; throws std::invalid_argument only for what the wire cannot carry (> 5 curls).
  std::uint64_t publish(const ControllerSample& sample);
  /// publish() as `client_id`, which starts with ClientOptions::relay_prefix, with the sample's
  /// own sequence number (not 0: the relay numbers each id's hands). Throws std::invalid_argument
  /// for an id outside the prefix or sequence number 0.
  std::uint64_t publish_as(const std::string& client_id, const ControllerSample& sample);
  /// Sends a scene command (reliable); returns its command id (1, 2, 3 ...). Throws
  /// std::invalid_argument for a model name longer than 128 characters, std::runtime_error when
  /// the secure profile's permissions give this identity no operator role.
  std::uint64_t send_command(const SceneCommand& command);

  /// Callbacks, one per output; setting one replaces the previous (no longer running when the
  /// setter returns), then calls the new one at once, on the caller's thread, with what arrived
  /// before it: the newest sample of each hand or output, and grasp events no callback has seen.
  /// Each callback gets each sample once, in arrival order. Empty function: none.
  void on_hand_skeleton(std::function<void(const HandSkeleton&)> callback);
  void on_grasp_state(std::function<void(const GraspState&)> callback);
  void on_contact_set(std::function<void(const ContactSet&)> callback);
  void on_grasp_event(std::function<void(const GraspEvent&)> callback);
  void on_scene_state(std::function<void(const SceneState&)> callback);
  void on_server_status(std::function<void(const ServerStatus&)> callback);
  /// Each model's geometry as it arrives; the caught-up snapshot is every model's newest one.
  void on_object_geometry(std::function<void(const std::shared_ptr<const ObjectGeometry>&)> callback);
  /// The server refused an input or command of this client (the error callback); the caught-up
  /// snapshot is the newest notice, if any.
  void on_notice(std::function<void(const Notice&)> callback);
  /// A restarted server: called when a SceneState or ServerStatus of a new incarnation arrives
  /// (never for the first server seen; nothing to catch up), before that sample is delivered. By
  /// then the old run's state is dropped: the latest hand skeletons, grasp states and contact sets
  /// it sent, and its scene state and status; its late samples are dropped too. Object ids, ticks
  /// and server times of the old run are not comparable with the new one's. The client goes on
  /// (its writers match the new server by themselves): nothing to reconnect.
  void on_server_restart(std::function<void(const ServerRestart&)> callback);
  /// The incarnation of the newest server run seen (0: none yet), and how many restarts were seen.
  std::uint64_t server_incarnation() const;
  std::uint64_t server_restarts() const;

  /// Polling: the newest sample of each output (per hand for per-hand outputs).
  std::optional<SceneState> latest_scene_state() const;
  std::optional<ServerStatus> latest_server_status() const;
  std::vector<HandSkeleton> latest_hand_skeletons() const;
  std::optional<GraspState> latest_grasp_state(const HandKey& hand) const;
  std::optional<ContactSet> latest_contact_set(const HandKey& hand) const;
  /// The newest geometry of `model`, or null if none has arrived. A geometry is checked on arrival
  /// (whole vertices and triangles, indices in range, finite coordinates, content hash) and
  /// dropped, with one line on stderr per model and reason, if it fails. Geometries are cached by
  /// content hash: the same geometry arriving again (e.g. from a restarted server) is not rebuilt
  /// and yields the same pointer; the same mesh under another name reuses the cached mesh.
  std::shared_ptr<const ObjectGeometry> object_geometry(const std::string& model) const;
  /// Every model's newest geometry, by model name.
  std::map<std::string, std::shared_ptr<const ObjectGeometry>> object_geometries() const;
  /// The newest refusal of this client, if the server refused anything (kNotices).
  std::optional<Notice> last_notice() const;
  /// The live servers on the scene directory, every scene (kSceneDirectory; empty without it).
  /// A server appears within about a second of discovery and goes when it stops, or 3 s after it
  /// dies.
  std::vector<SceneInfo> scenes() const;
  /// The scene joined (resolved: never empty).
  const std::string& scene() const;
  /// Every grasp event received since the last call, in arrival order.
  std::vector<GraspEvent> take_grasp_events();

  /// Waits until a server is matched (it reads our controller states and scene commands, and we
  /// have its status if subscribed to kServerStatuses); false on timeout.
  bool wait_for_server(std::chrono::milliseconds timeout) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace telegrasp::client
