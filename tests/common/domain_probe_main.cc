// telegrasp-test-domain-probe: one stand-in test run for domain_lease_test.cc. Joins a DDS domain
// (a DomainLease of its own, or --domain D), writes a sample marked with its process id every
// 10 ms on a test topic and reads that topic. Prints to stdout, one line each:
//   domain D      once, first: the domain it joined
//   own N         for each of its own samples it reads (N: how many so far)
//   foreign PID   for each sample it reads from another process
// and runs until SIGTERM or SIGINT (exit 0).
#include "test_domain.h"
#include "telegrasp/idl/dds_participant.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <thread>

namespace {

namespace fdds = eprosima::fastdds::dds;
using telegrasp::msg::ServerStatus;

constexpr const char* kTopic = "test/DomainProbe";

std::atomic<bool> stop{false};
extern "C" void on_signal(int) { stop = true; }

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  try {
    std::optional<telegrasp::testing::DomainLease> lease;
    int domain = -1;
    if (argc == 3 && std::strcmp(argv[1], "--domain") == 0) {
      domain = std::stoi(argv[2]);
    } else if (argc == 1) {
      lease.emplace();
      domain = lease->domain();
    } else {
      std::fprintf(stderr, "usage: telegrasp-test-domain-probe [--domain D]\n");
      return 2;
    }
    std::printf("domain %d\n", domain);
    std::fflush(stdout);

    telegrasp::idl::DdsParticipant participant(domain, "loopback");
    // Reliable and transient local (the ServerStatus QoS): a late reader still gets the last one.
    fdds::DataWriter* writer =
        participant.writer<telegrasp::msg::ServerStatusPubSubType>(kTopic, telegrasp::idl::kServerStatusTopic);
    fdds::DataReader* reader =
        participant.reader<telegrasp::msg::ServerStatusPubSubType>(kTopic, nullptr, telegrasp::idl::kServerStatusTopic);
    const int self = static_cast<int>(::getpid());
    long own = 0;
    for (std::uint64_t n = 1; !stop; ++n) {
      ServerStatus sample;
      sample.tick(n);
      sample.clients(self);
      writer->write(&sample);
      ServerStatus got;
      fdds::SampleInfo info;
      while (reader->take_next_sample(&got, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data) continue;
        if (got.clients() == self)
          std::printf("own %ld\n", ++own);
        else
          std::printf("foreign %d\n", got.clients());
      }
      std::fflush(stdout);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // pacing, not a measurement
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "telegrasp-test-domain-probe: %s\n", e.what());
    return 1;
  }
  return 0;
}
