// Fuzzes the hand rig text format (sim/proto/hand_rig.proto in protobuf text, sim/rigs): parsing
// and every check HandRig::parse makes; a rig that parses is mirrored and posed open and closed
// (forward kinematics), as the server does with the rigs it is given.
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
    for (double u : {0.0, 1.0}) {
      std::vector<double> q;
      for (const PhalanxSpec& p : mirrored.phalanges()) q.push_back(target_angle(p, u));
      forward_kinematics(mirrored, q, &X_PalmPhalanx);
    }
  } catch (const telegrasp::sim::RigError&) {
    // A refused rig: the expected outcome for most inputs.
  }
  return 0;
}
