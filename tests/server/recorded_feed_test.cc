// Tests server/src/recorded_feed on small hand-written recordings, driving it as ServerLoop does
// (wait, inputs, commands, tick): recorded calls are grouped into the loop's iterations; each
// call's recorded outputs are compared with the captured ones before the next call, which must
// leave none; an undecodable call is reported after the outputs before it; outputs beyond the end
// diverge. (replay_recording, which runs it under the real loop, is tested in recording_test.cc.)
#include "recorded_feed.h"

#include "scene_setup.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <ostream>

namespace telegrasp::server {
namespace {

proto::Record inputs_at(std::int64_t now_ns) {
  msg::ControllerState s;
  s.client_id("alice");
  s.hand_side(1);
  s.sequence_number(static_cast<std::uint64_t>(now_ns));
  proto::Record r;
  r.mutable_inputs()->set_now_ns(now_ns);
  proto::InputSample* p = r.mutable_inputs()->add_samples();
  p->mutable_hand()->set_client_id("alice");
  p->mutable_hand()->set_side(1);
  p->set_controller_state_cdr(to_cdr(s));
  p->set_received_ns(now_ns);
  return r;
}
proto::Record command_at(std::int64_t now_ns, std::string cdr = to_cdr(msg::SceneCommand{})) {
  proto::Record r;
  r.mutable_command()->set_now_ns(now_ns);
  r.mutable_command()->set_scene_command_cdr(std::move(cdr));
  return r;
}
proto::Record tick_at(std::int64_t now_ns) {
  proto::Record r;
  r.mutable_tick()->set_now_ns(now_ns);
  return r;
}
proto::Record output(proto::OutputType type, std::string cdr) {
  proto::Record r;
  r.mutable_output()->set_type(type);
  r.mutable_output()->set_cdr(std::move(cdr));
  return r;
}
msg::SceneState scene_at_tick(std::uint64_t tick) {
  msg::SceneState m;
  m.tick(tick);
  return m;
}

// What one loop iteration got from the feed.
struct Got {
  std::int64_t now_ns;
  std::size_t inputs, commands;
  bool tick;
  bool operator==(const Got&) const = default;
};
std::ostream& operator<<(std::ostream& o, const Got& g) {
  return o << "{" << g.now_ns << ": " << g.inputs << " inputs, " << g.commands << " commands"
           << (g.tick ? ", tick" : "") << "}";
}

struct RecordedFeedTest : ::testing::Test {
  std::string path =
      (std::filesystem::temp_directory_path() / ("telegrasp-feed-test-" + std::to_string(::getpid()) + ".tgrec"))
          .string();
  void TearDown() override { std::filesystem::remove(path); }

  void write(const std::vector<proto::Record>& records) {
    ServerSettings settings;
    settings.empty_scene = true;
    write_recording(path, make_recording_header(settings, load_scene_assets(settings)), records);
  }
  // One iteration as ServerLoop::step makes it: the observer is told of each call before it is
  // made; `publish` runs after the scene's tick (what it would have published).
  static Got iterate(RecordedFeed& feed, const std::function<void()>& publish = {}) {
    feed.wait_until({});
    Got got{std::chrono::duration_cast<std::chrono::nanoseconds>(feed.now().time_since_epoch()).count(), 0, 0, false};
    if (feed.finished()) return got;
    const auto inputs = feed.take_inputs();
    got.inputs = inputs.size();
    if (!inputs.empty()) feed.inputs(inputs, got.now_ns);
    for (const auto& c : feed.take_commands()) {
      feed.command(c, got.now_ns);
      ++got.commands;
    }
    if ((got.tick = feed.tick_due())) {
      feed.tick(got.now_ns);
      if (publish) publish();
    }
    return got;
  }
};

// A loop iteration is at most one inputs call, then commands, then at most one tick, all at one
// time; anything else starts the next iteration.
TEST_F(RecordedFeedTest, GroupsTheCallsIntoTheLoopsIterations) {
  write({inputs_at(10), command_at(10), command_at(10), tick_at(10), output(proto::OUTPUT_SERVER_STATUS, ""),  //
         inputs_at(20), command_at(20),  //
         tick_at(30), command_at(30),  // a command after the tick
         tick_at(40), tick_at(40),  // two ticks
         inputs_at(50), inputs_at(50),  // two inputs calls
         command_at(60), tick_at(61)});  // another time
  RecordingReader reader(path);
  OutputCapture capture;
  RecordedFeed feed(reader, capture);
  std::vector<Got> got;
  while (!feed.finished()) {
    const Got g = iterate(feed);
    if (!feed.finished()) got.push_back(g);
  }
  EXPECT_EQ(got, (std::vector<Got>{{10, 1, 2, true},
                                   {20, 1, 1, false},
                                   {30, 0, 0, true},
                                   {30, 0, 1, false},
                                   {40, 0, 0, true},
                                   {40, 0, 0, true},
                                   {50, 1, 0, false},
                                   {50, 1, 0, false},
                                   {60, 0, 1, false},
                                   {61, 0, 0, true}}));
  feed.finish();
  EXPECT_FALSE(feed.divergence()) << feed.divergence()->message;
  EXPECT_EQ(feed.ticks(), 5u);
  EXPECT_EQ(feed.statuses_skipped(), 1u);
}

// Each tick's recorded SceneState is compared with the published one before the next call; one
// published beyond the end of the recording diverges at its end.
TEST_F(RecordedFeedTest, ComparesEachCallsOutputsThenFindsAnExtraOneAtTheEnd) {
  write({tick_at(10), output(proto::OUTPUT_SCENE_STATE, to_cdr(scene_at_tick(1))), tick_at(20),
         output(proto::OUTPUT_SCENE_STATE, to_cdr(scene_at_tick(2)))});
  RecordingReader reader(path);
  OutputCapture capture;
  RecordedFeed feed(reader, capture);
  std::uint64_t tick = 0;
  auto publish_scene = [&] { capture.publish(scene_at_tick(++tick)); };
  iterate(feed, publish_scene);
  iterate(feed, [&] {
    publish_scene();
    publish_scene();  // one more than recorded
  });
  iterate(feed);
  ASSERT_TRUE(feed.finished());
  EXPECT_FALSE(feed.divergence());
  EXPECT_EQ(feed.outputs_compared(), 1u) << "the first tick's SceneState was compared when the second tick came";
  feed.finish();
  ASSERT_TRUE(feed.divergence());
  EXPECT_EQ(feed.outputs_compared(), 2u);
  EXPECT_EQ(feed.divergence()->record, 4u) << "at the end of the recording";
  EXPECT_EQ(feed.divergence()->tick, 2u);
  EXPECT_EQ(feed.divergence()->message,
            "record 4 (tick 2): the replay published a SceneState (scene at tick 3) that the recording does not have");
}

// Outputs belong to the call they follow: one published by the first tick that the recording has
// after the second tick diverges at the second tick, though the sequences of outputs agree.
TEST_F(RecordedFeedTest, AnOutputOfTheWrongCallDiverges) {
  write({tick_at(10), output(proto::OUTPUT_SCENE_STATE, to_cdr(scene_at_tick(1))), tick_at(20),
         output(proto::OUTPUT_SCENE_STATE, to_cdr(scene_at_tick(2)))});
  RecordingReader reader(path);
  OutputCapture capture;
  RecordedFeed feed(reader, capture);
  iterate(feed, [&] {
    capture.publish(scene_at_tick(1));
    capture.publish(scene_at_tick(2));
  });
  iterate(feed);
  ASSERT_TRUE(feed.divergence());
  EXPECT_EQ(feed.divergence()->message,
            "record 2 (tick 1): the replay published a SceneState (scene at tick 2) that the recording does not have");
}

// An undecodable command is reported when the replay reaches it, after the outputs of the call
// before it: if those differ, that difference is reported instead.
TEST_F(RecordedFeedTest, AnUndecodableCallIsReportedAfterTheOutputsBeforeIt) {
  write({tick_at(10), output(proto::OUTPUT_SCENE_STATE, to_cdr(scene_at_tick(1))), command_at(10, "not cdr"),
         tick_at(20)});
  for (const bool same_scene : {true, false}) {
    RecordingReader reader(path);
    OutputCapture capture;
    RecordedFeed feed(reader, capture);
    iterate(feed, [&] { capture.publish(scene_at_tick(same_scene ? 1 : 7)); });
    iterate(feed);
    ASSERT_TRUE(feed.finished());
    ASSERT_TRUE(feed.divergence());
    if (same_scene) {
      EXPECT_EQ(feed.divergence()->message,
                "record 2 (tick 1): the recorded SceneCommand does not decode with this build's IDL");
    } else {
      EXPECT_EQ(feed.divergence()->record, 1u);
      EXPECT_EQ(feed.divergence()->field, "tick");
    }
  }
}

}  // namespace
}  // namespace telegrasp::server
