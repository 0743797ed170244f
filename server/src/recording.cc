#include "recording.h"

#include "snapshot.h"

#include "server_config.pb.h"

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <iostream>

#ifndef TELEGRASP_IDL_SHA256
#error "TELEGRASP_IDL_SHA256 is defined by server/CMakeLists.txt"
#endif
#ifndef TELEGRASP_VERSION
#error "TELEGRASP_VERSION is defined by server/CMakeLists.txt"
#endif

namespace telegrasp::server {
namespace {

constexpr std::size_t kFlushBytes = 1u << 20;

// The reflected IEEE polynomial's table, built once.
const std::array<std::uint32_t, 256>& crc_table() {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  return table;
}

template <class T>
std::string serialize(const T& m) {
  // Into a zeroed buffer of the computed size (plus the encapsulation and some slack): Fast CDR
  // skips alignment padding without writing it, and a buffer it grows itself keeps whatever the
  // allocator left there, so equal messages would not always give equal bytes (replay compares
  // bytes).
  std::string out(4 + T::getCdrSerializedSize(m) + 64, '\0');
  eprosima::fastcdr::FastBuffer buffer(out.data(), out.size());
  // Little-endian whatever the host, so a recording reads the same everywhere.
  eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::LITTLE_ENDIANNESS, eprosima::fastcdr::Cdr::DDS_CDR);
  cdr.serialize_encapsulation();
  m.serialize(cdr);
  out.resize(cdr.getSerializedDataLength());
  return out;
}

template <class T>
bool deserialize(const std::string& bytes, T& m) {
  if (bytes.empty()) return false;
  eprosima::fastcdr::FastBuffer buffer(const_cast<char*>(bytes.data()), bytes.size());
  eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
  try {
    cdr.read_encapsulation();
    m.deserialize(cdr);
  } catch (const eprosima::fastcdr::exception::Exception&) {
    return false;
  }
  return cdr.getSerializedDataLength() == bytes.size();  // trailing bytes: another type
}

void append_varint(std::string& out, std::uint32_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
}

std::string plural(std::uint64_t n, const char* word) { return std::to_string(n) + " " + word + (n == 1 ? "" : "s"); }

}  // namespace

std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc) {
  const auto& t = crc_table();
  const auto* p = static_cast<const unsigned char*>(data);
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) crc = t[(crc ^ p[i]) & 0xffu] ^ (crc >> 8);
  return ~crc;
}

const char* idl_sha256() { return TELEGRASP_IDL_SHA256; }
const char* telegrasp_version() { return TELEGRASP_VERSION; }

std::string to_cdr(const msg::ControllerState& m) { return serialize(m); }
std::string to_cdr(const msg::SceneCommand& m) { return serialize(m); }
std::string to_cdr(const msg::HandSkeleton& m) { return serialize(m); }
std::string to_cdr(const msg::GraspState& m) { return serialize(m); }
std::string to_cdr(const msg::ContactSet& m) { return serialize(m); }
std::string to_cdr(const msg::GraspEvent& m) { return serialize(m); }
std::string to_cdr(const msg::SceneState& m) { return serialize(m); }
std::string to_cdr(const msg::ServerStatus& m) { return serialize(m); }
bool from_cdr(const std::string& b, msg::ControllerState& m) { return deserialize(b, m); }
bool from_cdr(const std::string& b, msg::SceneCommand& m) { return deserialize(b, m); }
bool from_cdr(const std::string& b, msg::HandSkeleton& m) { return deserialize(b, m); }
bool from_cdr(const std::string& b, msg::GraspState& m) { return deserialize(b, m); }
bool from_cdr(const std::string& b, msg::ContactSet& m) { return deserialize(b, m); }
bool from_cdr(const std::string& b, msg::GraspEvent& m) { return deserialize(b, m); }
bool from_cdr(const std::string& b, msg::SceneState& m) { return deserialize(b, m); }
bool from_cdr(const std::string& b, msg::ServerStatus& m) { return deserialize(b, m); }

proto::RecordingHeader make_recording_header(const ServerSettings& settings, const SceneAssets& assets) {
  proto::RecordingHeader h;
  h.set_format_version(kRecordingFormatVersion);
  h.set_telegrasp_version(TELEGRASP_VERSION);
  h.set_created_unix_ns(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count());
  *h.mutable_config() = to_proto(settings);
  h.mutable_right_rig()->set_path(assets.right_rig_path);
  h.mutable_right_rig()->set_text(assets.right_rig_text);
  h.mutable_left_rig()->set_path(assets.left_rig_path);
  h.mutable_left_rig()->set_text(assets.left_rig_text);
  proto::ModelSource* ms = h.mutable_models();
  ms->set_builtin_standins(assets.model_source.objects_dir.empty());
  ms->set_objects_dir(assets.model_source.objects_dir);
  for (const MeshFileInfo& f : assets.model_source.files) {
    proto::MeshFile* p = ms->add_files();
    p->set_name(f.name);
    p->set_size(f.size);
    p->set_fnv1a64(f.fnv1a64);
  }
  for (const std::string& n : assets.model_source.standins) ms->add_standin_names(n);
  for (const auto& m : assets.models) ms->add_model_names(m->name);
  h.set_idl_sha256(TELEGRASP_IDL_SHA256);
  h.set_incarnation(settings.incarnation);
  if (settings.restored_objects) *h.mutable_restored_scene() = make_snapshot(*settings.restored_objects);
  return h;
}

// ---------------------------------------------------------------------------------------------
// RecordingWriter

RecordingWriter::RecordingWriter(const std::string& path, const proto::RecordingHeader& header) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw RecordingError("recording " + path + ": cannot write (" + std::strerror(errno) + ")");
  buffer_.assign(kRecordingMagic, kRecordingMagicSize);
  append_frame(header);
  flush();  // the header is on disk before the first tick
  if (!error_.empty()) throw RecordingError(error_);
}

RecordingWriter::~RecordingWriter() { close(); }

void RecordingWriter::append_frame(const google::protobuf::MessageLite& message) {
  const std::size_t start = buffer_.size();
  append_varint(buffer_, static_cast<std::uint32_t>(message.ByteSizeLong()));
  message.AppendToString(&buffer_);
  // The checksum covers the length too, so a flipped length byte is caught as well.
  const std::uint32_t crc = crc32(buffer_.data() + start, buffer_.size() - start);
  for (int i = 0; i < 4; ++i) buffer_.push_back(static_cast<char>((crc >> (8 * i)) & 0xffu));
}

void RecordingWriter::write(const proto::Record& record) {
  if (!file_) return;
  append_frame(record);
  ++records_;
  if (buffer_.size() >= kFlushBytes) flush();
}

void RecordingWriter::flush() {
  if (!file_) return;
  if (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size()) {
    error_ = "recording " + path_ + ": write failed (" + std::strerror(errno) + ")";
  } else if (std::fflush(file_) != 0) {
    error_ = "recording " + path_ + ": write failed (" + std::strerror(errno) + ")";
  }
  buffer_.clear();
  if (!error_.empty()) {
    std::fclose(file_);
    file_ = nullptr;
  }
}

void RecordingWriter::close(bool end_record) {
  if (!file_) return;
  if (end_record) {
    proto::Record end;
    end.mutable_end()->set_records(records_);
    append_frame(end);
  }
  flush();
  if (file_ && std::fclose(file_) != 0 && error_.empty())
    error_ = "recording " + path_ + ": close failed (" + std::strerror(errno) + ")";
  file_ = nullptr;
}

// ---------------------------------------------------------------------------------------------
// Recorder

Recorder::Recorder(const std::string& path, const ServerSettings& settings, const SceneAssets& assets, OutputSink& next)
    : writer_(path, make_recording_header(settings, assets)), next_(next) {}

void Recorder::write(const proto::Record& record) {
  writer_.write(record);
  log_error_once();
}

void Recorder::log_error_once() {
  if (!writer_.error().empty() && !error_logged_) {
    std::cerr << "telegrasp-server: " << writer_.error() << ": recording stopped after " << writer_.records()
              << " records\n";
    error_logged_ = true;
  }
}

void Recorder::flush_now() {
  writer_.flush();
  log_error_once();
}

void Recorder::inputs(const std::vector<InputSample>& samples, std::int64_t now_ns) {
  proto::Record r;
  proto::Inputs* in = r.mutable_inputs();
  in->set_now_ns(now_ns);
  for (const InputSample& s : samples) {
    proto::InputSample* p = in->add_samples();
    p->mutable_hand()->set_client_id(s.hand.client_id);
    p->mutable_hand()->set_side(s.hand.side);
    p->set_controller_state_cdr(to_cdr(s.state));
    p->set_received_ns(s.received_ns);
  }
  write(r);
}

void Recorder::command(const msg::SceneCommand& command, std::int64_t now_ns) {
  proto::Record r;
  r.mutable_command()->set_now_ns(now_ns);
  r.mutable_command()->set_scene_command_cdr(to_cdr(command));
  write(r);
}

void Recorder::tick(std::int64_t now_ns) {
  proto::Record r;
  r.mutable_tick()->set_now_ns(now_ns);
  write(r);
}

void Recorder::output(proto::OutputType type, std::string cdr) {
  proto::Record r;
  r.mutable_output()->set_type(type);
  r.mutable_output()->set_cdr(std::move(cdr));
  write(r);
}

void Recorder::publish(const msg::HandSkeleton& m) {
  output(proto::OUTPUT_HAND_SKELETON, to_cdr(m));
  next_.publish(m);
}
void Recorder::publish(const msg::GraspState& m) {
  output(proto::OUTPUT_GRASP_STATE, to_cdr(m));
  next_.publish(m);
}
void Recorder::publish(const msg::ContactSet& m) {
  output(proto::OUTPUT_CONTACT_SET, to_cdr(m));
  next_.publish(m);
}
void Recorder::publish(const msg::GraspEvent& m) {
  output(proto::OUTPUT_GRASP_EVENT, to_cdr(m));
  flush_now();  // in the file before any subscriber can have it
  next_.publish(m);
}
void Recorder::publish(const msg::SceneState& m) {
  output(proto::OUTPUT_SCENE_STATE, to_cdr(m));
  flush_now();  // the tick's last output: the whole tick is in the file before its scene goes out
  next_.publish(m);
}
void Recorder::publish(const msg::ServerStatus& m) {
  output(proto::OUTPUT_SERVER_STATUS, to_cdr(m));
  flush_now();
  next_.publish(m);
}
void Recorder::hand_removed(const HandAddress& hand) {
  proto::Record r;
  r.mutable_output()->set_type(proto::OUTPUT_HAND_REMOVED);
  r.mutable_output()->mutable_removed()->set_client_id(hand.client_id);
  r.mutable_output()->mutable_removed()->set_side(hand.side);
  write(r);
  next_.hand_removed(hand);
}

// ---------------------------------------------------------------------------------------------
// RecordingReader

RecordingReader::RecordingReader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
  if (!in_) throw RecordingError("recording " + path + ": cannot open (" + std::strerror(errno) + ")");
  in_.seekg(0, std::ios::end);
  file_size_ = static_cast<std::uint64_t>(in_.tellg());
  in_.seekg(0);
  char magic[kRecordingMagicSize];
  in_.read(magic, kRecordingMagicSize);
  if (static_cast<std::size_t>(in_.gcount()) != kRecordingMagicSize ||
      std::memcmp(magic, kRecordingMagic, kRecordingMagicSize) != 0)
    throw RecordingError("recording " + path +
                         ": not a telegrasp recording (it does not start with \"telegrasp-recording\")");
  offset_ = kRecordingMagicSize;
  std::string payload, why;
  const Frame f = read_frame(payload, why);
  auto header_error = [&](const char* what, const std::string& detail) {
    return RecordingError("recording " + path + ": header at byte " + std::to_string(frame_start_) + " is " + what +
                          " (" + detail + ")");
  };
  if (f == Frame::kEndOfFile) throw header_error("missing", "the file ends after the magic");
  if (f == Frame::kTruncated) throw header_error("truncated", why);
  if (f == Frame::kCorrupt) throw header_error("corrupt", why);
  if (!header_.ParseFromString(payload)) throw header_error("corrupt", "not a RecordingHeader message");
  if (header_.format_version() == 0 || header_.format_version() > kRecordingFormatVersion)
    throw RecordingError("recording " + path + ": format version " + std::to_string(header_.format_version()) +
                         ", this build reads versions 1 to " + std::to_string(kRecordingFormatVersion));
}

RecordingReader::Frame RecordingReader::read_frame(std::string& payload, std::string& why) {
  frame_start_ = offset_;
  unsigned char length_bytes[5];
  std::size_t n = 0;
  std::uint64_t length = 0;
  for (;;) {
    const int c = in_.get();
    if (c == std::char_traits<char>::eof()) {
      if (n == 0) return Frame::kEndOfFile;
      why = "the file ends inside its length";
      return Frame::kTruncated;
    }
    ++offset_;
    if (n == sizeof length_bytes) {
      why = "its length is not a varint32";
      return Frame::kCorrupt;
    }
    length_bytes[n] = static_cast<unsigned char>(c);
    length |= static_cast<std::uint64_t>(c & 0x7f) << (7 * n);
    ++n;
    if (!(c & 0x80)) break;
  }
  if (length > kMaxFrameBytes) {
    why = "its length " + std::to_string(length) + " exceeds " + std::to_string(kMaxFrameBytes) + " bytes";
    return Frame::kCorrupt;
  }
  payload.resize(length);
  in_.read(payload.data(), static_cast<std::streamsize>(length));
  offset_ += static_cast<std::uint64_t>(in_.gcount());
  if (static_cast<std::uint64_t>(in_.gcount()) < length) {
    why = "its length says " + std::to_string(length) + " bytes and a checksum, the file has " +
          std::to_string(in_.gcount()) + " left";
    return Frame::kTruncated;
  }
  unsigned char stored[4];
  in_.read(reinterpret_cast<char*>(stored), 4);
  offset_ += static_cast<std::uint64_t>(in_.gcount());
  if (in_.gcount() < 4) {
    why = "the file ends inside its checksum";
    return Frame::kTruncated;
  }
  const std::uint32_t expected = static_cast<std::uint32_t>(stored[0]) | static_cast<std::uint32_t>(stored[1]) << 8 |
                                 static_cast<std::uint32_t>(stored[2]) << 16 |
                                 static_cast<std::uint32_t>(stored[3]) << 24;
  const std::uint32_t actual = crc32(payload.data(), payload.size(), crc32(length_bytes, n));
  if (actual != expected) {
    why = "checksum mismatch";
    return Frame::kCorrupt;
  }
  return Frame::kOk;
}

bool RecordingReader::fail(bool truncated, const std::string& why) {
  RecordingDamage d;
  d.record = records_;
  d.byte = frame_start_;
  d.truncated = truncated;
  d.message = "recording " + path_ + ": record " + std::to_string(records_) + " at byte " +
              std::to_string(frame_start_) + " is " + (truncated ? "truncated" : "corrupt") + " (" + why + "); the " +
              plural(records_, "record") + " before it are kept";
  damage_ = std::move(d);
  finished_ = true;
  return false;
}

bool RecordingReader::next(proto::Record& record) {
  if (finished_) return false;
  std::string payload, why;
  switch (read_frame(payload, why)) {
    case Frame::kEndOfFile:
      return fail(true, "the file ends without the End record a closed recorder writes: was the server killed?");
    case Frame::kTruncated:
      return fail(true, why);
    case Frame::kCorrupt:
      return fail(false, why);
    case Frame::kOk:
      break;
  }
  record.Clear();
  if (!record.ParseFromString(payload) || record.kind_case() == proto::Record::KIND_NOT_SET)
    return fail(false, "not a Record message");
  if (!record.has_end()) {
    ++records_;
    return true;
  }
  if (record.end().records() != records_)
    return fail(false, "its End record counts " + plural(record.end().records(), "record") + ", the file has " +
                           std::to_string(records_));
  complete_ = true;
  frame_start_ = offset_;
  if (in_.peek() != std::char_traits<char>::eof()) return fail(false, "bytes follow the End record");
  finished_ = true;
  return false;
}

Recording read_recording(const std::string& path) {
  RecordingReader reader(path);
  Recording r;
  r.header = reader.header();
  proto::Record record;
  while (reader.next(record)) r.records.push_back(record);
  r.damage = reader.damage();
  r.complete = reader.complete();
  return r;
}

void write_recording(const std::string& path, const proto::RecordingHeader& header,
                     const std::vector<proto::Record>& records, bool complete) {
  RecordingWriter w(path, header);
  for (const auto& r : records) w.write(r);
  w.close(complete);
  if (!w.error().empty()) throw RecordingError(w.error());
}

}  // namespace telegrasp::server
