// telegrasp-eval participant: one bot participant of a protocol run, in its own process (one DDS
// participant per process). It drives the right hand of a lockstep server: spawns each protocol
// object in turn with a SceneCommand, lets the scripted operator grasp, lift, hold and release
// it, removes it, and records each grasp from the server's GraspEvent. Every decision is a
// function of the SceneState sequence alone, so with a lockstep server a run is deterministic.
// Progress: one line per grasp on stdout ("grasp I/N OBJECT held|not-held"), read by the runner.
// Each record also keeps the hand at the grasp tick (the server's HandSkeleton of that tick, in the
// object's frame), so the report can draw the grasp.
#include "client_options.h"
#include "telegrasp/idl/cli.h"
#include "commands.h"
#include "eval_inputs.h"
#include "grasp_event_record.h"
#include "grasp_report.h"
#include "protocol_common.h"
#include "telegrasp/client/client.h"
#include "telegrasp/idl/network_flags.h"
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/hand_rig.h"
#include "skill_flag.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace telegrasp::eval {
namespace {

namespace client = telegrasp::client;
namespace cli = telegrasp::cli;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage = R"(Usage: telegrasp-eval participant [options]

One bot participant of `telegrasp-eval protocol`, which starts it (with a server in
lockstep) in its own process; run by hand only to debug a protocol run.

Options:
  --domain N        DDS domain of the server (default 0)
  --profile NAME    Fast DDS participant profile (default loopback)
  --profiles FILE   Fast DDS XML profiles (default: the shipped file)
  --scene NAME      the scene (room) to join (default $TELEGRASP_SCENE, else default)
  --discovery-server HOST[:PORT]
                    a Fast DDS discovery server; repeat in id order (telegrasp-server --help)
  --group NAME      experienced | inexperienced (default experienced)
  --skills FILE     skill profiles overriding the built-in ones (see telegrasp-eval protocol --help)
  --rig FILE        the server's right-hand rig, for planning (default: built-in human_right_opposable)
  --participant P   participant number, 1-based (default 1)
  --seed S          the run's seed (default 1)
  --mode M          the server's closing mode, written into the records (default precise)
  --objects DIR     the server's mesh folder (missing protocol objects: built-in stand-ins)
  --count N         grasp only the first N protocol objects (default 30)
  --json FILE       write the grasp records (JSON array) here (default: stdout at the end)
  --timeout-s S     give up when the server sends nothing for S seconds (default 20)
  -h, --help        this text

Exit status: 0 every object done, 1 a runtime failure (the --objects folder or a mesh missing or
unreadable, no server found or it went silent, the server lacks a protocol object, the --json
file not writable), 2 a usage error (a bad or missing option or value).
)";

constexpr double kTrialLimit = 30.0;  // s of simulated time before a grasp is cut short
constexpr double kAppearLimit = 2.0;  // s of simulated time for a spawned object to appear
constexpr double kEventWait = 2.0;  // s of wall time to wait for the GraspEvent of a grasp seen in SceneState
constexpr double kDt = 1.0 / 90.0;  // the operator's step; the server's tick is the same by default

struct Options {
  int domain = 0, participant = 1, count = 30;
  std::string scene;  // "": $TELEGRASP_SCENE, else default
  std::vector<std::string> discovery_servers;
  std::string profile = "loopback", profiles_file, group = "experienced", mode = "precise", objects_dir, json_path,
              skills_path, rig_path;
  std::vector<sim::OperatorSkill> skills;  // from --skills
  std::uint64_t seed = 1;
  double timeout_s = 20;
};

constexpr const char* kTool = "telegrasp-eval participant";

[[noreturn]] void usage_error(const std::string& what) { cli::usage_exit(kTool, what); }

Options parse(int argc, char** argv) {
  Options o;
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (telegrasp::idl::parse_network_flag(a, value, o, usage_error))
      ;
    else if (a == "--group")
      o.group = tools::parse_skill(a, value(), usage_error);
    else if (a == "--participant")
      o.participant = static_cast<int>(cli::parse_whole(a, value(), 1, 100'000, usage_error));
    else if (a == "--seed")
      o.seed = static_cast<std::uint64_t>(cli::parse_whole(a, value(), 0, 1L << 50, usage_error));
    else if (a == "--mode") {
      o.mode = value();
      if (!sim::parse_closing_mode(o.mode)) usage_error("--mode expects precise or discrete, got '" + o.mode + "'");
    } else if (cli::text_flag(a, value,
                              {{"--objects", &o.objects_dir},
                               {"--json", &o.json_path},
                               {"--skills", &o.skills_path},
                               {"--rig", &o.rig_path}}))
      ;
    else if (a == "--count")
      o.count = static_cast<int>(cli::parse_whole(a, value(), 1, 30, usage_error));
    else if (cli::is_flag(kTool, a, "--timeout-s", "--timeout"))
      o.timeout_s = cli::parse_number(a, value(), 0.1, 86400, usage_error);
    else
      return false;
    return true;
  });
  return o;
}

enum class Stage { kAppear, kRun, kRelease, kDone };

class Participant {
 public:
  Participant(const Options& opt, client::Client& c, std::map<std::string, sim::ObjectModelPtr> models)
      : opt_(opt),
        client_(c),
        models_(std::move(models)),
        rig_(std::make_shared<const sim::HandRig>(sim::HandRig::load(rig_path_or_default(opt.rig_path)))),
        skill_(participant_skill(opt.group, opt.seed, opt.participant, &opt.skills)) {
    const auto& order = paper_object_order();
    objects_.assign(order.begin(),
                    order.begin() + std::min<std::size_t>(order.size(), static_cast<std::size_t>(opt.count)));
    input_.X_WorldPalm = home_palm_pose();
  }

  bool done() const { return index_ >= objects_.size(); }

  // Sends the hand's current input as the answer to `tick`.
  void publish(std::uint64_t tick) {
    client::ControllerSample s;
    s.side = client::HandSide::kRight;
    s.X_WorldPalm = input_.X_WorldPalm;
    s.trigger = input_.trigger;
    if (input_.curls.size() == 5) s.curls = input_.curls;
    s.tracking_valid = input_.tracking_valid;
    s.lockstep_tick = tick;
    client_.publish(s);
  }

  const std::vector<report::Record>& records() const { return records_; }

  // The first sample, answering nothing yet: it joins the hand and, after the first spawn
  // command, lets the waiting lockstep server take its first tick.
  void start() {
    send_spawn(0);
    publish(0);
  }

  // Answers the SceneState of one tick with the hand's input for the next.
  void answer(const client::SceneState& scene) {
    const client::ObjectState* o = nullptr;
    for (const auto& s : scene.objects)
      if (s.id == object_id_ || (object_id_ < 0 && s.name == objects_[index_])) o = &s;
    const bool holding = o && o->held && o->holder.client_id == client_.client_id();
    if (holding && !rec_.grasped) wait_for_grasp_event();
    switch (stage_) {
      case Stage::kDone:
        break;
      case Stage::kAppear:
        if (o) {
          begin_trial(*o, scene);
        } else if (static_cast<double>(scene.tick - spawn_tick_) * kDt > kAppearLimit) {
          rec_ = {};
          rec_.object = objects_[index_];
          note_ = "did not appear within " + report::fmt(kAppearLimit, 0) +
                  " s of its spawn command (see the server's log)";
          finish(scene.tick);
        }
        break;
      case Stage::kRun: {
        if (!o) {
          note_ = "removed from the scene during the grasp";
          finish(scene.tick);
          break;
        }
        const double t = static_cast<double>(scene.tick - start_tick_) * kDt;
        for (const client::HandSkeleton& s : client_.latest_hand_skeletons())
          if (s.hand.client_id == client_.client_id() && s.hand.side == client::HandSide::kRight)
            op_->see_hand_raised(s.resolve_offset.z());
        input_ = op_->next(t, holding);
        if (op_->phase() == sim::OperatorPhase::kHold) {
          z_max_ = std::max(z_max_, o->X_WorldObject.translation().z());
          if (holding)
            if (auto q = tools::hold_quality(
                    client_.latest_grasp_state({client_.client_id(), client::HandSide::kRight}), object_id_))
              hold_quality_ = q;
        }
        if (op_->done() || t > kTrialLimit) {
          if (!op_->done()) note_ = "cut short after " + report::fmt(kTrialLimit, 0) + " s";
          input_.trigger = 0;
          input_.curls.clear();
          stage_ = Stage::kRelease;
        }
        break;
      }
      case Stage::kRelease:
        if (!holding) finish(scene.tick);
        break;
    }
    publish(scene.tick);
  }

 private:
  void send_spawn(std::uint64_t tick) {
    spawn_tick_ = tick;
    const Placement p = object_placement(opt_.seed, opt_.participant, static_cast<int>(index_));
    client::SceneCommand c;
    c.kind = client::SceneCommand::Kind::kSpawn;
    c.model = objects_[index_];
    c.on_table = true;
    c.x = p.x;
    c.y = p.y;
    c.yaw = p.yaw;
    client_.send_command(c);
    object_id_ = -1;
    stage_ = Stage::kAppear;
  }

  void begin_trial(const client::ObjectState& o, const client::SceneState& scene) {
    object_id_ = o.id;
    rec_ = {};
    rec_.object = o.name;
    note_.clear();
    z0_ = o.X_WorldObject.translation().z();
    z_max_ = -1e9;
    hold_quality_.reset();
    start_tick_ = scene.tick;
    op_ = std::make_unique<sim::ScriptedOperator>(
        rig_, skill_, grasp_seed(opt_.seed, opt_.participant, static_cast<int>(index_)), sim::GraspSettings{}, kDt);
    // Planning takes a while; the lockstep server waits for this answer, so simulated time does not run.
    op_->begin(*models_.at(o.name), o.X_WorldObject, home_palm_pose(), 0.0, static_cast<int>(index_));
    input_ = op_->next(0.0, false);
    stage_ = Stage::kRun;
  }

  // SceneState showed the grasp; its GraspEvent (reliable, another topic) may still be on its way.
  void wait_for_grasp_event() {
    const auto deadline = Clock::now() + std::chrono::duration<double>(kEventWait);
    while (true) {
      for (const client::GraspEvent& e : client_.take_grasp_events())
        if (e.kind == client::GraspEvent::Kind::kGrasp && e.hand.client_id == client_.client_id() &&
            e.object_id == object_id_ && !rec_.grasped)
          take_grasp_event(e);
      if (rec_.grasped || Clock::now() > deadline) return;
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
  }

  // The trial starts when the object appears: the hand waits at home, free to reach.
  void take_grasp_event(const client::GraspEvent& e) {
    tools::record_grasp_event(e, e.object_spawn_time, *rig_, rec_);
    record_grasp_tick_hand(e);
  }

  // The hand of the grasp tick, from that tick's HandSkeleton (published before the tick's
  // SceneState; a lockstep server does not tick again before this participant answers). Best
  // effort: a skeleton lost on the way leaves the record without the hand.
  void record_grasp_tick_hand(const client::GraspEvent& e) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(kEventWait);
    while (true) {
      for (const client::HandSkeleton& s : client_.latest_hand_skeletons()) {
        if (s.hand != e.hand || s.tick != e.tick || s.late_latched) continue;
        if (s.rig != rig_->name() || s.X_WorldPhalanx.size() != rig_->phalanges().size()) return;  // not our rig
        const Eigen::Isometry3d X_ObjectWorld = e.X_WorldObject.inverse();
        rec_.grasp_tick_X_WorldObject = e.X_WorldObject;
        rec_.grasp_tick_hand.push_back({"palm", X_ObjectWorld * s.X_WorldPalm});
        for (std::size_t i = 0; i < s.X_WorldPhalanx.size(); ++i)
          rec_.grasp_tick_hand.push_back({rig_->phalanges()[i].name, X_ObjectWorld * s.X_WorldPhalanx[i]});
        return;
      }
      if (Clock::now() > deadline) {
        std::cerr << "telegrasp-eval participant: no hand skeleton of grasp tick " << e.tick << " (" << rec_.object
                  << "): the record has no hand pose\n";
        return;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
  }

  void finish(std::uint64_t tick) {
    rec_.mode = opt_.mode;
    rec_.trial = static_cast<int>(index_);
    rec_.group = opt_.group;
    rec_.participant = opt_.participant;
    rec_.attempts = op_ ? op_->attempts() : 0;
    rec_.held_after_lift = op_ && op_->held_after_lift() && z_max_ - z0_ > 0.8 * sim::ScriptedOperator::kLiftHeight;
    report::set_hold_quality(rec_, hold_quality_);
    records_.push_back(rec_);
    std::printf("grasp %zu/%zu %s %s%s%s\n", index_ + 1, objects_.size(), rec_.object.c_str(),
                rec_.held_after_lift ? "held" : "not-held", note_.empty() ? "" : ": ", note_.c_str());
    std::fflush(stdout);
    if (object_id_ >= 0) {
      client::SceneCommand remove;
      remove.kind = client::SceneCommand::Kind::kRemove;
      remove.object_id = object_id_;
      client_.send_command(remove);
    }
    op_.reset();
    input_ = {};
    input_.X_WorldPalm = home_palm_pose();
    ++index_;
    if (!done())
      send_spawn(tick);
    else
      stage_ = Stage::kDone;
  }

  const Options& opt_;
  client::Client& client_;
  std::map<std::string, sim::ObjectModelPtr> models_;
  std::shared_ptr<const sim::HandRig> rig_;
  sim::OperatorSkill skill_;
  std::vector<std::string> objects_;
  std::size_t index_ = 0;
  Stage stage_ = Stage::kAppear;
  int object_id_ = -1;
  std::uint64_t start_tick_ = 0, spawn_tick_ = 0;
  double z0_ = 0, z_max_ = -1e9;
  std::optional<sim::GraspQuality> hold_quality_;  // the settled hold's (report::set_hold_quality)
  std::unique_ptr<sim::ScriptedOperator> op_;
  sim::ControllerInput input_;
  report::Record rec_;
  std::string note_;
  std::vector<report::Record> records_;
};

// Every protocol object must be a model of the server, else the run would wait for nothing.
bool server_has_the_objects(const client::Client& c, int count) {
  if (const auto status = c.latest_server_status())
    for (std::size_t i = 0; i < paper_object_order().size() && static_cast<int>(i) < count; ++i)
      if (std::find(status->models.begin(), status->models.end(), paper_object_order()[i]) == status->models.end()) {
        std::cerr << kTool << ": the server has no model named " << paper_object_order()[i]
                  << " (start it with --objects DIR --fill-standins, or without --objects)\n";
        return false;
      }
  return true;
}

// The records as a JSON array: on stdout, or in --json FILE. False, after saying so, if the
// file cannot be written.
bool write_records(const std::vector<report::Record>& records, const std::string& json_path) {
  json array = json::array();
  for (const report::Record& r : records) array.push_back(report::record_json(r));
  if (json_path.empty()) {
    std::cout << array.dump() << "\n";
    return true;
  }
  std::ofstream out(json_path);
  out << array.dump(1) << "\n";
  if (out.flush()) return true;
  std::cerr << kTool << ": --json " << json_path << ": cannot write\n";
  return false;
}

}  // namespace

int run_participant(int argc, char** argv) {
  Options opt = parse(argc, argv);
  if (!load_skills_flag(opt.skills_path, opt.skills, kTool)) return cli::kExitFailure;
  std::map<std::string, sim::ObjectModelPtr> models;
  try {
    models = protocol_models(opt.objects_dir, nullptr);
  } catch (const std::exception& e) {  // MeshLoadError, naming the folder or the file in it
    std::cerr << kTool << ": --objects " << e.what() << "\n";
    return cli::kExitFailure;
  }
  const client::ClientOptions copt =
      tools::client_options(opt, opt.group + "-" + std::to_string(opt.participant),
                            client::kNotices | client::kGraspEvents | client::kSceneStates | client::kServerStatuses |
                                client::kHandSkeletons | client::kGraspStates);
  try {
    client::Client c(copt);
    if (!c.wait_for_server(std::chrono::milliseconds(static_cast<long>(1000 * opt.timeout_s)))) {
      std::cerr << kTool << ": no telegrasp server found on domain " << opt.domain << " with profile " << opt.profile
                << " within " << opt.timeout_s << " s (--timeout-s)\n";
      return cli::kExitFailure;
    }
    // SceneStates arrive on a DDS thread; this thread answers each tick in order.
    std::mutex mutex;
    std::condition_variable cv;
    std::optional<client::SceneState> newest;
    c.on_scene_state([&](const client::SceneState& s) {
      std::lock_guard lock(mutex);
      if (!newest || s.tick > newest->tick) newest = s;
      cv.notify_one();
    });
    if (!server_has_the_objects(c, opt.count)) return cli::kExitFailure;
    Participant p(opt, c, std::move(models));
    p.start();
    std::uint64_t answered = 0;
    while (!p.done()) {
      std::unique_lock lock(mutex);
      // Controller states are best effort: an answer the server did not get (the very first one
      // may go out before the server's reader has matched ours) is sent again, unchanged.
      const auto give_up = Clock::now() + std::chrono::duration<double>(opt.timeout_s);
      while (!cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return newest && newest->tick > answered; })) {
        if (Clock::now() > give_up) {
          std::cerr << kTool << " " << copt.client_id << ": no scene state after tick " << answered << " for "
                    << opt.timeout_s << " s (--timeout-s)\n";
          return cli::kExitFailure;
        }
        lock.unlock();
        p.publish(answered);
        lock.lock();
      }
      const client::SceneState scene = *newest;
      lock.unlock();
      if (scene.tick != answered + 1 && answered > 0)
        std::cerr << kTool << " " << copt.client_id << ": scene states " << answered + 1 << ".." << scene.tick - 1
                  << " missed\n";
      answered = scene.tick;
      p.answer(scene);
    }
    c.on_scene_state({});
    if (!write_records(p.records(), opt.json_path)) return cli::kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return cli::kExitFailure;
  }
  return 0;
}

}  // namespace telegrasp::eval
