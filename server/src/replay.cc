#include "replay.h"

#include "telegrasp/idl/cli.h"
#include "recorded_feed.h"
#include "scene_server.h"
#include "server_loop.h"
#include "snapshot.h"
#include "server_config.pb.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/standin_objects.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace telegrasp::server {
namespace {

std::string join(const std::vector<std::string>& parts, const char* sep) {
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : sep) + p;
  return out;
}

// A rig from its embedded text, never from the file it names: that file may have changed since.
std::shared_ptr<const sim::HandRig> recorded_rig(const proto::RigText& r, const std::string& origin, const char* field,
                                                 std::string& path, std::string& text) {
  if (r.text().empty()) throw RecordingError(origin + ": header." + field + " holds no rig text");
  path = r.path();
  text = r.text();
  try {
    return std::make_shared<const sim::HandRig>(
        sim::HandRig::parse(r.text(), origin + ": header." + field + " (" + r.path() + ")"));
  } catch (const sim::RigError& e) {
    throw RecordingError(e.what());
  }
}

// Loads the recorded mesh files from `dir` into `a`. Every file is checked against its recorded
// size and hash before any is loaded, so one message names all that are missing or changed.
void load_recorded_meshes(const proto::ModelSource& ms, const std::string& dir, const std::string& origin,
                          SceneAssets& a) {
  namespace fs = std::filesystem;
  a.model_source.objects_dir = dir;
  std::vector<std::string> problems, paths;
  for (const proto::MeshFile& f : ms.files()) {
    const std::string path = (fs::path(dir) / f.name()).string();
    MeshFileInfo info;
    try {
      info = describe_file(path);
    } catch (const std::runtime_error&) {
      problems.push_back(path + " is missing");
      continue;
    }
    if (info.size != f.size() || info.fnv1a64 != f.fnv1a64()) {
      problems.push_back(path + " changed (" + std::to_string(info.size) + " bytes, FNV-1a " +
                         cli::format_hex64(info.fnv1a64) + "; recorded " + std::to_string(f.size()) + " bytes, " +
                         cli::format_hex64(f.fnv1a64()) + ")");
      continue;
    }
    a.model_source.files.push_back(info);
    paths.push_back(path);
  }
  if (!problems.empty())
    throw RecordingError(origin + ": the meshes it was recorded with are not in " + dir + ": " + join(problems, "; "));
  for (const std::string& path : paths) {
    try {
      a.models.push_back(sim::load_protocol_object_model(path));
    } catch (const sim::MeshLoadError& e) {
      throw RecordingError(origin + ": " + e.what());
    }
  }
}

// The stand-ins a fill_standins server added after its meshes.
void add_recorded_standins(const proto::ModelSource& ms, const std::string& origin, SceneAssets& a) {
  for (const std::string& name : ms.standin_names()) {
    const auto& all = sim::protocol_objects();
    auto it = std::find_if(all.begin(), all.end(), [&](const sim::ProtocolObject& o) { return o.name == name; });
    if (it == all.end())
      throw RecordingError(origin + ": header.models.standin_names: '" + name + "' is not a protocol object");
    a.models.push_back(sim::make_standin_model(*it));
    a.model_source.standins.push_back(name);
  }
}

// The scene's object ids and default layout follow the model order: it must be the recorded one.
void check_model_order(const proto::ModelSource& ms, const SceneAssets& a, const std::string& origin) {
  const auto& names = ms.model_names();
  for (std::size_t i = 0; i < std::max<std::size_t>(a.models.size(), names.size()); ++i) {
    const std::string rebuilt = i < a.models.size() ? "'" + a.models[i]->name + "'" : "none";
    const std::string recorded =
        i < static_cast<std::size_t>(names.size()) ? "'" + names[static_cast<int>(i)] + "'" : "none";
    if (rebuilt != recorded)
      throw RecordingError(origin + ": header.models.model_names[" + std::to_string(i) + "] is " + recorded +
                           ", the rebuilt model is " + rebuilt);
  }
}

// Warnings for a recording made by another build.
std::vector<std::string> version_warnings(const proto::RecordingHeader& header) {
  std::vector<std::string> w;
  if (header.idl_sha256() != idl_sha256())
    w.push_back("recorded with another idl/telegrasp.idl (SHA-256 " + header.idl_sha256() + ", this build's is " +
                idl_sha256() + "): messages may not decode or compare");
  if (header.telegrasp_version() != telegrasp_version())
    w.push_back("recorded by telegrasp " + header.telegrasp_version() + ", replayed by " + telegrasp_version() +
                ": the simulation may differ");
  return w;
}

ServerSettings recorded_settings(const proto::RecordingHeader& header, const std::string& path) {
  try {
    ServerSettings s = settings_from_proto(header.config(), "recording " + path + ": header.config");
    // Recordings from before the quality worker computed it within the tick, with the volume.
    if (!header.config().has_quality_delay_ticks()) s.quality_delay_ticks = 0, s.quality_volume = true;
    return s;
  } catch (const std::runtime_error& e) {
    throw RecordingError(e.what());
  }
}

}  // namespace

SceneAssets load_recorded_assets(const proto::RecordingHeader& header, const std::string& recording_path,
                                 const std::string& objects_dir) {
  const std::string origin = "recording " + recording_path;
  SceneAssets a;
  a.right_rig = recorded_rig(header.right_rig(), origin, "right_rig", a.right_rig_path, a.right_rig_text);
  a.left_rig = recorded_rig(header.left_rig(), origin, "left_rig", a.left_rig_path, a.left_rig_text);
  const proto::ModelSource& ms = header.models();
  if (ms.builtin_standins()) {
    for (const auto& o : sim::protocol_objects()) a.models.push_back(sim::make_standin_model(o));
  } else {
    load_recorded_meshes(ms, objects_dir.empty() ? ms.objects_dir() : objects_dir, origin, a);
    add_recorded_standins(ms, origin, a);
  }
  check_model_order(ms, a, origin);
  return a;
}

std::string ReplayResult::summary() const {
  std::string s;
  if (divergence) {
    s = "divergence: " + divergence->message + "\n";
  } else {
    s = "identical: " + std::to_string(outputs_compared) + " outputs over " + std::to_string(ticks) + " ticks (" +
        std::to_string(records) + " records; " + std::to_string(statuses_skipped) + " ServerStatus not compared)\n";
  }
  if (damage) s += damage->message + (divergence ? "\n" : "; replayed up to it\n");
  for (const auto& w : warnings) s += "warning: " + w + "\n";
  return s;
}

int ReplayResult::exit_code() const {
  if (divergence) return cli::kExitDiverged;
  if (damage) return cli::kExitDamaged;
  return 0;
}

ReplayResult replay_recording(const std::string& path, const ReplayOptions& options) {
  RecordingReader reader(path);
  ReplayResult result;
  result.warnings = version_warnings(reader.header());
  ServerSettings settings = recorded_settings(reader.header(), path);
  const SceneAssets assets = load_recorded_assets(reader.header(), path, options.objects_dir);
  // The run's own incarnation and restored objects: its SceneStates compare byte for byte.
  settings.incarnation = reader.header().incarnation();
  if (reader.header().has_restored_scene()) {
    try {
      settings.restored_objects = placed_objects(reader.header().restored_scene(), assets.models,
                                                 "recording " + path + ": header.restored_scene");
    } catch (const SnapshotError& e) {
      throw RecordingError(e.what());
    }
  }
  // A fresh mailbox: the scene only asks it to forget removed hands and for the status counts.
  InputMailbox mailbox({assets.left_rig->fingers().size(), assets.right_rig->fingers().size()}, settings.max_hands,
                       [](const std::string&) {});
  OutputCapture capture;
  std::unique_ptr<SceneServer> scene;
  try {
    scene = std::make_unique<SceneServer>(settings, assets.models, assets.right_rig, assets.left_rig, mailbox, capture);
  } catch (const std::runtime_error& e) {
    throw RecordingError("recording " + path + ": the scene cannot be rebuilt from the header: " + e.what());
  }

  // The server's loop, ticking where the recording ticked, fed and checked by the recording.
  RecordedFeed feed(reader, capture, options.progress);
  LoopSettings loop = loop_settings(settings);
  loop.schedule = TickSchedule::kSource;
  ServerLoop(loop, *scene, feed, feed, capture, &feed).run();
  feed.finish();

  result.divergence = feed.divergence();
  result.ticks = feed.ticks();
  result.outputs_compared = feed.outputs_compared();
  result.statuses_skipped = feed.statuses_skipped();
  // The feed reads a loop iteration ahead; the records up to a divergence are those reported as
  // read, and damage beyond it was not reached.
  result.records = result.divergence ? std::min(result.divergence->record + 1, reader.records()) : reader.records();
  if (!result.divergence) result.damage = reader.damage();
  if (options.progress) options.progress(reader);
  return result;
}

}  // namespace telegrasp::server
