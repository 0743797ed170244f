// Fuzzes the hand rig text format (sim/proto/hand_rig.proto in protobuf text, sim/rigs): parsing
// and every check HandRig::parse makes; a rig that parses is mirrored and posed open, half and
// fully closed (forward kinematics) as each of its grasp types closes it, as the server does with
// the rigs it is given.
#include "fuzz_common.h"
#include "telegrasp/sim/hand_kinematics.h"
#include "telegrasp/sim/hand_rig.h"

#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool silenced = (telegrasp::fuzz::silence_cerr(), true);
  (void)silenced;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    using namespace telegrasp::sim;
    const HandRig rig = HandRig::parse(text, "fuzz.textproto");
    const HandRig mirrored = rig.mirrored();
    std::vector<Eigen::Isometry3d> X_PalmPhalanx;
    for (int t = 0; t < kGraspTypeCount; ++t) {
      const auto type = static_cast<GraspType>(t);
      if (!mirrored.has_grasp_type(type)) continue;
      (void)mirrored.grasp_rule(type);
      for (double u : {0.0, 0.5, 1.0}) {
        std::vector<double> q;
        for (const PhalanxSpec& p : mirrored.phalanges(type)) q.push_back(target_angle(p, u));
        forward_kinematics(mirrored, q, &X_PalmPhalanx);
      }
    }
  } catch (const telegrasp::sim::RigError&) {
    // A refused rig: the expected outcome for most inputs.
  }
  return 0;
}
