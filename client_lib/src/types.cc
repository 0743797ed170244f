#include "telegrasp/client/types.h"

namespace telegrasp::client {

std::string to_string(HandSide side) {
  switch (side) {
    case HandSide::kLeft:
      return "left";
    case HandSide::kRight:
      return "right";
  }
  return "side" + std::to_string(static_cast<unsigned>(side));
}

}  // namespace telegrasp::client
