// Tests idl/src/dds_participant.cc: DdsParticipant joins by profile, names what failed, makes one
// topic per name, connects its own writers and readers, and leaves nothing behind.
#include "telegrasp/idl/dds_participant.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"
#include "test_domain.h"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

namespace telegrasp::idl {
namespace {

namespace dds = eprosima::fastdds::dds;
using namespace std::chrono_literals;

// A domain no concurrent test uses, leased for the life of the test process. One participant at
// a time (one per process).
int test_domain() {
  static const testing::DomainLease lease;
  return lease.domain();
}
// Generous: a loaded machine can be slow to match; a passing test returns at once.
constexpr auto kTimeout = 20s;

// The message of the std::runtime_error `f` throws, or "" if it does not throw.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(DdsParticipantTest, NamesAParticipantProfileNotInTheFile) {
  const std::string error = error_of([] { DdsParticipant p(test_domain(), "no_such_profile"); });
  EXPECT_NE(error.find("'no_such_profile'"), std::string::npos) << error;
}

TEST(DdsParticipantTest, NamesTheTopicAndWriterOrReaderProfileNotInTheFile) {
  DdsParticipant p(test_domain(), kDefaultParticipantProfile);
  const std::string writer_error =
      error_of([&] { p.writer<msg::ServerStatusPubSubType>("test/Status", "test/NoQos"); });
  EXPECT_NE(writer_error.find("test/Status"), std::string::npos) << writer_error;
  EXPECT_NE(writer_error.find("'test/NoQos.writer'"), std::string::npos) << writer_error;
  EXPECT_NE(writer_error.find(p.profiles_file()), std::string::npos) << writer_error;
  const std::string reader_error =
      error_of([&] { p.reader<msg::ServerStatusPubSubType>("test/Status", nullptr, "test/NoQos"); });
  EXPECT_NE(reader_error.find("'test/NoQos.reader'"), std::string::npos) << reader_error;
}

TEST(DdsParticipantTest, MakesOneTopicPerNameAndRejectsASecondTypeOnIt) {
  DdsParticipant p(test_domain(), kDefaultParticipantProfile);
  // A second writer and a reader on the same topic reuse it (a second create_topic would fail).
  EXPECT_NE(p.writer<msg::ServerStatusPubSubType>(kServerStatusTopic), nullptr);
  EXPECT_NE(p.writer<msg::ServerStatusPubSubType>(kServerStatusTopic), nullptr);
  EXPECT_NE(p.reader<msg::ServerStatusPubSubType>(kServerStatusTopic), nullptr);
  // One type serves two topics; one topic does not take two types.
  EXPECT_NE(p.writer<msg::ServerStatusPubSubType>("test/Status", kServerStatusTopic), nullptr);
  const std::string error = error_of([&] { p.reader<msg::GraspEventPubSubType>(kServerStatusTopic); });
  EXPECT_NE(error.find(kServerStatusTopic), std::string::npos) << error;
  EXPECT_NE(error.find("GraspEvent"), std::string::npos) << error;
}

TEST(DdsParticipantTest, ItsOwnReaderTakesWhatItsWriterWrites) {
  DdsParticipant p(test_domain(), kDefaultParticipantProfile);
  // ServerStatus: reliable and transient local, so the sample waits for the reader.
  dds::DataWriter* writer = p.writer<msg::ServerStatusPubSubType>(kServerStatusTopic);
  msg::ServerStatus sent;
  sent.tick(42);
  ASSERT_TRUE(writer->write(&sent));
  dds::DataReader* reader = p.reader<msg::ServerStatusPubSubType>(kServerStatusTopic);

  msg::ServerStatus got;
  dds::SampleInfo info;
  bool taken = false;
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (!taken && std::chrono::steady_clock::now() < deadline) {
    taken = reader->take_next_sample(&got, &info) == ReturnCode_t::RETCODE_OK && info.valid_data;
    if (!taken) std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(taken) << "no ServerStatus within the timeout";
  EXPECT_EQ(got.tick(), 42u);
}

TEST(DdsParticipantTest, DestructionLeavesNoParticipantOnTheDomain) {
  auto* factory = dds::DomainParticipantFactory::get_instance();
  {
    DdsParticipant p(test_domain(), kDefaultParticipantProfile);
    p.writer<msg::GraspEventPubSubType>(kGraspEventTopic);
    p.reader<msg::ControllerStatePubSubType>(kControllerStateTopic);
    EXPECT_EQ(factory->lookup_participant(test_domain()), p.get());
  }
  EXPECT_EQ(factory->lookup_participant(test_domain()), nullptr);
}

}  // namespace
}  // namespace telegrasp::idl
