// ServerLoop: the simulation thread's loop around a SceneServer. It sleeps until the next tick is
// due or an input or command arrives, hands inputs and commands to the scene at once (so late
// latching publishes skeletons on arrival), ticks on schedule, and publishes ServerStatus. Time,
// inputs and tick decisions come through small interfaces, so the live server (LiveFeed), a
// replayed recording (RecordedFeed) and tests (a fake clock) drive the same loop.
#pragma once

#include "input_mailbox.h"
#include "output_sink.h"
#include "scene_call_observer.h"
#include "scene_server.h"
#include "server_config.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <vector>

namespace telegrasp::server {

/// The loop's time. steady_clock's time points; times handed to the scene are their
/// nanoseconds since the clock's epoch.
class LoopClock {
 public:
  using time_point = std::chrono::steady_clock::time_point;
  virtual ~LoopClock() = default;
  virtual time_point now() = 0;
  /// Returns at `deadline`, or earlier when an input or command may be pending or wake() is
  /// called.
  virtual void wait_until(time_point deadline) = 0;
  /// Ends the current (or next) wait_until early. Any thread.
  virtual void wake() = 0;
};

/// Where each iteration's inputs and commands come from.
class LoopSource {
 public:
  virtual ~LoopSource() = default;
  /// The samples that arrived since the last call (the newest per hand, in hand order).
  virtual std::vector<InputSample> take_inputs() = 0;
  /// The commands that arrived since the last call, in arrival order.
  virtual std::vector<msg::SceneCommand> take_commands() = 0;
  /// TickSchedule::kSource only: whether this iteration ticks (after its inputs and commands).
  virtual bool tick_due() { return false; }
  /// True once nothing more will come (a recording's end): the loop returns.
  virtual bool finished() const { return false; }
};

/// When the loop ticks.
enum class TickSchedule {
  kClock,  ///< At fixed due times 1 / tick_hz apart (a tick late by a whole period or more skips the due times passed).
  kLockstep,  ///< When SceneServer::lockstep_ready(), or when hands are present and nothing happened for stall_after_s.
  kSource,  ///< When LoopSource::tick_due() says so: replay ticks where the recording did.
};

struct LoopSettings {
  TickSchedule schedule = TickSchedule::kClock;
  double tick_hz = 90;
  double status_period_s = 1;
  /// kLockstep: a tick is taken anyway after this long without any input, command or tick; it
  /// freezes the hands that did not answer, and later ticks no longer wait for them.
  double stall_after_s = 1;
};
/// The loop settings of a server: kLockstep if settings.lockstep, else kClock; stall_after_s is
/// freeze_after_s.
LoopSettings loop_settings(const ServerSettings& settings);

/// Runs the simulation thread's loop. All calls but stop() from the thread that calls run().
class ServerLoop {
 public:
  /// `status_sink` receives ServerStatus (the scene's own sink, so a Recorder records it too);
  /// `observer` (may be null) is told of every scene call before it is made. All must outlive
  /// the loop.
  ServerLoop(const LoopSettings& settings, SceneServer& scene, LoopClock& clock, LoopSource& source,
             OutputSink& status_sink, SceneCallObserver* observer = nullptr);

  /// Loops until stop() is called or the source is finished. Each iteration: waits (until the
  /// next tick, status or, in lockstep with hands, stall is due, or until woken), then hands the scene the
  /// new inputs, then the new commands, ticks if due, and publishes ServerStatus every
  /// status_period_s (the first at once).
  void run();
  /// Makes run() return: at once if it is waiting, else after its current iteration. Any thread
  /// (not a signal handler: it wakes the clock).
  void stop();

  std::uint64_t ticks() const { return ticks_; }
  /// kClock: due times that passed without a tick.
  std::uint64_t missed_ticks() const { return missed_; }

 private:
  using time_point = LoopClock::time_point;
  using duration = std::chrono::steady_clock::duration;
  time_point wake_deadline() const;
  void step(time_point now);
  bool tick_due(time_point now);
  void tick(time_point now);
  void publish_status(time_point now);

  const LoopSettings settings_;
  const duration period_, status_period_, stall_after_;
  SceneServer& scene_;
  LoopClock& clock_;
  LoopSource& source_;
  OutputSink& status_sink_;
  SceneCallObserver* const observer_;
  std::atomic<bool> stop_{false};
  time_point next_tick_{}, next_status_{}, last_activity_{};
  std::uint64_t ticks_ = 0, missed_ = 0;
  std::vector<double> tick_us_;  // work time of each tick since the last status
};

}  // namespace telegrasp::server
