// telegrasp-mcap-sample: writes the MCAP files that tests/js/mcap_check.mjs reads with the
// reference TypeScript reader, and times the writer.
//
//   telegrasp-mcap-sample OUT_DIR
//     OUT_DIR/sample.mcap      3 channels (JSON, jsonschema), 3 schemas, 10,000 messages, ~20 chunks
//     OUT_DIR/sample_cut.mcap  sample.mcap cut in the middle of a chunk
//     OUT_DIR/sample_killed.mcap  sample.mcap as on disk 2/3 through writing (a killed recorder)
//     OUT_DIR/sample.json      what the reader must find in each: counts and times per channel
//   telegrasp-mcap-sample --bench MESSAGES OUT.mcap
//     prints write speed and compression ratio for MESSAGES small JSON messages
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "mcap_writer.h"

namespace mcap = telegrasp::mcap;
namespace fs = std::filesystem;

namespace {

constexpr std::uint64_t kStartNs = 1'700'000'000'000'000'000ull;  // 2023-11-14, past 2^53
constexpr std::uint64_t kTickNs = 1'000'000;  // 1 kHz hand state
constexpr int kMessages = 10'000;

const char* kHandStateSchema = R"({"title":"telegrasp.HandState","type":"object","properties":{
"seq":{"type":"integer"},"joints":{"type":"array","items":{"type":"number"}},
"grasped":{"type":"boolean"}}})";
const char* kFrameTransformSchema = R"({"title":"foxglove.FrameTransform","type":"object",
"properties":{"parent_frame_id":{"type":"string"},"child_frame_id":{"type":"string"},
"translation":{"type":"object"},"rotation":{"type":"object"}}})";
const char* kLogSchema = R"({"title":"foxglove.Log","type":"object","properties":{
"level":{"type":"integer"},"message":{"type":"string"},"name":{"type":"string"}}})";

// One message as the recorder would produce it: channel index 0..2, JSON text.
struct Sample {
  int channel;
  std::uint64_t log_time_ns;
  std::string json;
};

// The message stream: hand state every tick, a transform every 4th tick, a log line every 50th,
// in log-time order, until `count` messages; `seq` counts per channel.
std::vector<Sample> make_samples(int count) {
  std::vector<Sample> out;
  out.reserve(count);
  int seq[3] = {0, 0, 0};
  char buffer[256];
  for (std::uint64_t tick = 0; static_cast<int>(out.size()) < count; ++tick) {
    const std::uint64_t t = kStartNs + tick * kTickNs;
    const double s = static_cast<double>(tick) * 1e-3;
    std::snprintf(buffer, sizeof buffer, R"({"seq":%d,"joints":[%.4f,%.4f,%.4f,%.4f],"grasped":%s})", seq[0]++,
                  0.6 * std::sin(s), 0.4 * std::sin(1.3 * s), 0.5 * std::cos(0.7 * s), 0.1 * s,
                  (tick / 700) % 2 ? "true" : "false");
    out.push_back({0, t, buffer});
    if (tick % 4 == 0 && static_cast<int>(out.size()) < count) {
      std::snprintf(buffer, sizeof buffer,
                    R"({"seq":%d,"parent_frame_id":"world","child_frame_id":"palm",)"
                    R"("translation":{"x":%.5f,"y":%.5f,"z":%.5f},"rotation":{"x":0,"y":0,"z":%.5f,"w":%.5f}})",
                    seq[1]++, 0.3 + 0.05 * std::sin(s), 0.02 * std::cos(s), 0.12, std::sin(s / 2), std::cos(s / 2));
      out.push_back({1, t, buffer});
    }
    if (tick % 50 == 0 && static_cast<int>(out.size()) < count) {
      std::snprintf(buffer, sizeof buffer,
                    R"({"seq":%d,"level":2,"message":"tick %llu: hand controller ok","name":"sim"})", seq[2]++,
                    static_cast<unsigned long long>(tick));
      out.push_back({2, t, buffer});
    }
  }
  return out;
}

struct Channels {
  mcap::ChannelId ids[3];
};

Channels add_channels(mcap::Writer& writer) {
  const mcap::SchemaId hand =
      writer.add_schema("telegrasp.HandState", mcap::kSchemaEncodingJsonSchema, kHandStateSchema);
  const mcap::SchemaId tf =
      writer.add_schema("foxglove.FrameTransform", mcap::kSchemaEncodingJsonSchema, kFrameTransformSchema);
  const mcap::SchemaId log = writer.add_schema("foxglove.Log", mcap::kSchemaEncodingJsonSchema, kLogSchema);
  return {{writer.add_channel("/hand/state", mcap::kMessageEncodingJson, hand, {{"hand", "right"}}),
           writer.add_channel("/tf", mcap::kMessageEncodingJson, tf),
           writer.add_channel("/log", mcap::kMessageEncodingJson, log)}};
}

const char* const kTopics[3] = {"/hand/state", "/tf", "/log"};
const char* const kSchemas[3] = {"telegrasp.HandState", "foxglove.FrameTransform", "foxglove.Log"};

// Per-channel counts and time range of samples [0, end).
nlohmann::json channel_summary(const std::vector<Sample>& samples, std::size_t end) {
  nlohmann::json channels = nlohmann::json::array();
  for (int c = 0; c < 3; ++c) {
    std::uint64_t count = 0, first = 0, last = 0;
    for (std::size_t i = 0; i < end; ++i) {
      if (samples[i].channel != c) continue;
      if (count++ == 0) first = samples[i].log_time_ns;
      last = samples[i].log_time_ns;
    }
    // Times as strings: nanoseconds since 1970 exceed a JSON number's exact range (2^53).
    channels.push_back({{"topic", kTopics[c]},
                        {"schema", kSchemas[c]},
                        {"count", count},
                        {"start_time_ns", std::to_string(first)},
                        {"end_time_ns", std::to_string(last)}});
  }
  return channels;
}

int write_sample(const fs::path& dir) {
  fs::create_directories(dir);
  const std::vector<Sample> samples = make_samples(kMessages);
  const fs::path full = dir / "sample.mcap";
  const fs::path killed_path = dir / "sample_killed.mcap";
  std::vector<mcap::ChunkInfo> chunks;
  std::uint64_t killed_complete = 0;
  {
    mcap::Writer writer(full.string(), {.profile = "", .chunk_size_bytes = 64 * 1024});
    const Channels channels = add_channels(writer);
    std::uint32_t seq[3] = {0, 0, 0};
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Sample& s = samples[i];
      writer.write(channels.ids[s.channel], seq[s.channel]++, s.log_time_ns, s.log_time_ns - 20'000, s.json);
      if (i + 1 == samples.size() * 2 / 3) {
        // What a recorder killed now would leave: the file as it is on disk, writer still open.
        fs::copy_file(full, killed_path, fs::copy_options::overwrite_existing);
        for (const mcap::ChunkInfo& c : writer.chunks()) killed_complete += c.message_count;
      }
    }
    writer.close();
    chunks = writer.chunks();
  }
  if (chunks.size() < 4) throw std::runtime_error("expected several chunks, got " + std::to_string(chunks.size()));

  // Cut in the middle of the middle chunk: a reader gets every message of the chunks before it.
  const std::size_t cut_chunk = chunks.size() / 2;
  const std::uint64_t cut = chunks[cut_chunk].offset + chunks[cut_chunk].length / 2;
  std::uint64_t complete = 0;
  for (std::size_t k = 0; k < cut_chunk; ++k) complete += chunks[k].message_count;
  const fs::path cut_path = dir / "sample_cut.mcap";
  fs::copy_file(full, cut_path, fs::copy_options::overwrite_existing);
  fs::resize_file(cut_path, cut);

  nlohmann::json sidecar = {
      {"file", full.filename().string()},
      {"profile", ""},
      {"library", "telegrasp-mcap"},
      {"message_count", samples.size()},
      {"schema_count", 3},
      {"channel_count", 3},
      {"chunk_count", chunks.size()},
      {"start_time_ns", std::to_string(samples.front().log_time_ns)},
      {"end_time_ns", std::to_string(samples.back().log_time_ns)},
      {"publish_time_offset_ns", "-20000"},
      {"channels", channel_summary(samples, samples.size())},
      {"cut",
       {{"file", cut_path.filename().string()},
        {"size", cut},
        {"complete_chunks", cut_chunk},
        {"message_count", complete},
        {"channels", channel_summary(samples, complete)}}},
      {"killed",
       {{"file", killed_path.filename().string()},
        {"size", fs::file_size(killed_path)},
        {"message_count", killed_complete},
        {"channels", channel_summary(samples, killed_complete)}}},
  };
  std::ofstream(dir / "sample.json") << sidecar.dump(2) << '\n';
  std::cout << "wrote " << full.string() << ": " << samples.size() << " messages in " << chunks.size() << " chunks, "
            << fs::file_size(full) << " bytes; cut at byte " << cut << " (chunk " << cut_chunk << ", " << complete
            << " messages before it); " << killed_path.filename().string() << ": " << killed_complete
            << " messages in complete chunks\n";
  return 0;
}

int bench(int messages, const std::string& path) {
  const std::vector<Sample> samples = make_samples(messages);
  std::uint64_t payload = 0;
  for (const Sample& s : samples) payload += s.json.size();
  struct Config {
    const char* name;
    mcap::Compression compression;
    int level;
  };
  const Config configs[] = {{"none", mcap::Compression::kNone, 3},
                            {"zstd-1", mcap::Compression::kZstd, 1},
                            {"zstd-3 (default)", mcap::Compression::kZstd, 3}};
  std::printf("%d JSON messages on 3 channels, %.1f B average, %.2f MB payload; 1 MiB chunks; best of 3\n", messages,
              static_cast<double>(payload) / messages, payload / 1e6);
  std::printf("%-18s %10s %12s %12s %10s %8s\n", "compression", "file MB", "payload MB/s", "messages/s", "chunk x",
              "chunks");
  for (const Config& config : configs) {
    double best = 1e30;
    std::uint64_t file_size = 0, raw = 0, stored = 0, chunk_count = 0;
    for (int run = 0; run < 3; ++run) {
      const auto begin = std::chrono::steady_clock::now();
      mcap::Writer writer(path, {.compression = config.compression, .zstd_level = config.level});
      const Channels channels = add_channels(writer);
      std::uint32_t seq = 0;
      for (const Sample& s : samples)
        writer.write(channels.ids[s.channel], seq++, s.log_time_ns, s.log_time_ns, s.json);
      writer.close();
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count());
      file_size = writer.bytes_written();
      raw = stored = 0;
      for (const mcap::ChunkInfo& c : writer.chunks()) {
        raw += c.uncompressed_size;
        stored += c.compressed_size;
      }
      chunk_count = writer.chunks().size();
    }
    std::printf("%-18s %10.2f %12.1f %12.0f %10.2f %8llu\n", config.name, file_size / 1e6, payload / 1e6 / best,
                messages / best, static_cast<double>(raw) / stored, static_cast<unsigned long long>(chunk_count));
  }
  std::printf("chunk x: uncompressed / stored chunk records; payload MB/s: message bytes per second\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc == 4 && std::string(argv[1]) == "--bench") return bench(std::stoi(argv[2]), argv[3]);
    if (argc == 2 && argv[1][0] != '-') return write_sample(argv[1]);
    std::cerr << "usage: telegrasp-mcap-sample OUT_DIR | --bench MESSAGES OUT.mcap\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-mcap-sample: " << e.what() << '\n';
    return 1;
  }
}
