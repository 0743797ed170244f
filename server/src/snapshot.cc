#include "snapshot.h"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>

namespace telegrasp::server {
namespace {

constexpr std::size_t kMaxObjects = 128;  // the SceneState bound in telegrasp.idl
constexpr double kUnitTolerance = 1e-3;

std::int64_t unix_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

class ErrorCollector : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int line, int column, const std::string& message) override {
    if (text.empty()) text = "line " + std::to_string(line + 1) + ":" + std::to_string(column + 1) + ": " + message;
  }
  std::string text;
};

proto::SnapshotPose to_proto(const Eigen::Vector3d& p_WorldObject, const Eigen::Quaterniond& q) {
  proto::SnapshotPose p;
  p.set_x(p_WorldObject.x());
  p.set_y(p_WorldObject.y());
  p.set_z(p_WorldObject.z());
  p.set_qw(q.w());
  p.set_qx(q.x());
  p.set_qy(q.y());
  p.set_qz(q.z());
  return p;
}

std::string errno_text() { return std::strerror(errno); }

// The folder of `path` ("." for a bare file name).
std::filesystem::path folder_of(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::filesystem::path(".") : parent;
}

}  // namespace

std::uint64_t new_incarnation() {
  std::random_device device;
  std::uint64_t id = (static_cast<std::uint64_t>(device()) << 32) ^ device();
  id ^= static_cast<std::uint64_t>(unix_now_ns()) * 0x9E3779B97F4A7C15ULL;  // if random_device is weak
  return id == 0 ? 1 : id;
}

proto::SceneSnapshot make_snapshot(const msg::SceneState& scene) {
  proto::SceneSnapshot s;
  s.set_format_version(kSnapshotFormatVersion);
  s.set_incarnation(scene.incarnation());
  s.set_tick(scene.tick());
  s.set_time(scene.time());
  s.set_written_unix_ns(unix_now_ns());
  for (const msg::ObjectState& o : scene.objects()) {
    proto::SnapshotObject* p = s.add_objects();
    p->set_model(o.name().to_string());
    p->set_id(o.id());
    const msg::Pose3& pose = o.pose();
    proto::SnapshotPose* q = p->mutable_pose();
    q->set_x(pose.position().x());
    q->set_y(pose.position().y());
    q->set_z(pose.position().z());
    q->set_qw(pose.orientation().w());
    q->set_qx(pose.orientation().x());
    q->set_qy(pose.orientation().y());
    q->set_qz(pose.orientation().z());
    p->set_held(o.held());
  }
  s.set_object_count(static_cast<std::uint32_t>(s.objects_size()));
  return s;
}

proto::SceneSnapshot make_snapshot(const std::vector<PlacedObject>& objects) {
  proto::SceneSnapshot s;
  s.set_format_version(kSnapshotFormatVersion);
  int id = 0;
  for (const PlacedObject& o : objects) {
    proto::SnapshotObject* p = s.add_objects();
    p->set_model(o.model);
    p->set_id(id++);
    *p->mutable_pose() = to_proto(o.p_WorldObject, o.q_WorldObject);
  }
  s.set_object_count(static_cast<std::uint32_t>(s.objects_size()));
  return s;
}

std::vector<PlacedObject> placed_objects(const proto::SceneSnapshot& s, const std::vector<sim::ObjectModelPtr>& models,
                                         const std::string& origin) {
  auto fail = [&](const std::string& what) -> void { throw SnapshotError(origin + ": " + what); };
  if (!s.has_format_version()) fail("no format_version: not a scene snapshot");
  if (s.format_version() != kSnapshotFormatVersion)
    fail("format_version is " + std::to_string(s.format_version()) + "; this build reads " +
         std::to_string(kSnapshotFormatVersion));
  if (!s.has_object_count() || s.object_count() != static_cast<std::uint32_t>(s.objects_size()))
    fail("object_count " + (s.has_object_count() ? std::to_string(s.object_count()) : std::string("missing")) +
         " but " + std::to_string(s.objects_size()) + " objects: the file is not whole");
  if (static_cast<std::size_t>(s.objects_size()) > kMaxObjects)
    fail(std::to_string(s.objects_size()) + " objects; at most " + std::to_string(kMaxObjects));
  std::map<std::string, bool> known;
  for (const auto& m : models) known[m->name] = true;
  std::vector<PlacedObject> out;
  for (int i = 0; i < s.objects_size(); ++i) {
    const proto::SnapshotObject& o = s.objects(i);
    const std::string which = "objects[" + std::to_string(i) + "] (model '" + o.model() + "')";
    if (!known.count(o.model())) fail(which + ": no such model in this server (see --list-models)");
    const proto::SnapshotPose& p = o.pose();
    const double values[] = {p.x(), p.y(), p.z(), p.qw(), p.qx(), p.qy(), p.qz()};
    for (double v : values)
      if (!std::isfinite(v)) fail(which + ": pose has a value that is not finite");
    Eigen::Quaterniond q(p.qw(), p.qx(), p.qy(), p.qz());
    if (std::abs(q.norm() - 1) > kUnitTolerance)
      fail(which + ": pose quaternion has norm " + std::to_string(q.norm()) + "; expected 1");
    PlacedObject placed;
    placed.model = o.model();
    placed.q_WorldObject = q;
    placed.p_WorldObject = Eigen::Vector3d(p.x(), p.y(), p.z());
    out.push_back(std::move(placed));
  }
  return out;
}

std::optional<proto::SceneSnapshot> read_snapshot(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return std::nullopt;
  std::ifstream in(path);
  if (!in) throw SnapshotError("snapshot " + path + ": cannot open");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw SnapshotError("snapshot " + path + ": cannot read");
  proto::SceneSnapshot s;
  google::protobuf::TextFormat::Parser parser;
  ErrorCollector errors;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(buffer.str(), &s)) throw SnapshotError("snapshot " + path + ": " + errors.text);
  return s;
}

void write_snapshot(const std::string& path, const proto::SceneSnapshot& snapshot) {
  std::string text;
  if (!google::protobuf::TextFormat::PrintToString(snapshot, &text))
    throw SnapshotError("snapshot " + path + ": cannot format");
  text = "# telegrasp scene snapshot (server/proto/snapshot.proto), written by telegrasp-server --snapshot\n" + text;
  const std::string tmp = path + ".tmp-" + std::to_string(getpid());
  auto fail = [&](const std::string& step) {
    const std::string why = errno_text();
    ::unlink(tmp.c_str());
    throw SnapshotError("snapshot " + path + ": " + step + ": " + why);
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("cannot create " + tmp);
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ::close(fd);
      fail("cannot write " + tmp);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    ::close(fd);
    fail("cannot fsync " + tmp);
  }
  if (::close(fd) != 0) fail("cannot close " + tmp);
  if (::rename(tmp.c_str(), path.c_str()) != 0) fail("cannot rename " + tmp + " over it");
  // The rename itself reaches the disk with the folder.
  const int dir = ::open(folder_of(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
}

void check_snapshot_writable(const std::string& path) {
  const std::string probe = path + ".probe-" + std::to_string(getpid());
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0)
    throw SnapshotError("snapshot " + path + ": cannot create a file in " + folder_of(path).string() + ": " +
                        errno_text());
  ::close(fd);
  ::unlink(probe.c_str());
}

SnapshotWriter::SnapshotWriter(std::string path, OutputSink& next, double period_s)
    : path_(std::move(path)),
      next_(next),
      period_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(period_s))),
      thread_([this] { run(); }) {}

SnapshotWriter::~SnapshotWriter() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
  if (latest_) write(*latest_);  // a clean stop: the very last poses
}

void SnapshotWriter::publish(const msg::SceneState& m) {
  next_.publish(m);
  latest_ = m;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_due_) return;
  next_due_ = now + period_;
  {
    std::lock_guard lock(mutex_);
    pending_ = m;
  }
  wake_.notify_all();
}

std::uint64_t SnapshotWriter::written() const {
  std::lock_guard lock(mutex_);
  return written_;
}

void SnapshotWriter::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stop_ || pending_; });
    if (stop_) return;
    const msg::SceneState scene = std::move(*pending_);
    pending_.reset();
    lock.unlock();
    write(scene);
    lock.lock();
  }
}

void SnapshotWriter::write(const msg::SceneState& scene) {
  std::string error;
  try {
    write_snapshot(path_, make_snapshot(scene));
  } catch (const SnapshotError& e) {
    error = e.what();
  }
  std::lock_guard lock(mutex_);
  if (error.empty()) {
    ++written_;
    if (failing_) std::cerr << "telegrasp-server: snapshot " << path_ << " written again\n";
    failing_ = false;
  } else if (!failing_) {
    failing_ = true;
    std::cerr << "telegrasp-server: " << error << " (the server goes on; said once until a write succeeds)\n";
  }
}

}  // namespace telegrasp::server
