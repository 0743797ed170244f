// Tests server/src/server_loop with a fake clock and a real SceneServer: ticks at exactly the due
// times, the loop sleeping in between; a sample between ticks applied on arrival (its skeleton
// published at once with late latching, at the next tick without); lockstep ticks only when every
// live hand answered, or after a stall; missed due times counted; ServerStatus once a period;
// stop() ending a wait at once.
#include "controller_state.h"
#include "server_loop.h"

#include "telegrasp/sim/standin_objects.h"
#include "test_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace telegrasp::server {
namespace {

using time_point = LoopClock::time_point;
using duration = std::chrono::steady_clock::duration;

// The tick period as the loop computes it from 90 Hz, and fractions of it.
const duration kPeriod = std::chrono::duration_cast<duration>(std::chrono::duration<double>(1.0 / 90));
duration periods(double n) { return std::chrono::duration_cast<duration>(n * kPeriod); }
const time_point kStart{std::chrono::seconds(1000)};
const ParticipantKey kParticipant{1};

// Time moves only when the loop waits: to the wait's deadline, or to the next scripted event if
// that comes first; the events of that time then run (a sample arriving wakes the wait, as the
// mailbox does).
class FakeClock : public LoopClock {
 public:
  time_point now() override { return now_; }
  void wait_until(time_point deadline) override {
    if (++waits_ > 100000) throw std::runtime_error("the loop never stopped");
    deadlines.push_back(deadline);
    if (!events_.empty() && events_.begin()->first <= deadline) {
      const time_point t = events_.begin()->first;
      now_ = std::max(now_, t);
      while (!events_.empty() && events_.begin()->first == t) events_.extract(events_.begin()).mapped()();
    } else {
      now_ = std::max(now_, deadline);
    }
  }
  void wake() override {}

  /// Runs `f` when the loop's wait reaches `t`.
  void at(time_point t, std::function<void()> f) { events_.emplace(t, std::move(f)); }
  /// Time leaps (the thread was descheduled).
  void jump_to(time_point t) { now_ = t; }
  std::vector<time_point> deadlines;  ///< Of every wait, in order.

 private:
  time_point now_ = kStart;
  std::multimap<time_point, std::function<void()>> events_;
  int waits_ = 0;
};

struct FakeSource : LoopSource {
  std::vector<InputSample> inputs;
  std::vector<msg::SceneCommand> commands;
  std::vector<InputSample> take_inputs() override { return std::exchange(inputs, {}); }
  std::vector<msg::SceneCommand> take_commands() override { return std::exchange(commands, {}); }
};

// What happened, in order, at which time since kStart: the scene calls the loop made (as its
// observer) and what was published (as the scene's sink).
struct Trace : OutputSink, SceneCallObserver {
  struct Entry {
    std::string what;
    duration at;
    std::uint64_t detail = 0;  // skeleton: input_sequence; status: missed_ticks
    bool late_latched = false;
  };
  explicit Trace(LoopClock& clock) : clock(clock) {}
  LoopClock& clock;
  std::vector<Entry> entries;

  void add(std::string what, std::uint64_t detail = 0, bool late = false) {
    entries.push_back({std::move(what), clock.now() - kStart, detail, late});
  }
  void inputs(const std::vector<InputSample>&, std::int64_t now_ns) override { call("inputs", now_ns); }
  void command(const msg::SceneCommand&, std::int64_t now_ns) override { call("command", now_ns); }
  void tick(std::int64_t now_ns) override { call("tick", now_ns); }
  void publish(const msg::HandSkeleton& m) override { add("skeleton", m.input_sequence(), m.late_latched()); }
  void publish(const msg::GraspState&) override {}
  void publish(const msg::ContactSet&) override {}
  void publish(const msg::GraspEvent&) override {}
  void publish(const msg::SceneState&) override { add("scene"); }
  void publish(const msg::ServerStatus& m) override { add("status", m.missed_ticks()); }
  void hand_removed(const HandAddress&) override {}

  // The scene gets the time the loop read from the clock, in nanoseconds since its epoch.
  void call(const char* what, std::int64_t now_ns) {
    EXPECT_EQ(now_ns, std::chrono::duration_cast<std::chrono::nanoseconds>(clock.now().time_since_epoch()).count());
    add(what);
  }
  std::vector<duration> times(const std::string& what) const {
    std::vector<duration> out;
    for (const Entry& e : entries)
      if (e.what == what) out.push_back(e.at);
    return out;
  }
  std::vector<const Entry*> all(const std::string& what) const {
    std::vector<const Entry*> out;
    for (const Entry& e : entries)
      if (e.what == what) out.push_back(&e);
    return out;
  }
};

// An empty scene at 90 Hz driven by a ServerLoop on the fake clock; scene calls and outputs go to
// the trace.
struct ServerLoopTest : ::testing::Test {
  ServerSettings settings = [] {
    ServerSettings s;
    s.empty_scene = true;
    return s;
  }();
  std::shared_ptr<const sim::HandRig> right = rig("human_right"), left = rig("human_left");
  InputMailbox mailbox{{5, 5}, 16, [](const std::string&) {}};  // the scene forgets removed hands in it
  FakeClock clock;
  FakeSource source;
  Trace trace{clock};
  std::unique_ptr<SceneServer> scene;
  std::unique_ptr<ServerLoop> loop;
  std::uint64_t seq = 0;

  void make_loop() {
    scene = std::make_unique<SceneServer>(settings, standins(), right, left, mailbox, trace);
    loop = std::make_unique<ServerLoop>(loop_settings(settings), *scene, clock, source, trace, &trace);
  }
  // Runs the loop until `end` (since kStart), when the clock calls stop().
  void run_until(duration end) {
    if (!loop) make_loop();
    clock.at(kStart + end, [this] { loop->stop(); });
    loop->run();
  }
  // A sample of `client`'s right hand arriving at `t` (since kStart).
  void arrives(duration t, const std::string& client, std::uint64_t lockstep_tick = 0) {
    clock.at(kStart + t, [this, client, lockstep_tick, t] {
      InputSample s;
      s.hand = {client, 1};
      s.state = to_state(client, 1, ++seq, sim::ControllerInput{});
      s.state.lockstep_tick(lockstep_tick);
      s.received_ns = std::chrono::duration_cast<std::chrono::nanoseconds>((kStart + t).time_since_epoch()).count();
      source.inputs.push_back(s);
    });
  }
};

TEST_F(ServerLoopTest, TicksAtExactlyTheDueTimesAndSleepsInBetween) {
  run_until(periods(5.5));
  EXPECT_EQ(trace.times("tick"), (std::vector<duration>{periods(1), periods(2), periods(3), periods(4), periods(5)}));
  // One wait per due time: the status due at once, then each tick's; the last is cut by stop().
  std::vector<time_point> expected{kStart};
  for (int k = 1; k <= 6; ++k) expected.push_back(kStart + periods(k));
  EXPECT_EQ(clock.deadlines, expected);
  EXPECT_EQ(loop->ticks(), 5u);
  EXPECT_EQ(loop->missed_ticks(), 0u);
}

TEST_F(ServerLoopTest, ASampleBetweenTicksIsAppliedOnArrivalAndItsSkeletonPublishedAtOnce) {
  arrives(periods(1.5), "alice");
  run_until(periods(2.5));
  EXPECT_EQ(trace.times("inputs"), std::vector<duration>{periods(1.5)}) << "the sample woke the loop";
  EXPECT_EQ(trace.times("tick"), (std::vector<duration>{periods(1), periods(2)})) << "the schedule is unchanged";
  const auto skeletons = trace.all("skeleton");
  ASSERT_EQ(skeletons.size(), 2u);
  EXPECT_EQ(skeletons[0]->at, periods(1.5));
  EXPECT_TRUE(skeletons[0]->late_latched);
  EXPECT_EQ(skeletons[0]->detail, 1u) << "the skeleton of that sample";
  EXPECT_EQ(skeletons[1]->at, periods(2));
  EXPECT_FALSE(skeletons[1]->late_latched);
  EXPECT_EQ(skeletons[1]->detail, 1u) << "the tick stepped the hand with it";
}

TEST_F(ServerLoopTest, WithoutLateLatchingTheSkeletonWaitsForTheTick) {
  settings.late_latch = false;
  arrives(periods(1.5), "alice");
  run_until(periods(2.5));
  EXPECT_EQ(trace.times("inputs"), std::vector<duration>{periods(1.5)}) << "still applied on arrival";
  const auto skeletons = trace.all("skeleton");
  ASSERT_EQ(skeletons.size(), 1u);
  EXPECT_EQ(skeletons[0]->at, periods(2));
  EXPECT_FALSE(skeletons[0]->late_latched);
  EXPECT_EQ(skeletons[0]->detail, 1u);
}

// Lockstep: alice and bob both answer tick 0, and the loop ticks on the second answer; for tick 1
// alice's answer alone is not enough; when only bob answers tick 2, the loop waits for alice until
// nothing has happened for freeze_after_s, then ticks anyway.
TEST_F(ServerLoopTest, LockstepTicksWhenEveryLiveHandAnsweredOrAfterAStall) {
  settings.lockstep = true;
  arrives(periods(0.2), "alice", 0);
  arrives(periods(0.2), "bob", 0);
  arrives(periods(0.5), "alice", 1);
  arrives(periods(0.9), "bob", 1);
  arrives(periods(1.3), "bob", 2);
  const duration stall = std::chrono::duration_cast<duration>(std::chrono::duration<double>(settings.freeze_after_s));
  run_until(periods(1.3) + stall + periods(0.5));
  EXPECT_EQ(trace.times("tick"), (std::vector<duration>{periods(0.2), periods(0.9), periods(1.3) + stall}));
  EXPECT_EQ(trace.times("inputs"), (std::vector<duration>{periods(0.2), periods(0.5), periods(0.9), periods(1.3)}));
  const auto ticks = trace.times("tick");
  for (const Trace::Entry* s : trace.all("skeleton")) {
    EXPECT_FALSE(s->late_latched) << "no late latching in lockstep";
    EXPECT_NE(std::find(ticks.begin(), ticks.end(), s->at), ticks.end()) << "a skeleton between ticks";
  }
}

// With no hands, a lockstep scene waits for one without a stall tick to look for: the loop sleeps
// from status to status.
TEST_F(ServerLoopTest, LockstepWithNoHandsSleepsUntilTheNextStatus) {
  settings.lockstep = true;
  run_until(std::chrono::milliseconds(2500));
  EXPECT_EQ(trace.times("status"),
            (std::vector<duration>{duration::zero(), std::chrono::seconds(1), std::chrono::seconds(2)}));
  EXPECT_EQ(clock.deadlines.size(), 4u) << "the loop woke between statuses";
  EXPECT_EQ(loop->ticks(), 0u);
}

// The thread was descheduled: the first tick (due at 1 period) runs at 4.5 periods. The due times
// 2, 3 and 4 periods passed without a tick: counted as missed (and in the next ServerStatus), and
// the schedule restarts one period after the late tick.
TEST_F(ServerLoopTest, CountsMissedTicksWhenTheClockJumps) {
  clock.at(kStart + periods(1), [this] { clock.jump_to(kStart + periods(4.5)); });
  run_until(std::chrono::seconds(1) + periods(0.1));
  const auto ticks = trace.times("tick");
  ASSERT_GE(ticks.size(), 3u);
  EXPECT_EQ(ticks[0], periods(4.5));
  EXPECT_EQ(ticks[1], periods(5.5));
  EXPECT_EQ(ticks[2], periods(6.5));
  EXPECT_EQ(loop->missed_ticks(), 3u);
  const auto statuses = trace.all("status");
  ASSERT_EQ(statuses.size(), 2u);
  EXPECT_EQ(statuses[1]->at, std::chrono::seconds(1));
  EXPECT_EQ(statuses[1]->detail, 3u);
}

// Late by less than two periods, the next tick follows at once and the schedule is kept.
TEST_F(ServerLoopTest, CatchesUpATickLateByLessThanTwoPeriods) {
  clock.at(kStart + periods(1), [this] { clock.jump_to(kStart + periods(2.5)); });
  run_until(periods(3.5));
  EXPECT_EQ(trace.times("tick"), (std::vector<duration>{periods(2.5), periods(2.5), periods(3)}));
  EXPECT_EQ(loop->missed_ticks(), 0u);
}

TEST_F(ServerLoopTest, PublishesServerStatusAtOnceThenOncePerPeriod) {
  settings.status_period_s = 0.5;
  run_until(std::chrono::milliseconds(1200));
  EXPECT_EQ(trace.times("status"),
            (std::vector<duration>{duration::zero(), std::chrono::milliseconds(500), std::chrono::seconds(1)}));
}

// stop() during the wait for the third tick: the loop returns from that wait without ticking.
TEST_F(ServerLoopTest, StopEndsTheLoopAtOnce) {
  clock.at(kStart + periods(3), [this] { loop->stop(); });
  run_until(periods(10));
  EXPECT_EQ(loop->ticks(), 2u) << "no tick after stop()";
  EXPECT_EQ(clock.deadlines.size(), 4u) << "no wait after stop()";
}

// A clock whose wait blocks the loop's thread until wake(), or a guard of 3 s, and says which.
class BlockingClock : public LoopClock {
 public:
  time_point now() override { return kStart; }
  void wait_until(time_point deadline) override {
    if (deadline <= kStart) return;  // due now (the first ServerStatus)
    std::unique_lock lock(mutex_);
    waiting_ = true;
    cv_.notify_all();
    woken = cv_.wait_for(lock, std::chrono::seconds(3), [this] { return wake_; });
  }
  void wake() override {
    std::lock_guard lock(mutex_);
    wake_ = true;
    cv_.notify_all();
  }
  void wait_for_waiter() {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [this] { return waiting_; });
  }
  bool woken = false;  ///< The wait ended by wake(), not the guard.

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool waiting_ = false, wake_ = false;
};

// stop() from another thread (the server's signal thread) wakes the waiting loop: it returns
// because of the wake, not the guard, and without ticking.
TEST_F(ServerLoopTest, StopFromAnotherThreadEndsAWaitAtOnce) {
  BlockingClock blocking;
  scene = std::make_unique<SceneServer>(settings, standins(), right, left, mailbox, trace);
  ServerLoop blocked(loop_settings(settings), *scene, blocking, source, trace, &trace);
  std::thread runner([&] { blocked.run(); });
  blocking.wait_for_waiter();
  blocked.stop();
  runner.join();
  EXPECT_TRUE(blocking.woken) << "the wait ran to its guard: stop() did not wake the clock";
  EXPECT_EQ(blocked.ticks(), 0u);
}

}  // namespace
}  // namespace telegrasp::server
