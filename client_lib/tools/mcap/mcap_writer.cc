// MCAP writer: record layouts follow the MCAP specification's "Records" and "Serialization"
// sections (little-endian integers, uint32-length-prefixed strings, maps and arrays).
#include "mcap_writer.h"

#include <zstd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <utility>

namespace telegrasp::mcap {
namespace {

// "\x89MCAP0\r\n": the magic at both ends of the file (major version '0').
constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Opcode (1) + content length (8).
constexpr std::uint64_t kRecordPrefixSize = 9;
// A Message record's fixed fields: channel_id, sequence, log_time, publish_time.
constexpr std::uint64_t kMessageFixedSize = 2 + 4 + 8 + 8;

// CRC-32 lookup tables for slicing by 8: table[0] is the classic byte-at-a-time table, table[k]
// advances a byte's contribution by k more zero bytes.
using CrcTables = std::array<std::array<std::uint32_t, 256>, 8>;

CrcTables make_crc_tables() {
  CrcTables t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
    t[0][i] = c;
  }
  for (std::size_t k = 1; k < 8; ++k)
    for (std::size_t i = 0; i < 256; ++i) t[k][i] = (t[k - 1][i] >> 8) ^ t[0][t[k - 1][i] & 0xFFu];
  return t;
}

const CrcTables kCrc = make_crc_tables();

// Little-endian serialization into a growing byte vector.
class Bytes {
 public:
  void u8(std::uint8_t v) { out_.push_back(std::byte{v}); }
  void u16(std::uint16_t v) { le(v, 2); }
  void u32(std::uint32_t v) { le(v, 4); }
  void u64(std::uint64_t v) { le(v, 8); }
  void raw(const void* data, std::size_t size) {
    const auto* p = static_cast<const std::byte*>(data);
    out_.insert(out_.end(), p, p + size);
  }
  void string(std::string_view s) {
    u32(checked_u32(s.size(), "string"));
    raw(s.data(), s.size());
  }
  // Overwrites 8 bytes at `at` (a length reserved earlier).
  void patch_u64(std::size_t at, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out_[at + i] = std::byte(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  // Starts a record: opcode and a length placeholder; returns the placeholder's position.
  std::size_t begin_record(std::uint8_t opcode) {
    u8(opcode);
    const std::size_t at = out_.size();
    u64(0);
    return at;
  }
  void end_record(std::size_t length_at) { patch_u64(length_at, out_.size() - length_at - 8); }

  std::size_t size() const { return out_.size(); }
  std::span<const std::byte> view() const { return out_; }
  void clear() { out_.clear(); }
  void reserve(std::size_t n) { out_.reserve(n); }

  static std::uint32_t checked_u32(std::size_t n, const char* what) {
    if (n > std::numeric_limits<std::uint32_t>::max())
      throw std::length_error(std::string("mcap: ") + what + " longer than 4 GiB");
    return static_cast<std::uint32_t>(n);
  }

 private:
  void le(std::uint64_t v, int n) {
    const std::size_t at = out_.size();
    out_.resize(at + n);
    for (int i = 0; i < n; ++i) out_[at + i] = std::byte(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  std::vector<std::byte> out_;
};

// One Message Index entry: a message's log time and its offset in the uncompressed chunk.
struct IndexEntry {
  std::uint64_t log_time_ns;
  std::uint64_t offset;
};

}  // namespace

std::uint32_t crc32(std::span<const std::byte> bytes, std::uint32_t crc) {
  std::uint32_t c = ~crc;
  const std::byte* p = bytes.data();
  std::size_t n = bytes.size();
  const auto byte = [&p](int i) { return std::to_integer<std::uint32_t>(p[i]); };
  for (; n >= 8; n -= 8, p += 8) {
    const std::uint32_t lo = c ^ (byte(0) | byte(1) << 8 | byte(2) << 16 | byte(3) << 24);
    const std::uint32_t hi = byte(4) | byte(5) << 8 | byte(6) << 16 | byte(7) << 24;
    c = kCrc[7][lo & 0xFFu] ^ kCrc[6][(lo >> 8) & 0xFFu] ^ kCrc[5][(lo >> 16) & 0xFFu] ^ kCrc[4][lo >> 24] ^
        kCrc[3][hi & 0xFFu] ^ kCrc[2][(hi >> 8) & 0xFFu] ^ kCrc[1][(hi >> 16) & 0xFFu] ^ kCrc[0][hi >> 24];
  }
  for (; n > 0; --n, ++p) c = kCrc[0][(c ^ byte(0)) & 0xFFu] ^ (c >> 8);
  return ~c;
}

struct Writer::Impl {
  std::string path;
  Options options;
  std::FILE* file = nullptr;
  ZSTD_CCtx* zstd = nullptr;

  std::uint64_t position = 0;  // bytes written to the file
  // Running CRCs of the data section (magic through the record before Data End) and of the
  // summary (its first record through the Footer's summary_offset_start).
  enum class CrcSpan { kData, kSummary, kNone } crc_span = CrcSpan::kData;
  std::uint32_t data_crc = 0;
  std::uint32_t summary_crc = 0;

  // Serialized Schema and Channel records, repeated in the summary.
  std::vector<Bytes> schema_records;
  std::vector<Bytes> channel_records;
  std::vector<std::uint64_t> channel_message_counts;  // by channel id - 1

  std::uint64_t message_count = 0;
  std::uint64_t message_start_ns = 0;
  std::uint64_t message_end_ns = 0;

  // The open chunk: its uncompressed records and per-channel index entries.
  Bytes chunk;
  std::map<std::uint16_t, std::vector<IndexEntry>> chunk_index;
  std::uint64_t chunk_messages = 0;
  std::uint64_t chunk_start_ns = 0;
  std::uint64_t chunk_end_ns = 0;
  std::vector<std::byte> compressed;

  Bytes chunk_index_records;
  std::vector<ChunkInfo> chunks;

  ~Impl() {
    if (file != nullptr) std::fclose(file);
    ZSTD_freeCCtx(zstd);
  }

  [[noreturn]] void fail(const std::string& what) {
    const std::string reason = errno != 0 ? std::string(": ") + std::strerror(errno) : "";
    if (file != nullptr) std::fclose(file);
    file = nullptr;
    throw std::runtime_error("mcap: " + what + " " + path + reason);
  }

  void require_open(const char* call) const {
    if (file == nullptr) throw std::logic_error(std::string("mcap: ") + call + " on closed writer of " + path);
  }

  void write_raw(std::span<const std::byte> bytes) {
    if (bytes.empty()) return;
    errno = 0;
    if (std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size()) fail("cannot write");
    position += bytes.size();
    if (crc_span == CrcSpan::kData) data_crc = crc32(bytes, data_crc);
    if (crc_span == CrcSpan::kSummary) summary_crc = crc32(bytes, summary_crc);
  }

  void flush_file() {
    errno = 0;
    if (std::fflush(file) != 0) fail("cannot flush");
  }

  std::span<const std::byte> compress(std::span<const std::byte> records) {
    compressed.resize(ZSTD_compressBound(records.size()));
    const std::size_t n = ZSTD_compress2(zstd, compressed.data(), compressed.size(), records.data(), records.size());
    if (ZSTD_isError(n)) {
      errno = 0;
      fail(std::string("zstd failed (") + ZSTD_getErrorName(n) + ") writing");
    }
    return std::span<const std::byte>(compressed.data(), n);
  }

  // Writes the open chunk, its Message Index records after it, and flushes; keeps its Chunk Index.
  void write_chunk() {
    if (chunk_messages == 0) return;
    const std::span<const std::byte> records = chunk.view();
    const bool zstd_on = options.compression == Compression::kZstd;
    const std::span<const std::byte> stored = zstd_on ? compress(records) : records;
    const std::string_view compression = zstd_on ? "zstd" : "";

    // Chunk: times, uncompressed size and CRC, compression, then uint64-prefixed records.
    Bytes head;
    const std::size_t length_at = head.begin_record(kChunk);
    head.u64(chunk_start_ns);
    head.u64(chunk_end_ns);
    head.u64(records.size());
    head.u32(crc32(records));
    head.string(compression);
    head.u64(stored.size());
    head.patch_u64(length_at, head.size() - kRecordPrefixSize + stored.size());
    const std::uint64_t chunk_offset = position;
    write_raw(head.view());
    write_raw(stored);
    const std::uint64_t chunk_length = position - chunk_offset;

    // One Message Index per channel in the chunk, entries sorted by log time.
    std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;
    const std::uint64_t indexes_start = position;
    Bytes index;
    for (auto& [channel, entries] : chunk_index) {
      std::stable_sort(entries.begin(), entries.end(),
                       [](const IndexEntry& a, const IndexEntry& b) { return a.log_time_ns < b.log_time_ns; });
      index.clear();
      const std::size_t at = index.begin_record(kMessageIndex);
      index.u16(channel);
      index.u32(Bytes::checked_u32(entries.size() * 16, "message index"));
      for (const IndexEntry& e : entries) {
        index.u64(e.log_time_ns);
        index.u64(e.offset);
      }
      index.end_record(at);
      index_offsets.emplace_back(channel, position);
      write_raw(index.view());
    }
    const std::uint64_t indexes_length = position - indexes_start;
    flush_file();

    // Chunk Index, for the summary.
    const std::size_t at = chunk_index_records.begin_record(kChunkIndex);
    chunk_index_records.u64(chunk_start_ns);
    chunk_index_records.u64(chunk_end_ns);
    chunk_index_records.u64(chunk_offset);
    chunk_index_records.u64(chunk_length);
    chunk_index_records.u32(static_cast<std::uint32_t>(index_offsets.size() * 10));
    for (const auto& [channel, offset] : index_offsets) {
      chunk_index_records.u16(channel);
      chunk_index_records.u64(offset);
    }
    chunk_index_records.u64(indexes_length);
    chunk_index_records.string(compression);
    chunk_index_records.u64(stored.size());
    chunk_index_records.u64(records.size());
    chunk_index_records.end_record(at);

    chunks.push_back(ChunkInfo{.offset = chunk_offset,
                               .length = chunk_length,
                               .message_count = chunk_messages,
                               .uncompressed_size = records.size(),
                               .compressed_size = stored.size(),
                               .message_start_time_ns = chunk_start_ns,
                               .message_end_time_ns = chunk_end_ns});
    chunk.clear();
    chunk_index.clear();
    chunk_messages = 0;
  }

  // Writes a group of summary records and returns its Summary Offset (group length 0 if empty).
  std::pair<std::uint64_t, std::uint64_t> write_group(std::span<const std::byte> records) {
    const std::uint64_t start = position;
    write_raw(records);
    return {start, position - start};
  }

  void close() {
    write_chunk();

    // Data End closes the data section with its CRC.
    crc_span = CrcSpan::kNone;
    Bytes data_end;
    const std::size_t de = data_end.begin_record(kDataEnd);
    data_end.u32(data_crc);
    data_end.end_record(de);
    write_raw(data_end.view());

    // Summary, grouped by opcode: Schemas, Channels, Statistics, Chunk Indexes.
    crc_span = CrcSpan::kSummary;
    const std::uint64_t summary_start = position;
    std::vector<std::pair<std::uint8_t, std::pair<std::uint64_t, std::uint64_t>>> groups;
    Bytes group;
    for (const Bytes& r : schema_records) group.raw(r.view().data(), r.size());
    groups.emplace_back(kSchema, write_group(group.view()));
    group.clear();
    for (const Bytes& r : channel_records) group.raw(r.view().data(), r.size());
    groups.emplace_back(kChannel, write_group(group.view()));

    Bytes stats;
    const std::size_t st = stats.begin_record(kStatistics);
    stats.u64(message_count);
    stats.u16(static_cast<std::uint16_t>(schema_records.size()));
    stats.u32(static_cast<std::uint32_t>(channel_records.size()));
    stats.u32(0);  // attachments
    stats.u32(0);  // metadata
    stats.u32(static_cast<std::uint32_t>(chunks.size()));
    stats.u64(message_start_ns);
    stats.u64(message_end_ns);
    stats.u32(static_cast<std::uint32_t>(channel_message_counts.size() * 10));
    for (std::size_t i = 0; i < channel_message_counts.size(); ++i) {
      stats.u16(static_cast<std::uint16_t>(i + 1));
      stats.u64(channel_message_counts[i]);
    }
    stats.end_record(st);
    groups.emplace_back(kStatistics, write_group(stats.view()));
    groups.emplace_back(kChunkIndex, write_group(chunk_index_records.view()));

    const std::uint64_t summary_offset_start = position;
    for (const auto& [opcode, range] : groups) {
      if (range.second == 0) continue;
      Bytes offset;
      const std::size_t so = offset.begin_record(kSummaryOffset);
      offset.u8(opcode);
      offset.u64(range.first);
      offset.u64(range.second);
      offset.end_record(so);
      write_raw(offset.view());
    }

    // Footer: its summary CRC covers the summary through the Footer's summary_offset_start.
    Bytes footer;
    footer.u8(kFooter);
    footer.u64(8 + 8 + 4);
    footer.u64(summary_start);
    footer.u64(summary_offset_start);
    write_raw(footer.view());
    crc_span = CrcSpan::kNone;
    footer.clear();
    footer.u32(summary_crc);
    footer.raw(kMagic.data(), kMagic.size());
    write_raw(footer.view());

    errno = 0;
    std::FILE* f = std::exchange(file, nullptr);
    if (std::fclose(f) != 0) {
      const std::string reason = errno != 0 ? std::string(": ") + std::strerror(errno) : "";
      throw std::runtime_error("mcap: cannot close " + path + reason);
    }
  }
};

Writer::Writer(const std::string& path, Options options) : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.path = path;
  w.options = std::move(options);
  if (w.options.chunk_size_bytes == 0)
    throw std::invalid_argument("mcap: chunk_size_bytes must be positive for " + path);
  if (w.options.compression == Compression::kZstd) {
    if (w.options.zstd_level < 1 || w.options.zstd_level > ZSTD_maxCLevel())
      throw std::invalid_argument("mcap: zstd_level " + std::to_string(w.options.zstd_level) + " outside 1.." +
                                  std::to_string(ZSTD_maxCLevel()) + " for " + path);
    w.zstd = ZSTD_createCCtx();
    if (w.zstd == nullptr) throw std::runtime_error("mcap: cannot create a zstd context for " + path);
    ZSTD_CCtx_setParameter(w.zstd, ZSTD_c_compressionLevel, w.options.zstd_level);
  }
  errno = 0;
  w.file = std::fopen(path.c_str(), "wb");
  if (w.file == nullptr) w.fail("cannot open");
  w.chunk.reserve(w.options.chunk_size_bytes + 1024);

  Bytes start;
  start.raw(kMagic.data(), kMagic.size());
  const std::size_t at = start.begin_record(kHeader);
  start.string(w.options.profile);
  start.string(w.options.library);
  start.end_record(at);
  w.write_raw(start.view());
  w.flush_file();
}

Writer::~Writer() {
  if (!impl_ || impl_->file == nullptr) return;
  try {
    impl_->close();
  } catch (const std::exception& e) {
    std::cerr << e.what() << '\n';
  }
}

Writer::Writer(Writer&&) noexcept = default;

Writer& Writer::operator=(Writer&& other) noexcept {
  if (this != &other) {
    Writer closing(std::move(*this));  // closes the file this writer had, if any
    impl_ = std::move(other.impl_);
  }
  return *this;
}

SchemaId Writer::add_schema(std::string_view name, std::string_view encoding, std::string_view data) {
  Impl& w = *impl_;
  w.require_open("add_schema");
  if (w.schema_records.size() >= std::numeric_limits<std::uint16_t>::max())
    throw std::length_error("mcap: more than 65535 schemas in " + w.path);
  const auto id = static_cast<std::uint16_t>(w.schema_records.size() + 1);
  Bytes record;
  const std::size_t at = record.begin_record(kSchema);
  record.u16(id);
  record.string(name);
  record.string(encoding);
  record.u32(Bytes::checked_u32(data.size(), "schema"));
  record.raw(data.data(), data.size());
  record.end_record(at);
  w.write_raw(record.view());
  w.schema_records.push_back(std::move(record));
  return SchemaId{id};
}

ChannelId Writer::add_channel(std::string_view topic, std::string_view message_encoding, SchemaId schema,
                              const std::map<std::string, std::string>& metadata) {
  Impl& w = *impl_;
  w.require_open("add_channel");
  if (schema.value > w.schema_records.size())
    throw std::invalid_argument("mcap: channel " + std::string(topic) + " names unknown schema " +
                                std::to_string(schema.value) + " in " + w.path);
  if (w.channel_records.size() >= std::numeric_limits<std::uint16_t>::max())
    throw std::length_error("mcap: more than 65535 channels in " + w.path);
  const auto id = static_cast<std::uint16_t>(w.channel_records.size() + 1);
  Bytes map;
  for (const auto& [key, value] : metadata) {
    map.string(key);
    map.string(value);
  }
  Bytes record;
  const std::size_t at = record.begin_record(kChannel);
  record.u16(id);
  record.u16(schema.value);
  record.string(topic);
  record.string(message_encoding);
  record.u32(Bytes::checked_u32(map.size(), "channel metadata"));
  record.raw(map.view().data(), map.size());
  record.end_record(at);
  w.write_raw(record.view());
  w.channel_records.push_back(std::move(record));
  w.channel_message_counts.push_back(0);
  return ChannelId{id};
}

void Writer::write(ChannelId channel, std::uint32_t sequence, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                   std::span<const std::byte> data) {
  Impl& w = *impl_;
  w.require_open("write");
  if (channel.value == 0 || channel.value > w.channel_records.size())
    throw std::invalid_argument("mcap: write on unknown channel " + std::to_string(channel.value) + " in " + w.path);
  const std::uint64_t offset = w.chunk.size();
  w.chunk.u8(kMessage);
  w.chunk.u64(kMessageFixedSize + data.size());
  w.chunk.u16(channel.value);
  w.chunk.u32(sequence);
  w.chunk.u64(log_time_ns);
  w.chunk.u64(publish_time_ns);
  w.chunk.raw(data.data(), data.size());
  w.chunk_index[channel.value].push_back(IndexEntry{log_time_ns, offset});

  if (w.chunk_messages == 0) w.chunk_start_ns = w.chunk_end_ns = log_time_ns;
  w.chunk_start_ns = std::min(w.chunk_start_ns, log_time_ns);
  w.chunk_end_ns = std::max(w.chunk_end_ns, log_time_ns);
  ++w.chunk_messages;
  if (w.message_count == 0) w.message_start_ns = w.message_end_ns = log_time_ns;
  w.message_start_ns = std::min(w.message_start_ns, log_time_ns);
  w.message_end_ns = std::max(w.message_end_ns, log_time_ns);
  ++w.message_count;
  ++w.channel_message_counts[channel.value - 1];

  if (w.chunk.size() >= w.options.chunk_size_bytes) w.write_chunk();
}

void Writer::write(ChannelId channel, std::uint32_t sequence, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                   std::string_view data) {
  write(channel, sequence, log_time_ns, publish_time_ns, std::as_bytes(std::span(data)));
}

void Writer::flush_chunk() {
  impl_->require_open("flush_chunk");
  impl_->write_chunk();
}

void Writer::close() {
  if (impl_->file == nullptr) return;
  impl_->close();
}

bool Writer::is_open() const { return impl_->file != nullptr; }
const std::string& Writer::path() const { return impl_->path; }
std::uint64_t Writer::bytes_written() const { return impl_->position; }
std::uint64_t Writer::message_count() const { return impl_->message_count; }
const std::vector<ChunkInfo>& Writer::chunks() const { return impl_->chunks; }

}  // namespace telegrasp::mcap
