// Recordings of server runs (server/proto/recording.proto): the Recorder writes, on the
// simulation thread, every call into the SceneServer and every message it publishes; the
// RecordingReader reads them back, keeping everything before the first damaged frame.
#pragma once

#include "input_mailbox.h"
#include "output_sink.h"
#include "recording.pb.h"
#include "scene_call_observer.h"
#include "scene_setup.h"
#include "server_config.h"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

namespace telegrasp::server {

/// A recording cannot be written, or its header cannot be read; what() names the file.
class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The first bytes of every recording.
inline constexpr char kRecordingMagic[] = "telegrasp-recording\n";
inline constexpr std::size_t kRecordingMagicSize = sizeof(kRecordingMagic) - 1;
/// RecordingHeader.format_version this build writes (and the newest it reads).
inline constexpr std::uint32_t kRecordingFormatVersion = 1;
/// A frame longer than this is taken as a corrupt length.
inline constexpr std::uint32_t kMaxFrameBytes = 64u << 20;

/// CRC-32 (IEEE 802.3, the one zlib's crc32 computes) of `size` bytes, continuing from `crc`.
std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc = 0);
/// SHA-256 (hex) of the idl/telegrasp.idl this build was made from.
const char* idl_sha256();
/// The telegrasp version of this build, e.g. "0.1.0".
const char* telegrasp_version();

/// Wire messages as their CDR bytes (little-endian, with encapsulation), and back. from_cdr
/// returns false if the bytes do not decode as that type.
std::string to_cdr(const msg::ControllerState& m);
std::string to_cdr(const msg::SceneCommand& m);
std::string to_cdr(const msg::HandSkeleton& m);
std::string to_cdr(const msg::GraspState& m);
std::string to_cdr(const msg::ContactSet& m);
std::string to_cdr(const msg::GraspEvent& m);
std::string to_cdr(const msg::SceneState& m);
std::string to_cdr(const msg::ServerStatus& m);
bool from_cdr(const std::string& bytes, msg::ControllerState& m);
bool from_cdr(const std::string& bytes, msg::SceneCommand& m);
bool from_cdr(const std::string& bytes, msg::HandSkeleton& m);
bool from_cdr(const std::string& bytes, msg::GraspState& m);
bool from_cdr(const std::string& bytes, msg::ContactSet& m);
bool from_cdr(const std::string& bytes, msg::GraspEvent& m);
bool from_cdr(const std::string& bytes, msg::SceneState& m);
bool from_cdr(const std::string& bytes, msg::ServerStatus& m);

/// The output type of each wire message the server publishes (the argument only picks the type).
constexpr proto::OutputType output_type_of(const msg::HandSkeleton*) { return proto::OUTPUT_HAND_SKELETON; }
constexpr proto::OutputType output_type_of(const msg::GraspState*) { return proto::OUTPUT_GRASP_STATE; }
constexpr proto::OutputType output_type_of(const msg::ContactSet*) { return proto::OUTPUT_CONTACT_SET; }
constexpr proto::OutputType output_type_of(const msg::GraspEvent*) { return proto::OUTPUT_GRASP_EVENT; }
constexpr proto::OutputType output_type_of(const msg::SceneState*) { return proto::OUTPUT_SCENE_STATE; }
constexpr proto::OutputType output_type_of(const msg::ServerStatus*) { return proto::OUTPUT_SERVER_STATUS; }

/// Calls `f(std::type_identity<M>{})` with the wire message type M an output of `type` carries
/// (HandSkeleton, GraspState, ContactSet, GraspEvent, SceneState, ServerStatus) and returns true;
/// false, without calling it, for a hand removal or a type this build does not know.
template <class F>
bool visit_output_type(proto::OutputType type, F&& f) {
  const auto visit = [&]<class... M>(std::type_identity<std::tuple<M...>>) {
    return ((type == output_type_of(static_cast<const M*>(nullptr)) && (f(std::type_identity<M>{}), true)) || ...);
  };
  return visit(std::type_identity<std::tuple<msg::HandSkeleton, msg::GraspState, msg::ContactSet, msg::GraspEvent,
                                             msg::SceneState, msg::ServerStatus>>{});
}

/// The header a server with these settings and assets writes (created now).
proto::RecordingHeader make_recording_header(const ServerSettings& settings, const SceneAssets& assets);

/// Writes the framing of recording.proto: magic, header, then records. Buffered: bytes reach the
/// file on flush(), when the buffer passes 1 MiB, and on close() (also called by the destructor),
/// which first appends the End record. Not thread-safe.
class RecordingWriter {
 public:
  /// Creates (truncates) `path` and writes the magic and header; throws RecordingError naming
  /// the path if it cannot.
  RecordingWriter(const std::string& path, const proto::RecordingHeader& header);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  /// Appends one record. After a write error it does nothing (see error()).
  void write(const proto::Record& record);
  /// Hands the buffered bytes to the operating system.
  void flush();
  /// Appends the End record (unless `end_record` is false: the file then reads as cut short,
  /// like a killed server's), flushes and closes; later calls do nothing.
  void close(bool end_record = true);
  /// "" or the first write error, naming the file.
  const std::string& error() const { return error_; }
  std::uint64_t records() const { return records_; }
  const std::string& path() const { return path_; }

 private:
  void append_frame(const google::protobuf::MessageLite& message);

  std::string path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
  std::uint64_t records_ = 0;
  std::string error_;
};

/// Records a server run at the simulation thread's boundary: it is the ServerLoop's
/// SceneCallObserver (or, driving a SceneServer by hand: inputs() before on_inputs with the same
/// samples, command() before apply_command, tick() before tick), and the SceneServer's OutputSink
/// (ServerStatus too): each output is recorded, then forwarded to `next`. Bytes reach the file (the
/// operating system: they survive the server's SIGKILL, not a power cut) before each SceneState, a
/// tick's last output, and before each GraspEvent and ServerStatus, is forwarded: a subscriber
/// never has one of those the file lacks, and a killed server's file keeps every tick before the
/// one it was killed in (telegrasp-replay reads it up to the cut). That is one write() per tick.
/// The destructor closes the file with its End record. A write error at run time is logged once
/// to stderr and ends the recording; the server goes on. Simulation thread only.
class Recorder : public OutputSink, public SceneCallObserver {
 public:
  /// Throws RecordingError naming `path` if it cannot be written.
  Recorder(const std::string& path, const ServerSettings& settings, const SceneAssets& assets, OutputSink& next);

  void inputs(const std::vector<InputSample>& samples, std::int64_t now_ns) override;
  void command(const msg::SceneCommand& command, std::int64_t now_ns) override;
  void tick(std::int64_t now_ns) override;

  void publish(const msg::HandSkeleton& m) override;
  void publish(const msg::GraspState& m) override;
  void publish(const msg::ContactSet& m) override;
  void publish(const msg::GraspEvent& m) override;
  void publish(const msg::SceneState& m) override;
  void publish(const msg::ServerStatus& m) override;
  /// Not recorded (a replay derives it from the recorded commands): forwarded.
  void publish(const msg::ClientNotice& m) override { next_.publish(m); }
  void hand_removed(const HandAddress& hand) override;

  /// Records written so far.
  std::uint64_t records() const { return writer_.records(); }
  /// "" or why recording stopped.
  const std::string& error() const { return writer_.error(); }

 private:
  void output(proto::OutputType type, std::string cdr);
  void write(const proto::Record& record);
  void flush_now();
  void log_error_once();

  RecordingWriter writer_;
  OutputSink& next_;
  bool error_logged_ = false;
};

/// Where a recording is damaged: its first bad frame.
struct RecordingDamage {
  std::uint64_t record = 0;  ///< Index of the first damaged record = the records kept before it.
  std::uint64_t byte = 0;  ///< Offset of its frame in the file.
  bool truncated = false;  ///< The file ends inside (or, with no End record, at) this frame; else corrupt.
  std::string message;  ///< "recording F: record K at byte B is truncated (...); the K records before it are kept".
};

/// Reads a recording one record at a time. The magic and header are read on construction; every
/// record after them is returned until the End record, the end of the file, or the first
/// damaged frame (damage() then says where and why).
class RecordingReader {
 public:
  /// Throws RecordingError naming `path` if it cannot be opened, is not a recording, is of a
  /// newer format, or its header is damaged.
  explicit RecordingReader(const std::string& path);

  const proto::RecordingHeader& header() const { return header_; }
  /// The next record (never an End record); false at the end or at damage.
  bool next(proto::Record& record);
  /// Records returned so far.
  std::uint64_t records() const { return records_; }
  /// Bytes consumed so far, and the file's size (for progress).
  std::uint64_t offset() const { return offset_; }
  std::uint64_t file_size() const { return file_size_; }
  /// Set once next() has stopped at damage.
  const std::optional<RecordingDamage>& damage() const { return damage_; }
  /// True once the End record was read.
  bool complete() const { return complete_; }
  const std::string& path() const { return path_; }

 private:
  enum class Frame { kOk, kEndOfFile, kTruncated, kCorrupt };
  Frame read_frame(std::string& payload, std::string& why);
  bool fail(bool truncated, const std::string& why);

  std::string path_;
  std::ifstream in_;
  std::uint64_t offset_ = 0, file_size_ = 0, frame_start_ = 0;
  proto::RecordingHeader header_;
  std::uint64_t records_ = 0;
  std::optional<RecordingDamage> damage_;
  bool complete_ = false, finished_ = false;
};

/// A whole recording in memory (tests, small files).
struct Recording {
  proto::RecordingHeader header;
  std::vector<proto::Record> records;
  std::optional<RecordingDamage> damage;
  bool complete = false;
};
/// Reads every record of `path`; throws RecordingError as RecordingReader does.
Recording read_recording(const std::string& path);
/// Writes `header` and `records`, then an End record unless `complete` is false.
void write_recording(const std::string& path, const proto::RecordingHeader& header,
                     const std::vector<proto::Record>& records, bool complete = true);

}  // namespace telegrasp::server
