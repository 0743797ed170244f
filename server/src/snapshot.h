// Scene snapshots (server/proto/snapshot.proto): a server started with --snapshot FILE writes its
// objects' last published poses there about once a second and on a clean stop, atomically, and a
// server started with the file present brings its objects back at those poses. Also the server's
// incarnation: the random id of one run, published in SceneState and ServerStatus.
#pragma once

#include "output_sink.h"
#include "server_config.h"
#include "snapshot.pb.h"
#include "telegrasp/sim/object_model.h"

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace telegrasp::server {

/// A snapshot file cannot be read or written; what() names the file and what is wrong.
class SnapshotError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// SceneSnapshot.format_version this build writes and reads.
inline constexpr std::uint32_t kSnapshotFormatVersion = 1;

/// A new server incarnation: random (std::random_device mixed with the clock), never 0.
std::uint64_t new_incarnation();

/// The snapshot of a published scene state, stamped with the wall clock now.
proto::SceneSnapshot make_snapshot(const msg::SceneState& scene);
/// The snapshot of placed objects (a recording's header keeps the restored scene this way).
proto::SceneSnapshot make_snapshot(const std::vector<PlacedObject>& objects);
/// The objects of `snapshot`, checked: a format_version this build reads, object_count equal to the
/// objects, at most 128 objects, each of a model in `models` with a finite pose and a unit
/// quaternion (within 1e-3), kept as read. Throws SnapshotError starting with `origin` and naming
/// the object and field that are wrong.
std::vector<PlacedObject> placed_objects(const proto::SceneSnapshot& snapshot,
                                         const std::vector<sim::ObjectModelPtr>& models, const std::string& origin);

/// Reads the snapshot at `path`: nullopt if there is no file; throws SnapshotError naming the file
/// if it cannot be read or does not parse (with the line and column).
std::optional<proto::SceneSnapshot> read_snapshot(const std::string& path);
/// Writes `snapshot` to `path` atomically: a temporary file in the same folder, fsync, rename over
/// `path`, fsync of the folder. A reader sees the old file or the new one, never a part. Throws
/// SnapshotError naming the file and the step that failed.
void write_snapshot(const std::string& path, const proto::SceneSnapshot& snapshot);
/// Fails fast at start-up: throws SnapshotError unless a file can be created (and is removed
/// again) in the folder of `path`.
void check_snapshot_writable(const std::string& path);

/// The server's OutputSink in front of `next`: everything is forwarded; the newest SceneState is
/// also kept, and a thread of its own writes it to the snapshot file every `period_s` (so a slow
/// disk never delays a tick). The destructor writes the newest state once more (a clean stop) and
/// stops the thread. A failed write is logged to stderr (once until a write succeeds again); the
/// server goes on. publish() and hand_removed() from the simulation thread only.
class SnapshotWriter final : public OutputSink {
 public:
  SnapshotWriter(std::string path, OutputSink& next, double period_s = 1.0);
  ~SnapshotWriter() override;
  SnapshotWriter(const SnapshotWriter&) = delete;
  SnapshotWriter& operator=(const SnapshotWriter&) = delete;

  void publish(const msg::HandSkeleton& m) override { next_.publish(m); }
  void publish(const msg::GraspState& m) override { next_.publish(m); }
  void publish(const msg::ContactSet& m) override { next_.publish(m); }
  void publish(const msg::GraspEvent& m) override { next_.publish(m); }
  void publish(const msg::SceneState& m) override;
  void publish(const msg::ServerStatus& m) override { next_.publish(m); }
  void hand_removed(const HandAddress& hand) override { next_.hand_removed(hand); }

  /// Snapshots written so far.
  std::uint64_t written() const;

 private:
  void run();
  void write(const msg::SceneState& scene);

  const std::string path_;
  OutputSink& next_;
  const std::chrono::steady_clock::duration period_;
  std::optional<msg::SceneState> latest_;  // simulation thread only
  std::chrono::steady_clock::time_point next_due_{};  // simulation thread only
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<msg::SceneState> pending_;  // for the thread
  bool stop_ = false, failing_ = false;
  std::uint64_t written_ = 0;
  std::thread thread_;
};

}  // namespace telegrasp::server
