// Tests telegrasp-view's MCAP recording (client_lib/tools/view/mcap_recorder.h): every step
// message is written at the step's time, the whole scene is written again every 2 s of log time
// (so a player that seeks finds it), and a chunk goes to disk once the flush interval has passed.
// The files themselves are read by the reference reader in client_lib.view.record_killed and
// tools.replay_mcap.reference_reader.
#include "channels.h"
#include "mcap_recorder.h"
#include "right_hand_model.h"
#include "step_messages.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <memory>

namespace telegrasp::view {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kSecond = 1'000'000'000;
constexpr std::uint64_t kStart = 1'700'000'000 * kSecond;  // some wall-clock time, ns since the epoch

// The view's channels with placeholder schemas (the foxglove ones come from the build's npm step).
std::vector<Channel> test_channels() {
  return {{kSceneChannel, "/scene", "foxglove.SceneUpdate", "{}", false},
          {kTransformsChannel, "/tf", "foxglove.FrameTransforms", "{}", true},
          {kGraspStateChannel, "/grasp_state", "telegrasp.GraspState", "{}", false},
          {kGraspEventsChannel, "/grasp_events", "telegrasp.GraspEvent", "{}", false},
          {kServerStatusChannel, "/server_status", "telegrasp.ServerStatus", "{}", true}};
}

class McapRecorderTest : public RightHandModelTest {
 protected:
  McapRecorderTest() {
    skeleton_.X_WorldPhalanx.assign(rig_->phalanges().size(), skeleton_.X_WorldPalm);
    path_ = fs::temp_directory_path() / ("mcap_recorder_test_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".mcap");
  }
  ~McapRecorderTest() override { fs::remove(path_); }

  // One step of the model with the hand moved 1 mm along x from the last one.
  std::vector<StepMessage> step(std::uint64_t time_ns) {
    skeleton_.X_WorldPalm.translation().x() += 0.001;
    ClientSnapshot s;
    s.skeletons = {skeleton_};
    return step_messages(model_.update(s, time_ns));
  }

  fs::path path_;
};

TEST_F(McapRecorderTest, WritesEveryStepMessageAtTheStepsTime) {
  McapRecorder recorder(path_.string(), test_channels(), {});
  // The first step: the hand appears (/scene) and its frames (/tf).
  const std::vector<StepMessage> first = step(kStart);
  ASSERT_EQ(first.size(), 2u);
  EXPECT_EQ(first[0].channel, kSceneChannel);
  EXPECT_EQ(first[1].channel, kTransformsChannel);
  recorder.record(first, model_, kStart);
  // Then the palm moves: /tf only.
  const std::vector<StepMessage> second = step(kStart + kSecond / 30);
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(second[0].channel, kTransformsChannel);
  recorder.record(second, model_, kStart + kSecond / 30);
  recorder.close();

  EXPECT_EQ(recorder.writer().message_count(), 3u);
  EXPECT_EQ(recorder.keyframes(), 0u);  // the first /scene holds every entity: no extra one yet
  ASSERT_EQ(recorder.writer().chunks().size(), 1u);
  EXPECT_EQ(recorder.writer().chunks()[0].message_start_time_ns, kStart);
  EXPECT_EQ(recorder.writer().chunks()[0].message_end_time_ns, kStart + kSecond / 30);
  EXPECT_EQ(fs::file_size(path_), recorder.writer().bytes_written());
}

TEST_F(McapRecorderTest, WritesTheWholeSceneEveryTwoSecondsOfLogTime) {
  McapRecorder recorder(path_.string(), test_channels(), {});
  // 5 s of steps every 100 ms in which the hand only moves: the model sends /scene once.
  std::uint64_t step_messages_written = 0;
  for (std::uint64_t k = 0; k <= 50; ++k) {
    const std::uint64_t t = kStart + k * kSecond / 10;
    const std::vector<StepMessage> m = step(t);
    step_messages_written += m.size();
    recorder.record(m, model_, t);
  }
  // Keyframes after the first /scene (at 0 s): at 2 s and 4 s.
  EXPECT_EQ(recorder.keyframes(), 2u);
  EXPECT_EQ(recorder.writer().message_count(), step_messages_written + 2);

  // The closing keyframe of an export: the whole scene and every frame.
  recorder.record_keyframe(model_, kStart + 6 * kSecond);
  EXPECT_EQ(recorder.keyframes(), 3u);
  EXPECT_EQ(recorder.writer().message_count(), step_messages_written + 4);
}

TEST_F(McapRecorderTest, NoKeyframeOfAnEmptyModel) {
  McapRecorder recorder(path_.string(), test_channels(), {});
  recorder.record_keyframe(model_, kStart);
  EXPECT_EQ(recorder.keyframes(), 0u);
  EXPECT_EQ(recorder.writer().message_count(), 0u);
}

TEST_F(McapRecorderTest, WritesAChunkOnceTheFlushIntervalHasPassed) {
  McapRecorder recorder(path_.string(), test_channels(), {.flush_interval_ns = kSecond});
  std::uint64_t now = 5 * kSecond;  // the caller's monotonic clock
  recorder.flush_if_due(now);  // starts the interval
  recorder.record(step(kStart), model_, kStart);
  recorder.flush_if_due(now += kSecond / 2);
  EXPECT_EQ(recorder.writer().chunks().size(), 0u);  // half a second: the chunk stays open
  recorder.flush_if_due(now += kSecond / 2);
  ASSERT_EQ(recorder.writer().chunks().size(), 1u);  // one second: written...
  EXPECT_EQ(fs::file_size(path_), recorder.writer().bytes_written());  // ...and handed to the OS
  recorder.record(step(kStart + kSecond), model_, kStart + kSecond);
  recorder.flush_if_due(now += kSecond / 2);
  EXPECT_EQ(recorder.writer().chunks().size(), 1u);
  recorder.flush_if_due(now += kSecond / 2);
  EXPECT_EQ(recorder.writer().chunks().size(), 2u);
  EXPECT_EQ(recorder.writer().chunks()[1].message_count, 1u);
}

TEST_F(McapRecorderTest, WithoutAFlushIntervalOnlyFullChunksAreWritten) {
  McapRecorder recorder(path_.string(), test_channels(), {});
  recorder.record(step(kStart), model_, kStart);
  recorder.flush_if_due(0);
  recorder.flush_if_due(3600 * kSecond);
  EXPECT_EQ(recorder.writer().chunks().size(), 0u);
}

TEST_F(McapRecorderTest, UnknownChannelIsRefused) {
  McapRecorder recorder(path_.string(), test_channels(), {});
  EXPECT_THROW(recorder.write(99, "{}", kStart), std::invalid_argument);
}

}  // namespace
}  // namespace telegrasp::view
