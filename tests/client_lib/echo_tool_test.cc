// Tests client_lib/tools/echo/main.cc: telegrasp-echo, run as a process, prints what raw Fast DDS
// writers publish as one JSON object per line, and exits after --count lines.
#include "telegrasp/idl/dds_participant.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"
#include "test_domain.h"

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
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
using telegrasp::testing::DomainLease;

bool matched(dds::DataWriter* writer) {
  dds::PublicationMatchedStatus status;
  return writer->get_publication_matched_status(status) == ReturnCode_t::RETCODE_OK && status.current_count > 0;
}

TEST(EchoToolTest, PrintsOneJsonObjectPerSampleAndStopsAtTheCount) {
  const DomainLease lease;  // held by the echo process too while it runs
  const int domain = lease.domain();
  // Owns every DDS entity of the test, so a failed assertion below frees them too.
  idl::DdsParticipant participant(domain, "loopback");
  dds::DataWriter* status_writer = participant.writer<msg::ServerStatusPubSubType>(idl::kServerStatusTopic);
  dds::DataWriter* event_writer = participant.writer<msg::GraspEventPubSubType>(idl::kGraspEventTopic);

  // Transient local: the status reaches the echo whenever it joins.
  msg::ServerStatus status;
  status.tick(90);
  status.clients(1);
  ASSERT_TRUE(status_writer->write(&status));

  const std::string command = std::string(TELEGRASP_ECHO) + " --domain " + std::to_string(domain) +
                              " --topics ServerStatus,GraspEvent --count 2 --duration-s 60";
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
  EXPECT_EQ(event_line->at("v_WorldObject_m_per_s").at(2), -0.5);
  EXPECT_EQ(event_line->at("X_WorldObject").at("q_wxyz").at(0), 1.0);  // w first
}

}  // namespace
}  // namespace telegrasp::testing
