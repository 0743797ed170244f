// Small rigs several sim tests share, as rig text (HandRig::parse).
#pragma once

namespace telegrasp::sim::testing {

// One finger along +x from (0.04, 0, 0) in the palm frame: proximal (no capsule), middle and
// distal (capsules of radius 5 mm), all flexing about +y at 180 deg/s. Sp is on the axis and
// CTc on the palmar skin (-z) at mid-length, so |CTc - Sp| = 5 mm.
inline constexpr const char* kFingerRig = R"(
name: "finger3"
palm_selection_sphere { center { x: 0.07 } radius: 0.2 }
palm_contact_volume { radius: 0.005 }
palm_half_extent { x: 0.04 y: 0.04 z: 0.01 }
default_max_speed_deg_s: 180
nd_sweep_radius: 0.001
nd_sweep_beyond: 0.01
fingers {
  name: "f"
  phalanges { name: "f_prox" rest { translation { x: 0.04 } }
    joint { axis { y: 1 } open_deg: 0 closed_deg: 90 min_deg: 0 max_deg: 90 } length: 0.03 }
  phalanges { name: "f_mid" rest { translation { x: 0.03 } }
    joint { axis { y: 1 } open_deg: 0 closed_deg: 90 min_deg: 0 max_deg: 90 } length: 0.025
    capsule { a { } b { x: 0.025 } radius: 0.005 ctc { x: 0.0125 z: -0.005 } sp { x: 0.0125 } } }
  phalanges { name: "f_dist" rest { translation { x: 0.025 } }
    joint { axis { y: 1 } open_deg: 0 closed_deg: 70 min_deg: 0 max_deg: 70 } length: 0.02
    capsule { a { } b { x: 0.015 } radius: 0.005 ctc { x: 0.0075 z: -0.005 } sp { x: 0.0075 } } }
}
grasp_rule { members: ["f_mid", "f_dist"] }
)";

}  // namespace telegrasp::sim::testing
