#include "telegrasp/idl/dds_participant.h"

#include "telegrasp/idl/profiles.h"
#include "telegrasp/idl/security.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/PublisherQos.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <stdexcept>

namespace telegrasp::idl {

namespace dds = eprosima::fastdds::dds;

DdsParticipant::DdsParticipant(int domain, const std::string& profile, const std::string& profiles_file,
                               dds::DomainParticipantListener* listener, const Network& network)
    : profiles_file_(profiles_file.empty() ? default_profiles_file() : profiles_file),
      profile_(profile),
      network_(resolve_network(network)) {
  load_profiles(profiles_file_, profile_);
  dds::DomainParticipantFactory* factory = dds::DomainParticipantFactory::get_instance();
  dds::DomainParticipantQos qos;
  if (factory->get_participant_qos_from_profile(profile_, qos) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("no participant profile '" + profile_ + "' in " + profiles_file_);
  const SecurityFiles security = security_from_environment();
  secure_ = apply_security(qos, profile_, security);
  apply_discovery_servers(qos, network_.discovery_servers);
  // The profile alone, unless security or discovery servers change its QoS.
  // No status reaches `listener` (discovery always does): a participant listener with
  // data_on_readers would take the samples from the readers' own listeners.
  participant_ = secure_ || !network_.discovery_servers.empty()
                     ? factory->create_participant(domain, qos, listener, dds::StatusMask::none())
                     : factory->create_participant_with_profile(domain, profile_, listener, dds::StatusMask::none());
  if (participant_ == nullptr)
    throw std::runtime_error("cannot join DDS domain " + std::to_string(domain) + " with participant profile '" +
                             profile_ + "' of " + profiles_file_ +
                             (secure_
                                  ? " (DDS Security refused identity '" + security.identity + "' of " + security.dir +
                                        ": an expired certificate or one of another CA, a key "
                                        "that does not match, or an unsigned governance or permissions file?)"
                                  : ""));
  dds::PublisherQos scene_pub;
  dds::SubscriberQos scene_sub;
  scene_pub.partition().push_back(scene_partition(network_.scene).c_str());
  scene_sub.partition().push_back(scene_partition(network_.scene).c_str());
  dds::PublisherQos directory_pub;
  dds::SubscriberQos directory_sub;
  directory_pub.partition().push_back(kDirectoryPartition);
  directory_sub.partition().push_back(kDirectoryPartition);
  publisher_ = participant_->create_publisher(scene_pub);
  subscriber_ = participant_->create_subscriber(scene_sub);
  directory_publisher_ = participant_->create_publisher(directory_pub);
  directory_subscriber_ = participant_->create_subscriber(directory_sub);
  if (publisher_ == nullptr || subscriber_ == nullptr || directory_publisher_ == nullptr ||
      directory_subscriber_ == nullptr) {
    close();
    throw std::runtime_error("cannot create the DDS publisher or subscriber of participant profile '" + profile + "'");
  }
}

DdsParticipant::~DdsParticipant() { close(); }

void DdsParticipant::close() {
  if (participant_ == nullptr) return;
  for (dds::DataReader* r : readers_) r->set_listener(nullptr);
  participant_->delete_contained_entities();
  dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  participant_ = nullptr;
  publisher_ = nullptr;
  subscriber_ = nullptr;
  directory_publisher_ = nullptr;
  directory_subscriber_ = nullptr;
  topics_.clear();
  readers_.clear();
}

dds::Topic* DdsParticipant::topic(const std::string& name, TypeFactory type) {
  dds::TypeSupport support(type());  // owns the new type object from here on
  const std::string type_name = support.get_type_name();
  if (const auto it = topics_.find(name); it != topics_.end()) {
    if (it->second->get_type_name() != type_name)
      throw std::runtime_error("DDS topic " + name + " has type " + it->second->get_type_name() + ", not " + type_name);
    return it->second;
  }
  if (participant_->find_type(type_name).empty() && support.register_type(participant_) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("cannot register DDS type " + type_name + " of topic " + name);
  dds::Topic* t = participant_->create_topic(name, type_name, dds::TOPIC_QOS_DEFAULT);
  if (t == nullptr) throw std::runtime_error("cannot create DDS topic " + name + " of type " + type_name);
  topics_[name] = t;
  return t;
}

// Every endpoint goes without Fast DDS's data-sharing, which 2.9 otherwise uses by default for
// bounded types between processes of one host, whatever the transport. A writer notifies each
// data-sharing reader under a mutex in that reader's shared memory: a reader's process killed
// while holding it left the server's next write blocked for the mutex's timeout, then throwing
// "Interprocess mutex timeout when locking" (a SIGKILLed bot stopped the server that way, one
// run in a few under ASan). And under DDS Security it would hand readers buffers that were never
// encoded for them (Fast DDS 2.9.1 then fails to decode every sample). The transports copy.
dds::DataWriter* DdsParticipant::make_writer(const std::string& name, TypeFactory type, const std::string& qos_of) {
  const std::string profile = (qos_of.empty() ? name : qos_of) + kWriterSuffix;
  dds::Publisher* publisher = name == kSceneDirectoryTopic ? directory_publisher_ : publisher_;
  dds::DataWriterQos qos;
  dds::DataWriter* w = nullptr;
  if (publisher->get_datawriter_qos_from_profile(profile, qos) == ReturnCode_t::RETCODE_OK) {
    qos.data_sharing().off();
    w = publisher->create_datawriter(topic(name, type), qos);
  }
  if (w == nullptr)
    throw std::runtime_error("cannot create the DDS writer of topic " + name + ": is profile '" + profile + "' in " +
                             profiles_file_ + "?");
  return w;
}

dds::DataReader* DdsParticipant::make_reader(const std::string& name, TypeFactory type,
                                             dds::DataReaderListener* listener, const std::string& qos_of) {
  const std::string profile = (qos_of.empty() ? name : qos_of) + kReaderSuffix;
  dds::Subscriber* subscriber = name == kSceneDirectoryTopic ? directory_subscriber_ : subscriber_;
  dds::DataReaderQos qos;
  dds::DataReader* r = nullptr;
  if (subscriber->get_datareader_qos_from_profile(profile, qos) == ReturnCode_t::RETCODE_OK) {
    qos.data_sharing().off();  // as for writers
    r = subscriber->create_datareader(topic(name, type), qos, listener);
  }
  if (r == nullptr)
    throw std::runtime_error("cannot create the DDS reader of topic " + name + ": is profile '" + profile + "' in " +
                             profiles_file_ + "?");
  readers_.push_back(r);
  return r;
}

}  // namespace telegrasp::idl
