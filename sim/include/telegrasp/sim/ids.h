// Typed indices for the things the simulation addresses: objects, hands, phalanges.
#pragma once

#include <compare>
#include <cstdint>
#include <functional>

namespace telegrasp::sim {

/// A value-typed index that cannot be mixed up with another kind of index.
template <typename Tag>
struct TypedId {
  static constexpr std::int32_t kInvalid = -1;
  std::int32_t value = kInvalid;

  constexpr TypedId() = default;
  constexpr explicit TypedId(std::int32_t v) : value(v) {}
  [[nodiscard]] constexpr bool valid() const { return value >= 0; }
  constexpr auto operator<=>(const TypedId&) const = default;
};

using ObjectId = TypedId<struct ObjectTag>;
using HandId = TypedId<struct HandTag>;
/// Index of a phalanx in its HandRig (0 .. phalanges().size()-1).
using PhalanxId = TypedId<struct PhalanxTag>;

}  // namespace telegrasp::sim
