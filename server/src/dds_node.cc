#include "dds_node.h"

#include "telegrasp/idl/profiles.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <chrono>
#include <cstring>
#include <iostream>
#include <mutex>
#include <stdexcept>

namespace telegrasp::server {

namespace dds = eprosima::fastdds::dds;

namespace {

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Controller states go straight to the mailbox, with the writing participant's GUID prefix.
class ControllerStateListener : public dds::DataReaderListener {
 public:
  explicit ControllerStateListener(InputMailbox& mailbox) : mailbox_(mailbox) {}
  void on_data_available(dds::DataReader* reader) override {
    dds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;  // instance state changes, not samples
      ParticipantKey writer;
      std::memcpy(writer.data(), info.sample_identity.writer_guid().guidPrefix.value, writer.size());
      mailbox_.offer(sample_, writer, steady_now_ns());
    }
  }

 private:
  InputMailbox& mailbox_;
  msg::ControllerState sample_;  // reused: one listener thread per reader
};

class SceneCommandListener : public dds::DataReaderListener {
 public:
  explicit SceneCommandListener(InputMailbox& mailbox) : mailbox_(mailbox) {}
  void on_data_available(dds::DataReader* reader) override {
    msg::SceneCommand c;
    dds::SampleInfo info;
    bool any = false;
    while (reader->take_next_sample(&c, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard lock(mutex);
      queue.push_back(c);
      any = true;
    }
    if (any) mailbox_.wake();
  }
  std::mutex mutex;
  std::vector<msg::SceneCommand> queue;

 private:
  InputMailbox& mailbox_;
};

}  // namespace

struct DdsNode::Impl {
  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  dds::DataWriter *skeleton = nullptr, *grasp_state = nullptr, *contacts = nullptr, *events = nullptr,
                  *scene = nullptr, *status = nullptr;
  std::unique_ptr<ControllerStateListener> input_listener;
  std::unique_ptr<SceneCommandListener> command_listener;
  std::string profiles;

  dds::Topic* topic(const char* name, dds::TopicDataType* type) {
    dds::TypeSupport ts(type);
    if (ts.register_type(participant) != ReturnCode_t::RETCODE_OK) throw std::runtime_error(std::string("cannot register the type of ") + name);
    dds::Topic* t = participant->create_topic(name, ts.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    if (!t) throw std::runtime_error(std::string("cannot create topic ") + name);
    return t;
  }
  dds::DataWriter* writer(const char* name, dds::TopicDataType* type) {
    const std::string profile = std::string(name) + idl::kWriterSuffix;
    dds::DataWriter* w = publisher->create_datawriter_with_profile(topic(name, type), profile);
    if (!w) throw std::runtime_error("cannot create the writer of " + std::string(name) + ": is profile '" + profile + "' in " + profiles + "?");
    return w;
  }
  dds::DataReader* reader(const char* name, dds::TopicDataType* type, dds::DataReaderListener* listener) {
    const std::string profile = std::string(name) + idl::kReaderSuffix;
    dds::DataReader* r = subscriber->create_datareader_with_profile(topic(name, type), profile, listener);
    if (!r) throw std::runtime_error("cannot create the reader of " + std::string(name) + ": is profile '" + profile + "' in " + profiles + "?");
    return r;
  }
  void close() {
    if (!participant) return;
    participant->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant);
    participant = nullptr;
  }
};

DdsNode::DdsNode(int domain, const std::string& profile, const std::string& profiles_file, InputMailbox& mailbox)
    : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.profiles = profiles_file.empty() ? idl::default_profiles_file() : profiles_file;
  idl::load_profiles(d.profiles, profile);
  d.participant = dds::DomainParticipantFactory::get_instance()->create_participant_with_profile(domain, profile);
  if (!d.participant) throw std::runtime_error("cannot join DDS domain " + std::to_string(domain) + " with profile '" + profile + "'");
  try {
    d.publisher = d.participant->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    d.subscriber = d.participant->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    if (!d.publisher || !d.subscriber) throw std::runtime_error("cannot create the publisher or subscriber");
    d.skeleton = d.writer(idl::kHandSkeletonTopic, new msg::HandSkeletonPubSubType());
    d.grasp_state = d.writer(idl::kGraspStateTopic, new msg::GraspStatePubSubType());
    d.contacts = d.writer(idl::kContactSetTopic, new msg::ContactSetPubSubType());
    d.events = d.writer(idl::kGraspEventTopic, new msg::GraspEventPubSubType());
    d.scene = d.writer(idl::kSceneStateTopic, new msg::SceneStatePubSubType());
    d.status = d.writer(idl::kServerStatusTopic, new msg::ServerStatusPubSubType());
    d.input_listener = std::make_unique<ControllerStateListener>(mailbox);
    d.command_listener = std::make_unique<SceneCommandListener>(mailbox);
    d.reader(idl::kControllerStateTopic, new msg::ControllerStatePubSubType(), d.input_listener.get());
    d.reader(idl::kSceneCommandTopic, new msg::SceneCommandPubSubType(), d.command_listener.get());
  } catch (...) {
    d.close();
    throw;
  }
}

DdsNode::~DdsNode() { impl_->close(); }

std::vector<msg::SceneCommand> DdsNode::take_commands() {
  std::lock_guard lock(impl_->command_listener->mutex);
  return std::exchange(impl_->command_listener->queue, {});
}

// A failed write is not fatal (e.g. a reliable reader is slow): the next tick publishes again.
void DdsNode::publish(const msg::HandSkeleton& m) { impl_->skeleton->write(const_cast<msg::HandSkeleton*>(&m)); }
void DdsNode::publish(const msg::GraspState& m) { impl_->grasp_state->write(const_cast<msg::GraspState*>(&m)); }
void DdsNode::publish(const msg::ContactSet& m) { impl_->contacts->write(const_cast<msg::ContactSet*>(&m)); }
void DdsNode::publish(const msg::SceneState& m) { impl_->scene->write(const_cast<msg::SceneState*>(&m)); }
void DdsNode::publish(const msg::ServerStatus& m) { impl_->status->write(const_cast<msg::ServerStatus*>(&m)); }
void DdsNode::publish(const msg::GraspEvent& m) {
  if (!impl_->events->write(const_cast<msg::GraspEvent*>(&m)))
    std::cerr << "telegrasp-server: could not publish grasp event " << m.event_id() << "\n";
}

void DdsNode::hand_removed(const HandAddress& hand) {
  auto drop = [&](dds::DataWriter* w, auto sample) {
    sample.client_id(hand.client_id);
    sample.hand_side(hand.side);
    w->dispose(&sample, dds::HANDLE_NIL);
    w->unregister_instance(&sample, dds::HANDLE_NIL);
  };
  drop(impl_->skeleton, msg::HandSkeleton());
  drop(impl_->grasp_state, msg::GraspState());
  drop(impl_->contacts, msg::ContactSet());
}

}  // namespace telegrasp::server
