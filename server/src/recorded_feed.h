// RecordedFeed: drives a ServerLoop from a recording (TickSchedule::kSource), so replay runs the
// server's own loop, and checks what the replayed scene publishes against the recorded outputs.
#pragma once

#include "recording.h"
#include "replay_diff.h"
#include "scene_call_observer.h"
#include "server_loop.h"

#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <vector>

namespace telegrasp::server {

/// Collects what the replayed SceneServer publishes, in order, until it is compared. ServerStatus
/// is dropped: it holds wall-clock loop timings and is never compared.
class OutputCapture final : public OutputSink {
 public:
  std::deque<ReplayedOutput> outputs;

  void publish(const msg::HandSkeleton& m) override { add(proto::OUTPUT_HAND_SKELETON, to_cdr(m)); }
  void publish(const msg::GraspState& m) override { add(proto::OUTPUT_GRASP_STATE, to_cdr(m)); }
  void publish(const msg::ContactSet& m) override { add(proto::OUTPUT_CONTACT_SET, to_cdr(m)); }
  void publish(const msg::GraspEvent& m) override { add(proto::OUTPUT_GRASP_EVENT, to_cdr(m)); }
  void publish(const msg::SceneState& m) override { add(proto::OUTPUT_SCENE_STATE, to_cdr(m)); }
  void publish(const msg::ServerStatus&) override {}
  void hand_removed(const HandAddress& hand) override { outputs.push_back({proto::OUTPUT_HAND_REMOVED, "", hand}); }

 private:
  void add(proto::OutputType type, std::string cdr) { outputs.push_back({type, std::move(cdr), {}}); }
};

/// A recording, read one loop iteration at a time: at most one inputs call, then commands, then
/// at most one tick, all at one recorded time (the shape of ServerLoop's iterations).
///  - As the loop's clock: now() is the current iteration's recorded time; wait_until() moves to
///    the next iteration (recorded time leaps; the deadline is not used).
///  - As its source: the iteration's recorded inputs and commands, and whether it ticked.
///  - As its SceneCallObserver: before each call, the outputs recorded after the previous call
///    are compared, in order, with those `capture` collected since, which must then all be
///    matched. The first divergence ends the feed.
/// Recorded ServerStatus messages are skipped (counted).
class RecordedFeed final : public LoopClock, public LoopSource, public SceneCallObserver {
 public:
  /// `capture` must be the replayed scene's sink; `progress` is called every few thousand records.
  RecordedFeed(RecordingReader& reader, OutputCapture& capture,
               std::function<void(const RecordingReader&)> progress = {});

  time_point now() override;
  void wait_until(time_point deadline) override;
  void wake() override {}

  std::vector<InputSample> take_inputs() override;
  std::vector<msg::SceneCommand> take_commands() override;
  bool tick_due() override { return current_.tick; }
  /// True at the end of the recording (or its damage), or after a divergence.
  bool finished() const override { return finished_; }

  void inputs(const std::vector<InputSample>& samples, std::int64_t now_ns) override;
  void command(const msg::SceneCommand& command, std::int64_t now_ns) override;
  void tick(std::int64_t now_ns) override;

  /// Once the loop has returned: compares the outputs recorded after the last call. An output the
  /// replay published beyond them diverges, unless the recording is damaged (it may end among them).
  void finish();

  const std::optional<Divergence>& divergence() const { return divergence_; }
  std::uint64_t ticks() const { return ticks_; }  ///< Ticks replayed before the divergence, if any.
  std::uint64_t outputs_compared() const { return outputs_compared_; }
  std::uint64_t statuses_skipped() const { return statuses_skipped_; }

 private:
  struct Item {
    std::uint64_t index = 0;  // in the recording
    proto::Record record;
  };
  struct Iteration {
    std::int64_t now_ns = 0;
    std::vector<InputSample> inputs;
    std::vector<msg::SceneCommand> commands;
    bool tick = false;
    int calls = 0;
  };
  bool read();
  bool joins(const proto::Record& call) const;
  bool add(const proto::Record& call, Divergence& undecodable);
  bool before_call(proto::Record::KindCase kind);
  void compare_outputs();
  void extra_output(std::uint64_t record);
  void diverge(std::uint64_t record, Divergence d);

  RecordingReader& reader_;
  OutputCapture& capture_;
  std::function<void(const RecordingReader&)> progress_;
  std::deque<Item> items_;  // read, not yet matched: outputs and calls, in recording order
  Iteration current_;
  bool finished_ = false;
  std::optional<Divergence> divergence_;
  std::uint64_t ticks_ = 0, outputs_compared_ = 0, statuses_skipped_ = 0;
};

}  // namespace telegrasp::server
