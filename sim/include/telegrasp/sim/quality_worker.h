// QualityWorker: grasp qualities (and each grasp's metrics) computed off the simulation thread, in
// the order they were asked for, each a pure function of a copy of one tick's inputs (contacts,
// friction, torque scale; for the metrics, a copy of the hand as it grasped).
#pragma once

#include "telegrasp/sim/grasp_quality.h"
#include "telegrasp/sim/ids.h"

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace telegrasp::sim {

struct GraspMetrics;  // grasp_metrics.h

/// The quality of one hand's contacts on one tick.
struct QualityJob {
  std::uint64_t id = 0;  ///< Increasing in submission order (from 1).
  HandId hand;
  std::uint64_t grasp = 0;  ///< HandController::grasp_serial() of the grasp these contacts hold.
  std::uint64_t tick = 0;  ///< The World's tick whose contacts these are.
  bool grasp_tick = false;  ///< The grasp's first contact set: its GraspEvent's quality.
  bool forget = false;  ///< The hand is gone: drop what the worker keeps for it (no quality).
  std::vector<QualityContact> contacts;  ///< HandController::quality_contacts() of the hand's contacts.
  double mu = 0;  ///< Coulomb friction.
  double torque_scale = 1;  ///< The object's radius about its centre of mass.
  QualityVolume volume = QualityVolume::kSkip;
  /// Grasp ticks: takes the grasp's metrics (HandController::grasp_tick_metrics() of a copy of the
  /// hand as it grasped), on the worker with the quality; empty: none.
  std::function<std::shared_ptr<GraspMetrics>()> metrics;
};

/// A job's answer.
struct QualityResult {
  QualityJob job;  ///< Without its contacts.
  GraspQuality quality;
  std::uint64_t computed = 0;  ///< Qualities computed for the job's hand so far (not reused).
  std::shared_ptr<GraspMetrics> metrics;  ///< The job's metrics, if it asked for them, with `quality`.
};

/// Computes QualityJobs in submission order, on a thread of its own (threaded) or in submit()
/// (not threaded: the simulation thread, as before the worker existed). Per hand it keeps the
/// qualities of its last 8 wrench sets and reuses one for wrenches within 1e-11 of it (every
/// column; the bound on the reused quality's error: HandController::quality_contacts()); that
/// memo is the worker's alone and fed in submission order, so results are a deterministic
/// function of the jobs, threaded or not.
class QualityWorker {
 public:
  explicit QualityWorker(bool threaded);
  ~QualityWorker();  ///< Finishes the jobs submitted, then joins.
  QualityWorker(const QualityWorker&) = delete;
  QualityWorker& operator=(const QualityWorker&) = delete;

  /// Queues `job` (its id must exceed every earlier one's); threaded, returns at once.
  void submit(QualityJob job);
  /// The results of every job submitted up to id `last`, in order, waiting for those not done;
  /// `waited` tells whether any was not done when asked.
  std::vector<QualityResult> take(std::uint64_t last, bool& waited);

 private:
  struct Memo {
    struct Entry {
      Wrenches wrenches;
      GraspQuality quality;
    };
    std::vector<Entry> entries;  // most recently used first
    std::uint64_t computed = 0;
  };
  QualityResult compute(QualityJob job);  // the worker's thread only (or submit's, not threaded)
  void run();

  std::map<int, Memo> memos_;  // by hand id
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<QualityJob> queue_;
  std::deque<QualityResult> done_;
  std::uint64_t done_through_ = 0;  // the id of the last job done
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace telegrasp::sim
