#include "telegrasp/client/client.h"

#include "conversions.h"
#include "telegrasp/idl/dds_participant.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <iostream>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <utility>

namespace telegrasp::client {

namespace dds = eprosima::fastdds::dds;
namespace msg = telegrasp::msg;
using client_lib::from_msg;
using client_lib::to_msg;

namespace {

constexpr std::size_t kMaxClientIdChars = 64;  // string<64> in the IDL
constexpr int kMaxDomain = 232;  // the highest domain whose UDP ports fit in 16 bits
constexpr std::size_t kMaxCurls = 5;  // sequence<double, 5>
constexpr std::size_t kMaxModelChars = 128;  // string<128>
constexpr std::size_t kMaxQueuedGraspEvents = 4096;
constexpr std::chrono::milliseconds kServerPollPeriod{10};

// Start-up mistakes in the options: fail fast, naming the field and what was expected.
void validate(const ClientOptions& o) {
  if (o.client_id.empty() || o.client_id.size() > kMaxClientIdChars)
    throw std::runtime_error("ClientOptions.client_id '" + o.client_id + "' has " + std::to_string(o.client_id.size()) +
                             " characters; expected 1.." + std::to_string(kMaxClientIdChars));
  if (o.client_id.find('\0') != std::string::npos)
    throw std::runtime_error("ClientOptions.client_id contains a NUL character, which the wire cannot carry");
  if (o.relay_prefix.size() >= kMaxClientIdChars || o.relay_prefix.find('\0') != std::string::npos)
    throw std::runtime_error("ClientOptions.relay_prefix '" + o.relay_prefix + "' must be shorter than " +
                             std::to_string(kMaxClientIdChars) + " characters, without NUL");
  if (o.domain < 0 || o.domain > kMaxDomain)
    throw std::runtime_error("ClientOptions.domain is " + std::to_string(o.domain) + "; expected 0.." +
                             std::to_string(kMaxDomain));
  if (o.profile.empty())
    throw std::runtime_error(
        "ClientOptions.profile is empty; expected a participant profile name (loopback, lan, wan)");
  if ((o.topics & ~static_cast<unsigned>(kAllTopics | kSceneDirectory)) != 0)
    throw std::runtime_error("ClientOptions.topics has bits outside kAllTopics and kSceneDirectory");
  if (!o.scene.empty())
    if (const std::string e = idl::scene_name_error(o.scene); !e.empty())
      throw std::runtime_error("ClientOptions.scene: " + e);
}

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// A user callback of one output. The mutex is held while the callback runs, is replaced, or is
// caught up, so each callback sees every sample once and in order, and a replaced callback is no
// longer running when its setter returns.
template <class T>
struct Channel {
  std::mutex mutex;
  std::function<void(const T&)> callback;
};

// The participant (GUID prefix) of a sample's writer: which server run sent it.
using Source = std::array<std::uint8_t, 12>;

Source source_of(const dds::SampleInfo& info) {
  Source s{};
  const std::uint8_t* guid = info.publication_handle.value;  // the writer's GUID: prefix, then entity id
  std::copy_n(guid, s.size(), s.begin());
  return s;
}

// The newest sample of a per-hand output, the participant that sent it, and which DDS instance is
// which hand (a disposed instance arrives without its key).
template <class T>
struct PerHand {
  std::map<HandKey, T> latest;
  std::map<HandKey, Source> source;
  std::map<dds::InstanceHandle_t, HandKey> hand_of_instance;
};

}  // namespace

struct Client::Impl {
  template <class Msg>
  class Listener;

  explicit Impl(ClientOptions options_in);
  ~Impl() { close(); }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  template <class PubSubType>
  void reader(const char* name);
  void close();
  bool server_ready() const;

  // Called on DDS threads by the listeners, one per valid sample.
  void received(const msg::HandSkeleton& m, const dds::SampleInfo& info);
  void received(const msg::GraspState& m, const dds::SampleInfo& info);
  void received(const msg::ContactSet& m, const dds::SampleInfo& info);
  void received(const msg::GraspEvent& m, const dds::SampleInfo& info);
  void received(const msg::SceneState& m, const dds::SampleInfo& info);
  void received(const msg::ServerStatus& m, const dds::SampleInfo& info);
  void received(const msg::ObjectGeometry& m, const dds::SampleInfo& info);
  // A SceneState or ServerStatus of `incarnation` from `source` arrived: on a new incarnation, the
  // old run's per-hand samples, scene and status are dropped and the restart callback runs. False
  // if the sample is of an incarnation already replaced (late, from a server run that is gone): drop it.
  bool noticed(std::uint64_t incarnation, const Source& source);
  void received(const msg::ClientNotice& m, const dds::SampleInfo& info);
  /// Writes `sample` as `client_id`; `numbered_here`: a sequence number 0 takes the hand's next.
  std::uint64_t publish(const std::string& client_id, const ControllerSample& sample, bool numbered_here);
  // The (checked) geometry `m` describes, built from a cached one with the same content hash: the
  // very same object if nothing differs, else a new one with a copy of its mesh; null if none is cached.
  std::shared_ptr<const ObjectGeometry> cached_geometry(const msg::ObjectGeometry& m);
  // Called when the server disposes a hand's instance (the hand left): it leaves latest_*.
  void disposed(const msg::HandSkeleton*, const dds::InstanceHandle_t& instance) { forget(skeletons, instance); }
  void disposed(const msg::GraspState*, const dds::InstanceHandle_t& instance) { forget(grasp_states, instance); }
  void disposed(const msg::ContactSet*, const dds::InstanceHandle_t& instance) { forget(contact_sets, instance); }
  template <class Msg>
  void disposed(const Msg*, const dds::InstanceHandle_t&) {}  // unkeyed topics: nothing per instance

  template <class T>
  void remember(PerHand<T>& store, const T& value, const dds::SampleInfo& info);
  template <class T>
  void forget(PerHand<T>& store, const dds::InstanceHandle_t& instance);
  template <class T>
  void call(Channel<T>& channel, const T& value, const char* what);
  // A per-hand sample (HandSkeleton, GraspState, ContactSet): remembered in `store`, then delivered.
  template <class T, class Msg>
  void received_per_hand(const Msg& m, const dds::SampleInfo& info, PerHand<T>& store, Channel<T>& channel,
                         const char* what);
  // A scene-wide sample (SceneState, ServerStatus) the client keeps only the newest of: if
  // noticed(), kept in `newest`, then delivered.
  template <class T, class Msg>
  void received_newest(const Msg& m, const dds::SampleInfo& info, std::optional<T>& newest, Channel<T>& channel,
                       const char* what);
  template <class T, class Snapshot>
  void set_callback(Channel<T>& channel, std::function<void(const T&)> callback, const Snapshot& snapshot,
                    const char* what);

  const ClientOptions options;
  std::vector<std::unique_ptr<dds::DataReaderListener>> listeners;  // outlive their readers
  std::optional<idl::DdsParticipant> participant;  // after the listeners: destroyed before them
  dds::DataWriter* controller_writer = nullptr;
  dds::DataWriter* command_writer = nullptr;
  dds::DataReader* directory_reader = nullptr;  // kSceneDirectory: read on demand, no listener

  // Outgoing numbering; held across the write so numbers go out in order.
  std::mutex publish_mutex;
  std::map<std::uint8_t, std::uint64_t> last_sequence;  // per raw hand-side value
  std::uint64_t last_command_id = 0;

  // Received data.
  mutable std::mutex data_mutex;
  PerHand<HandSkeleton> skeletons;
  PerHand<GraspState> grasp_states;
  PerHand<ContactSet> contact_sets;
  std::optional<SceneState> scene;
  std::optional<ServerStatus> status;
  std::optional<Notice> notice;  // the newest of this client
  std::vector<GraspEvent> events;  // for take_grasp_events
  std::map<std::string, std::shared_ptr<const ObjectGeometry>> geometries;  // newest per model
  std::multimap<std::uint64_t, std::weak_ptr<const ObjectGeometry>> geometry_by_hash;  // cache of those in use
  std::set<std::string> geometry_rejections_logged;  // model and reason
  std::uint64_t incarnation = 0;  // of the newest server run seen; 0: none yet
  std::uint64_t restarts = 0;
  std::set<std::uint64_t> retired_incarnations;
  std::map<Source, std::uint64_t> incarnation_of;  // per server participant seen

  // User callbacks, one channel per output.
  Channel<HandSkeleton> skeleton_channel;
  Channel<GraspState> grasp_state_channel;
  Channel<ContactSet> contact_set_channel;
  Channel<GraspEvent> grasp_event_channel;
  Channel<SceneState> scene_state_channel;
  Channel<ServerStatus> server_status_channel;
  Channel<std::shared_ptr<const ObjectGeometry>> geometry_channel;
  Channel<Notice> notice_channel;
  Channel<ServerRestart> restart_channel;
  std::vector<GraspEvent> unseen_events;  // arrived while no event callback was set; under its channel's mutex
  std::atomic<bool> callback_threw{false};

  // Listener calls in flight; close() stops new ones and waits for these to finish.
  std::mutex dispatch_mutex;
  std::condition_variable dispatch_idle;
  int dispatching = 0;
  std::atomic<bool> closing{false};
};

// Drains a reader: every valid sample to Impl::received, every disposed instance to
// Impl::disposed. Does nothing once the client is closing.
template <class Msg>
class Client::Impl::Listener final : public dds::DataReaderListener {
 public:
  explicit Listener(Impl& impl) : impl_(impl) {}

  void on_data_available(dds::DataReader* reader) override {
    {
      std::lock_guard lock(impl_.dispatch_mutex);
      if (impl_.closing) return;
      ++impl_.dispatching;
    }
    Msg sample;
    dds::SampleInfo info;
    while (!impl_.closing && reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (info.valid_data)
        impl_.received(sample, info);
      else if (info.instance_state == dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE)
        impl_.disposed(static_cast<const Msg*>(nullptr), info.instance_handle);
    }
    std::lock_guard lock(impl_.dispatch_mutex);
    if (--impl_.dispatching == 0) impl_.dispatch_idle.notify_all();
  }

 private:
  Impl& impl_;
};

Client::Impl::Impl(ClientOptions options_in) : options(std::move(options_in)) {
  validate(options);
  try {
    participant.emplace(options.domain, options.profile, options.profiles_file, nullptr,
                        idl::Network{options.scene, options.discovery_servers});
    controller_writer = participant->writer<msg::ControllerStatePubSubType>(idl::kControllerStateTopic);
    try {
      command_writer = participant->writer<msg::SceneCommandPubSubType>(idl::kSceneCommandTopic);
    } catch (const std::runtime_error&) {
      // With DDS Security, only identities with the operator role may write SceneCommand: the
      // others drive hands and watch, and send_command() says why it cannot.
      if (!participant->secure()) throw;
    }
    // Readers last: their listeners may run as soon as they exist.
    if (options.topics & kHandSkeletons) reader<msg::HandSkeletonPubSubType>(idl::kHandSkeletonTopic);
    if (options.topics & kGraspStates) reader<msg::GraspStatePubSubType>(idl::kGraspStateTopic);
    if (options.topics & kContactSets) reader<msg::ContactSetPubSubType>(idl::kContactSetTopic);
    if (options.topics & kGraspEvents) reader<msg::GraspEventPubSubType>(idl::kGraspEventTopic);
    if (options.topics & kSceneStates) reader<msg::SceneStatePubSubType>(idl::kSceneStateTopic);
    if (options.topics & kServerStatuses) reader<msg::ServerStatusPubSubType>(idl::kServerStatusTopic);
    if (options.topics & kObjectGeometries) reader<msg::ObjectGeometryPubSubType>(idl::kObjectGeometryTopic);
    if (options.topics & kNotices) reader<msg::ClientNoticePubSubType>(idl::kClientNoticeTopic);
    if (options.topics & kSceneDirectory)
      directory_reader = participant->reader<msg::SceneAnnouncementPubSubType>(idl::kSceneDirectoryTopic);
  } catch (...) {
    close();
    throw;
  }
}

template <class PubSubType>
void Client::Impl::reader(const char* name) {
  listeners.push_back(std::make_unique<Listener<typename PubSubType::type>>(*this));
  participant->reader<PubSubType>(name, listeners.back().get());
}

void Client::Impl::close() {
  {
    std::unique_lock lock(dispatch_mutex);
    closing = true;
    dispatch_idle.wait(lock, [&] { return dispatching == 0; });
  }
  participant.reset();  // detaches the listeners, then deletes every entity
}

bool Client::Impl::server_ready() const {
  // Both writers: a command sent right after wait_for_server must not go to an unmatched reader.
  for (dds::DataWriter* w : {controller_writer, command_writer}) {
    if (w == nullptr) continue;  // no operator role: no commands to send
    dds::PublicationMatchedStatus matched;
    if (w->get_publication_matched_status(matched) != ReturnCode_t::RETCODE_OK || matched.current_count <= 0)
      return false;
  }
  if ((options.topics & kServerStatuses) == 0) return true;
  std::lock_guard lock(data_mutex);
  return status.has_value();
}

template <class T>
void Client::Impl::remember(PerHand<T>& store, const T& value, const dds::SampleInfo& info) {
  std::lock_guard lock(data_mutex);
  store.hand_of_instance[info.instance_handle] = value.hand;
  store.latest[value.hand] = value;
  store.source[value.hand] = source_of(info);
}

namespace {

// Drops the per-hand samples not sent by `source`.
template <class T>
void keep_only(PerHand<T>& store, const Source& source) {
  for (auto it = store.latest.begin(); it != store.latest.end();) {
    auto s = store.source.find(it->first);
    if (s != store.source.end() && s->second == source) {
      ++it;
      continue;
    }
    store.source.erase(it->first);
    it = store.latest.erase(it);
  }
}

}  // namespace

bool Client::Impl::noticed(std::uint64_t new_incarnation, const Source& source) {
  ServerRestart restart;
  {
    std::lock_guard lock(data_mutex);
    if (retired_incarnations.count(new_incarnation)) return false;
    incarnation_of[source] = new_incarnation;
    if (new_incarnation == incarnation) return true;
    restart = {incarnation, new_incarnation};
    incarnation = new_incarnation;
    if (restart.previous_incarnation == 0) return true;  // the first server seen
    // A new server run: what the old one said about hands and objects no longer holds.
    retired_incarnations.insert(restart.previous_incarnation);
    ++restarts;
    keep_only(skeletons, source);
    keep_only(grasp_states, source);
    keep_only(contact_sets, source);
    if (scene && scene->incarnation != new_incarnation) scene.reset();
    if (status && status->incarnation != new_incarnation) status.reset();
  }
  std::lock_guard delivery(restart_channel.mutex);
  call(restart_channel, restart, "server restart");
  return true;
}

template <class T>
void Client::Impl::forget(PerHand<T>& store, const dds::InstanceHandle_t& instance) {
  std::lock_guard lock(data_mutex);
  const auto it = store.hand_of_instance.find(instance);
  if (it == store.hand_of_instance.end()) return;
  store.latest.erase(it->second);
  store.hand_of_instance.erase(it);
}

template <class T>
void Client::Impl::call(Channel<T>& channel, const T& value, const char* what) {
  if (!channel.callback) return;
  // An exception must not unwind into Fast DDS's threads: report the first one, drop the rest.
  try {
    channel.callback(value);
  } catch (const std::exception& e) {
    if (!callback_threw.exchange(true))
      std::cerr << "telegrasp client: the " << what << " callback threw: " << e.what() << "\n";
  } catch (...) {
    if (!callback_threw.exchange(true)) std::cerr << "telegrasp client: the " << what << " callback threw\n";
  }
}

// Replaces the callback, then catches the new one up with `snapshot()` (what arrived before it).
template <class T, class Snapshot>
void Client::Impl::set_callback(Channel<T>& channel, std::function<void(const T&)> callback, const Snapshot& snapshot,
                                const char* what) {
  std::lock_guard delivery(channel.mutex);
  channel.callback = std::move(callback);
  if (!channel.callback) return;
  for (const T& value : snapshot()) call(channel, value, what);
}

template <class T, class Msg>
void Client::Impl::received_per_hand(const Msg& m, const dds::SampleInfo& info, PerHand<T>& store,
                                     Channel<T>& channel, const char* what) {
  const T s = from_msg(m);
  std::lock_guard delivery(channel.mutex);
  remember(store, s, info);
  call(channel, s, what);
}

void Client::Impl::received(const msg::HandSkeleton& m, const dds::SampleInfo& info) {
  received_per_hand(m, info, skeletons, skeleton_channel, "HandSkeleton");
}

void Client::Impl::received(const msg::GraspState& m, const dds::SampleInfo& info) {
  received_per_hand(m, info, grasp_states, grasp_state_channel, "GraspState");
}

void Client::Impl::received(const msg::ContactSet& m, const dds::SampleInfo& info) {
  received_per_hand(m, info, contact_sets, contact_set_channel, "ContactSet");
}

void Client::Impl::received(const msg::GraspEvent& m, const dds::SampleInfo& info) {
  GraspEvent e = from_msg(m);
  std::lock_guard delivery(grasp_event_channel.mutex);
  {
    std::lock_guard lock(data_mutex);
    const auto known = incarnation_of.find(source_of(info));
    e.server_incarnation = known != incarnation_of.end() ? known->second : incarnation;
    if (events.size() == kMaxQueuedGraspEvents) events.erase(events.begin());  // nobody polls: keep the newest
    events.push_back(e);
  }
  if (grasp_event_channel.callback) {
    call(grasp_event_channel, e, "GraspEvent");
  } else {
    if (unseen_events.size() == kMaxQueuedGraspEvents) unseen_events.erase(unseen_events.begin());
    unseen_events.push_back(e);
  }
}

template <class T, class Msg>
void Client::Impl::received_newest(const Msg& m, const dds::SampleInfo& info, std::optional<T>& newest,
                                   Channel<T>& channel, const char* what) {
  if (!noticed(m.incarnation(), source_of(info))) return;
  const T s = from_msg(m);
  std::lock_guard delivery(channel.mutex);
  {
    std::lock_guard lock(data_mutex);
    newest = s;
  }
  call(channel, s, what);
}

void Client::Impl::received(const msg::SceneState& m, const dds::SampleInfo& info) {
  received_newest(m, info, scene, scene_state_channel, "SceneState");
}

void Client::Impl::received(const msg::ServerStatus& m, const dds::SampleInfo& info) {
  received_newest(m, info, status, server_status_channel, "ServerStatus");
}

std::shared_ptr<const ObjectGeometry> Client::Impl::cached_geometry(const msg::ObjectGeometry& m) {
  const ObjectGeometry header = client_lib::from_msg_without_mesh(m);
  auto same_mesh = [&](const ObjectGeometry& c) {
    return c.vertex_count == header.vertex_count && c.triangle_count == header.triangle_count &&
           c.mesh_omitted == header.mesh_omitted;
  };
  auto same_rest = [&](const ObjectGeometry& c) {
    return c.model == header.model && c.p_ObjectMin == header.p_ObjectMin && c.p_ObjectMax == header.p_ObjectMax &&
           c.mass_kg == header.mass_kg && c.volume_m3 == header.volume_m3 &&
           c.inertia_diagonal == header.inertia_diagonal && c.p_ObjectSourceOrigin == header.p_ObjectSourceOrigin;
  };
  std::shared_ptr<const ObjectGeometry> mesh_donor;
  {
    std::lock_guard lock(data_mutex);
    const auto [begin, end] = geometry_by_hash.equal_range(m.content_hash());
    for (auto it = begin; it != end; ++it) {
      std::shared_ptr<const ObjectGeometry> c = it->second.lock();
      if (!c || !same_mesh(*c)) continue;
      if (same_rest(*c)) return c;  // nothing differs: the very same object
      mesh_donor = std::move(c);
    }
  }
  if (!mesh_donor) return nullptr;
  ObjectGeometry g = header;  // the same mesh under another name or with other properties
  g.vertices = mesh_donor->vertices;
  g.triangles = mesh_donor->triangles;
  return std::make_shared<const ObjectGeometry>(std::move(g));
}

void Client::Impl::received(const msg::ObjectGeometry& m, const dds::SampleInfo&) {
  // Checked every time (the hash over ~200 KB costs well under a millisecond), so a sample that
  // claims a cached hash but carries other bytes is dropped, not mistaken for the cached mesh.
  if (const std::string why = client_lib::check_object_geometry(m); !why.empty()) {
    const std::string model = m.model().to_string();
    bool first = false;
    {
      std::lock_guard lock(data_mutex);
      first = geometry_rejections_logged.insert(model + '\n' + why).second;
    }
    if (first) std::cerr << "telegrasp client: dropped the ObjectGeometry of model '" << model << "': " << why << "\n";
    return;
  }
  std::shared_ptr<const ObjectGeometry> g = cached_geometry(m);
  if (!g) g = std::make_shared<const ObjectGeometry>(from_msg(m));
  std::lock_guard delivery(geometry_channel.mutex);
  {
    std::lock_guard lock(data_mutex);
    geometries[g->model] = g;
    std::erase_if(geometry_by_hash, [](const auto& entry) { return entry.second.expired(); });
    const auto [begin, end] = geometry_by_hash.equal_range(g->content_hash);
    if (std::none_of(begin, end, [&](const auto& entry) { return entry.second.lock() == g; }))
      geometry_by_hash.emplace(g->content_hash, g);
  }
  call(geometry_channel, g, "ObjectGeometry");
}

void Client::Impl::received(const msg::ClientNotice& m, const dds::SampleInfo&) {
  const std::string id = m.client_id().to_string();
  if (id != options.client_id && (options.relay_prefix.empty() || !id.starts_with(options.relay_prefix)))
    return;  // another client's
  const Notice n = from_msg(m);
  std::lock_guard delivery(notice_channel.mutex);
  {
    std::lock_guard lock(data_mutex);
    notice = n;
  }
  call(notice_channel, n, "Notice");
}

Client::Client(ClientOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}

Client::~Client() = default;

const std::string& Client::client_id() const { return impl_->options.client_id; }

std::uint64_t Client::publish(const ControllerSample& sample) {
  return impl_->publish(impl_->options.client_id, sample, true);
}

std::uint64_t Client::publish_as(const std::string& client_id, const ControllerSample& sample) {
  const std::string& prefix = impl_->options.relay_prefix;
  if (prefix.empty() || !client_id.starts_with(prefix) || client_id.size() > kMaxClientIdChars)
    throw std::invalid_argument("publish_as: client id '" + client_id + "' is not under this client's relay_prefix '" +
                                prefix + "' (or longer than " + std::to_string(kMaxClientIdChars) + " characters)");
  if (sample.sequence_number == 0)
    throw std::invalid_argument("publish_as: client " + client_id + " needs the sample's own sequence number");
  return impl_->publish(client_id, sample, false);
}

std::uint64_t Client::Impl::publish(const std::string& client_id, const ControllerSample& sample, bool numbered_here) {
  if (sample.curls.size() > kMaxCurls)
    throw std::invalid_argument("ControllerSample.curls has " + std::to_string(sample.curls.size()) +
                                " values; the wire carries at most " + std::to_string(kMaxCurls));
  msg::ControllerState m = to_msg(sample, client_id);
  if (m.client_time_ns() == 0) m.client_time_ns(steady_now_ns());
  std::lock_guard lock(publish_mutex);
  if (numbered_here) {
    // 0: one more than the largest number this hand has carried, so an explicit stale number
    // (sent on purpose) does not make the following automatic ones stale too.
    std::uint64_t& last = last_sequence[m.hand_side()];
    if (m.sequence_number() == 0) m.sequence_number(last + 1);
    last = std::max(last, m.sequence_number());
  }
  m.commands_sent(static_cast<std::uint32_t>(last_command_id));
  if (!controller_writer->write(&m))
    throw std::runtime_error("cannot write ControllerState " + std::to_string(m.sequence_number()) + " of client " +
                             client_id);
  return m.sequence_number();
}

std::uint64_t Client::send_command(const SceneCommand& command) {
  if (command.model.size() > kMaxModelChars)
    throw std::invalid_argument("SceneCommand.model has " + std::to_string(command.model.size()) +
                                " characters; the wire carries at most " + std::to_string(kMaxModelChars));
  std::lock_guard lock(impl_->publish_mutex);
  const std::uint64_t command_id = impl_->last_command_id + 1;
  msg::SceneCommand m = to_msg(command, impl_->options.client_id, command_id);
  if (impl_->command_writer == nullptr)
    throw std::runtime_error("client " + impl_->options.client_id +
                             " may not send scene commands: its DDS Security permissions do not allow writing "
                             "telegrasp/SceneCommand (an operator identity may)");
  if (!impl_->command_writer->write(&m))
    throw std::runtime_error("cannot write SceneCommand " + std::to_string(command_id) + " of client " +
                             impl_->options.client_id);
  impl_->last_command_id = command_id;
  return command_id;
}

namespace {

template <class T>
std::vector<T> optional_as_vector(const std::optional<T>& value) {
  return value ? std::vector<T>{*value} : std::vector<T>{};
}

template <class T>
std::vector<T> values_of(const std::map<HandKey, T>& by_hand) {
  std::vector<T> out;
  out.reserve(by_hand.size());
  for (const auto& [hand, value] : by_hand) out.push_back(value);
  return out;
}

// A copy of `value`, read under `data_mutex`.
template <class T>
T locked_copy(std::mutex& data_mutex, const T& value) {
  std::lock_guard lock(data_mutex);
  return value;
}

// The newest value of every hand, read under `data_mutex`.
template <class T>
std::vector<T> latest_values(std::mutex& data_mutex, const PerHand<T>& per_hand) {
  std::lock_guard lock(data_mutex);
  return values_of(per_hand.latest);
}

// The newest value of `hand`, read under `data_mutex` (none before its first).
template <class T>
std::optional<T> latest_value(std::mutex& data_mutex, const PerHand<T>& per_hand, const HandKey& hand) {
  std::lock_guard lock(data_mutex);
  const auto it = per_hand.latest.find(hand);
  if (it == per_hand.latest.end()) return std::nullopt;
  return it->second;
}

}  // namespace

void Client::on_hand_skeleton(std::function<void(const HandSkeleton&)> callback) {
  impl_->set_callback(
      impl_->skeleton_channel, std::move(callback), [&] { return latest_hand_skeletons(); }, "HandSkeleton");
}

void Client::on_grasp_state(std::function<void(const GraspState&)> callback) {
  impl_->set_callback(
      impl_->grasp_state_channel, std::move(callback),
      [&] { return latest_values(impl_->data_mutex, impl_->grasp_states); }, "GraspState");
}

void Client::on_contact_set(std::function<void(const ContactSet&)> callback) {
  impl_->set_callback(
      impl_->contact_set_channel, std::move(callback),
      [&] { return latest_values(impl_->data_mutex, impl_->contact_sets); }, "ContactSet");
}

void Client::on_grasp_event(std::function<void(const GraspEvent&)> callback) {
  // Events are delivered once: only those no callback has seen are caught up.
  impl_->set_callback(
      impl_->grasp_event_channel, std::move(callback), [&] { return std::exchange(impl_->unseen_events, {}); },
      "GraspEvent");
}

void Client::on_scene_state(std::function<void(const SceneState&)> callback) {
  impl_->set_callback(
      impl_->scene_state_channel, std::move(callback), [&] { return optional_as_vector(latest_scene_state()); },
      "SceneState");
}

void Client::on_server_status(std::function<void(const ServerStatus&)> callback) {
  impl_->set_callback(
      impl_->server_status_channel, std::move(callback), [&] { return optional_as_vector(latest_server_status()); },
      "ServerStatus");
}

void Client::on_notice(std::function<void(const Notice&)> callback) {
  impl_->set_callback(
      impl_->notice_channel, std::move(callback), [&] { return optional_as_vector(last_notice()); }, "Notice");
}

void Client::on_object_geometry(std::function<void(const std::shared_ptr<const ObjectGeometry>&)> callback) {
  impl_->set_callback(
      impl_->geometry_channel, std::move(callback),
      [&] {
        std::vector<std::shared_ptr<const ObjectGeometry>> all;
        for (auto& [model, g] : object_geometries()) all.push_back(std::move(g));
        return all;
      },
      "ObjectGeometry");
}

void Client::on_server_restart(std::function<void(const ServerRestart&)> callback) {
  impl_->set_callback(
      impl_->restart_channel, std::move(callback), [] { return std::vector<ServerRestart>{}; }, "server restart");
}

std::uint64_t Client::server_incarnation() const { return locked_copy(impl_->data_mutex, impl_->incarnation); }

std::uint64_t Client::server_restarts() const { return locked_copy(impl_->data_mutex, impl_->restarts); }

std::shared_ptr<const ObjectGeometry> Client::object_geometry(const std::string& model) const {
  std::lock_guard lock(impl_->data_mutex);
  const auto it = impl_->geometries.find(model);
  return it == impl_->geometries.end() ? nullptr : it->second;
}

std::map<std::string, std::shared_ptr<const ObjectGeometry>> Client::object_geometries() const {
  return locked_copy(impl_->data_mutex, impl_->geometries);
}

std::optional<SceneState> Client::latest_scene_state() const { return locked_copy(impl_->data_mutex, impl_->scene); }

std::optional<Notice> Client::last_notice() const { return locked_copy(impl_->data_mutex, impl_->notice); }

std::optional<ServerStatus> Client::latest_server_status() const {
  return locked_copy(impl_->data_mutex, impl_->status);
}

std::vector<HandSkeleton> Client::latest_hand_skeletons() const {
  return latest_values(impl_->data_mutex, impl_->skeletons);
}

std::optional<GraspState> Client::latest_grasp_state(const HandKey& hand) const {
  return latest_value(impl_->data_mutex, impl_->grasp_states, hand);
}

std::optional<ContactSet> Client::latest_contact_set(const HandKey& hand) const {
  return latest_value(impl_->data_mutex, impl_->contact_sets, hand);
}

std::string scene_name_error(const std::string& name) { return idl::scene_name_error(name); }

std::string discovery_server_error(const std::string& address) {
  try {
    idl::resolve_network({idl::kDefaultScene, {address}});
    return "";
  } catch (const std::exception& e) {
    return e.what();
  }
}

const std::string& Client::scene() const { return impl_->participant->network().scene; }

std::vector<SceneInfo> Client::scenes() const {
  std::vector<SceneInfo> live;
  if (impl_->directory_reader == nullptr) return live;
  for (const msg::SceneAnnouncement& a : idl::read_alive_instances<msg::SceneAnnouncement>(impl_->directory_reader))
    live.push_back(from_msg(a));
  std::sort(live.begin(), live.end(), [](const SceneInfo& a, const SceneInfo& b) {
    return std::tie(a.scene, a.started, a.incarnation) < std::tie(b.scene, b.started, b.incarnation);
  });
  return live;
}

std::vector<GraspEvent> Client::take_grasp_events() {
  std::lock_guard lock(impl_->data_mutex);
  return std::exchange(impl_->events, {});
}

bool Client::wait_for_server(std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (impl_->server_ready()) return true;
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return false;
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(kServerPollPeriod, deadline - now));
  }
}

}  // namespace telegrasp::client
