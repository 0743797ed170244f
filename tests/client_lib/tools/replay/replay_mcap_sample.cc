// telegrasp-replay-mcap-sample DIR: writes DIR/session.tgrec (the recorded session of
// recorded_session.h) and DIR/expected.json, what tests/js/mcap_export_check.mjs checks the
// file `telegrasp-replay DIR/session.tgrec --export-mcap DIR/session.mcap` against. The
// expectations are read from the recording here, independently of the export: the outputs per
// type, the recording's start and the server time of its first and last output, every grasp
// event (id, kind, object, time), every ServerStatus tick, every palm pose a skeleton carried,
// and the objects of the first SceneState.
#include "recorded_session.h"
#include "recording.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

namespace {

using namespace telegrasp::server;
using Json = nlohmann::json;
namespace msg = telegrasp::msg;

template <class Msg>
Msg decode(const proto::Output& o) {
  Msg m;
  if (!from_cdr(o.cdr(), m)) throw std::runtime_error("an output does not decode");
  return m;
}

std::string side_name(unsigned side) { return side == 0 ? "left" : "right"; }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: telegrasp-replay-mcap-sample DIR\n";
    return 2;
  }
  try {
    const std::filesystem::path dir = argv[1];
    std::filesystem::create_directories(dir);
    const RecordedSession session = record_session((dir / "session.tgrec").string());

    RecordingReader reader(session.path);
    const std::int64_t created_ns = reader.header().created_unix_ns();
    // Nanoseconds since the epoch pass 2^53: written as strings, which JavaScript reads as BigInt.
    const auto ns = [&](double server_time_s) {
      return std::to_string(created_ns + std::llround(server_time_s * 1e9));
    };
    std::map<std::string, int> outputs;
    double first_s = INFINITY, last_s = -INFINITY;
    Json events = Json::array(), status_ticks = Json::array(), palms = Json::array(), objects = Json::array();
    std::map<std::string, bool> hands;
    const auto at = [&](double t) {
      first_s = std::min(first_s, t);
      last_s = std::max(last_s, t);
    };
    proto::Record r;
    while (reader.next(r)) {
      if (!r.has_output()) continue;
      const proto::Output& o = r.output();
      switch (o.type()) {
        case proto::OUTPUT_HAND_SKELETON: {
          const auto m = decode<msg::HandSkeleton>(o);
          ++outputs["hand_skeleton"];
          at(m.time());
          const std::string hand = m.client_id().to_string() + "/" + side_name(m.hand_side());
          hands[hand] = true;
          const auto& p = m.palm().position();
          const auto& q = m.palm().orientation();
          palms.push_back({{"time_ns", ns(m.time())},
                           {"frame", hand + "/palm"},
                           {"p", {p.x(), p.y(), p.z()}},
                           {"q", {q.w(), q.x(), q.y(), q.z()}}});
          break;
        }
        case proto::OUTPUT_GRASP_STATE:
          ++outputs["grasp_state"];
          at(decode<msg::GraspState>(o).time());
          break;
        case proto::OUTPUT_CONTACT_SET:
          ++outputs["contact_set"];
          at(decode<msg::ContactSet>(o).time());
          break;
        case proto::OUTPUT_GRASP_EVENT: {
          const auto m = decode<msg::GraspEvent>(o);
          ++outputs["grasp_event"];
          at(m.time());
          events.push_back({{"event_id", m.event_id()},
                            {"kind", m.kind() == msg::GRASP_EVENT_GRASP ? "grasp" : "release"},
                            {"object_name", m.object_name().to_string()},
                            {"time_ns", ns(m.time())}});
          break;
        }
        case proto::OUTPUT_SCENE_STATE: {
          const auto m = decode<msg::SceneState>(o);
          ++outputs["scene_state"];
          at(m.time());
          if (objects.empty())
            for (const msg::ObjectState& obj : m.objects()) objects.push_back("object/" + std::to_string(obj.id()));
          break;
        }
        case proto::OUTPUT_SERVER_STATUS: {
          const auto m = decode<msg::ServerStatus>(o);
          ++outputs["server_status"];
          at(m.time());
          status_ticks.push_back(m.tick());
          break;
        }
        case proto::OUTPUT_HAND_REMOVED:
          ++outputs["hand_removed"];
          break;
        default:
          break;
      }
    }
    if (!reader.complete()) throw std::runtime_error("the recording is not complete");
    Json hand_list = Json::array();
    for (const auto& [h, seen] : hands) hand_list.push_back(h);
    const Json expected = {{"recording", "session.tgrec"},
                           {"file", "session.mcap"},
                           {"created_unix_ns", std::to_string(created_ns)},
                           {"rate_hz", 30},
                           {"tick_s", 1.0 / 90},
                           {"outputs", outputs},
                           {"start_time_ns", ns(first_s)},
                           {"end_time_ns", ns(last_s)},
                           {"events", events},
                           {"status_ticks", status_ticks},
                           {"hands", hand_list},
                           {"objects", objects},
                           {"palms", palms}};
    std::ofstream out(dir / "expected.json");
    out << expected.dump(1) << "\n";
    if (!out) throw std::runtime_error((dir / "expected.json").string() + ": cannot write");
    std::cout << "telegrasp-replay-mcap-sample: " << (dir / "session.tgrec").string() << ", " << events.size()
              << " grasp events, " << palms.size() << " skeletons\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-replay-mcap-sample: " << e.what() << "\n";
    return 1;
  }
}
