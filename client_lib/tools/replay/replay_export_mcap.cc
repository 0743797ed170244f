#include "replay_export_mcap.h"

#include "channels.h"
#include "mcap_recorder.h"
#include "replay_diff.h"
#include "step_messages.h"
#include "telegrasp/sim/data_paths.h"
#include "telegrasp/sim/hand_rig.h"
#include "view_model.h"
#include "wire_feed.h"

#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

namespace telegrasp::server {
namespace {

// The rigs skeletons name: the recording's own (what the server ran with), else the shipped ones.
class RecordedRigs {
 public:
  explicit RecordedRigs(const proto::RecordingHeader& header) {
    for (const proto::RigText* r : {&header.right_rig(), &header.left_rig()}) {
      if (r->text().empty()) continue;
      try {
        auto rig = std::make_unique<sim::HandRig>(sim::HandRig::parse(r->text(), r->path()));
        const std::string name = rig->name();
        rigs_.try_emplace(name, std::move(rig));
      } catch (const sim::RigError&) {  // a rig this build cannot parse: drawn as joint spheres
      }
    }
  }
  const sim::HandRig* get(const std::string& name) {
    auto [it, added] = rigs_.try_emplace(name);
    if (added) {
      try {
        it->second = std::make_unique<sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path(name)));
      } catch (const std::exception&) {}
    }
    return it->second.get();
  }

 private:
  std::map<std::string, std::unique_ptr<sim::HandRig>> rigs_;
};

template <class Msg>
Msg decode(const proto::Output& output, const RecordingReader& reader) {
  Msg m;
  if (!from_cdr(output.cdr(), m))
    throw RecordingError("recording " + reader.path() + ": record " + std::to_string(reader.records() - 1) + ": the " +
                         output_type_name(output.type()) + " does not decode with this build's IDL");
  return m;
}

}  // namespace

McapExport export_mcap(const std::string& recording_path, const std::string& mcap_path,
                       const McapExportOptions& options) {
  if (!(options.rate_hz > 0 && options.rate_hz <= 1000))
    throw std::invalid_argument("export_mcap: rate_hz must be in (0, 1000]");
  RecordingReader reader(recording_path);
  const std::filesystem::path schema_dir =
      options.schema_dir.empty() ? sim::data_dir() / "view" / "schemas" : std::filesystem::path(options.schema_dir);
  std::vector<view::Channel> channels;
  try {
    channels = view::view_channels(schema_dir);
  } catch (const std::runtime_error& e) {
    throw RecordingError(e.what());
  }

  RecordedRigs rigs(reader.header());
  view::ViewModel model([&](const std::string& name) { return rigs.get(name); });
  view::WireFeed feed;
  std::optional<view::McapRecorder> recorder;
  try {
    recorder.emplace(mcap_path, channels, view::McapRecorder::Options{});
  } catch (const std::runtime_error& e) {
    throw RecordingError(std::string("MCAP ") + e.what());
  }

  const std::int64_t start_ns = reader.header().created_unix_ns();
  const auto log_time = [&](double server_time_s) {
    return static_cast<std::uint64_t>(start_ns + std::llround(server_time_s * 1e9));
  };
  // A step (the view's poll) follows the first tick, then every tick at least a period after the
  // previous step's (1 us of slack, so every 3rd tick at 90 Hz makes 30 Hz despite rounding).
  const double period_s = 1.0 / options.rate_hz - 1e-6;
  McapExport out;
  double newest_s = -std::numeric_limits<double>::infinity();  // server time of the newest output taken in
  double next_step_s = newest_s;  // the first tick at or after this ends a step
  bool pending = false;  // outputs taken in since the last step
  const auto step = [&] {
    const std::uint64_t t = log_time(newest_s);
    const view::ViewUpdate update = model.update(feed.snapshot(), t);
    recorder->record(view::step_messages(update), model, t);
    ++out.steps;
    pending = false;
    next_step_s = newest_s + period_s;
  };

  try {
    proto::Record r;
    while (reader.next(r)) {
      if (!r.has_output()) continue;
      const proto::Output& o = r.output();
      ++out.outputs;
      if (o.type() == proto::OUTPUT_HAND_REMOVED) {
        feed.hand_removed(o.removed().client_id(), static_cast<std::uint8_t>(o.removed().side()));
        pending = pending || std::isfinite(newest_s);  // in the tick of the newest output
        continue;
      }
      // A later tick's first output: the tick before it is complete and may end a step.
      const auto take = [&](const auto& m) {
        const double time_s = m.time();
        if (pending && time_s > newest_s && newest_s >= next_step_s) step();
        feed.add(m);
        newest_s = std::max(newest_s, time_s);
        pending = true;
      };
      // Each message decoded as its type; a type this build does not know: nothing to draw.
      visit_output_type(o.type(), [&]<class Msg>(std::type_identity<Msg>) { take(decode<Msg>(o, reader)); });
    }
    if (pending && std::isfinite(newest_s)) step();
    if (std::isfinite(newest_s)) recorder->record_keyframe(model, log_time(newest_s));
    out.damage = reader.damage();
    recorder->close();
  } catch (const RecordingError&) {
    throw;
  } catch (const std::runtime_error& e) {  // the MCAP file
    throw RecordingError(std::string("MCAP ") + e.what());
  }
  const mcap::Writer& w = recorder->writer();
  out.messages = w.message_count();
  out.bytes = w.bytes_written();
  if (!w.chunks().empty()) {
    out.start_time_ns = std::numeric_limits<std::uint64_t>::max();
    for (const mcap::ChunkInfo& c : w.chunks()) {
      out.start_time_ns = std::min(out.start_time_ns, c.message_start_time_ns);
      out.end_time_ns = std::max(out.end_time_ns, c.message_end_time_ns);
    }
  }
  return out;
}

}  // namespace telegrasp::server
