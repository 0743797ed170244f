#include "dds_node.h"

#include "identity.h"

#include "telegrasp/idl/dds_participant.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <deque>
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

// Every remote participant as it is discovered (after authentication with DDS Security, before
// its endpoints match, so before any of its samples): its certificate subject under security; when
// it leaves (or its lease runs out), the client ids it owned are free again.
class ParticipantListener : public dds::DomainParticipantListener {
 public:
  explicit ParticipantListener(InputMailbox& mailbox) : mailbox_(mailbox) {}
  void on_participant_discovery(dds::DomainParticipant*,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    using Status = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo;
    const ParticipantKey key = key_of(info.info.m_guid.guidPrefix);
    if (info.status == Status::DISCOVERED_PARTICIPANT || info.status == Status::CHANGED_QOS_PARTICIPANT) {
      identities.participant_discovered(key, certificate_subject(info.info));
    } else {
      identities.participant_left(key);
      if (info.status == Status::REMOVED_PARTICIPANT || info.status == Status::DROPPED_PARTICIPANT)
        mailbox_.forget_participant(key);
    }
  }
  /// Whom a sample of `client_id` from `writer` counts as: the writer's participant, or with DDS
  /// Security the identity owning the id (none: another identity owns it).
  std::optional<ParticipantKey> sender(const ParticipantKey& writer, const std::string& client_id) {
    if (!secure) return writer;
    return identities.admit(writer, client_id);
  }
  ClientIdentities identities;
  bool secure = false;  // set before any reader exists

 private:
  InputMailbox& mailbox_;
};

// What the input listeners share: the mailbox they feed and who sent a sample.
class InputListener : public dds::DataReaderListener {
 public:
  InputListener(InputMailbox& mailbox, ParticipantListener& participants)
      : mailbox_(mailbox), participants_(participants) {}

 protected:
  // The sender of a sample of `client_id` (ParticipantListener::sender).
  std::optional<ParticipantKey> sender_of(const dds::SampleInfo& info, const std::string& client_id) {
    return participants_.sender(key_of(info.sample_identity.writer_guid().guidPrefix), client_id);
  }

  InputMailbox& mailbox_;

 private:
  ParticipantListener& participants_;
};

// Controller states go straight to the mailbox, with their sender.
class ControllerStateListener : public InputListener {
 public:
  using InputListener::InputListener;
  void on_data_available(dds::DataReader* reader) override {
    dds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;  // instance state changes, not samples
      const std::string client_id = sample_.client_id().to_string();
      const std::optional<ParticipantKey> sender = sender_of(info, client_id);
      if (!sender) {
        mailbox_.refuse(RejectReason::kClientIdOwnedByAnotherParticipant, client_id);
        continue;
      }
      mailbox_.offer(sample_, *sender, steady_now_ns());
    }
  }

 private:
  msg::ControllerState sample_;  // reused: one listener thread per reader
};

// Commands are admitted (owner of the client id, rate) before they are queued for the scene.
class SceneCommandListener : public InputListener {
 public:
  using InputListener::InputListener;
  void on_data_available(dds::DataReader* reader) override {
    msg::SceneCommand c;
    dds::SampleInfo info;
    bool any = false;
    while (reader->take_next_sample(&c, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      const std::optional<ParticipantKey> sender = sender_of(info, c.client_id().to_string());
      if (!mailbox_.admit_command(c, sender, steady_now_ns()).empty()) continue;
      std::lock_guard lock(mutex);
      queue.push_back(c);
      any = true;
    }
    if (any) mailbox_.wake();
  }
  std::mutex mutex;
  std::vector<msg::SceneCommand> queue;
};

// A failed write is not fatal (a reliable reader is slow, or Fast DDS threw on the way: a peer's
// process may die holding a lock in shared memory): the next tick publishes again.
template <typename Message>
bool write(dds::DataWriter* writer, const Message& m, const char* what) {
  try {
    return writer->write(const_cast<Message*>(&m));
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-server: could not publish a " << what << ": " << e.what() << "\n";
    return false;
  }
}

}  // namespace

// Members in destruction order: the participant (and its readers) goes before the listeners.
struct DdsNode::Impl {
  Impl(int domain, const std::string& profile, const std::string& profiles_file, InputMailbox& mailbox,
       const idl::Network& network)
      : participant_listener(mailbox),
        input_listener(mailbox, participant_listener),
        command_listener(mailbox, participant_listener),
        participant(domain, profile, profiles_file, &participant_listener, network) {
    participant_listener.secure = participant.secure();
  }

  ParticipantListener participant_listener;
  ControllerStateListener input_listener;
  SceneCommandListener command_listener;
  idl::DdsParticipant participant;
  dds::DataWriter *skeleton = nullptr, *grasp_state = nullptr, *contacts = nullptr, *events = nullptr, *scene = nullptr,
                  *status = nullptr, *geometry = nullptr, *notices = nullptr;
  std::mutex notice_mutex;
  std::deque<std::string> notice_clients;  // clients with a notice instance, oldest first
  dds::DataWriter* directory_writer = nullptr;
  dds::DataReader* directory_reader = nullptr;
  // The scene directory, once announce() was called (then only the simulation thread's status).
  std::optional<AnnouncerFacts> facts;
  ProcessLoad load;
  std::uint64_t conflict_logged = 0;  // the incarnation of the last conflicting claim logged
};

DdsNode::DdsNode(int domain, const std::string& profile, const std::string& profiles_file, InputMailbox& mailbox,
                 const idl::Network& network)
    : impl_(std::make_unique<Impl>(domain, profile, profiles_file, mailbox, network)) {
  Impl& d = *impl_;
  idl::DdsParticipant& p = d.participant;
  d.skeleton = p.writer<msg::HandSkeletonPubSubType>(idl::kHandSkeletonTopic);
  d.grasp_state = p.writer<msg::GraspStatePubSubType>(idl::kGraspStateTopic);
  d.contacts = p.writer<msg::ContactSetPubSubType>(idl::kContactSetTopic);
  d.events = p.writer<msg::GraspEventPubSubType>(idl::kGraspEventTopic);
  d.scene = p.writer<msg::SceneStatePubSubType>(idl::kSceneStateTopic);
  d.status = p.writer<msg::ServerStatusPubSubType>(idl::kServerStatusTopic);
  d.geometry = p.writer<msg::ObjectGeometryPubSubType>(idl::kObjectGeometryTopic);
  d.notices = p.writer<msg::ClientNoticePubSubType>(idl::kClientNoticeTopic);
  p.reader<msg::ControllerStatePubSubType>(idl::kControllerStateTopic, &d.input_listener);
  p.reader<msg::SceneCommandPubSubType>(idl::kSceneCommandTopic, &d.command_listener);
  d.directory_writer = p.writer<msg::SceneAnnouncementPubSubType>(idl::kSceneDirectoryTopic);
  d.directory_reader = p.reader<msg::SceneAnnouncementPubSubType>(idl::kSceneDirectoryTopic);
}

DdsNode::~DdsNode() {
  // A clean stop leaves the directory at once (a dead server's entry goes when its lease ends).
  if (!impl_->facts) return;
  msg::SceneAnnouncement gone = make_claim(*impl_->facts);
  impl_->directory_writer->dispose(&gone, dds::HANDLE_NIL);
  impl_->directory_writer->unregister_instance(&gone, dds::HANDLE_NIL);
}

const std::string& DdsNode::scene() const { return impl_->participant.network().scene; }

void DdsNode::announce(const AnnouncerFacts& facts) {
  impl_->facts = facts;
  msg::SceneAnnouncement claim = make_claim(facts);
  impl_->directory_writer->write(&claim);
}

std::vector<msg::SceneAnnouncement> DdsNode::directory() {
  std::vector<msg::SceneAnnouncement> live = idl::read_alive_instances<msg::SceneAnnouncement>(impl_->directory_reader);
  if (impl_->facts)
    std::erase_if(live, [&](const msg::SceneAnnouncement& a) { return a.incarnation() == impl_->facts->incarnation; });
  return live;
}

void DdsNode::announce_status(const msg::ServerStatus& status) {
  Impl& d = *impl_;
  msg::SceneAnnouncement a =
      make_announcement(*d.facts, status, d.load.cpu_percent(), ProcessLoad::host_cores(), ProcessLoad::host_load());
  write(d.directory_writer, a, "SceneAnnouncement");
  // Another run serving this scene too (e.g. the network between them was cut while both
  // started): the newer one refused to start if it saw this one; say so once per run.
  for (const msg::SceneAnnouncement& other : directory()) {
    if (other.scene() != a.scene() || other.incarnation() == d.conflict_logged) continue;
    d.conflict_logged = other.incarnation();
    std::cerr << "telegrasp-server: warning: scene '" << a.scene().to_string() << "' is also served by "
              << describe_run(other) << "; the run that started later should stop\n";
  }
}

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

void DdsNode::publish(const msg::HandSkeleton& m) { write(impl_->skeleton, m, "HandSkeleton"); }
void DdsNode::publish(const msg::GraspState& m) { write(impl_->grasp_state, m, "GraspState"); }
void DdsNode::publish(const msg::ContactSet& m) { write(impl_->contacts, m, "ContactSet"); }
void DdsNode::publish(const msg::SceneState& m) { write(impl_->scene, m, "SceneState"); }
void DdsNode::publish(const msg::ServerStatus& m) {
  write(impl_->status, m, "ServerStatus");
  if (impl_->facts) announce_status(m);
}
void DdsNode::publish(const msg::GraspEvent& m) {
  if (!write(impl_->events, m, "GraspEvent"))
    std::cerr << "telegrasp-server: could not publish grasp event " << m.event_id() << "\n";
}

void DdsNode::publish(const msg::ClientNotice& m) {
  Impl& d = *impl_;
  std::lock_guard lock(d.notice_mutex);
  const std::string client = m.client_id().to_string();
  if (auto it = std::find(d.notice_clients.begin(), d.notice_clients.end(), client); it != d.notice_clients.end())
    d.notice_clients.erase(it);
  d.notice_clients.push_back(client);
  if (d.notice_clients.size() > kMaxNoticeInstances) {
    msg::ClientNotice oldest;
    oldest.client_id(d.notice_clients.front());
    d.notices->unregister_instance(&oldest, dds::HANDLE_NIL);
    d.notice_clients.pop_front();
  }
  write(d.notices, m, "ClientNotice");
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
