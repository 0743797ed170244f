// PoseResolver: the pose at which a hand is shown and grasps (the resolved pose), kept outside
// every object and the table while the tracked controller pose goes through them.
#pragma once

#include "telegrasp/sim/ids.h"
#include "telegrasp/sim/object_model.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <span>
#include <vector>

namespace telegrasp::sim {

struct ObjectView;

/// One solid volume of the hand: a capsule (segment [a, b] and radius) in the palm frame.
struct HandVolume {
  Eigen::Vector3d p_PalmA{0, 0, 0}, p_PalmB{0, 0, 0};
  double radius = 0;
  bool palm = false;  ///< Part of the palm (always kept outside), not a finger capsule.
};

/// The palm box (half extents `h`, thickness along z) as capsules of radius h.z() along x, side by
/// side across y at most 1.2 h.z() apart: the box with its edges rounded (the dips between two
/// capsules are at most 2.2 mm deep for the human rigs).
std::vector<HandVolume> palm_volumes(const Eigen::Vector3d& h);

/// Tunables of the resolution.
struct ResolverSettings {
  double rejoin_speed = 1.0;  ///< The resolved pose closes its offset to the tracked one at most this fast, m/s.
  double rejoin_turn = 2.0 * 3.141592653589793;  ///< ... and turns toward it at most this fast, rad/s.
  double table_half_extent = 0;  ///< > 0: the table top z = 0 over [-this, this]^2 is an obstacle, m.
  /// Holding nothing and farther than this from the tracked pose (caught behind an object while
  /// the controller went on), the hand jumps to the tracked pose if it is clear there, as VR hands
  /// do; m, 0: never.
  double snap_distance = 0.2;
  double tolerance = 0.05e-3;  ///< A pushed-out volume ends within [0, this] of the surface, m.
  bool fingers_may_rest_inside = false;  ///< Discrete closing: hand motion only never deepens a finger's overlap.
};

/// Finds, tick by tick, the pose nearest the tracked one at which every HandVolume lies outside
/// every object (exact distances) and the table. The resolved pose follows the tracked pose's
/// motion plus an offset that shrinks at a bounded speed; the motion from the last resolved pose
/// is taken in sub-steps short enough that no volume can pass through a surface between two,
/// and after each a volume found inside pushes the hand out along the surface normal (so the hand
/// slides over surfaces). Deterministic.
class PoseResolver {
 public:
  explicit PoseResolver(ResolverSettings settings) : settings_(settings) {}

  /// The resolved pose for this tick. `X_WorldResolved` and `X_WorldTrackedBefore` are last tick's
  /// (equal on the first tick, `has_previous` false: then only pushed out), `X_WorldTracked` this
  /// tick's; `volumes` the hand's volumes as posed now; objects whose id is `held` are ignored.
  Eigen::Isometry3d resolve(const Eigen::Isometry3d& X_WorldResolved, const Eigen::Isometry3d& X_WorldTrackedBefore,
                            const Eigen::Isometry3d& X_WorldTracked, bool has_previous, double dt,
                            std::span<const HandVolume> volumes, std::span<const ObjectView> objects, ObjectId held);

  const ResolverSettings& settings() const { return settings_; }

 private:
  // An obstacle near the hand this tick: an object (model set) or the table (model null).
  struct Obstacle {
    const ObjectModel* model = nullptr;
    Eigen::Isometry3d X_ObjectWorld = Eigen::Isometry3d::Identity();
    ObjectId id;  // invalid for the table
  };
  // What a gap query found: the gap (> horizon when `far`) and the world direction that opens it.
  struct Gap {
    double gap = 0;
    Eigen::Vector3d n_World{0, 0, 1};
    bool far = false;
  };
  Eigen::Isometry3d candidate(const Eigen::Isometry3d& X_WorldResolved, const Eigen::Isometry3d& X_WorldTrackedBefore,
                              const Eigen::Isometry3d& X_WorldTracked, double dt) const;
  void carry_over(const std::vector<Obstacle>& last, const std::vector<double>& last_bound,
                  const std::vector<std::uint32_t>& last_hint, const std::vector<HandVolume>& last_volumes);
  void gather(const Eigen::Isometry3d& X0, const Eigen::Isometry3d& X1, std::span<const HandVolume> volumes,
              std::span<const ObjectView> objects, ObjectId held);
  Gap gap(std::size_t o, std::size_t v, const Eigen::Isometry3d& X_WorldPalm, double horizon);
  void set_floors(const Eigen::Isometry3d& X_WorldPalm);
  bool push_out(Eigen::Isometry3d& X_WorldPalm);
  bool unchanged(const Eigen::Isometry3d& X0, const Eigen::Isometry3d& X1, std::span<const ObjectView> objects,
                 ObjectId held) const;

  ResolverSettings settings_;
  std::span<const HandVolume> volumes_;
  std::vector<Obstacle> obstacles_;
  // Per obstacle x volume: a lower bound on the gap (shrunk by every motion), the floor the gap
  // may not go below, and the triangle last found nearest (a search hint).
  std::vector<double> bound_, floor_;
  std::vector<std::uint32_t> hint_;
  std::vector<double> reach_;  // per volume: max |p| over its segment, palm frame
  double horizon_ = 0;  // how far the rest of this tick's motion can move a volume point
  // What the last resolve saw, to skip the work when nothing moved.
  bool last_valid_ = false;
  std::vector<std::pair<ObjectId, Eigen::Isometry3d>> last_objects_;
  // The volumes as last resolved (to carry bounds over to the next tick), and the normal of the
  // last push if the hand ended last tick held back by a surface.
  std::vector<HandVolume> last_volumes_;
  bool pushed_ = false;
  Eigen::Vector3d push_normal_{0, 0, 1};
};

}  // namespace telegrasp::sim
