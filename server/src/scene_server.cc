#include "scene_server.h"

#include "telegrasp/idl/topics.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <set>
#include <stdexcept>

namespace telegrasp::server {
namespace {

constexpr std::size_t kMaxObjects = 128;  // the SceneState bound in telegrasp.idl

// The model as `spec` configures its object: a copy of the shared one when it sets the object's
// own friction or shape.
sim::ObjectModelPtr with_overrides(const sim::ObjectModelPtr& model, const SceneObjectSpec& spec) {
  if (!spec.friction && !spec.shape) return model;
  auto own = std::make_shared<sim::ObjectModel>(*model);
  if (spec.friction) own->friction = spec.friction;
  if (spec.shape) own->shape.shape = *spec.shape;
  return own;
}

}  // namespace

std::vector<SceneObjectSpec> default_layout(const std::vector<sim::ObjectModelPtr>& models, double gap,
                                            double table_half_extent) {
  const double y_min = -table_half_extent + gap, y_max = table_half_extent - gap;
  double row_x = 0.35, row_depth = 0, cursor_y = y_min;
  std::vector<SceneObjectSpec> out;
  for (const auto& m : models) {
    const Eigen::Vector3d lo = m->p_ObjectMin, hi = m->p_ObjectMax;
    if (cursor_y + (hi.y() - lo.y()) > y_max && cursor_y > y_min) {  // next row
      row_x += row_depth + gap;
      row_depth = 0;
      cursor_y = y_min;
    }
    out.push_back({m->name, row_x - lo.x(), cursor_y - lo.y(), 0.0});
    cursor_y += (hi.y() - lo.y()) + gap;
    row_depth = std::max(row_depth, hi.x() - lo.x());
  }
  if (!out.empty() && row_x + row_depth > table_half_extent)
    throw std::runtime_error("default scene: " + std::to_string(models.size()) + " objects do not fit on the table");
  return out;
}

SceneServer::SceneServer(const ServerSettings& settings, std::vector<sim::ObjectModelPtr> models,
                         std::shared_ptr<const sim::HandRig> right_rig, std::shared_ptr<const sim::HandRig> left_rig,
                         InputMailbox& mailbox, OutputSink& sink)
    : settings_(settings), mailbox_(mailbox), sink_(sink) {
  if (settings_.lockstep) settings_.late_latch = false;  // the tick follows the sample at once
  rigs_[idl::kHandLeft] = std::move(left_rig);
  rigs_[idl::kHandRight] = std::move(right_rig);
  for (auto& m : models) {
    if (models_.count(m->name)) throw std::runtime_error("two models are named '" + m->name + "'");
    model_names_.push_back(m->name);
    models_.emplace(m->name, std::move(m));
  }
  sim::WorldSettings ws;
  ws.dt = 1.0 / settings.tick_hz;
  ws.grasp.mode = settings.closing_mode;
  ws.grasp.quality_volume = settings.quality_volume ? sim::QualityVolume::kCompute : sim::QualityVolume::kSkip;
  ws.quality_delay_ticks = settings.quality_delay_ticks;
  ws.two_hand_mode = settings.two_hand_mode;
  ws.table_half_extent = kTableHalfExtent;
  world_ = std::make_unique<sim::World>(ws);
  if (settings_.restored_objects)
    spawn_restored_objects();
  else
    spawn_initial_scene();
}

void SceneServer::spawn_restored_objects() {
  std::map<std::string, int> seen;  // per model: restored objects so far
  for (const PlacedObject& o : *settings_.restored_objects) {
    auto it = models_.find(o.model);
    if (it == models_.end())
      throw std::runtime_error("restored object '" + o.model + "': no such model (see --list-models)");
    if (world_->objects().size() >= kMaxObjects)
      throw std::runtime_error("restored scene: at most " + std::to_string(kMaxObjects) + " objects");
    sim::ObjectModelPtr model = it->second;
    // The k-th restored object of a model takes the friction and shape of the k-th configured
    // object of that model (the snapshot keeps poses, not those).
    int k = seen[o.model]++;
    for (const SceneObjectSpec& spec : settings_.objects) {
      if (spec.model != o.model || k-- > 0) continue;
      model = with_overrides(model, spec);
      break;
    }
    spawn(model, o.X_WorldObject());
  }
}

void SceneServer::spawn_initial_scene() {
  if (settings_.empty_scene) return;
  std::vector<SceneObjectSpec> specs = settings_.objects;
  if (specs.empty()) {
    std::vector<sim::ObjectModelPtr> all;
    for (const auto& n : model_names_) all.push_back(models_.at(n));
    specs = default_layout(all, 0.15, kTableHalfExtent);
  }
  if (specs.size() > kMaxObjects)
    throw std::runtime_error("scene: at most " + std::to_string(kMaxObjects) + " objects");
  for (const auto& s : specs) {
    auto it = models_.find(s.model);
    if (it == models_.end())
      throw std::runtime_error("scene object '" + s.model + "': no such model (see --list-models)");
    const sim::ObjectModelPtr model = with_overrides(it->second, s);
    spawn(model, sim::World::resting_pose(*model, s.x, s.y, s.yaw));
  }
}

sim::ObjectId SceneServer::spawn(const sim::ObjectModelPtr& model, const Eigen::Isometry3d& X_WorldObject,
                                 const std::string& owner) {
  const sim::ObjectId id = world_->add_object(model, X_WorldObject);
  objects_[id.value] = {model->name, owner, world_->time(), X_WorldObject};
  return id;
}

void SceneServer::remove_object(sim::ObjectId id) {
  world_->remove_object(id);
  retired_objects_.push_back(id.value);
}

std::optional<sim::HandId> SceneServer::hand_id(const HandAddress& hand) const {
  auto it = hands_.find(hand);
  if (it == hands_.end()) return std::nullopt;
  return it->second.id;
}

void SceneServer::on_inputs(std::vector<InputSample> samples, std::int64_t now_ns) {
  (void)now_ns;
  // Lockstep: a sample answering an older tick than the current one means its client missed the
  // current SceneState (best effort); it is sent again, else both sides would wait for each other.
  if (settings_.lockstep && std::any_of(samples.begin(), samples.end(), [&](const InputSample& s) {
        return hands_.count(s.hand) && s.state.lockstep_tick() < world_->tick();
      }))
    sink_.publish(scene_state());
  for (InputSample& s : samples) {
    auto it = hands_.find(s.hand);
    if (it == hands_.end()) {
      const sim::HandId id = world_->add_hand(rigs_[s.hand.side]);
      address_of_[id.value] = s.hand;
      it = hands_.emplace(s.hand, Hand{id, {}, 0, false, 0, 0, std::nullopt}).first;
    }
    Hand& h = it->second;
    const sim::ControllerInput input = to_sim_input(s.state);
    if (const std::string why = world_->set_input(h.id, input); !why.empty()) {
      // validate_controller_state admits only what the sim accepts; this is a broken invariant.
      std::cerr << "telegrasp-server: internal: sim rejected a validated input of " << s.hand.client_id << ": " << why
                << "\n";
      continue;
    }
    h.stamp = {s.state.sequence_number(), s.state.client_time_ns()};
    h.last_received_ns = s.received_ns;
    h.frozen = false;
    h.answered_tick = s.state.lockstep_tick();
    h.commands_sent = s.state.commands_sent();
    if (settings_.late_latch) {
      const sim::HandController& hand = world_->hand(h.id);
      const Eigen::Isometry3d X_WorldPalm = input.tracking_valid ? input.X_WorldPalm : hand.state().X_WorldPalm;
      sink_.publish(make_hand_skeleton(s.hand, hand, world_->tick(), world_->time(), h.stamp, false, &X_WorldPalm));
    }
  }
}

void SceneServer::remove_hand(std::map<HandAddress, Hand>::iterator it) {
  world_->remove_hand(it->second.id);
  retired_hands_.push_back(it->second.id.value);
  mailbox_.forget_hand(it->first);
  sink_.hand_removed(it->first);
  hands_.erase(it);
}

void SceneServer::tick(std::int64_t now_ns) {
  for (auto it = hands_.begin(); it != hands_.end();) {
    Hand& h = it->second;
    const double silent = static_cast<double>(now_ns - h.last_received_ns) * 1e-9;
    if (silent > settings_.remove_after_s) {
      std::cerr << "telegrasp-server: client '" << it->first.client_id << "' "
                << (it->first.side == idl::kHandLeft ? "left" : "right") << " hand silent for " << silent
                << " s: removed\n";
      remove_hand(it++);
      continue;
    }
    h.frozen = silent > settings_.freeze_after_s;
    ++it;
  }
  world_->step();
  publish_events();
  // Forget the addresses and names of removed hands and objects once their events are out.
  for (int id : retired_hands_) address_of_.erase(id);
  for (int id : retired_objects_) objects_.erase(id);
  retired_hands_.clear();
  retired_objects_.clear();

  put_back_fallen();

  const std::uint64_t tick = world_->tick();
  const double time = world_->time();
  for (auto& [addr, h] : hands_) {
    const sim::HandController& hand = world_->hand(h.id);
    sink_.publish(make_hand_skeleton(addr, hand, tick, time, h.stamp, h.frozen));
    msg::GraspState gs = make_grasp_state(addr, hand, tick, time);
    bool changed = !h.published_state;
    // A change of selection, grasp, blocking, palm contact or (beyond a threshold) grasp quality;
    // not of the trigger alone.
    if (h.published_state) {
      msg::GraspState old = *h.published_state;
      old.tick(tick);
      old.time(time);
      old.trigger(gs.trigger());
      if (!quality_changed(old, gs)) {  // quality moves below the threshold do not count
        old.epsilon(gs.epsilon());
        old.volume(gs.volume());
      }
      changed = !(old == gs);
    }
    if (changed) {
      sink_.publish(gs);
      h.published_state = std::move(gs);
    }
    if (const auto X_WorldObject = hand.grasped_object_pose())
      sink_.publish(make_contact_set(addr, hand, tick, time, *X_WorldObject));
  }
  sink_.publish(scene_state());
}

void SceneServer::publish_events() {
  for (const sim::GraspEvent& e : world_->events()) {
    auto addr = address_of_.find(e.hand.value);
    if (addr == address_of_.end()) continue;  // cannot happen: addresses live one tick past removal
    EventContext ctx;
    ctx.hand = addr->second;
    ctx.event_id = next_event_id_++;
    if (auto o = objects_.find(e.object.value); o != objects_.end()) {
      ctx.object_name = o->second.name;
      ctx.object_spawn_time = o->second.spawn_time;
    }
    const auto objects = world_->objects();
    if (std::find(objects.begin(), objects.end(), e.object) != objects.end())
      ctx.X_WorldObject = world_->object_pose(e.object);
    if (auto h = hands_.find(ctx.hand); h != hands_.end()) ctx.input_sequence = h->second.stamp.sequence;
    const std::uint64_t due = world_->tick() + static_cast<std::uint64_t>(settings_.quality_delay_ticks);
    held_events_.push_back({due, e.quality_job, make_grasp_event(e, *rigs_[ctx.hand.side], ctx)});
  }
  for (const sim::QualityResult& r : world_->quality_results()) {
    if (!r.job.grasp_tick) continue;
    auto held = std::find_if(held_events_.begin(), held_events_.end(),
                             [&](const HeldEvent& h) { return h.quality_job == r.job.id; });
    if (held != held_events_.end() && r.metrics)
      set_metrics(held->message, *r.metrics, *rigs_[held->message.hand_side()]);
  }
  while (!held_events_.empty() && held_events_.front().due_tick <= world_->tick()) {
    sink_.publish(held_events_.front().message);
    held_events_.pop_front();
  }
}

msg::SceneState SceneServer::scene_state() const {
  msg::SceneState m;
  m.tick(world_->tick());
  m.time(world_->time());
  m.incarnation(settings_.incarnation);
  for (sim::ObjectId id : world_->objects()) {
    msg::ObjectState o;
    o.id(id.value);
    o.name(objects_.at(id.value).name);
    o.spawn_time(objects_.at(id.value).spawn_time);
    o.pose(to_msg(world_->object_pose(id)));
    o.linear_velocity(to_msg(world_->object_velocity(id)));
    std::vector<HandAddress> holders;
    for (sim::HandId holder : world_->holders(id)) holders.push_back(address_of_.at(holder.value));
    set_holders(o, holders);
    m.objects().push_back(std::move(o));
  }
  return m;
}

bool SceneServer::lockstep_ready() const {
  bool any_live = false;
  for (const auto& [addr, h] : hands_) {
    if (h.frozen) continue;
    any_live = true;
    if (h.answered_tick < world_->tick()) return false;
    auto seen = commands_seen_.find(addr.client_id);
    if (h.commands_sent > (seen == commands_seen_.end() ? 0 : seen->second)) return false;
  }
  return any_live;
}

bool SceneServer::is_operator(const std::string& client_id) const {
  return settings_.open_scene ||
         std::find(settings_.operators.begin(), settings_.operators.end(), client_id) != settings_.operators.end();
}

void SceneServer::put_back_fallen() {
  for (auto& [id, o] : objects_) {
    const sim::ObjectId object(id);
    if (world_->object_pose(object).translation().z() >= kFallenHeight || world_->holder(object).valid()) continue;
    // Another object may have come to rest where this one was spawned: placed into it, Bullet
    // would push the two apart at metres per second. A spawn pose off the table stays as it is.
    Eigen::Isometry3d X_WorldObject = o.X_WorldSpawn;
    const Eigen::Vector3d spawn = o.X_WorldSpawn.translation();
    const bool on_table = spawn.head<2>().cwiseAbs().maxCoeff() <= kTableHalfExtent - kTableMargin;
    const auto spot = on_table ? free_spot(world_->object_model(object), spawn.x(), spawn.y(), object) : std::nullopt;
    if (spot) X_WorldObject.translation().head<2>() = *spot;
    if (!world_->place_object(object, X_WorldObject)) continue;
    std::cerr << "telegrasp-server: " << o.name << " (object " << id << ") fell off the table: put back "
              << (!on_table || (spot && *spot == spawn.head<2>()) ? "where it was spawned"
                  : spot                                          ? "at the free spot nearest to where it was spawned"
                         : "where it was spawned, though no spot within " + std::to_string(kFreeSpotSearch) +
                               " m of it is free")
              << "\n";
  }
}

std::optional<Eigen::Vector2d> SceneServer::free_spot(const sim::ObjectModel& model, double x, double y,
                                                      sim::ObjectId ignored) const {
  // Footprints as circles about the centre of mass: the new object's horizontal reach (its
  // bounds turn with yaw), every other object's whole reach (it may lie in any orientation).
  const Eigen::Vector3d reach = model.p_ObjectMin.cwiseAbs().cwiseMax(model.p_ObjectMax.cwiseAbs());
  const double radius = std::hypot(reach.x(), reach.y()), gap = 0.005, lim = kTableHalfExtent - kTableMargin;
  auto free = [&](const Eigen::Vector2d& p) {
    if (std::abs(p.x()) > lim || std::abs(p.y()) > lim) return false;
    for (sim::ObjectId id : world_->objects()) {
      if (id == ignored) continue;
      const Eigen::Vector3d at = world_->object_pose(id).translation();
      if ((at.head<2>() - p).norm() < radius + world_->object_model(id).max_radius + gap) return false;
    }
    return true;
  };
  const Eigen::Vector2d want(x, y);
  if (free(want)) return want;
  constexpr double kStep = 0.01;  // rings 1 cm apart, points about 1 cm apart on each
  for (double r = kStep; r <= kFreeSpotSearch + 1e-9; r += kStep) {
    const int n = std::max(8, static_cast<int>(std::ceil(2 * M_PI * r / kStep)));
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      const Eigen::Vector2d p = want + r * Eigen::Vector2d(std::cos(a), std::sin(a));
      if (free(p)) return p;
    }
  }
  return std::nullopt;
}

std::pair<std::string, std::string> SceneServer::try_spawn(const msg::SceneCommand& c, bool is_operator) {
  auto it = models_.find(c.model().to_string());
  if (it == models_.end()) return {"unknown_model", "unknown model '" + c.model().to_string() + "'"};
  if (world_->objects().size() >= kMaxObjects)
    return {"scene_full", "the scene is full (" + std::to_string(kMaxObjects) + " objects)"};
  const std::string client = c.client_id().to_string();
  if (!is_operator) {
    const auto own = std::count_if(objects_.begin(), objects_.end(), [&](const auto& o) {
      return o.second.owner == client && world_->has_object(sim::ObjectId(o.first));
    });
    if (own >= settings_.max_objects_per_client)
      return {"spawn_limit", "a client may have spawned at most " + std::to_string(settings_.max_objects_per_client) +
                                 " objects at once (remove one first)"};
  }
  const sim::ObjectModel& model = *it->second;
  if (c.on_table()) {
    const double lim = kTableHalfExtent - kTableMargin;
    if (!std::isfinite(c.x()) || !std::isfinite(c.y()) || !std::isfinite(c.yaw()) || std::abs(c.x()) > lim ||
        std::abs(c.y()) > lim)
      return {"bad_pose", "spawn on the table needs finite x, y in [-" + std::to_string(lim) + ", " +
                              std::to_string(lim) + "] and a finite yaw"};
    const std::optional<Eigen::Vector2d> spot = free_spot(model, c.x(), c.y());
    if (!spot)
      return {"no_free_spot", "no free spot within " + std::to_string(kFreeSpotSearch) + " m of the requested one"};
    spawn(it->second, sim::World::resting_pose(model, spot->x(), spot->y(), c.yaw()), client);
    return {};
  }
  if (!finite_unit_pose(c.pose())) return {"bad_pose", "spawn pose must be finite with a unit quaternion"};
  const Eigen::Isometry3d X_WorldObject = to_eigen(c.pose());
  for (sim::ObjectId id : world_->objects())
    if ((world_->object_pose(id).translation() - X_WorldObject.translation()).norm() <
        model.max_radius + world_->object_model(id).max_radius)
      return {"overlap", "the spawn pose overlaps object " + std::to_string(id.value) +
                             " (spawn on the table to be placed at the nearest free spot)"};
  spawn(it->second, X_WorldObject, client);
  return {};
}

std::pair<std::string, std::string> SceneServer::try_command(const msg::SceneCommand& c) {
  const std::string client = c.client_id().to_string();
  const bool op = is_operator(client);
  switch (c.kind()) {
    case msg::SCENE_SPAWN:
      return try_spawn(c, op);
    case msg::SCENE_REMOVE: {
      const sim::ObjectId id(c.object_id());
      if (!world_->has_object(id)) return {"no_such_object", "no object with id " + std::to_string(c.object_id())};
      const auto holders = world_->holders(id);
      const bool holds = std::any_of(holders.begin(), holders.end(),
                                     [&](sim::HandId h) { return address_of_.at(h.value).client_id == client; });
      if (!op && !holds && objects_.at(id.value).owner != client)
        return {"not_permitted", "only an operator may remove an object this client neither spawned nor holds"};
      remove_object(id);
      return {};
    }
    case msg::SCENE_RESET:
      if (!op) return {"not_permitted", "only an operator may reset the scene"};
      for (sim::ObjectId id : world_->objects()) remove_object(id);
      spawn_initial_scene();
      return {};
    default:
      return {"unknown_kind", "unknown command kind " + std::to_string(static_cast<int>(c.kind()))};
  }
}

std::string SceneServer::apply_command(const msg::SceneCommand& c) {
  std::uint64_t& seen = commands_seen_[c.client_id().to_string()];
  seen = std::max(seen, c.command_id());
  const auto [reason, detail] = try_command(c);
  if (reason.empty()) {
    ++commands_accepted_;
    return "";
  }
  ++commands_rejected_;
  ++commands_rejected_by_reason_[reason];
  const std::string client = c.client_id().to_string();
  constexpr std::size_t kMaxRefusals = 4096;  // (client, reason) pairs logged; a flood of ids is only counted
  auto refusals = command_refusals_.find({client, reason});
  if (refusals == command_refusals_.end() && command_refusals_.size() < kMaxRefusals) {
    refusals = command_refusals_.emplace(std::make_pair(client, reason), 0).first;
    std::cerr << "telegrasp-server: rejected scene command " << c.command_id() << " from '" << client << "': " << detail
              << " (" << reason << "; counted in ServerStatus, said once per client and reason, told to the client)\n";
  }
  if (refusals != command_refusals_.end()) {
    msg::ClientNotice n;
    n.client_id(client);
    n.kind(msg::NOTICE_COMMAND_REJECTED);
    n.reason(reason);
    n.detail(detail.substr(0, 256));
    n.command_id(c.command_id());
    n.count(++refusals->second);
    n.time(world_->time());
    sink_.publish(n);
    ++notices_;
  }
  return detail;
}

msg::ServerStatus SceneServer::status(const LoopStats& loop) const {
  msg::ServerStatus m;
  m.tick(world_->tick());
  m.time(world_->time());
  m.tick_rate_hz(settings_.tick_hz);
  std::set<std::string> clients;
  for (const auto& [addr, h] : hands_) clients.insert(addr.client_id);
  m.clients(static_cast<std::int32_t>(clients.size()));
  m.hands(static_cast<std::int32_t>(hands_.size()));
  m.objects(static_cast<std::int32_t>(world_->objects().size()));
  m.tick_us_p50(loop.tick_us_p50);
  m.tick_us_max(loop.tick_us_max);
  m.tick_us_p99(loop.tick_us_p99);
  m.rss_kib(loop.rss_kib);
  m.heap_kib(loop.heap_kib);
  m.missed_ticks(loop.missed_ticks);
  m.inputs_accepted(mailbox_.accepted());
  const auto rejected = mailbox_.rejected();
  std::uint64_t total = 0;
  for (int r = 0; r < static_cast<int>(RejectReason::kCount); ++r) {
    msg::RejectCount rc;
    rc.reason(std::string(name(static_cast<RejectReason>(r))));
    rc.count(rejected[r]);
    total += rejected[r];
    m.rejected().push_back(std::move(rc));
  }
  m.inputs_rejected(total);
  std::map<std::string, std::uint64_t> by_reason = mailbox_.commands_rejected();
  std::uint64_t refused_early = 0;  // before the scene saw them
  for (const auto& [reason, n] : by_reason) refused_early += n;
  for (const auto& [reason, n] : commands_rejected_by_reason_) by_reason[reason] += n;
  for (const auto& [reason, n] : by_reason) {
    msg::RejectCount rc;
    rc.reason(reason);
    rc.count(n);
    m.commands_rejected_by_reason().push_back(std::move(rc));
  }
  m.commands_accepted(commands_accepted_);
  m.commands_rejected(commands_rejected_ + refused_early);
  m.notices_sent(notices_ + mailbox_.notices());
  for (const auto& n : model_names_) m.models().push_back(n);
  m.incarnation(settings_.incarnation);
  m.quality_late(world_->quality_late());
  return m;
}

}  // namespace telegrasp::server
