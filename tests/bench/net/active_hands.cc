#include "active_hands.h"

#include "bench_common.h"

#include "telegrasp/idl/eigen_conversions.h"
#include "telegrasp/idl/topics.h"
#include "telegrasp/sim/standin_objects.h"
#include "telegrasp/sim/world.h"

#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace telegrasp::bench {

namespace {
constexpr int kColumns = 11, kRows = 12;
constexpr double kColumnStep = 0.35, kRowStep = 0.30;
constexpr double kX0 = -0.5 * (kColumns - 1) * kColumnStep, kY0 = -0.5 * (kRows - 1) * kRowStep;
constexpr double kPlaced = 0.12;  // m: an object this near its grid place is that hand's
constexpr double kUprightTilt = 0.3;  // rad: an object tilted more has fallen over; no trial on it
constexpr double kPause = 0.3;  // s open at the release pose between two trials
constexpr double kRetry = 1.0;  // s before a hand whose object is not found tries again
constexpr double kPosesMaxAge = 0.2;  // s: object poses are taken again when older

// The hand of a bench client id "scale-<c>" and side, or -1.
int hand_of(const std::string& client_id, int side) {
  constexpr std::string_view kPrefix = "scale-";
  if (client_id.rfind(kPrefix, 0) != 0 || side < 0 || side > 1) return -1;
  try {
    return 2 * std::stoi(client_id.substr(kPrefix.size())) + side;
  } catch (const std::exception&) {
    return -1;
  }
}
}  // namespace

Eigen::Vector2d active_object_xy(int hand) {
  return {kX0 + kColumnStep * (hand % kColumns), kY0 + kRowStep * (hand / kColumns)};
}

bool is_active_model(const std::string& model) {
  const auto object = sim::find_protocol_object(model);
  return object && object->name == model;
}

std::string active_objects_config(int hands, const std::string& model) {
  std::ostringstream out;
  out.precision(6);
  for (int h = 0; h < hands; ++h) {
    const Eigen::Vector2d xy = active_object_xy(h);
    out << "objects { model: \"" << model << "\" x: " << xy.x() << " y: " << xy.y() << " }\n";
  }
  return out.str();
}

ActiveHands::ActiveHands(const std::string& model, int max_hands, double sample_hz)
    : model_name_(model), sample_hz_(sample_hz), hands_(max_hands), grasped_(new std::atomic<bool>[max_hands]) {
  if (!is_active_model(model)) throw std::runtime_error("no built-in stand-in '" + model + "'");
  model_ = sim::make_standin_model(*sim::find_protocol_object(model));
  // The server's default hands.
  for (const auto& [hand, side] :
       {std::pair{idl::kHandLeft, sim::HandSide::kLeft}, std::pair{idl::kHandRight, sim::HandSide::kRight}})
    rigs_[hand] = std::make_shared<const sim::HandRig>(
        sim::HandRig::load(sim::HandRig::builtin_path(sim::HandRig::default_human(side))));
  X_WorldObject0_ = sim::World::resting_pose(*model_, 0, 0, 0);
  for (int side = 0; side < 2; ++side)
    plans_[side] = sim::plan_grasp(rigs_[side], {}, *model_, X_WorldObject0_, 1.0 / sample_hz_);
  for (int h = 0; h < max_hands; ++h) grasped_[h] = false;
  counts_.grasps_per_hand.assign(max_hands, 0);
}

void ActiveHands::on_data_available(eprosima::fastdds::dds::DataReader* reader) {
  msg::GraspEvent e;
  eprosima::fastdds::dds::SampleInfo info;
  while (reader->take_next_sample(&e, &info) == ReturnCode_t::RETCODE_OK)
    if (info.valid_data) on_grasp_event(e);
}

void ActiveHands::on_grasp_event(const msg::GraspEvent& e) {
  const int h = hand_of(e.client_id().to_string(), e.hand_side());
  if (h < 0 || h >= static_cast<int>(hands_.size())) return;
  const bool grasp = e.kind() == msg::GRASP_EVENT_GRASP;
  grasped_[h] = grasp;
  std::lock_guard lock(mutex_);
  if (grasp) {
    ++counts_.grasps;
    ++counts_.grasps_per_hand[h];
  } else {
    ++counts_.releases;
  }
}

void ActiveHands::on_scene_state(const msg::SceneState& scene, double t) {
  std::lock_guard lock(mutex_);
  take_poses(scene, t);
}

void ActiveHands::take_poses(const msg::SceneState& scene, double t) {
  poses_taken_t_ = t;
  object_poses_.clear();
  for (const msg::ObjectState& o : scene.objects()) {
    const Eigen::Isometry3d X = idl::to_eigen(o.pose());
    const int col = static_cast<int>(std::lround((X.translation().x() - kX0) / kColumnStep));
    const int row = static_cast<int>(std::lround((X.translation().y() - kY0) / kRowStep));
    if (col < 0 || col >= kColumns || row < 0) continue;
    const int h = row * kColumns + col;
    if ((X.translation().head<2>() - active_object_xy(h)).norm() < kPlaced) object_poses_[h] = X;
  }
}

Eigen::Isometry3d ActiveHands::hover_pose(int hand, int side) const {
  const Eigen::Vector2d xy = active_object_xy(hand);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(xy.x() - 0.15, xy.y() + (side == idl::kHandLeft ? 0.1 : -0.1), 0.3);
  return X;
}

std::optional<Eigen::Isometry3d> ActiveHands::object_pose(int hand, double t) {
  std::lock_guard lock(mutex_);
  if (t - poses_taken_t_ > kPosesMaxAge && scene_reader_) {
    msg::SceneState scene, newest;
    eprosima::fastdds::dds::SampleInfo info;
    bool any = false;
    while (scene_reader_->take_next_sample(&scene, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) newest = scene, any = true;
    if (any) take_poses(newest, t);
  }
  const auto it = object_poses_.find(hand);
  if (it == object_poses_.end()) {
    ++counts_.objects_missing;
    return std::nullopt;
  }
  if ((it->second.linear() * Eigen::Vector3d::UnitZ()).z() < std::cos(kUprightTilt)) {
    ++counts_.objects_fallen;
    return std::nullopt;
  }
  return it->second;
}

msg::ControllerState ActiveHands::sample(const std::string& client_id, int client, int side, std::uint64_t seq,
                                         double t) {
  const int h = 2 * client + side;
  Hand& hand = hands_[h];
  sim::ControllerInput input;
  if (!active_.load()) {
    // Idle: hover over the object as the idle bench's hands move in the air.
    hand.op.reset();
    hand.t_next = -1;
    constexpr double kTwoPi = 2 * std::numbers::pi;
    const double phase = 0.37 * client + 1.3 * side;
    input.X_WorldPalm = hover_pose(h, side);
    input.X_WorldPalm.translation() +=
        Eigen::Vector3d(0.05 * std::sin(kTwoPi * 0.3 * t + phase), 0.05 * std::cos(kTwoPi * 0.4 * t + phase),
                        0.05 * std::sin(kTwoPi * 0.5 * t + phase));
    const msg::Quat q = wobble_quaternion(0.6 * std::sin(kTwoPi * 0.25 * t + phase));
    input.X_WorldPalm.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).toRotationMatrix();
    input.trigger = std::clamp(0.5 - 0.5 * std::cos(kTwoPi * 0.5 * t + phase), 0.0, 1.0);
    hand.X_WorldPalm = input.X_WorldPalm;
  } else {
    if (hand.t_next < 0) {
      // First active sample: start from the hover pose, trials staggered over 2 s.
      hand.X_WorldPalm = hover_pose(h, side);
      hand.t_next = t + 2.0 * std::fmod(0.6180339887 * h, 1.0);
    }
    if (!hand.op && t >= hand.t_next) {
      if (const auto X_WorldObject = object_pose(h, t)) {
        // The plan made at X_WorldObject0_, moved with the object to where it is.
        const Eigen::Isometry3d moved = *X_WorldObject * X_WorldObject0_.inverse();
        sim::GraspPlan plan = plans_[side];
        plan.X_WorldPalm = moved * plan.X_WorldPalm;
        plan.approach_World = moved.linear() * plan.approach_World;
        hand.op = std::make_unique<sim::ScriptedOperator>(rigs_[side], sim::skill_profile("perfect"),
                                                          static_cast<std::uint64_t>(h) + 1, sim::GraspSettings{},
                                                          1.0 / sample_hz_);
        hand.op->put_down_before_release(true);  // a dropped can may fall over
        hand.op->begin(plan, *model_, hand.X_WorldPalm, t);
        hand.t_begin = t;
      } else {
        hand.t_next = t + kRetry;
      }
    }
    if (hand.op) {
      input = hand.op->next(t, grasped_[h].load());
      if (hand.op->done()) {
        std::lock_guard lock(mutex_);
        ++counts_.cycles;
        counts_.cycles_held += hand.op->held_after_lift();
        cycle_s_sum_ += t - hand.t_begin;
        hand.op.reset();
        hand.t_next = t + kPause;
      }
    } else {
      input.X_WorldPalm = hand.X_WorldPalm;  // open, waiting
    }
    hand.X_WorldPalm = input.X_WorldPalm;
  }
  msg::ControllerState s;
  s.client_id(client_id);
  s.hand_side(static_cast<std::uint8_t>(side));
  s.sequence_number(seq);
  s.palm(idl::to_msg(input.X_WorldPalm));
  s.trigger(input.trigger);
  s.buttons(0);
  s.tracking_valid(true);
  return s;
}

ActiveCounts ActiveHands::counts() const {
  std::lock_guard lock(mutex_);
  return counts_;
}

int ActiveHands::holding() const {
  int n = 0;
  for (std::size_t h = 0; h < hands_.size(); ++h) n += grasped_[h].load();
  return n;
}

double ActiveHands::mean_cycle_s() const {
  std::lock_guard lock(mutex_);
  return counts_.cycles ? cycle_s_sum_ / static_cast<double>(counts_.cycles) : 0;
}

}  // namespace telegrasp::bench
