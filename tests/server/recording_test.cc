// Tests server/src/recording and server/src/replay: a SceneServer run recorded through the
// Recorder (no DDS) replays with zero divergence; an altered input diverges where it should;
// truncated and corrupted files keep exactly the records before the damage; the header carries
// the settings; fill_standins completes a mesh folder.
#include "telegrasp/idl/cli.h"
#include "recorded_session.h"
#include "scratch_dir.h"
#include "recording.h"
#include "replay.h"
#include "scene_setup.h"
#include "server_config.pb.h"

#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/standin_objects.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace telegrasp::server {
namespace {

namespace fs = std::filesystem;

const fs::path& scratch() { return scratch_dir("telegrasp-recording-test"); }

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
  ASSERT_TRUE(out.good()) << path;
}

// One recorded session per test process, shared by the tests that only read it.
class RecordingTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    session_ = new RecordedSession(record_session((scratch() / "session.tgrec").string()));
    ASSERT_FALSE(session_->events.empty());
    ASSERT_EQ(session_->events[0].kind(), msg::GRASP_EVENT_GRASP);
    ASSERT_FALSE(session_->events[0].contacts().empty());
  }
  static void TearDownTestSuite() {
    delete session_;
    session_ = nullptr;
  }
  const RecordedSession& session() const { return *session_; }
  // Byte offsets at which each record's frame starts (the last entry: the End record's).
  static std::vector<std::uint64_t> frame_starts(const std::string& path) {
    RecordingReader reader(path);
    std::vector<std::uint64_t> starts{reader.offset()};
    proto::Record r;
    while (reader.next(r)) starts.push_back(reader.offset());
    EXPECT_TRUE(reader.complete());
    return starts;
  }

 private:
  static RecordedSession* session_;
};
RecordedSession* RecordingTest::session_ = nullptr;

std::uint64_t count_ticks(const std::vector<proto::Record>& records, std::size_t before) {
  std::uint64_t n = 0;
  for (std::size_t i = 0; i < before && i < records.size(); ++i) n += records[i].has_tick();
  return n;
}

TEST_F(RecordingTest, RecordThenReplayGivesZeroDivergence) {
  const Recording rec = read_recording(session().path);
  EXPECT_TRUE(rec.complete);
  EXPECT_FALSE(rec.damage);
  EXPECT_EQ(rec.header.format_version(), kRecordingFormatVersion);
  EXPECT_EQ(rec.header.idl_sha256(), idl_sha256());
  std::uint64_t outputs = 0, statuses = 0, events = 0, removals = 0;
  for (const auto& r : rec.records) {
    if (!r.has_output()) continue;
    if (r.output().type() == proto::OUTPUT_SERVER_STATUS)
      ++statuses;
    else
      ++outputs;
    events += r.output().type() == proto::OUTPUT_GRASP_EVENT;
    removals += r.output().type() == proto::OUTPUT_HAND_REMOVED;
  }
  EXPECT_EQ(events, session().events.size());
  EXPECT_EQ(removals, 1u);

  const ReplayResult result = replay_recording(session().path);
  EXPECT_FALSE(result.divergence) << result.summary();
  EXPECT_FALSE(result.damage);
  EXPECT_EQ(result.records, rec.records.size());
  EXPECT_EQ(result.outputs_compared, outputs);  // every output but the status, grasp and release included
  EXPECT_EQ(result.statuses_skipped, statuses);
  EXPECT_EQ(statuses, 1u);
  EXPECT_EQ(result.ticks, count_ticks(rec.records, rec.records.size()));
  EXPECT_EQ(result.exit_code(), 0);
  EXPECT_EQ(result.summary().rfind("identical: " + std::to_string(outputs) + " outputs", 0), 0u) << result.summary();
}

// The palm of one sample moved by 1 cm: the first output built from it, the late-latched
// skeleton right after the inputs record, is the first divergence, at its palm's x.
TEST_F(RecordingTest, AnAlteredInputDivergesAtItsFirstOutput) {
  Recording rec = read_recording(session().path);
  std::size_t k = 0, inputs_seen = 0;
  for (; k < rec.records.size(); ++k)
    if (rec.records[k].has_inputs() && ++inputs_seen == 20) break;
  ASSERT_LT(k + 1, rec.records.size());
  ASSERT_TRUE(rec.records[k + 1].has_output());
  ASSERT_EQ(rec.records[k + 1].output().type(), proto::OUTPUT_HAND_SKELETON);
  proto::InputSample* sample = rec.records[k].mutable_inputs()->mutable_samples(0);
  msg::ControllerState state;
  ASSERT_TRUE(from_cdr(sample->controller_state_cdr(), state));
  state.palm().position().x(state.palm().position().x() + 0.01);
  sample->set_controller_state_cdr(to_cdr(state));
  const std::string altered = (scratch() / "altered.tgrec").string();
  write_recording(altered, rec.header, rec.records);

  const ReplayResult result = replay_recording(altered);
  ASSERT_TRUE(result.divergence);
  EXPECT_EQ(result.divergence->record, k + 1);
  EXPECT_EQ(result.divergence->tick, count_ticks(rec.records, k));
  EXPECT_EQ(result.divergence->type, "HandSkeleton");
  EXPECT_EQ(result.divergence->key, "client 'alice' right hand");
  EXPECT_EQ(result.divergence->field, "palm.position.x");
  EXPECT_NE(result.divergence->message.find("record " + std::to_string(k + 1)), std::string::npos)
      << result.divergence->message;
  EXPECT_EQ(result.exit_code(), cli::kExitDiverged);
}

// Cut at a frame boundary, inside a length, inside a payload, inside the End record: the reader
// keeps exactly the records before the cut and names the file, record and byte; replay replays
// them all and reports the damage.
TEST_F(RecordingTest, ATruncatedRecordingIsReadUpToTheCut) {
  const std::string original = read_bytes(session().path);
  const Recording rec = read_recording(session().path);
  const std::vector<std::uint64_t> starts = frame_starts(session().path);
  const std::size_t n = rec.records.size();
  ASSERT_EQ(starts.size(), n + 1);
  ASSERT_GT(n, 100u);
  struct Cut {
    std::uint64_t bytes;
    std::size_t kept;
  };
  const std::size_t mid = n / 2;
  const std::vector<Cut> cuts = {
      {starts[0], 0},  // right after the header
      {starts[7] + 1, 7},  // inside record 7's frame
      {starts[mid], mid},  // at a frame boundary: no End record
      {starts[mid] + (starts[mid + 1] - starts[mid]) / 2, mid},
      {starts[n - 1] + 2, n - 1},  // inside the last record
      {original.size() - 1, n},  // inside the End record's checksum
  };
  const std::string cut_path = (scratch() / "cut.tgrec").string();
  for (const Cut& cut : cuts) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut.bytes));
    write_bytes(cut_path, original.substr(0, cut.bytes));
    const Recording r = read_recording(cut_path);
    ASSERT_EQ(r.records.size(), cut.kept);
    for (std::size_t i = 0; i < cut.kept; ++i)
      ASSERT_EQ(r.records[i].SerializeAsString(), rec.records[i].SerializeAsString()) << i;
    EXPECT_FALSE(r.complete);
    ASSERT_TRUE(r.damage);
    EXPECT_TRUE(r.damage->truncated);
    EXPECT_EQ(r.damage->record, cut.kept);
    EXPECT_EQ(r.damage->byte, starts[cut.kept]);
    EXPECT_NE(r.damage->message.find("recording " + cut_path + ": record " + std::to_string(cut.kept) + " at byte " +
                                     std::to_string(starts[cut.kept]) + " is truncated"),
              std::string::npos)
        << r.damage->message;
    EXPECT_NE(r.damage->message.find("the " + std::to_string(cut.kept) + " records before it are kept"),
              std::string::npos)
        << r.damage->message;
  }

  // Replay of the file cut mid-way: identical up to the cut, exit code 3.
  write_bytes(cut_path, original.substr(0, starts[mid] + 3));
  const ReplayResult result = replay_recording(cut_path);
  EXPECT_FALSE(result.divergence) << result.summary();
  ASSERT_TRUE(result.damage);
  EXPECT_EQ(result.records, mid);
  EXPECT_EQ(result.ticks, count_ticks(rec.records, mid));
  EXPECT_EQ(result.exit_code(), cli::kExitDamaged);

  // Inside the header nothing can be kept: an error naming the file.
  write_bytes(cut_path, original.substr(0, kRecordingMagicSize + 10));
  try {
    RecordingReader reader(cut_path);
    ADD_FAILURE() << "a recording cut inside its header was read";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("recording " + cut_path + ": header at byte " +
                                         std::to_string(kRecordingMagicSize) + " is truncated"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(RecordingTest, AFlippedByteIsReportedAsCorruptWithTheRecordsBeforeKept) {
  std::string bytes = read_bytes(session().path);
  const Recording rec = read_recording(session().path);
  const std::vector<std::uint64_t> starts = frame_starts(session().path);
  const std::size_t k = rec.records.size() / 3;
  const std::uint64_t at = starts[k] + (starts[k + 1] - starts[k]) / 2;  // past the length, inside the frame
  bytes[at] = static_cast<char>(bytes[at] ^ 0x10);
  const std::string path = (scratch() / "flipped.tgrec").string();
  write_bytes(path, bytes);

  const Recording r = read_recording(path);
  ASSERT_EQ(r.records.size(), k);
  for (std::size_t i = 0; i < k; ++i)
    ASSERT_EQ(r.records[i].SerializeAsString(), rec.records[i].SerializeAsString()) << i;
  ASSERT_TRUE(r.damage);
  EXPECT_FALSE(r.damage->truncated);
  EXPECT_EQ(r.damage->record, k);
  EXPECT_EQ(r.damage->byte, starts[k]);
  EXPECT_NE(r.damage->message.find("recording " + path + ": record " + std::to_string(k) + " at byte " +
                                   std::to_string(starts[k]) + " is corrupt (checksum mismatch)"),
            std::string::npos)
      << r.damage->message;

  const ReplayResult result = replay_recording(path);
  EXPECT_FALSE(result.divergence) << result.summary();
  EXPECT_EQ(result.records, k);
  EXPECT_EQ(result.exit_code(), cli::kExitDamaged);
}

// Every setting goes into the header and comes back, lockstep and fill_standins included.
TEST(RecordingHeaderTest, SettingsRoundTrip) {
  ServerSettings s;
  s.domain = 7;
  s.profile = "lan";
  s.profiles_file = "/etc/telegrasp/profiles.xml";
  s.tick_hz = 120;
  s.objects_dir = "/data/ycb";
  s.fill_standins = true;
  s.objects = {{"005_tomato_soup_can", 0.4, -0.1, 0.3}};
  s.right_rig = "/rigs/r.textproto";
  s.left_rig = "/rigs/l.textproto";
  s.closing_mode = sim::ClosingMode::kDiscrete;
  s.freeze_after_s = 0.2;
  s.remove_after_s = 0.6;
  s.late_latch = false;
  s.status_period_s = 2;
  s.max_hands = 12;
  s.lockstep = true;
  s.record_path = "/tmp/run.tgrec";
  SceneAssets assets;  // the header's settings need no models or rigs
  const std::string path = (scratch() / "header.tgrec").string();
  write_recording(path, make_recording_header(s, assets), {});

  const Recording rec = read_recording(path);
  EXPECT_TRUE(rec.complete);
  EXPECT_TRUE(rec.records.empty());
  const ServerSettings r = settings_from_proto(rec.header.config(), "test");
  EXPECT_TRUE(r.lockstep);
  EXPECT_TRUE(r.fill_standins);
  EXPECT_EQ(r.closing_mode, sim::ClosingMode::kDiscrete);
  EXPECT_FALSE(r.late_latch);
  ASSERT_EQ(r.objects.size(), 1u);
  EXPECT_EQ(r.objects[0].yaw, 0.3);
  EXPECT_EQ(to_proto(r).SerializeAsString(), to_proto(s).SerializeAsString());  // every other field too
  // Defaults survive as well (to_proto sets every field, false and 0 included).
  const ServerSettings d = settings_from_proto(to_proto(ServerSettings{}), "test");
  EXPECT_FALSE(d.lockstep);
  EXPECT_FALSE(d.fill_standins);
  EXPECT_EQ(to_proto(d).SerializeAsString(), to_proto(ServerSettings{}).SerializeAsString());
}

// A closed, outward-facing box of the given extent, as OBJ text.
std::string box_obj(double x, double y, double z) {
  std::ostringstream o;
  for (int i = 0; i < 8; ++i) {
    const int corner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                              {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    o << "v " << corner[i][0] * x / 2 << " " << corner[i][1] * y / 2 << " " << corner[i][2] * z / 2 << "\n";
  }
  o << "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";
  return o.str();
}

// With no rig named, the server's hands are the opposable ones with grasp types; a server
// configured with the flat-thumb rigs (the default before) gets them, and a recording made with
// them replays with them, whatever the default is now: the header holds the rig's text.
TEST(SceneAssetsTest, TheDefaultHandsOpposeTheirThumbAndARecordingKeepsItsOwn) {
  const SceneAssets a = load_scene_assets(ServerSettings{});
  EXPECT_EQ(a.right_rig->name(), "human_right_opposable");
  EXPECT_EQ(a.left_rig->name(), "human_left_opposable");
  EXPECT_TRUE(a.right_rig->has_grasp_types());
  EXPECT_TRUE(a.left_rig->has_grasp_types());

  ServerSettings flat;
  flat.right_rig = sim::HandRig::builtin_path("human_right");
  flat.left_rig = sim::HandRig::builtin_path("human_left");
  const SceneAssets b = load_scene_assets(flat);
  EXPECT_EQ(b.right_rig->name(), "human_right");
  EXPECT_FALSE(b.right_rig->has_grasp_types());
  const SceneAssets replayed = load_recorded_assets(make_recording_header(flat, b), "old.tgrec");
  EXPECT_EQ(replayed.right_rig->name(), "human_right");
  EXPECT_EQ(replayed.left_rig->name(), "human_left");
  EXPECT_EQ(replayed.right_rig_text, b.right_rig_text);
}

// A folder with one protocol object's mesh, with fill_standins: that mesh, then the 29 other
// stand-ins in protocol order; a recording of it rebuilds the same list and names a changed mesh.
TEST(SceneAssetsTest, FillStandinsAddsTheProtocolObjectsTheFolderLacks) {
  const fs::path dir = scratch() / "meshes";
  fs::create_directories(dir);
  const std::string mesh = (dir / "003_cracker_box.obj").string();
  write_bytes(mesh, box_obj(0.072, 0.164, 0.213));

  ServerSettings s;
  s.objects_dir = dir.string();
  EXPECT_EQ(load_scene_assets(s).models.size(), 1u);  // off by default
  s.fill_standins = true;
  const SceneAssets a = load_scene_assets(s);
  ASSERT_EQ(a.models.size(), 30u);
  EXPECT_EQ(a.models[0]->name, "003_cracker_box");
  EXPECT_EQ(a.models[0]->source, mesh);
  ASSERT_EQ(a.model_source.files.size(), 1u);
  EXPECT_EQ(a.model_source.files[0].name, "003_cracker_box.obj");
  ASSERT_EQ(a.model_source.standins.size(), 29u);
  std::size_t next = 1;
  for (const auto& o : sim::protocol_objects()) {
    if (o.name == "003_cracker_box") continue;
    ASSERT_EQ(a.models[next]->name, o.name);
    EXPECT_EQ(a.models[next]->source, "built-in stand-in");
    EXPECT_EQ(a.model_source.standins[next - 1], o.name);
    ++next;
  }

  const proto::RecordingHeader header = make_recording_header(s, a);
  EXPECT_FALSE(header.models().builtin_standins());
  EXPECT_EQ(header.models().standin_names_size(), 29);
  const SceneAssets b = load_recorded_assets(header, "test.tgrec");
  ASSERT_EQ(b.models.size(), a.models.size());
  for (std::size_t i = 0; i < a.models.size(); ++i) EXPECT_EQ(b.models[i]->name, a.models[i]->name) << i;
  EXPECT_EQ(b.right_rig_text, a.right_rig_text);

  // A changed mesh file is refused, by name.
  write_bytes(mesh, box_obj(0.072, 0.164, 0.214));
  try {
    load_recorded_assets(header, "test.tgrec");
    ADD_FAILURE() << "a changed mesh was accepted";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("recording test.tgrec: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(mesh + " changed"), std::string::npos) << e.what();
  }
  fs::remove(mesh);
  try {
    load_recorded_assets(header, "test.tgrec");
    ADD_FAILURE() << "a missing mesh was accepted";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find(mesh + " is missing"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace telegrasp::server
