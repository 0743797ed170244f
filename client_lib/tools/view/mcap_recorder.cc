#include "mcap_recorder.h"

#include <stdexcept>

namespace telegrasp::view {

McapRecorder::McapRecorder(const std::string& path, const std::vector<Channel>& channels, Options options)
    : writer_(path,
              mcap::Options{.profile = "", .library = "telegrasp-view", .chunk_size_bytes = options.chunk_size_bytes}),
      options_(options) {
  for (const Channel& c : channels) {
    const mcap::SchemaId schema = writer_.add_schema(c.schema_name, mcap::kSchemaEncodingJsonSchema, c.schema);
    channels_[c.id] = Out{writer_.add_channel(c.topic, mcap::kMessageEncodingJson, schema)};
  }
}

void McapRecorder::write(std::uint32_t channel, std::string_view json, std::uint64_t time_ns) {
  const auto it = channels_.find(channel);
  if (it == channels_.end())
    throw std::invalid_argument("McapRecorder: unknown view channel " + std::to_string(channel));
  writer_.write(it->second.id, it->second.sequence++, time_ns, time_ns, json);
}

void McapRecorder::write_scene_keyframe(const ViewModel& model, std::uint64_t time_ns) {
  last_keyframe_ns_ = time_ns;
  if (model.hand_count() == 0 && model.object_count() == 0) return;
  write(kSceneChannel, model.scene_full(time_ns).dump(), time_ns);
  ++keyframes_;
}

void McapRecorder::record(const std::vector<StepMessage>& messages, const ViewModel& model, std::uint64_t time_ns) {
  for (const StepMessage& m : messages) write(m.channel, *m.payload, time_ns);
  // The model's first /scene holds every entity (it starts empty): a keyframe, the next one 2 s later.
  if (!last_keyframe_ns_) {
    for (const StepMessage& m : messages)
      if (m.channel == kSceneChannel) last_keyframe_ns_ = time_ns;
  } else if (time_ns >= *last_keyframe_ns_ + kKeyframeEveryNs) {
    write_scene_keyframe(model, time_ns);
  }
}

void McapRecorder::record_keyframe(const ViewModel& model, std::uint64_t time_ns) {
  write_scene_keyframe(model, time_ns);
  if (auto tf = model.transforms_full(time_ns)) write(kTransformsChannel, tf->dump(), time_ns);
}

void McapRecorder::flush_if_due(std::uint64_t now_ns) {
  if (options_.flush_interval_ns == 0) return;
  if (!last_flush_ns_) last_flush_ns_ = now_ns;
  if (now_ns < *last_flush_ns_ + options_.flush_interval_ns) return;
  writer_.flush_chunk();
  last_flush_ns_ = now_ns;
}

void McapRecorder::close() { writer_.close(); }

}  // namespace telegrasp::view
