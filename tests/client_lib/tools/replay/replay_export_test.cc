// Tests telegrasp-replay's exports (client_lib/tools/replay) on a recorded session: the contacts
// CSV holds every grasp contact, numbers read back exactly; --export-mcap reads and writes what
// the recording holds, exports a damaged recording up to the damage, sets the number of view
// updates by the step rate, and fails naming the file when the schemas are missing or the file
// cannot be written. The MCAP file itself is read by the reference reader in
// tools.replay_mcap.reference_reader (tests/js/mcap_export_check.mjs).
#include "recorded_session.h"
#include "scratch_dir.h"
#include "recording.h"
#include "replay_export.h"
#include "replay_export_mcap.h"

#include "telegrasp/sim/hand_rig.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

namespace telegrasp::server {
namespace {

namespace fs = std::filesystem;

const fs::path& scratch() { return scratch_dir("telegrasp-replay-export-test"); }

// The recording's outputs and the server time of the first and last, counted here.
struct Outputs {
  std::uint64_t all = 0;
  double first_s = INFINITY, last_s = -INFINITY;
};
Outputs count_outputs(const Recording& rec) {
  Outputs o;
  for (const proto::Record& r : rec.records) {
    if (!r.has_output()) continue;
    ++o.all;
    double t = NAN;
    if (msg::HandSkeleton m; r.output().type() == proto::OUTPUT_HAND_SKELETON && from_cdr(r.output().cdr(), m))
      t = m.time();
    if (msg::SceneState m; r.output().type() == proto::OUTPUT_SCENE_STATE && from_cdr(r.output().cdr(), m))
      t = m.time();
    if (std::isfinite(t)) {
      o.first_s = std::min(o.first_s, t);
      o.last_s = std::max(o.last_s, t);
    }
  }
  return o;
}

class ReplayExportTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    session_ = new RecordedSession(record_session((scratch() / "session.tgrec").string()));
  }
  static void TearDownTestSuite() {
    delete session_;
    session_ = nullptr;
  }
  static const RecordedSession& session() { return *session_; }

 private:
  static RecordedSession* session_;
};
RecordedSession* ReplayExportTest::session_ = nullptr;

// One row per contact of every grasp event, numbers read back exactly.
TEST_F(ReplayExportTest, ContactsCsvHoldsEveryGraspContact) {
  const std::string csv = (scratch() / "contacts.csv").string();
  const ContactExport e = export_contacts_csv(session().path, csv);
  std::uint64_t grasps = 0, contacts = 0;
  for (const auto& ev : session().events) {
    if (ev.kind() != msg::GRASP_EVENT_GRASP) continue;
    ++grasps;
    contacts += ev.contacts().size();
  }
  EXPECT_EQ(e.events, grasps);
  EXPECT_EQ(e.rows, contacts);
  EXPECT_FALSE(e.damage);

  std::ifstream in(csv);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), contacts + 1);
  EXPECT_EQ(lines[0], kContactCsvHeader);

  // The last contact of the first grasp.
  ASSERT_FALSE(session().events.empty());
  const msg::GraspEvent& ev = session().events[0];
  const std::size_t c_index = ev.contacts().size() - 1;
  const msg::ContactPoint& c = ev.contacts()[c_index];
  std::vector<std::string> f;
  std::stringstream row(lines[1 + c_index]);
  for (std::string cell; std::getline(row, cell, ',');) f.push_back(cell);
  ASSERT_EQ(f.size(), 23u) << lines[1 + c_index];
  auto num = [](const std::string& s) { return std::strtod(s.c_str(), nullptr); };
  EXPECT_EQ(f[0], std::to_string(ev.event_id()));
  EXPECT_EQ(f[1], "alice");
  EXPECT_EQ(f[2], "right");
  EXPECT_EQ(f[3], std::to_string(ev.object_id()));
  EXPECT_EQ(f[4], "005_tomato_soup_can");
  EXPECT_EQ(f[5], std::to_string(ev.tick()));
  EXPECT_EQ(num(f[6]), ev.time());
  EXPECT_EQ(f[7], std::to_string(c.phalanx()));
  const sim::HandRig rig =  // the server's
      sim::HandRig::load(sim::HandRig::builtin_path(sim::HandRig::default_human(sim::HandSide::kRight)));
  ASSERT_LT(c.phalanx(), static_cast<int>(rig.phalanges().size()));
  EXPECT_EQ(f[8], c.phalanx() < 0 ? std::string("palm") : rig.phalanges()[c.phalanx()].name);
  const msg::Vec3* vecs[] = {&c.p_world(), &c.n_world(), &c.p_object(), &c.n_object()};
  for (int v = 0; v < 4; ++v) {
    EXPECT_EQ(num(f[9 + 3 * v]), vecs[v]->x()) << v;  // exact: shortest round-trip text
    EXPECT_EQ(num(f[10 + 3 * v]), vecs[v]->y()) << v;
    EXPECT_EQ(num(f[11 + 3 * v]), vecs[v]->z()) << v;
  }
  EXPECT_EQ(num(f[21]), c.nd());
  EXPECT_EQ(f[22], c.nd_hit() ? "1" : "0");
}

TEST_F(ReplayExportTest, ReadsEveryOutputAndSpansTheRecordingsTime) {
  const Recording rec = read_recording(session().path);
  const Outputs expected = count_outputs(rec);
  const std::string path = (scratch() / "all.mcap").string();
  const McapExport e = export_mcap(session().path, path);
  EXPECT_FALSE(e.damage);
  EXPECT_EQ(e.outputs, expected.all);
  // Log time: the recording's start plus the server time; the file ends with a keyframe at the
  // last output's time.
  const std::int64_t created = rec.header.created_unix_ns();
  EXPECT_EQ(e.start_time_ns, static_cast<std::uint64_t>(created + std::llround(expected.first_s * 1e9)));
  EXPECT_EQ(e.end_time_ns, static_cast<std::uint64_t>(created + std::llround(expected.last_s * 1e9)));
  EXPECT_EQ(e.bytes, fs::file_size(path));
  // At least one message per grasp event, and at most 5 per update plus the closing keyframe, as
  // the model sends at most /scene, /tf, a grasp state per hand, the events and the status.
  EXPECT_GE(e.messages, session().events.size());
  EXPECT_LE(e.messages, 5 * e.steps + session().events.size() + 2);
}

TEST_F(ReplayExportTest, TheRateSetsTheViewUpdatesPerSecondOfServerTime) {
  const Recording rec = read_recording(session().path);
  const Outputs o = count_outputs(rec);
  const double seconds = o.last_s - o.first_s;
  for (double rate : {10.0, 30.0, 90.0}) {
    SCOPED_TRACE("rate " + std::to_string(rate));
    const McapExport e =
        export_mcap(session().path, (scratch() / "rate.mcap").string(), {.rate_hz = rate, .schema_dir = ""});
    // One update per period of server time (ticks are 1/90 s, so at most 90 Hz), plus the last.
    const double per_second = std::min(rate, 90.0);
    EXPECT_GE(static_cast<double>(e.steps), std::floor(seconds * per_second * 0.99));
    EXPECT_LE(static_cast<double>(e.steps), std::ceil(seconds * per_second) + 2);
  }
}

TEST_F(ReplayExportTest, ADamagedRecordingIsExportedUpToTheDamage) {
  std::ifstream in(session().path, std::ios::binary);
  const std::string bytes(std::istreambuf_iterator<char>(in), {});
  const std::string cut = (scratch() / "cut.tgrec").string();
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  const Recording rec = read_recording(cut);
  ASSERT_TRUE(rec.damage);
  const McapExport e = export_mcap(cut, (scratch() / "cut.mcap").string());
  ASSERT_TRUE(e.damage);
  EXPECT_EQ(e.damage->record, rec.damage->record);
  EXPECT_TRUE(e.damage->truncated);
  EXPECT_EQ(e.outputs, count_outputs(rec).all);
  EXPECT_GT(e.messages, 0u);
}

TEST_F(ReplayExportTest, MissingSchemasFailNamingTheFile) {
  const std::string missing = (scratch() / "no-schemas").string();
  try {
    export_mcap(session().path, (scratch() / "x.mcap").string(), {.schema_dir = missing});
    FAIL() << "no error";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find(missing + "/foxglove.SceneUpdate.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("deploy/install-deps.sh"), std::string::npos) << e.what();
  }
}

TEST_F(ReplayExportTest, AnUnwritableFileFailsNamingIt) {
  const std::string path = (scratch() / "no-such-dir" / "x.mcap").string();
  try {
    export_mcap(session().path, path);
    FAIL() << "no error";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace telegrasp::server
