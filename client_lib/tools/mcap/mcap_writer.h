// An MCAP file writer, written to the public MCAP specification (major version 0): a leading
// magic, the Header, a data section of compressed Chunks each followed by its Message Index
// records, Data End, a summary section (Schemas, Channels, Statistics, Chunk Indexes), the
// Summary Offset records, the Footer and the trailing magic. Debian ships no MCAP library, hence
// this one; it writes only what telegrasp needs (no attachments, metadata or appending).
//
// Compression: zstd through Debian's libzstd (libzstd-dev), not lz4. zstd compresses text such as
// telegrasp's JSON messages markedly better than lz4 (4.7x at level 3 on the sample's hand state,
// transforms and logs), and lz4's extra speed buys nothing here: the writer takes ~1M such
// messages/s with zstd (telegrasp-mcap-sample --bench), far above any recording's rate. Every MCAP
// reader (Foxglove, the reference TypeScript, C++, Go and Rust readers) decodes zstd chunks.
// Compression::kNone writes uncompressed chunks.
//
// Durability: each chunk is written and flushed to the operating system as soon as it is full,
// so a process killed mid-run leaves a file that a streaming reader reads up to its last complete
// chunk (no summary or footer; the data is not fsync'ed, so a power cut may lose more).
//
// Typical use (a live recording of Foxglove channels, JSON messages with jsonschema schemas):
//   mcap::Writer writer("run.mcap", {.profile = ""});
//   const mcap::SchemaId schema =
//       writer.add_schema("foxglove.FrameTransform", mcap::kSchemaEncodingJsonSchema, schema_json);
//   const mcap::ChannelId tf = writer.add_channel("/tf", mcap::kMessageEncodingJson, schema);
//   writer.write(tf, sequence, log_time_ns, publish_time_ns, message_json);
//   writer.close();  // or let the destructor close it
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace telegrasp::mcap {

// Well-known encodings from the MCAP registry, for the Foxglove channels telegrasp writes.
inline constexpr std::string_view kSchemaEncodingJsonSchema = "jsonschema";
inline constexpr std::string_view kMessageEncodingJson = "json";

// A schema's id within one file; 0 means "no schema".
struct SchemaId {
  std::uint16_t value = 0;
  friend bool operator==(SchemaId, SchemaId) = default;
};

// A channel's id within one file.
struct ChannelId {
  std::uint16_t value = 0;
  friend bool operator==(ChannelId, ChannelId) = default;
};

enum class Compression { kNone, kZstd };

struct Options {
  // The Header's profile: "" or a well-known profile ("ros2", ...); custom ones start with "x-".
  std::string profile = "";
  // The Header's library field.
  std::string library = "telegrasp-mcap";
  // A chunk is compressed and written once its uncompressed records reach this size.
  std::uint64_t chunk_size_bytes = 1024 * 1024;
  Compression compression = Compression::kZstd;
  // zstd's level (1 fastest .. 22 smallest); ignored without compression.
  int zstd_level = 3;
};

// Where one written chunk sits in the file and what it holds.
struct ChunkInfo {
  std::uint64_t offset = 0;  // of the Chunk record (its opcode) from the start of the file
  std::uint64_t length = 0;  // of the Chunk record, opcode and length prefix included
  std::uint64_t message_count = 0;  // Message records in the chunk
  std::uint64_t uncompressed_size = 0;  // of the chunk's records
  std::uint64_t compressed_size = 0;  // of the chunk's records as stored
  std::uint64_t message_start_time_ns = 0;
  std::uint64_t message_end_time_ns = 0;
};

// Writes one MCAP file. Call add_schema and add_channel before writing on a channel, write the
// messages, then close (the destructor closes too). Not thread-safe: one writer, one thread. A
// moved-from writer may only be destroyed or assigned to.
class Writer {
 public:
  // Creates (truncates) `path` and writes the magic and the Header; throws std::runtime_error
  // naming the path when the file cannot be opened or written, std::invalid_argument for a zero
  // chunk size or a zstd level outside 1..22. After an error writing the file, the writer is
  // closed and the file keeps what reached it (its complete chunks stay readable).
  Writer(const std::string& path, Options options = {});
  ~Writer();  // Closes; an error there is printed to stderr, since a destructor cannot throw.
  Writer(Writer&&) noexcept;
  Writer& operator=(Writer&&) noexcept;
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Adds a Schema record; `encoding` is e.g. kSchemaEncodingJsonSchema, `data` the schema text.
  // Ids count up from 1. Throws std::length_error past 65535 schemas, std::logic_error after close.
  SchemaId add_schema(std::string_view name, std::string_view encoding, std::string_view data);

  // Adds a Channel record; `schema` is an id from add_schema or SchemaId{} for none. Throws
  // std::invalid_argument for an unknown schema, std::length_error past 65535 channels (ids count
  // up from 1), std::logic_error after close.
  ChannelId add_channel(std::string_view topic, std::string_view message_encoding, SchemaId schema,
                        const std::map<std::string, std::string>& metadata = {});

  // Appends one message to the open chunk and writes the chunk once it is full. Times are in
  // nanoseconds since the caller's epoch. Log times need not be ordered: each chunk's message
  // indexes are sorted by log time and its time range is its min and max, but writing in log-time
  // order keeps chunks from overlapping, which indexed readers prefer. Throws std::invalid_argument
  // for an unknown channel, std::logic_error after close, std::runtime_error naming the path when
  // the file cannot be written.
  void write(ChannelId channel, std::uint32_t sequence, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
             std::string_view data);
  void write(ChannelId channel, std::uint32_t sequence, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
             std::span<const std::byte> data);

  // Writes the open chunk (if it holds anything) and flushes the file; the file stays open.
  void flush_chunk();

  // Writes the last chunk, Data End, the summary, the Summary Offsets, the Footer and the trailing
  // magic, and closes the file. Throws std::runtime_error naming the path when that fails. Idempotent.
  void close();

  bool is_open() const;
  const std::string& path() const;
  // Bytes written to the file so far (the whole file's size once closed).
  std::uint64_t bytes_written() const;
  std::uint64_t message_count() const;
  // The chunks written so far, in file order.
  const std::vector<ChunkInfo>& chunks() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The CRC-32 MCAP uses (ISO-HDLC / zlib: reflected polynomial 0xEDB88320, initial value and final
// xor 0xFFFFFFFF). Pass a previous result as `crc` to continue over more bytes.
std::uint32_t crc32(std::span<const std::byte> bytes, std::uint32_t crc = 0);

}  // namespace telegrasp::mcap
