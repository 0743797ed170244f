// Tests telegrasp::mcap::Writer (client_lib/tools/mcap/mcap_writer.h) at the byte level: every expectation
// comes from the MCAP specification, read back with this file's own little-endian parser and a
// bitwise CRC-32, independent of the writer's serialization and table-driven CRC.
#include "mcap_writer.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zstd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace telegrasp::mcap {

// Names the parameter in test listings.
void PrintTo(Compression c, std::ostream* os) { *os << (c == Compression::kZstd ? "zstd" : "none"); }

namespace {

namespace fs = std::filesystem;

const std::string kMagic = std::string("\x89MCAP0\r\n", 8);

// A scratch folder per test, removed afterwards.
class McapWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("mcap_writer_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Little-endian reads at an offset of a byte string.
std::uint64_t le(const std::string& s, std::size_t at, int n) {
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(s.at(at + i));
  return v;
}
std::uint16_t u16(const std::string& s, std::size_t at) { return static_cast<std::uint16_t>(le(s, at, 2)); }
std::uint32_t u32(const std::string& s, std::size_t at) { return static_cast<std::uint32_t>(le(s, at, 4)); }
std::uint64_t u64(const std::string& s, std::size_t at) { return le(s, at, 8); }

// CRC-32 bit by bit (reflected polynomial 0xEDB88320, init and final xor 0xFFFFFFFF).
std::uint32_t bitwise_crc32(const std::string& s, std::size_t begin, std::size_t end) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = begin; i < end; ++i) {
    c ^= static_cast<unsigned char>(s[i]);
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}

struct Record {
  std::uint8_t opcode;
  std::size_t offset;  // of the opcode
  std::size_t content;  // offset of the content
  std::uint64_t length;  // of the content
};

// Splits [begin, end) into records; fails the test if they do not tile the range exactly.
std::vector<Record> records_in(const std::string& s, std::size_t begin, std::size_t end) {
  std::vector<Record> out;
  std::size_t at = begin;
  while (at < end) {
    Record r{static_cast<std::uint8_t>(s.at(at)), at, at + 9, u64(s, at + 1)};
    out.push_back(r);
    at = r.content + r.length;
  }
  EXPECT_EQ(at, end) << "records overrun their section";
  return out;
}

// The parts of a finished file that the spec fixes: magic, header, sections and footer.
struct Layout {
  std::size_t footer = 0;  // offset of the Footer record
  std::uint64_t summary_start = 0;
  std::uint64_t summary_offset_start = 0;
  std::uint32_t summary_crc = 0;
  std::vector<Record> data;  // records after the Header, Data End included
  std::vector<Record> summary;  // summary section records
  std::vector<Record> summary_offsets;  // summary offset section records
};

Layout parse_layout(const std::string& s) {
  Layout l;
  EXPECT_GE(s.size(), 8u + 9 + 9 + 13 + 29 + 8);
  EXPECT_EQ(s.substr(0, 8), kMagic);
  EXPECT_EQ(s.substr(s.size() - 8), kMagic);
  l.footer = s.size() - 8 - 29;  // Footer: opcode, length, 8 + 8 + 4 bytes
  EXPECT_EQ(static_cast<std::uint8_t>(s[l.footer]), 0x02);
  EXPECT_EQ(u64(s, l.footer + 1), 20u);
  l.summary_start = u64(s, l.footer + 9);
  l.summary_offset_start = u64(s, l.footer + 17);
  l.summary_crc = u32(s, l.footer + 25);
  const std::size_t header_end = 8 + 9 + u64(s, 9);
  l.data = records_in(s, header_end, l.summary_start);
  l.summary = records_in(s, l.summary_start, l.summary_offset_start);
  l.summary_offsets = records_in(s, l.summary_offset_start, l.footer);
  return l;
}

// A Message record inside a chunk's uncompressed records.
struct Message {
  std::uint16_t channel;
  std::uint32_t sequence;
  std::uint64_t log_time;
  std::uint64_t publish_time;
  std::string data;
  std::uint64_t offset;  // in the uncompressed records
};

struct Chunk {
  std::uint64_t start, end, uncompressed_size;
  std::uint32_t crc;
  std::string compression;
  std::string records;  // uncompressed
  std::vector<Message> messages;
};

Chunk parse_chunk(const std::string& s, const Record& r) {
  Chunk c;
  std::size_t at = r.content;
  c.start = u64(s, at);
  c.end = u64(s, at + 8);
  c.uncompressed_size = u64(s, at + 16);
  c.crc = u32(s, at + 24);
  const std::uint32_t name_length = u32(s, at + 28);
  c.compression = s.substr(at + 32, name_length);
  at += 32 + name_length;
  const std::uint64_t stored_size = u64(s, at);
  EXPECT_EQ(at + 8 + stored_size, r.content + r.length) << "chunk records end the chunk";
  const std::string stored = s.substr(at + 8, stored_size);
  if (c.compression.empty()) {
    c.records = stored;
  } else {
    EXPECT_EQ(c.compression, "zstd");
    c.records.resize(c.uncompressed_size);
    const std::size_t n = ZSTD_decompress(c.records.data(), c.records.size(), stored.data(), stored.size());
    EXPECT_FALSE(ZSTD_isError(n)) << ZSTD_getErrorName(n);
    EXPECT_EQ(n, c.uncompressed_size);
  }
  for (const Record& m : records_in(c.records, 0, c.records.size())) {
    EXPECT_EQ(m.opcode, 0x05) << "only Message records in telegrasp's chunks";
    c.messages.push_back(Message{u16(c.records, m.content), u32(c.records, m.content + 2),
                                 u64(c.records, m.content + 6), u64(c.records, m.content + 14),
                                 c.records.substr(m.content + 22, m.length - 22), m.offset});
  }
  return c;
}

std::string schema_json(const std::string& title) { return R"({"title":")" + title + R"(","type":"object"})"; }

TEST(McapCrcTest, MatchesTheStandardCheckValue) {
  // CRC-32/ISO-HDLC of "123456789" is 0xCBF43926 (the catalogue's check value).
  const std::string digits = "123456789";
  EXPECT_EQ(crc32(std::as_bytes(std::span(digits))), 0xCBF43926u);
  // Continuing over a second part gives the CRC of the whole.
  const std::string a = "12345", b = "6789";
  EXPECT_EQ(crc32(std::as_bytes(std::span(b)), crc32(std::as_bytes(std::span(a)))), 0xCBF43926u);
  EXPECT_EQ(bitwise_crc32(digits, 0, digits.size()), 0xCBF43926u);
  // Every length and split point up to 40 bytes (8-byte blocks and tails) agrees bit by bit.
  std::string bytes;
  for (int i = 0; i < 40; ++i) bytes.push_back(static_cast<char>((i * 151 + 7) & 0xFF));
  for (std::size_t n = 0; n <= bytes.size(); ++n) {
    const std::string head = bytes.substr(0, n / 3), tail = bytes.substr(n / 3, n - n / 3);
    EXPECT_EQ(crc32(std::as_bytes(std::span(tail)), crc32(std::as_bytes(std::span(head)))), bitwise_crc32(bytes, 0, n))
        << n << " bytes";
  }
}

TEST_F(McapWriterTest, EmptyFileHasMagicHeaderDataEndSummaryAndFooter) {
  {
    Writer writer(file("empty.mcap"), {.profile = "x-telegrasp", .library = "lib-under-test"});
  }  // the destructor closes
  const std::string s = read_file(file("empty.mcap"));

  // Header right after the magic: opcode 0x01, then profile and library strings.
  ASSERT_EQ(static_cast<std::uint8_t>(s[8]), 0x01);
  EXPECT_EQ(u64(s, 9), (4 + 11) + (4 + 14));
  EXPECT_EQ(u32(s, 17), 11u);
  EXPECT_EQ(s.substr(21, 11), "x-telegrasp");
  EXPECT_EQ(s.substr(36, 14), "lib-under-test");

  const Layout l = parse_layout(s);
  // The data section holds only Data End, 13 bytes right before the summary.
  ASSERT_EQ(l.data.size(), 1u);
  EXPECT_EQ(l.data[0].opcode, 0x0F);
  EXPECT_EQ(l.data[0].offset, l.summary_start - 13);
  // Data End's CRC covers the magic, the header and the data section before it.
  EXPECT_EQ(u32(s, l.data[0].content), bitwise_crc32(s, 0, l.summary_start - 13));
  // The summary is just Statistics; summary_start points at it.
  ASSERT_EQ(l.summary.size(), 1u);
  EXPECT_EQ(l.summary[0].offset, l.summary_start);
  EXPECT_EQ(l.summary[0].opcode, 0x0B);
  EXPECT_EQ(u64(s, l.summary[0].content), 0u) << "message_count";
  // The summary CRC runs from summary_start through the Footer's summary_offset_start field.
  EXPECT_EQ(l.summary_crc, bitwise_crc32(s, l.summary_start, l.footer + 25));
}

// Writes 3 channels on 2 schemas (one channel schemaless) over several chunks and reads all back.
void write_three_channels(const std::string& path, Compression compression, int messages,
                          std::vector<ChunkInfo>* chunks) {
  Writer writer(path, {.chunk_size_bytes = 4096, .compression = compression});
  const SchemaId pose = writer.add_schema("telegrasp.Pose", kSchemaEncodingJsonSchema, schema_json("Pose"));
  const SchemaId log = writer.add_schema("foxglove.Log", kSchemaEncodingJsonSchema, schema_json("Log"));
  const ChannelId c1 = writer.add_channel("/hand/pose", kMessageEncodingJson, pose, {{"frame", "world"}});
  const ChannelId c2 = writer.add_channel("/log", kMessageEncodingJson, log);
  const ChannelId c3 = writer.add_channel("/raw", "x-bytes", SchemaId{});
  for (int i = 0; i < messages; ++i) {
    // Channel i % 3 + 1, 1 ms apart, publish time 10 us before the log time.
    const ChannelId c = i % 3 == 0 ? c1 : (i % 3 == 1 ? c2 : c3);
    const std::uint64_t t = 1'000'000'000ull + static_cast<std::uint64_t>(i) * 1'000'000ull;
    writer.write(c, static_cast<std::uint32_t>(i), t, t - 10'000, R"({"i":)" + std::to_string(i) + "}");
  }
  writer.close();
  *chunks = writer.chunks();
}

class McapWriterCompressionTest : public McapWriterTest, public ::testing::WithParamInterface<Compression> {};

TEST_P(McapWriterCompressionTest, ChunksIndexesSummaryAndOffsetsAgreeWithTheMessages) {
  constexpr int kMessages = 3000;
  std::vector<ChunkInfo> infos;
  write_three_channels(file("three.mcap"), GetParam(), kMessages, &infos);
  const std::string s = read_file(file("three.mcap"));
  const Layout l = parse_layout(s);

  // Data section: 2 Schemas and 3 Channels, then each Chunk followed by its Message Indexes, then
  // Data End.
  ASSERT_GE(l.data.size(), 7u);
  EXPECT_EQ(l.data[0].opcode, 0x03);
  EXPECT_EQ(l.data[1].opcode, 0x03);
  EXPECT_EQ(l.data[2].opcode, 0x04);
  EXPECT_EQ(l.data[4].opcode, 0x04);
  EXPECT_EQ(l.data.back().opcode, 0x0F);
  EXPECT_EQ(u32(s, l.data.back().content), bitwise_crc32(s, 0, l.summary_start - 13));

  std::map<std::uint16_t, std::uint64_t> per_channel;
  std::size_t chunk_count = 0;
  std::vector<std::uint64_t> index_lengths;  // bytes of Message Index records after each chunk
  int next_sequence = 0;
  for (std::size_t i = 5; i + 1 < l.data.size();) {
    ASSERT_EQ(l.data[i].opcode, 0x06) << "record " << i;
    const Chunk chunk = parse_chunk(s, l.data[i]);
    ASSERT_LT(chunk_count, infos.size());
    const ChunkInfo& info = infos[chunk_count];
    EXPECT_EQ(info.offset, l.data[i].offset);
    EXPECT_EQ(info.length, 9 + l.data[i].length);
    EXPECT_EQ(chunk.compression, GetParam() == Compression::kZstd ? "zstd" : "");
    EXPECT_EQ(chunk.records.size(), chunk.uncompressed_size);
    EXPECT_EQ(chunk.crc, bitwise_crc32(chunk.records, 0, chunk.records.size()));
    EXPECT_EQ(chunk.messages.size(), info.message_count);
    EXPECT_EQ(chunk.start, chunk.messages.front().log_time);
    EXPECT_EQ(chunk.end, chunk.messages.back().log_time);
    for (const Message& m : chunk.messages) {
      EXPECT_EQ(m.sequence, static_cast<std::uint32_t>(next_sequence)) << "messages in write order";
      EXPECT_EQ(m.channel, next_sequence % 3 + 1);
      EXPECT_EQ(m.publish_time, m.log_time - 10'000);
      EXPECT_EQ(m.data, R"({"i":)" + std::to_string(next_sequence) + "}");
      ++per_channel[m.channel];
      ++next_sequence;
    }
    // One Message Index per channel in the chunk, each entry pointing at that channel's message.
    std::map<std::uint16_t, std::size_t> indexed;
    std::uint64_t index_length = 0;
    for (++i; l.data[i].opcode == 0x07; ++i) {
      index_length += 9 + l.data[i].length;
      const std::string& r = chunk.records;
      const std::uint16_t channel = u16(s, l.data[i].content);
      const std::uint32_t bytes = u32(s, l.data[i].content + 2);
      ASSERT_EQ(bytes % 16, 0u);
      for (std::size_t e = 0; e < bytes / 16; ++e) {
        const std::uint64_t log_time = u64(s, l.data[i].content + 6 + 16 * e);
        const std::uint64_t offset = u64(s, l.data[i].content + 14 + 16 * e);
        ASSERT_EQ(static_cast<std::uint8_t>(r.at(offset)), 0x05);
        EXPECT_EQ(u16(r, offset + 9), channel);
        EXPECT_EQ(u64(r, offset + 15), log_time);
      }
      indexed[channel] += bytes / 16;
    }
    std::map<std::uint16_t, std::size_t> in_chunk;
    for (const Message& m : chunk.messages) ++in_chunk[m.channel];
    EXPECT_EQ(indexed, in_chunk);
    index_lengths.push_back(index_length);
    ++chunk_count;
  }
  EXPECT_EQ(next_sequence, kMessages);
  EXPECT_EQ(chunk_count, infos.size());
  EXPECT_GT(chunk_count, 3u) << "4 KiB chunks split 3000 messages";

  // Summary: Schemas, Channels, Statistics, Chunk Indexes, grouped by opcode.
  std::map<std::uint8_t, std::vector<Record>> groups;
  for (const Record& r : l.summary) groups[r.opcode].push_back(r);
  EXPECT_EQ(groups[0x03].size(), 2u);
  EXPECT_EQ(groups[0x04].size(), 3u);
  ASSERT_EQ(groups[0x0B].size(), 1u);
  EXPECT_EQ(groups[0x08].size(), chunk_count);
  EXPECT_EQ(l.summary.front().offset, l.summary_start);
  // Statistics: counts, time range and per-channel counts.
  const std::size_t st = groups[0x0B][0].content;
  EXPECT_EQ(u64(s, st), static_cast<std::uint64_t>(kMessages));
  EXPECT_EQ(u16(s, st + 8), 2u);
  EXPECT_EQ(u32(s, st + 10), 3u);
  EXPECT_EQ(u32(s, st + 22), chunk_count);
  EXPECT_EQ(u64(s, st + 26), 1'000'000'000u);
  EXPECT_EQ(u64(s, st + 34), 1'000'000'000u + (kMessages - 1) * 1'000'000u);
  ASSERT_EQ(u32(s, st + 42), 3u * 10);
  for (int c = 0; c < 3; ++c) {
    const std::uint16_t id = u16(s, st + 46 + 10 * c);
    EXPECT_EQ(u64(s, st + 48 + 10 * c), per_channel[id]) << "channel " << id;
  }
  // Each Chunk Index points at its chunk and says where its message indexes are.
  for (std::size_t k = 0; k < chunk_count; ++k) {
    const std::size_t ci = groups[0x08][k].content;
    EXPECT_EQ(u64(s, ci + 16), infos[k].offset);
    EXPECT_EQ(u64(s, ci + 24), infos[k].length);
    const std::uint32_t map_bytes = u32(s, ci + 32);
    for (std::size_t e = 0; e < map_bytes / 10; ++e) {
      const std::uint64_t index_offset = u64(s, ci + 36 + 10 * e + 2);
      EXPECT_EQ(static_cast<std::uint8_t>(s[index_offset]), 0x07);
      EXPECT_EQ(u16(s, index_offset + 9), u16(s, ci + 36 + 10 * e));
    }
    std::size_t at = ci + 36 + map_bytes;
    EXPECT_EQ(u64(s, at), index_lengths[k]) << "message_index_length";
    const std::uint32_t name_length = u32(s, at + 8);
    EXPECT_EQ(s.substr(at + 12, name_length), GetParam() == Compression::kZstd ? "zstd" : "");
    at += 12 + name_length;
    EXPECT_EQ(u64(s, at), infos[k].compressed_size);
    EXPECT_EQ(u64(s, at + 8), infos[k].uncompressed_size);
    EXPECT_EQ(at + 16, groups[0x08][k].content + groups[0x08][k].length) << "no bytes left over";
    EXPECT_EQ(u64(s, ci), infos[k].message_start_time_ns);
    EXPECT_EQ(u64(s, ci + 8), infos[k].message_end_time_ns);
  }
  // Summary Offsets: one per group, each covering exactly that group's records.
  ASSERT_EQ(l.summary_offsets.size(), 4u);
  for (const Record& so : l.summary_offsets) {
    ASSERT_EQ(so.opcode, 0x0E);
    const auto opcode = static_cast<std::uint8_t>(s[so.content]);
    const std::uint64_t start = u64(s, so.content + 1), length = u64(s, so.content + 9);
    ASSERT_FALSE(groups[opcode].empty());
    EXPECT_EQ(start, groups[opcode].front().offset);
    EXPECT_EQ(start + length, groups[opcode].back().content + groups[opcode].back().length);
  }
  EXPECT_EQ(l.summary_crc, bitwise_crc32(s, l.summary_start, l.footer + 25));
}

INSTANTIATE_TEST_SUITE_P(Compressions, McapWriterCompressionTest,
                         ::testing::Values(Compression::kNone, Compression::kZstd),
                         [](const auto& info) { return info.param == Compression::kZstd ? "Zstd" : "None"; });

TEST_F(McapWriterTest, OutOfOrderLogTimesAreIndexedInTimeOrder) {
  const std::string path = file("unordered.mcap");
  {
    Writer writer(path, {.compression = Compression::kNone});
    const ChannelId c = writer.add_channel("/a", kMessageEncodingJson, SchemaId{});
    for (std::uint64_t t : {30u, 10u, 20u}) writer.write(c, 0, t, t, "{}");
  }
  const std::string s = read_file(path);
  const Layout l = parse_layout(s);
  ASSERT_EQ(l.data[1].opcode, 0x06);
  const Chunk chunk = parse_chunk(s, l.data[1]);
  // The chunk's time range is the min and max; the index lists 10, 20, 30 at the messages' offsets.
  EXPECT_EQ(chunk.start, 10u);
  EXPECT_EQ(chunk.end, 30u);
  ASSERT_EQ(l.data[2].opcode, 0x07);
  const std::size_t mi = l.data[2].content;
  ASSERT_EQ(u32(s, mi + 2), 3u * 16);
  EXPECT_EQ(u64(s, mi + 6), 10u);
  EXPECT_EQ(u64(s, mi + 14), chunk.messages[1].offset);
  EXPECT_EQ(u64(s, mi + 22), 20u);
  EXPECT_EQ(u64(s, mi + 30), chunk.messages[2].offset);
  EXPECT_EQ(u64(s, mi + 38), 30u);
  EXPECT_EQ(u64(s, mi + 46), chunk.messages[0].offset);
}

TEST_F(McapWriterTest, AFullChunkIsOnDiskBeforeClose) {
  const std::string path = file("live.mcap");
  Writer writer(path, {.chunk_size_bytes = 1024});
  const ChannelId c = writer.add_channel("/a", kMessageEncodingJson, SchemaId{});
  // Write until the first chunk fills, then read the file as another process would.
  std::uint64_t t = 0;
  while (writer.chunks().empty()) {
    ++t;
    writer.write(c, 0, t, t, R"({"padding":"0123456789"})");
  }
  const std::string on_disk = read_file(path);
  EXPECT_EQ(on_disk.size(), writer.bytes_written());
  const ChunkInfo& first = writer.chunks().front();
  ASSERT_GE(on_disk.size(), first.offset + first.length);
  EXPECT_EQ(static_cast<std::uint8_t>(on_disk[first.offset]), 0x06);
  // The chunk is followed by exactly its one Message Index, and the file ends there.
  EXPECT_EQ(static_cast<std::uint8_t>(on_disk[first.offset + first.length]), 0x07);
  EXPECT_EQ(first.offset + first.length + 9 + u64(on_disk, first.offset + first.length + 1), on_disk.size());
  EXPECT_EQ(parse_chunk(on_disk, Record{0x06, first.offset, first.offset + 9, first.length - 9}).messages.size(),
            first.message_count);
}

TEST_F(McapWriterTest, UnwritablePathIsNamedInTheError) {
  const std::string path = file("no-such-folder") + "/out.mcap";
  try {
    Writer writer(path);
    FAIL() << "opened " << path;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST_F(McapWriterTest, CallerMistakesThrow) {
  Writer writer(file("mistakes.mcap"));
  EXPECT_THROW(writer.add_channel("/a", kMessageEncodingJson, SchemaId{7}), std::invalid_argument);
  EXPECT_THROW(writer.write(ChannelId{1}, 0, 0, 0, "{}"), std::invalid_argument);
  const ChannelId c = writer.add_channel("/a", kMessageEncodingJson, SchemaId{});
  writer.close();
  writer.close();  // idempotent
  EXPECT_THROW(writer.write(c, 0, 0, 0, "{}"), std::logic_error);
  EXPECT_THROW(Writer(file("zero.mcap"), {.chunk_size_bytes = 0}), std::invalid_argument);
  EXPECT_THROW(Writer(file("level.mcap"), {.zstd_level = 0}), std::invalid_argument);
}

}  // namespace
}  // namespace telegrasp::mcap
