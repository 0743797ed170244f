#include "recorded_feed.h"

#include <cassert>
#include <utility>

namespace telegrasp::server {
namespace {

constexpr std::uint64_t kProgressEvery = 4096;  // records between progress callbacks

bool is_call(const proto::Record& r) { return r.has_inputs() || r.has_command() || r.has_tick(); }

std::int64_t call_time(const proto::Record& r) {
  if (r.has_inputs()) return r.inputs().now_ns();
  if (r.has_command()) return r.command().now_ns();
  return r.tick().now_ns();
}

}  // namespace

RecordedFeed::RecordedFeed(RecordingReader& reader, OutputCapture& capture,
                           std::function<void(const RecordingReader&)> progress)
    : reader_(reader), capture_(capture), progress_(std::move(progress)) {}

LoopClock::time_point RecordedFeed::now() {
  return time_point(std::chrono::duration_cast<time_point::duration>(std::chrono::nanoseconds(current_.now_ns)));
}

// Appends the next output or call to items_; false at the end of the recording or its damage.
// The loop never records an empty inputs call (one would do nothing), nor anything else.
bool RecordedFeed::read() {
  proto::Record r;
  while (reader_.next(r)) {
    if (progress_ && reader_.records() % kProgressEvery == 0) progress_(reader_);
    if (!r.has_output() && !is_call(r)) continue;
    if (r.has_inputs() && r.inputs().samples().empty()) continue;
    items_.push_back({reader_.records() - 1, std::move(r)});
    return true;
  }
  return false;
}

// Gathers the calls of the next iteration: they follow the outputs of the last call made.
void RecordedFeed::wait_until(time_point) {
  current_ = {};
  if (finished_ || divergence_) {
    finished_ = true;
    return;
  }
  for (std::size_t i = 0;; ++i) {
    if (i == items_.size() && !read()) break;
    const proto::Record& r = items_[i].record;
    if (r.has_output()) continue;
    if (!joins(r)) break;
    if (Divergence undecodable; !add(r, undecodable)) {
      // Reported when the replay gets there: after the outputs of the calls before it.
      const std::uint64_t index = items_[i].index;
      if (current_.calls == 0 && before_call(r.kind_case())) diverge(index, std::move(undecodable));
      break;
    }
  }
  if (current_.calls == 0) finished_ = true;
}

// Whether a call belongs to the iteration gathered so far (the order of ServerLoop::step).
bool RecordedFeed::joins(const proto::Record& call) const {
  if (current_.calls == 0) return true;
  if (call_time(call) != current_.now_ns || current_.tick) return false;
  return !call.has_inputs();
}

// Adds a call to the current iteration; false (and why) if its message does not decode.
bool RecordedFeed::add(const proto::Record& call, Divergence& undecodable) {
  if (call.has_inputs()) {
    for (const proto::InputSample& p : call.inputs().samples()) {
      InputSample s;
      s.hand = hand_address(p.hand());
      s.received_ns = p.received_ns();
      if (!from_cdr(p.controller_state_cdr(), s.state)) {
        undecodable.type = "ControllerState";
        undecodable.key = hand_text(s.hand.client_id, s.hand.side);
        undecodable.message =
            "the recorded ControllerState of the " + undecodable.key + " does not decode with this build's IDL";
        current_.inputs.clear();
        return false;
      }
      current_.inputs.push_back(std::move(s));
    }
  } else if (call.has_command()) {
    msg::SceneCommand c;
    if (!from_cdr(call.command().scene_command_cdr(), c)) {
      undecodable.type = "SceneCommand";
      undecodable.message = "the recorded SceneCommand does not decode with this build's IDL";
      return false;
    }
    current_.commands.push_back(std::move(c));
  } else {
    current_.tick = true;
  }
  current_.now_ns = call_time(call);
  ++current_.calls;
  return true;
}

std::vector<InputSample> RecordedFeed::take_inputs() { return std::exchange(current_.inputs, {}); }
std::vector<msg::SceneCommand> RecordedFeed::take_commands() { return std::exchange(current_.commands, {}); }

void RecordedFeed::inputs(const std::vector<InputSample>&, std::int64_t) { before_call(proto::Record::kInputs); }
void RecordedFeed::command(const msg::SceneCommand&, std::int64_t) { before_call(proto::Record::kCommand); }
void RecordedFeed::tick(std::int64_t) {
  if (before_call(proto::Record::kTick)) ++ticks_;
}

// The loop is about to make the next recorded call (of kind `kind`): the outputs recorded after
// the previous call must be exactly those the replay published since. Consumes the call; false
// once diverged.
bool RecordedFeed::before_call(proto::Record::KindCase kind) {
  if (divergence_) return false;
  compare_outputs();
  if (divergence_) return false;
  assert(!items_.empty() && items_.front().record.kind_case() == kind);
  (void)kind;
  if (!capture_.outputs.empty()) {
    extra_output(items_.front().index);
    return false;
  }
  items_.pop_front();
  return true;
}

// Compares the recorded outputs at the front of items_ with the captured ones, in order.
void RecordedFeed::compare_outputs() {
  while (!divergence_ && !items_.empty() && items_.front().record.has_output()) {
    const Item& item = items_.front();
    const proto::Output& out = item.record.output();
    if (out.type() == proto::OUTPUT_SERVER_STATUS) {
      ++statuses_skipped_;  // wall-clock loop timings: not reproducible
    } else if (capture_.outputs.empty()) {
      Divergence d;
      d.type = output_type_name(out.type());
      d.key = key_of_output(out.type(), out.cdr(), hand_address(out.removed()));
      d.message = "the recording has a " + d.type + " (" + d.key + ") that the replay did not publish";
      diverge(item.index, std::move(d));
      return;
    } else if (Divergence d; !same_output(out, capture_.outputs.front(), d)) {
      diverge(item.index, std::move(d));
      return;
    } else {
      capture_.outputs.pop_front();
      ++outputs_compared_;
    }
    items_.pop_front();
  }
}

void RecordedFeed::finish() {
  compare_outputs();
  // A complete recording holds every output of its last call; a damaged one may end among them.
  if (!divergence_ && !reader_.damage() && !capture_.outputs.empty()) extra_output(reader_.records());
}

// The replay published something the recording does not have before its next call (or end).
void RecordedFeed::extra_output(std::uint64_t record) {
  const ReplayedOutput& p = capture_.outputs.front();
  Divergence d;
  d.type = output_type_name(p.type);
  d.key = key_of_output(p.type, p.cdr, p.removed);
  d.message = "the replay published a " + d.type + " (" + d.key + ") that the recording does not have";
  diverge(record, std::move(d));
}

void RecordedFeed::diverge(std::uint64_t record, Divergence d) {
  d.record = record;
  d.tick = ticks_;
  d.message = "record " + std::to_string(record) + " (tick " + std::to_string(d.tick) + "): " + d.message;
  divergence_ = std::move(d);
  finished_ = true;
}

}  // namespace telegrasp::server
