#include "dds_node.h"

#include "identity.h"

#include "telegrasp/idl/dds_participant.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include <chrono>
#include <cstring>
#include <iostream>
#include <mutex>
#include <optional>
#include <utility>

namespace telegrasp::server {

namespace dds = eprosima::fastdds::dds;

namespace {

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

ParticipantKey key_of(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) {
  ParticipantKey key;
  std::memcpy(key.data(), prefix.value, key.size());
  return key;
}

// With DDS Security: the certificate subject of every remote participant, as it is discovered
// (after authentication; before its endpoints match, so before any of its samples).
class IdentityListener : public dds::DomainParticipantListener {
 public:
  void on_participant_discovery(dds::DomainParticipant*,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    using Status = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo;
    const ParticipantKey key = key_of(info.info.m_guid.guidPrefix);
    if (info.status == Status::DISCOVERED_PARTICIPANT || info.status == Status::CHANGED_QOS_PARTICIPANT)
      identities.participant_discovered(key, certificate_subject(info.info));
    else
      identities.participant_left(key);
  }
  ClientIdentities identities;
};

// Controller states go straight to the mailbox, with the writing participant's GUID prefix or,
// with DDS Security, its identity's owner key.
class ControllerStateListener : public dds::DataReaderListener {
 public:
  ControllerStateListener(InputMailbox& mailbox, ClientIdentities& identities)
      : mailbox_(mailbox), identities_(identities) {}
  void on_data_available(dds::DataReader* reader) override {
    dds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;  // instance state changes, not samples
      ParticipantKey writer = key_of(info.sample_identity.writer_guid().guidPrefix);
      if (secure) {
        const std::optional<ParticipantKey> owner = identities_.admit(writer, sample_.client_id().to_string());
        if (!owner) {
          mailbox_.refuse(RejectReason::kClientIdOwnedByAnotherParticipant, sample_.client_id().to_string());
          continue;
        }
        writer = *owner;
      }
      mailbox_.offer(sample_, writer, steady_now_ns());
    }
  }
  bool secure = false;  // set before the reader exists

 private:
  InputMailbox& mailbox_;
  ClientIdentities& identities_;
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

// Members in destruction order: the participant (and its readers) goes before the listeners.
struct DdsNode::Impl {
  Impl(int domain, const std::string& profile, const std::string& profiles_file, InputMailbox& mailbox)
      : input_listener(mailbox, identity_listener.identities),
        command_listener(mailbox),
        participant(domain, profile, profiles_file, &identity_listener) {
    input_listener.secure = participant.secure();
  }

  IdentityListener identity_listener;
  ControllerStateListener input_listener;
  SceneCommandListener command_listener;
  idl::DdsParticipant participant;
  dds::DataWriter *skeleton = nullptr, *grasp_state = nullptr, *contacts = nullptr, *events = nullptr, *scene = nullptr,
                  *status = nullptr, *geometry = nullptr;
};

DdsNode::DdsNode(int domain, const std::string& profile, const std::string& profiles_file, InputMailbox& mailbox)
    : impl_(std::make_unique<Impl>(domain, profile, profiles_file, mailbox)) {
  Impl& d = *impl_;
  idl::DdsParticipant& p = d.participant;
  d.skeleton = p.writer<msg::HandSkeletonPubSubType>(idl::kHandSkeletonTopic);
  d.grasp_state = p.writer<msg::GraspStatePubSubType>(idl::kGraspStateTopic);
  d.contacts = p.writer<msg::ContactSetPubSubType>(idl::kContactSetTopic);
  d.events = p.writer<msg::GraspEventPubSubType>(idl::kGraspEventTopic);
  d.scene = p.writer<msg::SceneStatePubSubType>(idl::kSceneStateTopic);
  d.status = p.writer<msg::ServerStatusPubSubType>(idl::kServerStatusTopic);
  d.geometry = p.writer<msg::ObjectGeometryPubSubType>(idl::kObjectGeometryTopic);
  p.reader<msg::ControllerStatePubSubType>(idl::kControllerStateTopic, &d.input_listener);
  p.reader<msg::SceneCommandPubSubType>(idl::kSceneCommandTopic, &d.command_listener);
}

DdsNode::~DdsNode() = default;

void DdsNode::publish_geometries(const std::vector<sim::ObjectModelPtr>& models) {
  for (const sim::ObjectModelPtr& model : models) {
    msg::ObjectGeometry m = make_object_geometry(*model);
    if (m.mesh_omitted())
      std::cerr << "telegrasp-server: model " << model->name << " has " << m.triangle_count() << " triangles, over the "
                << msg::OBJECT_GEOMETRY_MAX_TRIANGLES << " ObjectGeometry carries: published without its mesh\n";
    if (!impl_->geometry->write(&m))
      std::cerr << "telegrasp-server: could not publish the geometry of model " << model->name << "\n";
  }
}

std::vector<msg::SceneCommand> DdsNode::take_commands() {
  std::lock_guard lock(impl_->command_listener.mutex);
  return std::exchange(impl_->command_listener.queue, {});
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
