// Tests client_lib/tools/echo_main.cc: telegrasp-echo, run as a process, prints what raw Fast DDS
// writers publish as one JSON object per line, and exits after --count lines.
#include "telegrasp/idl/profiles.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

namespace telegrasp::testing {
namespace {

namespace dds = eprosima::fastdds::dds;
using namespace std::chrono_literals;

dds::DataWriter* make_writer(dds::DomainParticipant* participant, const char* name, dds::TopicDataType* type) {
  dds::TypeSupport support(type);
  support.register_type(participant);
  dds::Topic* topic = participant->create_topic(name, support.get_type_name(), dds::TOPIC_QOS_DEFAULT);
  dds::Publisher* publisher = participant->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  return publisher->create_datawriter_with_profile(topic, std::string(name) + idl::kWriterSuffix);
}

bool matched(dds::DataWriter* writer) {
  dds::PublicationMatchedStatus status;
  return writer->get_publication_matched_status(status) == ReturnCode_t::RETCODE_OK && status.current_count > 0;
}

TEST(EchoToolTest, PrintsOneJsonObjectPerSampleAndStopsAtTheCount) {
  const int domain = 208;
  idl::load_profiles("", "loopback");
  auto* factory = dds::DomainParticipantFactory::get_instance();
  dds::DomainParticipant* participant = factory->create_participant_with_profile(domain, "loopback");
  ASSERT_NE(participant, nullptr);
  dds::DataWriter* status_writer = make_writer(participant, idl::kServerStatusTopic, new msg::ServerStatusPubSubType());
  dds::DataWriter* event_writer = make_writer(participant, idl::kGraspEventTopic, new msg::GraspEventPubSubType());
  ASSERT_NE(status_writer, nullptr);
  ASSERT_NE(event_writer, nullptr);

  // Transient local: the status reaches the echo whenever it joins.
  msg::ServerStatus status;
  status.tick(90);
  status.clients(1);
  ASSERT_TRUE(status_writer->write(&status));

  const std::string command = std::string(TELEGRASP_ECHO) + " --domain " + std::to_string(domain) +
                              " --topics ServerStatus,GraspEvent --count 2 --seconds 60";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);

  // The grasp event (reliable, volatile) once the echo's reader has matched.
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (!matched(event_writer) && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(10ms);
  EXPECT_TRUE(matched(event_writer)) << "telegrasp-echo never subscribed";
  msg::GraspEvent event;
  event.event_id(5);
  event.kind(msg::GRASP_EVENT_RELEASE);
  event.client_id("bot-a");
  event.hand_side(msg::HAND_LEFT);
  event.object_pose().orientation().w(1);
  event.release_velocity().z(-0.5);
  ASSERT_TRUE(event_writer->write(&event));

  // Lines until the echo exits (after 2 lines, or at the latest after 60 s).
  std::vector<nlohmann::json> lines;
  char buffer[1 << 16];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) lines.push_back(nlohmann::json::parse(buffer));
  const int status_code = pclose(pipe);
  participant->delete_contained_entities();
  factory->delete_participant(participant);

  EXPECT_TRUE(WIFEXITED(status_code) && WEXITSTATUS(status_code) == 0) << "exit status " << status_code;
  ASSERT_EQ(lines.size(), 2u) << (lines.empty() ? std::string("no line") : lines.front().dump());
  const nlohmann::json* status_line = nullptr;
  const nlohmann::json* event_line = nullptr;
  for (const auto& line : lines) {
    if (line.at("topic") == "ServerStatus") status_line = &line;
    if (line.at("topic") == "GraspEvent") event_line = &line;
  }
  ASSERT_NE(status_line, nullptr);
  ASSERT_NE(event_line, nullptr);
  EXPECT_EQ(status_line->at("tick"), 90);
  EXPECT_EQ(status_line->at("clients"), 1);
  EXPECT_EQ(event_line->at("event_id"), 5);
  EXPECT_EQ(event_line->at("kind"), "release");
  EXPECT_EQ(event_line->at("hand").at("client_id"), "bot-a");
  EXPECT_EQ(event_line->at("hand").at("side"), "left");
  EXPECT_EQ(event_line->at("v_WorldObject").at(2), -0.5);
  EXPECT_EQ(event_line->at("X_WorldObject").at("q").at(0), 1.0);  // w first
}

}  // namespace
}  // namespace telegrasp::testing
