// DdsParticipant: the one RAII owner of a process's Fast DDS entities (participant, publisher,
// subscriber, topics, writers, readers), all made from the XML profiles by name.
#pragma once

#include "telegrasp/idl/network.h"
#include "telegrasp/idl/safe_type.h"

#include <fastdds/dds/core/LoanableSequence.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>

#include <map>
#include <string>
#include <vector>

namespace eprosima::fastdds::dds {
class DomainParticipant;
class DomainParticipantListener;
class Publisher;
class Subscriber;
class Topic;
}  // namespace eprosima::fastdds::dds

namespace telegrasp::idl {

/// A DomainParticipant joined by participant profile, with one publisher and one subscriber, the
/// topics (one per name, its type registered once) and the writers and readers made with the
/// profiles "<topic>.writer" and "<topic>.reader" (topics.h). Writers and readers are in the
/// scene's DDS partition, those of the scene directory topic in the directory's. Everything it creates it deletes.
/// Several participants in one process can deadlock Fast DDS 2.9: make one per process (the
/// network benchmarks make several, with intraprocess delivery off).
class DdsParticipant {
 public:
  /// Loads `profiles_file` ("" = default_profiles_file()) and joins `domain` with the participant
  /// profile `profile`. A profile with DDS Security (`secure`) gets its identity's files from
  /// security_from_environment() (security.h). `listener` (may be null; must outlive this object)
  /// hears of remote participants from the start, before any sample of theirs arrives. `network`
  /// (resolve_network(): the environment fills what it leaves empty) names the scene, whose DDS
  /// partition every topic but the directory's is in, and any discovery servers. Throws
  /// std::runtime_error naming the file, variable, value or profile that failed.
  DdsParticipant(int domain, const std::string& profile, const std::string& profiles_file = "",
                 eprosima::fastdds::dds::DomainParticipantListener* listener = nullptr, const Network& network = {});
  /// Detaches the readers' listeners, deletes every contained entity, then the participant.
  /// Listeners given to reader() must outlive this object.
  ~DdsParticipant();
  DdsParticipant(const DdsParticipant&) = delete;
  DdsParticipant& operator=(const DdsParticipant&) = delete;

  /// A new writer on `topic` (type PubSubType, e.g. msg::HandSkeletonPubSubType) with the QoS
  /// profile "<qos_of>.writer" ("" = `topic`'s own). Owned by this participant. Throws
  /// std::runtime_error naming the topic or profile that failed.
  template <class PubSubType>
  eprosima::fastdds::dds::DataWriter* writer(const std::string& topic, const std::string& qos_of = "") {
    return make_writer(topic, &new_type<PubSubType>, qos_of);
  }

  /// A new reader on `topic` with the QoS profile "<qos_of>.reader" ("" = `topic`'s own); its
  /// listener (may be null) runs as soon as it returns. Owned by this participant. Throws
  /// std::runtime_error naming the topic or profile that failed.
  template <class PubSubType>
  eprosima::fastdds::dds::DataReader* reader(const std::string& topic,
                                             eprosima::fastdds::dds::DataReaderListener* listener = nullptr,
                                             const std::string& qos_of = "") {
    return make_reader(topic, &new_type<PubSubType>, listener, qos_of);
  }

  /// The participant itself (for status queries; entities made on it directly are deleted too).
  eprosima::fastdds::dds::DomainParticipant* get() const { return participant_; }
  /// The profiles file in use (resolved: never empty).
  const std::string& profiles_file() const { return profiles_file_; }
  /// Whether the participant runs with DDS Security (authenticated, access controlled).
  bool secure() const { return secure_; }
  /// The scene and discovery servers in use (resolved).
  const Network& network() const { return network_; }

 private:
  using TypeFactory = eprosima::fastdds::dds::TopicDataType* (*)();
  template <class PubSubType>
  static eprosima::fastdds::dds::TopicDataType* new_type() {
    return new SafeType<PubSubType>();  // a malformed sample is dropped, never thrown
  }

  eprosima::fastdds::dds::Topic* topic(const std::string& name, TypeFactory type);
  eprosima::fastdds::dds::DataWriter* make_writer(const std::string& topic, TypeFactory type,
                                                  const std::string& qos_of);
  eprosima::fastdds::dds::DataReader* make_reader(const std::string& topic, TypeFactory type,
                                                  eprosima::fastdds::dds::DataReaderListener* listener,
                                                  const std::string& qos_of);
  void close();

  std::string profiles_file_;
  std::string profile_;
  Network network_;
  bool secure_ = false;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  // The scene directory's topic, in its own partition (topics.h).
  eprosima::fastdds::dds::Publisher* directory_publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* directory_subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
  std::vector<eprosima::fastdds::dds::DataReader*> readers_;
};

/// The newest sample of every alive instance of `reader` (of type T), read, not taken: they stay
/// for the next call. An instance whose writer is gone (unregistered, or its liveliness lost) is
/// left out.
template <class T>
std::vector<T> read_alive_instances(eprosima::fastdds::dds::DataReader* reader) {
  namespace dds = eprosima::fastdds::dds;
  dds::LoanableSequence<T> data;
  dds::SampleInfoSeq infos;
  std::vector<T> alive;
  if (reader->read(data, infos, dds::LENGTH_UNLIMITED, dds::ANY_SAMPLE_STATE, dds::ANY_VIEW_STATE,
                   dds::ALIVE_INSTANCE_STATE) != ReturnCode_t::RETCODE_OK)
    return alive;
  for (dds::LoanableCollection::size_type i = 0; i < data.length(); ++i)
    if (infos[i].valid_data) alive.push_back(data[i]);
  reader->return_loan(data, infos);
  return alive;
}

}  // namespace telegrasp::idl
