#include "grasp_event_record.h"

#include <algorithm>

namespace telegrasp::tools {

void record_grasp_event(const client::GraspEvent& e, double trial_start_time, const sim::HandRig& rig,
                        report::Record& rec) {
  rec.grasped = true;
  rec.time_to_grasp_s = e.time - std::max(e.object_spawn_time, trial_start_time);
  rec.hand_error_mm = rec.grasp_tick_hand_error_mm = e.hand_error_mm;
  rec.capsules.clear();
  for (const client::CapsuleMetric& c : e.capsules)
    rec.capsules.push_back(
        {c.phalanx_name, c.hit, c.blocked, 1000 * c.nd, 1000 * c.signed_distance, c.contact_hit, 1000 * c.nd_contact});
  rec.grasp_tick_capsules = rec.capsules;
  // The event is the grasp tick's: the record's settled figures are the same.
  rec.figures = rec.grasp_tick_figures = {1000 * e.palm_signed_distance, e.epsilon, e.volume, e.force_closure};
  rec.grasp_type = e.grasp_type;
  rec.contacts.clear();
  std::vector<sim::Contact> contacts;  // for the thumb's opposition
  for (const client::ContactPoint& c : e.contacts) {
    const bool palm = c.phalanx < 0 || c.phalanx >= static_cast<int>(rig.phalanges().size());
    rec.contacts.push_back({palm ? std::string("palm") : rig.phalanges()[c.phalanx].name, c.p_WorldContact, c.n_World,
                            c.p_ObjectContact, c.n_Object});
    sim::Contact k;
    if (!palm) k.phalanx = sim::PhalanxId(c.phalanx);
    k.n_Object = c.n_Object;
    contacts.push_back(k);
  }
  rec.opposition_deg = report::opposition_deg(contacts, rig);
}

std::optional<sim::GraspQuality> hold_quality(const std::optional<client::GraspState>& s, int object) {
  if (!s || s->grasped_object != object || s->epsilon < 0) return std::nullopt;
  return sim::GraspQuality{s->epsilon, s->volume, s->force_closure};
}

}  // namespace telegrasp::tools
