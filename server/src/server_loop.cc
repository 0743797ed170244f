#include "server_loop.h"

#include "process_stats.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace telegrasp::server {
namespace {

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

std::int64_t to_ns(LoopClock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

// Median, 99th percentile (nearest rank) and maximum of the tick work times of one status period;
// clears them.
LoopStats summarize(std::vector<double>& tick_us, std::uint64_t missed) {
  LoopStats s;
  s.missed_ticks = missed;
  if (tick_us.empty()) return s;
  const auto rank = [&](double q) {
    const std::size_t i = std::min(tick_us.size() - 1, static_cast<std::size_t>(std::ceil(q * tick_us.size())) - 1);
    std::nth_element(tick_us.begin(), tick_us.begin() + i, tick_us.end());
    return tick_us[i];
  };
  s.tick_us_p50 = rank(0.5);
  s.tick_us_p99 = rank(0.99);
  s.tick_us_max = *std::max_element(tick_us.begin(), tick_us.end());
  tick_us.clear();
  return s;
}

}  // namespace

LoopSettings loop_settings(const ServerSettings& settings) {
  LoopSettings s;
  s.schedule = settings.lockstep ? TickSchedule::kLockstep : TickSchedule::kClock;
  s.tick_hz = settings.tick_hz;
  s.status_period_s = settings.status_period_s;
  s.stall_after_s = settings.freeze_after_s;
  return s;
}

ServerLoop::ServerLoop(const LoopSettings& settings, SceneServer& scene, LoopClock& clock, LoopSource& source,
                       OutputSink& status_sink, SceneCallObserver* observer)
    : settings_(settings),
      period_(seconds(1.0 / settings.tick_hz)),
      status_period_(seconds(settings.status_period_s)),
      stall_after_(seconds(settings.stall_after_s)),
      scene_(scene),
      clock_(clock),
      source_(source),
      status_sink_(status_sink),
      observer_(observer) {
  assert(period_.count() > 0 && status_period_.count() > 0);
}

void ServerLoop::run() {
  const time_point start = clock_.now();
  next_tick_ = start + period_;
  next_status_ = start;
  last_activity_ = start;
  while (!stop_ && !source_.finished()) {
    clock_.wait_until(wake_deadline());
    if (stop_ || source_.finished()) break;
    step(clock_.now());
  }
}

void ServerLoop::stop() {
  stop_ = true;
  clock_.wake();
}

LoopClock::time_point ServerLoop::wake_deadline() const {
  switch (settings_.schedule) {
    case TickSchedule::kClock:
      return std::min(next_tick_, next_status_);
    case TickSchedule::kLockstep:  // with no hands there is no stall tick to wait for
      return scene_.hand_count() > 0 ? std::min(last_activity_ + stall_after_, next_status_) : next_status_;
    case TickSchedule::kSource:
      break;
  }
  return next_status_;
}

void ServerLoop::step(time_point now) {
  const std::int64_t now_ns = to_ns(now);
  if (std::vector<InputSample> inputs = source_.take_inputs(); !inputs.empty()) {
    if (observer_) observer_->inputs(inputs, now_ns);
    scene_.on_inputs(std::move(inputs), now_ns);
    last_activity_ = now;
  }
  for (const msg::SceneCommand& c : source_.take_commands()) {
    if (observer_) observer_->command(c, now_ns);
    scene_.apply_command(c);
    last_activity_ = now;
  }
  if (tick_due(now)) tick(now);
  if (now >= next_status_) publish_status(now);
}

bool ServerLoop::tick_due(time_point now) {
  switch (settings_.schedule) {
    case TickSchedule::kClock:
      return now >= next_tick_;
    case TickSchedule::kLockstep:
      return scene_.lockstep_ready() || (scene_.hand_count() > 0 && now - last_activity_ >= stall_after_);
    case TickSchedule::kSource:
      return source_.tick_due();
  }
  return false;
}

void ServerLoop::tick(time_point now) {
  const std::int64_t now_ns = to_ns(now);
  if (observer_) observer_->tick(now_ns);
  scene_.tick(now_ns);
  ++ticks_;
  last_activity_ = now;
  tick_us_.push_back(std::chrono::duration<double, std::micro>(clock_.now() - now).count());
  if (settings_.schedule != TickSchedule::kClock) return;
  // This tick was due at next_tick_. Late by less than two periods, the next one follows at once
  // and the schedule catches up; later than that, every due time passed is skipped and counted,
  // and the schedule restarts from now.
  next_tick_ += period_;
  if (now - next_tick_ >= period_) {
    missed_ += static_cast<std::uint64_t>((now - next_tick_) / period_) + 1;
    next_tick_ = now + period_;
  }
}

void ServerLoop::publish_status(time_point now) {
  LoopStats stats = summarize(tick_us_, missed_);
  const ProcessMemory memory = process_memory();
  stats.rss_kib = memory.rss_kib;
  stats.heap_kib = memory.heap_kib;
  status_sink_.publish(scene_.status(stats));
  next_status_ += status_period_;
  if (next_status_ <= now) next_status_ = now + status_period_;
}

}  // namespace telegrasp::server
