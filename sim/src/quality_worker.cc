#include "telegrasp/sim/quality_worker.h"

#include "telegrasp/sim/grasp_metrics.h"

#include <algorithm>
#include <limits>
#include <utility>

namespace telegrasp::sim {
namespace {

// A memo entry serves wrenches within this of its own, column by column (wrench units: forces
// per unit normal force), so that rounding (a two-hand hold re-attaching each tick moves the
// contacts by ~1e-17 m) does not recompute. Error bound: HandController::quality_contacts().
constexpr std::size_t kMemoEntries = 8;
constexpr double kSameWrench = 1e-11;

// Largest distance between corresponding wrenches; infinite when the sets differ in size.
double wrench_distance(const Wrenches& a, const Wrenches& b) {
  if (a.cols() != b.cols()) return std::numeric_limits<double>::infinity();
  if (a.cols() == 0) return 0;
  return (a - b).colwise().norm().maxCoeff();
}

}  // namespace

QualityWorker::QualityWorker(bool threaded) {
  if (threaded) thread_ = std::thread([this] { run(); });
}

QualityWorker::~QualityWorker() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void QualityWorker::submit(QualityJob job) {
  if (!thread_.joinable()) {
    QualityResult r = compute(std::move(job));
    done_through_ = r.job.id;
    done_.push_back(std::move(r));
    return;
  }
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(std::move(job));
  }
  cv_.notify_all();
}

std::vector<QualityResult> QualityWorker::take(std::uint64_t last, bool& waited) {
  std::vector<QualityResult> out;
  std::unique_lock lock(mutex_, std::defer_lock);
  if (thread_.joinable()) lock.lock();
  waited = done_through_ < last;
  if (thread_.joinable()) cv_.wait(lock, [&] { return done_through_ >= last; });
  while (!done_.empty() && done_.front().job.id <= last) {
    out.push_back(std::move(done_.front()));
    done_.pop_front();
  }
  return out;
}

void QualityWorker::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping, and nothing is left
    QualityJob job = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    QualityResult r = compute(std::move(job));
    lock.lock();
    done_through_ = r.job.id;
    done_.push_back(std::move(r));
    cv_.notify_all();
  }
}

QualityResult QualityWorker::compute(QualityJob job) {
  QualityResult r;
  if (job.forget) {
    memos_.erase(job.hand.value);
    r.job = std::move(job);
    return r;
  }
  Memo& memo = memos_[job.hand.value];
  Wrenches wrenches = contact_wrenches(job.contacts, job.mu, job.torque_scale);
  // A pure function of the wrenches (friction and radius are in them): an entry serves any object.
  auto it = std::find_if(memo.entries.begin(), memo.entries.end(),
                         [&](const Memo::Entry& e) { return wrench_distance(e.wrenches, wrenches) <= kSameWrench; });
  if (it == memo.entries.end()) {
    ++memo.computed;
    const GraspQuality q = wrench_quality(wrenches, job.volume);
    if (memo.entries.size() == kMemoEntries) memo.entries.pop_back();
    memo.entries.insert(memo.entries.begin(), Memo::Entry{std::move(wrenches), q});
  } else {
    std::rotate(memo.entries.begin(), it, it + 1);
  }
  r.quality = memo.entries.front().quality;
  r.computed = memo.computed;
  if (job.metrics && (r.metrics = job.metrics())) r.metrics->quality = r.quality;
  job.metrics = nullptr;  // releases the copy of the hand
  job.contacts.clear();
  job.contacts.shrink_to_fit();
  r.job = std::move(job);
  return r;
}

}  // namespace telegrasp::sim
