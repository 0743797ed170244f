// Tests telegrasp::client::Client against raw Fast DDS readers and writers, each test on a DDS
// domain of its own (DomainLease, loopback profile): what it publishes arrives with the right
// key, fields and sequence numbers; what a server would publish reaches its callbacks and polling
// functions.
#include "telegrasp/client/client.h"
#include "telegrasp/idl/dds_participant.h"
#include "telegrasp/idl/geometry_hash.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"
#include "test_domain.h"

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

namespace telegrasp::client {
namespace {

namespace dds = eprosima::fastdds::dds;
using namespace std::chrono_literals;
using telegrasp::testing::DomainLease;

// Generous: discovery on a loaded machine can take seconds; passing tests return at once.
constexpr auto kTimeout = 20s;
constexpr double kRotationTolerance = 1e-12;

// Polls `condition` every 10 ms until it holds (true) or `timeout` passes (false).
bool eventually(const std::function<bool()>& condition, std::chrono::milliseconds timeout = kTimeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(10ms);
  }
  return true;
}

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

bool matched(dds::DataWriter* writer) {
  dds::PublicationMatchedStatus status;
  return writer->get_publication_matched_status(status) == ReturnCode_t::RETCODE_OK && status.current_count > 0;
}

int subscription_matches(dds::DataReader* reader) {
  dds::SubscriptionMatchedStatus status;
  return reader->get_subscription_matched_status(status) == ReturnCode_t::RETCODE_OK ? status.current_count : -1;
}

// Every valid ControllerState the raw reader holds, appended to `out`.
void take_all(dds::DataReader* reader, std::vector<msg::ControllerState>& out) {
  msg::ControllerState sample;
  dds::SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK)
    if (info.valid_data) out.push_back(sample);
}

Eigen::Isometry3d make_pose(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  X.translation() = p;
  return X;
}

ClientOptions options(const std::string& id, int domain, unsigned topics) {
  ClientOptions o;
  o.client_id = id;
  o.domain = domain;
  o.profile = "loopback";
  o.topics = topics;
  return o;
}

// Each test on a DDS domain of its own, where the server side is a raw participant.
class ClientLoopbackTest : public ::testing::Test {
 protected:
  // The server's participant, made on first use (some tests start with nobody there).
  idl::DdsParticipant& server() {
    if (!server_) server_.emplace(domain, "loopback");
    return *server_;
  }

  const DomainLease lease_;  // a domain no concurrent test uses
  const int domain = lease_.domain();

 private:
  std::optional<idl::DdsParticipant> server_;
};

// ---------------------------------------------------------------------------------------------

TEST_F(ClientLoopbackTest, PublishedControllerStatesArriveNumberedWithTheirFields) {
  dds::DataReader* reader = server().reader<msg::ControllerStatePubSubType>(idl::kControllerStateTopic);
  server().reader<msg::SceneCommandPubSubType>(idl::kSceneCommandTopic);
  Client client(options("alice", domain, 0));
  // With no status topic subscribed, matched ControllerState and SceneCommand readers are a server.
  ASSERT_TRUE(client.wait_for_server(kTimeout));

  // Best effort: until both sides have matched, samples may be lost. Publish until one arrives;
  // every publish numbers the right hand's samples 1, 2, 3 ...
  std::vector<msg::ControllerState> got;
  ControllerSample right;
  std::uint64_t expected = 1;
  ASSERT_TRUE(eventually([&] {
    EXPECT_EQ(client.publish(right), expected++);
    take_all(reader, got);
    return !got.empty();
  }));
  for (const auto& m : got) {
    EXPECT_EQ(m.client_id().to_string(), "alice");
    EXPECT_EQ(m.hand_side(), msg::HAND_RIGHT);
    EXPECT_LT(m.sequence_number(), expected);
  }

  // One at a time (keep-last 1 per hand), so each sample is waited for before the next.
  auto publish_and_receive = [&](const ControllerSample& s) {
    const std::uint64_t seq = client.publish(s);
    std::optional<msg::ControllerState> found;
    eventually([&] {
      got.clear();
      take_all(reader, got);
      for (const auto& m : got)
        if (m.sequence_number() == seq && m.hand_side() == static_cast<std::uint8_t>(s.side)) found = m;
      return found.has_value();
    });
    return std::make_pair(seq, found);
  };

  // Every field, client time stamped from steady_clock when 0.
  ControllerSample full;
  full.side = HandSide::kRight;
  full.X_WorldPalm = make_pose(0.8, {0.1, 1, 0.4}, {0.12, -0.34, 0.95});
  full.trigger = 0.375;
  full.curls = {0.1, 0.2, 0.3, 0.4, 0.5};
  full.buttons = msg::BUTTON_PRIMARY | msg::BUTTON_GRIP;
  full.tracking_valid = false;
  const std::int64_t before_ns = steady_now_ns();
  auto [seq, m] = publish_and_receive(full);
  EXPECT_EQ(seq, expected++);
  ASSERT_TRUE(m) << "sample " << seq << " never arrived";
  EXPECT_EQ(m->client_id().to_string(), "alice");
  EXPECT_EQ(m->hand_side(), msg::HAND_RIGHT);
  EXPECT_GE(m->client_time_ns(), before_ns);
  EXPECT_LE(m->client_time_ns(), steady_now_ns());
  EXPECT_EQ(m->palm().position().x(), 0.12);
  EXPECT_EQ(m->palm().position().y(), -0.34);
  EXPECT_EQ(m->palm().position().z(), 0.95);
  const Eigen::Quaterniond q_expected(full.X_WorldPalm.linear());
  EXPECT_NEAR(m->palm().orientation().w(), q_expected.w(), kRotationTolerance);
  EXPECT_NEAR(m->palm().orientation().x(), q_expected.x(), kRotationTolerance);
  EXPECT_NEAR(m->palm().orientation().y(), q_expected.y(), kRotationTolerance);
  EXPECT_NEAR(m->palm().orientation().z(), q_expected.z(), kRotationTolerance);
  EXPECT_EQ(m->trigger(), 0.375);
  EXPECT_EQ(m->curls(), full.curls);
  EXPECT_EQ(m->buttons(), full.buttons);
  EXPECT_FALSE(m->tracking_valid());

  // The left hand has its own numbering; an explicit client time is kept.
  ControllerSample left;
  left.side = HandSide::kLeft;
  left.client_time_ns = 12345;
  std::tie(seq, m) = publish_and_receive(left);
  EXPECT_EQ(seq, 1u);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->hand_side(), msg::HAND_LEFT);
  EXPECT_EQ(m->client_time_ns(), 12345);

  // An explicit stale number goes out as given; automatic numbering continues after the largest.
  ControllerSample stale = right;
  stale.sequence_number = 1;
  std::tie(seq, m) = publish_and_receive(stale);
  EXPECT_EQ(seq, 1u);
  EXPECT_TRUE(m);
  std::tie(seq, m) = publish_and_receive(right);
  EXPECT_EQ(seq, expected++);
  EXPECT_TRUE(m);

  // Invalid values go out unchanged: the server's validation is tested with them.
  ControllerSample bad;
  bad.side = static_cast<HandSide>(7);
  bad.X_WorldPalm.translation().x() = std::numeric_limits<double>::quiet_NaN();
  bad.X_WorldPalm.linear() *= 0.5;
  bad.trigger = 5;
  std::tie(seq, m) = publish_and_receive(bad);
  EXPECT_EQ(seq, 1u);  // a hand of its own
  ASSERT_TRUE(m);
  EXPECT_EQ(m->hand_side(), 7);
  EXPECT_TRUE(std::isnan(m->palm().position().x()));
  const auto& q = m->palm().orientation();
  EXPECT_GT(std::abs(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z() - 1), 0.1);
  EXPECT_EQ(m->trigger(), 5);
}

// A relay publishes as ids under its prefix with its own sequence numbers, which go out as given
// and do not touch the client's own numbering; ids outside the prefix and number 0 are refused.
TEST_F(ClientLoopbackTest, ARelayPublishesAsIdsUnderItsPrefix) {
  dds::DataReader* reader = server().reader<msg::ControllerStatePubSubType>(idl::kControllerStateTopic);
  server().reader<msg::SceneCommandPubSubType>(idl::kSceneCommandTopic);
  ClientOptions o = options("bridge", domain, 0);
  o.relay_prefix = "xr-";
  Client client(o);
  ASSERT_TRUE(client.wait_for_server(kTimeout));
  ControllerSample s;
  s.sequence_number = 41;
  EXPECT_THROW(client.publish_as("alice", s), std::invalid_argument);
  EXPECT_THROW(client.publish_as("xr-" + std::string(70, 'a'), s), std::invalid_argument);
  s.sequence_number = 0;
  EXPECT_THROW(client.publish_as("xr-1", s), std::invalid_argument);
  std::vector<msg::ControllerState> got;
  std::uint64_t seq = 100;
  ASSERT_TRUE(eventually([&] {
    s.sequence_number = ++seq;
    EXPECT_EQ(client.publish_as("xr-1", s), seq);
    take_all(reader, got);
    return !got.empty();
  }));
  EXPECT_EQ(got.back().client_id().to_string(), "xr-1");
  EXPECT_GT(got.back().sequence_number(), 100u);
  EXPECT_EQ(client.publish(ControllerSample{}), 1u);  // its own hands are numbered apart
  ClientOptions plain = options("carol", domain, 0);
  Client not_a_relay(plain);
  s.sequence_number = 5;
  EXPECT_THROW(not_a_relay.publish_as("xr-1", s), std::invalid_argument);
}

TEST_F(ClientLoopbackTest, SceneCommandsArriveNumbered) {
  dds::DataReader* reader = server().reader<msg::SceneCommandPubSubType>(idl::kSceneCommandTopic);
  server().reader<msg::ControllerStatePubSubType>(idl::kControllerStateTopic);
  Client client(options("operator", domain, 0));
  // Reliable, but only to readers matched when written: wait_for_server waits for that match.
  ASSERT_TRUE(client.wait_for_server(kTimeout));
  SceneCommand spawn;
  spawn.kind = SceneCommand::Kind::kSpawn;
  spawn.model = "011_banana";
  spawn.x = 0.4;
  SceneCommand reset;
  reset.kind = SceneCommand::Kind::kReset;
  EXPECT_EQ(client.send_command(spawn), 1u);
  EXPECT_EQ(client.send_command(reset), 2u);
  std::vector<msg::SceneCommand> got;
  ASSERT_TRUE(eventually([&] {
    msg::SceneCommand c;
    dds::SampleInfo info;
    while (reader->take_next_sample(&c, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) got.push_back(c);
    return got.size() >= 2;
  }));
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].command_id(), 1u);
  EXPECT_EQ(got[0].client_id().to_string(), "operator");
  EXPECT_EQ(got[0].kind(), msg::SCENE_SPAWN);
  EXPECT_EQ(got[0].model().to_string(), "011_banana");
  EXPECT_EQ(got[0].x(), 0.4);
  EXPECT_EQ(got[1].command_id(), 2u);
  EXPECT_EQ(got[1].kind(), msg::SCENE_RESET);
}

// What the client received through its callbacks, guarded by one mutex.
struct Received {
  std::mutex mutex;
  std::vector<HandSkeleton> skeletons;
  std::vector<GraspEvent> events;
  std::vector<GraspState> grasp_states;
  std::vector<ServerStatus> statuses;
};

msg::HandSkeleton make_skeleton(const std::string& id, std::uint8_t side, std::uint64_t tick) {
  msg::HandSkeleton m;
  m.client_id(id);
  m.hand_side(side);
  m.rig("test_rig");
  m.tick(tick);
  m.time(tick / 90.0);
  m.input_sequence(tick + 1000);
  m.palm().position().z(0.9);
  m.palm().orientation().w(1);
  msg::Pose3 X_WorldPhalanx;
  X_WorldPhalanx.position().x(0.05);
  X_WorldPhalanx.orientation().z(1);  // half a turn about z
  m.phalanges().assign(3, X_WorldPhalanx);
  m.joint_angles({0.1, 0.2, 0.3});
  return m;
}

TEST_F(ClientLoopbackTest, ServerOutputsReachCallbacksAndPolling) {
  dds::DataWriter* skeleton_writer = server().writer<msg::HandSkeletonPubSubType>(idl::kHandSkeletonTopic);
  dds::DataWriter* event_writer = server().writer<msg::GraspEventPubSubType>(idl::kGraspEventTopic);
  dds::DataWriter* grasp_state_writer = server().writer<msg::GraspStatePubSubType>(idl::kGraspStateTopic);

  Client client(options("viewer", domain, kAllTopics));
  Received received;
  client.on_hand_skeleton([&](const HandSkeleton& s) {
    std::lock_guard l(received.mutex);
    received.skeletons.push_back(s);
  });
  client.on_grasp_event([&](const GraspEvent& e) {
    std::lock_guard l(received.mutex);
    received.events.push_back(e);
  });
  client.on_grasp_state([&](const GraspState& s) {
    std::lock_guard l(received.mutex);
    received.grasp_states.push_back(s);
  });

  // Hand skeletons (best effort): write both hands of "bob" until the client has both.
  std::uint64_t tick = 0;
  ASSERT_TRUE(eventually([&] {
    ++tick;
    msg::HandSkeleton left = make_skeleton("bob", msg::HAND_LEFT, tick),
                      right = make_skeleton("bob", msg::HAND_RIGHT, tick);
    skeleton_writer->write(&left);
    skeleton_writer->write(&right);
    return client.latest_hand_skeletons().size() == 2;
  }));
  {
    std::lock_guard l(received.mutex);
    ASSERT_FALSE(received.skeletons.empty());
    const HandSkeleton& s = received.skeletons.front();
    EXPECT_EQ(s.hand.client_id, "bob");
    EXPECT_EQ(s.rig, "test_rig");
    EXPECT_EQ(s.input_sequence, s.tick + 1000);
    EXPECT_EQ(s.X_WorldPalm.translation(), Eigen::Vector3d(0, 0, 0.9));
    ASSERT_EQ(s.X_WorldPhalanx.size(), 3u);
    EXPECT_TRUE(s.X_WorldPhalanx[1].linear().isApprox(Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix()));
    EXPECT_EQ(s.joint_angles, (std::vector<double>{0.1, 0.2, 0.3}));
  }
  const std::vector<HandSkeleton> latest = client.latest_hand_skeletons();
  ASSERT_EQ(latest.size(), 2u);  // one per hand, in HandKey order
  EXPECT_EQ(latest[0].hand, (HandKey{"bob", HandSide::kLeft}));
  EXPECT_EQ(latest[1].hand, (HandKey{"bob", HandSide::kRight}));

  // The server removes the left hand (disposes its instance): it leaves the polled skeletons.
  {
    msg::HandSkeleton left = make_skeleton("bob", msg::HAND_LEFT, 0);
    ASSERT_EQ(skeleton_writer->dispose(&left, dds::HANDLE_NIL), ReturnCode_t::RETCODE_OK);
  }
  EXPECT_TRUE(eventually([&] {
    const auto now = client.latest_hand_skeletons();
    return now.size() == 1 && now[0].hand == HandKey{"bob", HandSide::kRight};
  }));

  // Grasp events (reliable, keep all): once matched, all of them, in order, once.
  ASSERT_TRUE(eventually([&] { return matched(event_writer); }));
  for (std::uint64_t id = 1; id <= 3; ++id) {
    msg::GraspEvent e;
    e.event_id(id);
    e.kind(id == 2 ? msg::GRASP_EVENT_RELEASE : msg::GRASP_EVENT_GRASP);
    e.client_id("bob");
    e.hand_side(msg::HAND_RIGHT);
    e.object_id(7);
    e.object_name("011_banana");
    e.object_pose().orientation().w(1);
    e.release_velocity().x(0.25 * id);
    ASSERT_TRUE(event_writer->write(&e));
  }
  ASSERT_TRUE(eventually([&] {
    std::lock_guard l(received.mutex);
    return received.events.size() >= 3;
  }));
  {
    std::lock_guard l(received.mutex);
    ASSERT_EQ(received.events.size(), 3u);
    for (std::uint64_t i = 0; i < 3; ++i) {
      EXPECT_EQ(received.events[i].event_id, i + 1);
      EXPECT_EQ(received.events[i].hand, (HandKey{"bob", HandSide::kRight}));
      EXPECT_EQ(received.events[i].object_name, "011_banana");
      EXPECT_EQ(received.events[i].v_WorldObject.x(), 0.25 * (i + 1));
    }
    EXPECT_EQ(received.events[1].kind, GraspEvent::Kind::kRelease);
  }
  const std::vector<GraspEvent> taken = client.take_grasp_events();
  ASSERT_EQ(taken.size(), 3u);
  EXPECT_EQ(taken[0].event_id, 1u);
  EXPECT_EQ(taken[2].event_id, 3u);
  EXPECT_TRUE(client.take_grasp_events().empty());

  // Grasp states (reliable, transient local): polled per hand.
  ASSERT_TRUE(eventually([&] { return matched(grasp_state_writer); }));
  msg::GraspState gs;
  gs.client_id("bob");
  gs.hand_side(msg::HAND_RIGHT);
  gs.grasped_object(7);
  gs.blocked({true, false, true});
  ASSERT_TRUE(grasp_state_writer->write(&gs));
  ASSERT_TRUE(eventually([&] { return client.latest_grasp_state({"bob", HandSide::kRight}).has_value(); }));
  const GraspState state = *client.latest_grasp_state({"bob", HandSide::kRight});
  EXPECT_EQ(state.grasped_object, 7);
  EXPECT_EQ(state.blocked, (std::vector<bool>{true, false, true}));
  EXPECT_FALSE(client.latest_grasp_state({"bob", HandSide::kLeft}).has_value());
  EXPECT_FALSE(client.latest_contact_set({"bob", HandSide::kRight}).has_value());
  std::lock_guard l(received.mutex);
  EXPECT_EQ(received.grasp_states.size(), 1u);
}

TEST_F(ClientLoopbackTest, WaitForServerNeedsAMatchedReaderAndAStatus) {
  Client client(options("waiter", domain, kAllTopics));
  EXPECT_FALSE(client.wait_for_server(100ms));  // nobody there
  dds::DataReader* reader = server().reader<msg::ControllerStatePubSubType>(idl::kControllerStateTopic);
  server().reader<msg::SceneCommandPubSubType>(idl::kSceneCommandTopic);
  // A client without the status topic calls the matched readers a server; ours needs a status too.
  Client no_status(options("no-status", domain, 0));
  ASSERT_TRUE(no_status.wait_for_server(kTimeout));
  ASSERT_TRUE(eventually([&] { return subscription_matches(reader) == 2; }));
  EXPECT_FALSE(client.wait_for_server(200ms));
  EXPECT_FALSE(client.latest_server_status().has_value());

  // The status is transient local: written now, it reaches the client whenever it matches.
  dds::DataWriter* status_writer = server().writer<msg::ServerStatusPubSubType>(idl::kServerStatusTopic);
  msg::ServerStatus status;
  status.tick(900);
  status.clients(2);
  status.models().emplace_back("011_banana");
  msg::RejectCount stale;
  stale.reason("stale_sequence");
  stale.count(3);
  status.rejected().push_back(stale);
  ASSERT_TRUE(status_writer->write(&status));
  ASSERT_TRUE(client.wait_for_server(kTimeout));
  const std::optional<ServerStatus> got = client.latest_server_status();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->tick, 900u);
  EXPECT_EQ(got->clients, 2);
  EXPECT_EQ(got->models, std::vector<std::string>{"011_banana"});
  EXPECT_EQ(got->rejected.at("stale_sequence"), 3u);
}

// Samples that arrive before a callback is set are not lost to it: setting it catches it up.
TEST_F(ClientLoopbackTest, ANewCallbackIsCaughtUpWithWhatArrivedBefore) {
  dds::DataWriter* status_writer = server().writer<msg::ServerStatusPubSubType>(idl::kServerStatusTopic);
  dds::DataWriter* event_writer = server().writer<msg::GraspEventPubSubType>(idl::kGraspEventTopic);
  Client client(options("late", domain, kServerStatuses | kGraspEvents));

  // A status and two events arrive while no callback is set (seen by polling). Written once the
  // client's reader has matched, so the test does not depend on how fast discovery is.
  ASSERT_TRUE(eventually([&] { return matched(status_writer); }));
  msg::ServerStatus status;
  status.tick(42);
  ASSERT_TRUE(status_writer->write(&status));
  ASSERT_TRUE(eventually([&] { return client.latest_server_status().has_value(); }));
  ASSERT_TRUE(eventually([&] { return matched(event_writer); }));
  for (std::uint64_t id : {7u, 8u}) {
    msg::GraspEvent e;
    e.event_id(id);
    e.object_pose().orientation().w(1);
    ASSERT_TRUE(event_writer->write(&e));
  }
  std::vector<GraspEvent> polled;
  ASSERT_TRUE(eventually([&] {
    for (auto& e : client.take_grasp_events()) polled.push_back(e);
    return polled.size() == 2;
  }));

  // Setting the callbacks calls them before the setter returns.
  std::vector<std::uint64_t> statuses, events;
  client.on_server_status([&](const ServerStatus& s) { statuses.push_back(s.tick); });
  client.on_grasp_event([&](const GraspEvent& e) { events.push_back(e.event_id); });
  EXPECT_EQ(statuses, std::vector<std::uint64_t>{42});
  EXPECT_EQ(events, (std::vector<std::uint64_t>{7, 8}));

  // Events are delivered once: a replacing callback gets no old events; a state callback gets
  // the current state again.
  std::vector<std::uint64_t> later_events, later_statuses;
  client.on_grasp_event([&](const GraspEvent& e) { later_events.push_back(e.event_id); });
  client.on_server_status([&](const ServerStatus& s) { later_statuses.push_back(s.tick); });
  EXPECT_TRUE(later_events.empty());
  EXPECT_EQ(later_statuses, std::vector<std::uint64_t>{42});
  client.on_grasp_event(nullptr);  // before the vectors go out of scope
  client.on_server_status(nullptr);
}

TEST_F(ClientLoopbackTest, NoCallbackRunsAfterTheDestructorReturns) {
  dds::DataWriter* skeleton_writer = server().writer<msg::HandSkeletonPubSubType>(idl::kHandSkeletonTopic);
  std::atomic<bool> destroyed{false}, called_after_destroy{false};
  std::atomic<int> calls{0};
  auto client = std::make_unique<Client>(options("short-lived", domain, kHandSkeletons));
  client->on_hand_skeleton([&](const HandSkeleton&) {
    if (destroyed) called_after_destroy = true;
    ++calls;
    std::this_thread::sleep_for(1ms);  // widen the window in which the destructor can race a callback
  });
  // A writer keeps publishing while the client goes away.
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> written{0};
  std::thread spammer([&] {
    while (!stop) {
      msg::HandSkeleton s = make_skeleton("bob", msg::HAND_RIGHT, ++written);
      skeleton_writer->write(&s);
      std::this_thread::sleep_for(1ms);
    }
  });
  const bool delivered = eventually([&] { return calls > 5; });
  client.reset();
  destroyed = true;
  const int calls_at_destruction = calls;
  // The writer goes on for 50 more samples: a callback after the destructor would show.
  const std::uint64_t written_at_destruction = written;
  EXPECT_TRUE(eventually([&] { return written >= written_at_destruction + 50; }));
  stop = true;
  spammer.join();
  EXPECT_TRUE(delivered);
  EXPECT_FALSE(called_after_destroy);
  EXPECT_EQ(calls, calls_at_destruction);
}

TEST_F(ClientLoopbackTest, AThrowingCallbackDoesNotStopDelivery) {
  dds::DataWriter* skeleton_writer = server().writer<msg::HandSkeletonPubSubType>(idl::kHandSkeletonTopic);
  std::atomic<int> calls{0};  // before the client: its callbacks may run until its destructor returns
  Client client(options("thrower", domain, kHandSkeletons));
  client.on_hand_skeleton([&](const HandSkeleton&) {
    ++calls;
    throw std::runtime_error("thrown on purpose by the test");
  });
  std::uint64_t tick = 0;
  EXPECT_TRUE(eventually([&] {
    msg::HandSkeleton s = make_skeleton("bob", msg::HAND_RIGHT, ++tick);
    skeleton_writer->write(&s);
    return calls >= 3;
  }));
  ASSERT_EQ(client.latest_hand_skeletons().size(), 1u);
  EXPECT_GT(client.latest_hand_skeletons()[0].tick, 0u);
}

// A tetrahedron's geometry as a server publishes it, named `model`, with its true content hash.
msg::ObjectGeometry tetrahedron_geometry(const std::string& model) {
  msg::ObjectGeometry m;
  m.model(model);
  m.vertices({0.f, 0.f, 0.f, 0.1f, 0.f, 0.f, 0.f, 0.1f, 0.f, 0.f, 0.f, 0.1f});
  m.triangles({0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3});
  m.vertex_count(4);
  m.triangle_count(4);
  m.content_hash(idl::geometry_content_hash(m.vertices().data(), 4, m.triangles().data(), 4));
  m.mass(0.25);
  return m;
}

// Geometries arrive checked and cached by content hash: a damaged one is dropped, the same one
// arriving again is the same object, and the same mesh under another name is taken from the cache.
TEST_F(ClientLoopbackTest, ObjectGeometriesAreCheckedAndCachedByHash) {
  dds::DataWriter* writer = server().writer<msg::ObjectGeometryPubSubType>(idl::kObjectGeometryTopic);
  std::atomic<int> calls{0};  // before the client: its callbacks may run until its destructor returns
  Client client(options("viewer", domain, kObjectGeometries));
  client.on_object_geometry([&](const std::shared_ptr<const ObjectGeometry>&) { ++calls; });

  // Transient local: written before or after the client matched, it arrives.
  msg::ObjectGeometry good = tetrahedron_geometry("tetra"), damaged = tetrahedron_geometry("damaged");
  damaged.vertices()[4] = 0.5f;  // no longer what its hash says
  ASSERT_TRUE(writer->write(&good));
  ASSERT_TRUE(writer->write(&damaged));
  msg::ObjectGeometry marker = tetrahedron_geometry("marker");
  marker.mass(3.0);
  ASSERT_TRUE(writer->write(&marker));  // reliable and in order: once it is in, so is the damaged one
  ASSERT_TRUE(eventually([&] { return client.object_geometry("marker") != nullptr; }));
  EXPECT_EQ(client.object_geometry("damaged"), nullptr);
  const std::shared_ptr<const ObjectGeometry> first = client.object_geometry("tetra");
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->vertices.size(), 4u);
  EXPECT_EQ(first->triangles[1], (std::array<std::uint32_t, 3>{0, 1, 3}));
  EXPECT_EQ(first->mass_kg, 0.25);
  EXPECT_EQ(client.object_geometries().size(), 2u);
  // The marker is the tetrahedron's mesh with another mass: its own object, the same mesh.
  EXPECT_NE(client.object_geometry("marker").get(), first.get());
  EXPECT_EQ(client.object_geometry("marker")->vertices, first->vertices);
  EXPECT_EQ(client.object_geometry("marker")->mass_kg, 3.0);

  // The same geometry again (e.g. a restarted server): delivered, but not rebuilt.
  ASSERT_TRUE(eventually([&] { return calls == 2; })) << "tetra and marker, not the damaged one";
  ASSERT_TRUE(writer->write(&good));
  ASSERT_TRUE(eventually([&] { return calls == 3; }));
  EXPECT_EQ(client.object_geometry("tetra").get(), first.get());
  client.on_object_geometry(nullptr);  // before `calls` goes out of scope
}

}  // namespace
}  // namespace telegrasp::client

namespace telegrasp::client {
namespace {

// One server run as a raw participant: writers of the outputs the restart test uses.
struct FakeServer {
  explicit FakeServer(int domain) : participant(domain, "loopback") {}
  idl::DdsParticipant participant;
  dds::DataWriter* status = participant.writer<msg::ServerStatusPubSubType>(idl::kServerStatusTopic);
  dds::DataWriter* grasp_state = participant.writer<msg::GraspStatePubSubType>(idl::kGraspStateTopic);
  dds::DataWriter* event = participant.writer<msg::GraspEventPubSubType>(idl::kGraspEventTopic);
  bool matched_all() const { return matched(status) && matched(grasp_state) && matched(event); }
  void write_status(std::uint64_t incarnation, std::uint64_t tick) {
    msg::ServerStatus s;
    s.incarnation(incarnation);
    s.tick(tick);
    ASSERT_TRUE(status->write(&s));
  }
  void write_grasp_state(const std::string& client_id, int grasped) {
    msg::GraspState g;
    g.client_id(client_id);
    g.hand_side(msg::HAND_RIGHT);
    g.grasped_object(grasped);
    ASSERT_TRUE(grasp_state->write(&g));
  }
  void write_event(std::uint64_t id) {
    msg::GraspEvent e;
    e.event_id(id);
    e.object_pose().orientation().w(1);
    ASSERT_TRUE(event->write(&e));
  }
};

// A server that comes back with a new incarnation is noticed once (not the first one seen); what
// the old run said about hands and its status is dropped, not what the new run sent before its
// first status arrived; a late sample of the old run is dropped; grasp events carry the
// incarnation of the run that sent them. The old run stays on the wire here (a hung server, or
// one whose last samples are late), so nothing of it is disposed by its writers going away.
TEST_F(ClientLoopbackTest, ANewIncarnationIsNoticedOnceAndTheOldRunsStateDropped) {
  std::mutex mutex;  // these two before the client: its callbacks may run until its destructor returns
  std::vector<ServerRestart> restarts;
  Client client(options("restarts", domain, kServerStatuses | kGraspStates | kGraspEvents));
  client.on_server_restart([&](const ServerRestart& r) {
    std::lock_guard l(mutex);
    restarts.push_back(r);
  });
  auto restart_count = [&] {
    std::lock_guard l(mutex);
    return restarts.size();
  };
  auto take_events = [&] {
    std::vector<GraspEvent> events;
    eventually([&] {
      for (auto& e : client.take_grasp_events()) events.push_back(e);
      return !events.empty();
    });
    return events;
  };
  const HandKey alice{"alice", HandSide::kRight}, bob{"bob", HandSide::kRight};

  // The first run: a status, alice holding object 3, one event.
  FakeServer a(domain);
  ASSERT_TRUE(eventually([&] { return a.matched_all(); }));
  a.write_status(11, 100);
  a.write_grasp_state("alice", 3);
  ASSERT_TRUE(eventually([&] { return client.server_incarnation() == 11 && client.latest_grasp_state(alice); }));
  // After the status: an event that overtakes its server's first status (another writer, another
  // listener thread) is tagged 0, its run not yet known.
  a.write_event(1);
  std::vector<GraspEvent> events = take_events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].server_incarnation, 11u);
  EXPECT_EQ(restart_count(), 0u) << "the first server seen is no restart";

  // The second run. Its grasp state may come before its first status: kept through the restart.
  FakeServer b(domain);
  ASSERT_TRUE(eventually([&] { return b.matched_all(); }));
  b.write_grasp_state("bob", 5);
  ASSERT_TRUE(eventually([&] { return client.latest_grasp_state(bob).has_value(); }));
  EXPECT_TRUE(client.latest_grasp_state(alice)) << "no new incarnation is known yet";
  b.write_status(22, 1);
  ASSERT_TRUE(eventually([&] { return client.server_incarnation() == 22; }));
  ASSERT_EQ(restart_count(), 1u);
  {
    std::lock_guard l(mutex);
    EXPECT_EQ(restarts[0].previous_incarnation, 11u);
    EXPECT_EQ(restarts[0].incarnation, 22u);
  }
  EXPECT_EQ(client.server_restarts(), 1u);
  EXPECT_FALSE(client.latest_grasp_state(alice)) << "the old run's hands are dropped";
  ASSERT_TRUE(client.latest_grasp_state(bob));
  EXPECT_EQ(client.latest_grasp_state(bob)->grasped_object, 5);
  ASSERT_TRUE(client.latest_server_status());
  EXPECT_EQ(client.latest_server_status()->incarnation, 22u);

  // A late status of the old run is dropped: the new run's next one, written after it, is the latest.
  a.write_status(11, 101);
  std::this_thread::sleep_for(200ms);
  b.write_status(22, 2);
  ASSERT_TRUE(eventually([&] { return client.latest_server_status()->tick == 2; }));
  EXPECT_EQ(client.latest_server_status()->incarnation, 22u);
  EXPECT_EQ(client.server_incarnation(), 22u);
  EXPECT_EQ(restart_count(), 1u) << "a late sample of the old run is no restart";

  // Events say which run they are of, whatever arrives when.
  b.write_event(1);
  events = take_events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].server_incarnation, 22u);
  a.write_event(2);
  events = take_events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].server_incarnation, 11u);
  client.on_server_restart(nullptr);
}

}  // namespace
}  // namespace telegrasp::client
