// Tests tests/common/test_domain.cc: leases never share a domain, in one process or across
// processes; a lease holds until its owner and the children it started have let go; a domain
// that another DDS program uses is skipped; and two test runs started at the same time on one
// machine get disjoint domains and never receive each other's samples.
#include "test_domain.h"
#include "child_process.h"
#include "telegrasp/idl/dds_participant.h"

#include <fcntl.h>
#include <netinet/in.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
using tools::ChildProcess;

// Generous: a guard against hangs on a loaded machine; passing tests return at once.
constexpr auto kGuard = 60s;

// `size` domains leased from the test pool (so no other test process uses them), offered again
// as a pool of their own with a fresh lock folder: the test alone decides who holds them there.
class PrivatePool {
 public:
  explicit PrivatePool(int size) : lease_(size) {
    char dir[] = "/tmp/telegrasp-domain-lease-test.XXXXXX";
    if (::mkdtemp(dir) == nullptr) throw std::runtime_error("mkdtemp failed");
    dir_ = dir;
    pool_ = {lease_.domain(), lease_.domain(size - 1), dir_ + "/locks"};
  }
  ~PrivatePool() { std::filesystem::remove_all(dir_); }
  const DomainPool& get() const { return pool_; }

 private:
  DomainLease lease_;
  std::string dir_;
  DomainPool pool_;
};

// Whether DomainLease(1, pool) throws (no domain of `pool` is free).
bool pool_exhausted(const DomainPool& pool) {
  try {
    DomainLease lease(1, pool);
    return false;
  } catch (const std::runtime_error&) {
    return true;
  }
}

TEST(DomainLeaseTest, LeasesInOneProcessNeverShareADomain) {
  PrivatePool pool(8);
  DomainLease a(1, pool.get()), b(3, pool.get()), c(2, pool.get());
  std::set<int> seen;
  for (const DomainLease* l : {&a, &b, &c})
    for (int i = 0; i < l->count(); ++i) {
      EXPECT_GE(l->domain(i), pool.get().first);
      EXPECT_LE(l->domain(i), pool.get().last);
      EXPECT_TRUE(seen.insert(l->domain(i)).second) << "domain " << l->domain(i) << " leased twice";
    }
  EXPECT_EQ(b.domain(2), b.domain() + 2) << "a block is consecutive";
  EXPECT_EQ(seen.size(), 6u);
}

TEST(DomainLeaseTest, ALeasedDomainIsTakenUntilReleasedAndNotReusedAtOnce) {
  PrivatePool pool(2);
  std::optional<DomainLease> first(std::in_place, 1, pool.get());
  const int d = first->domain();
  {
    DomainLease second(1, pool.get());
    EXPECT_NE(second.domain(), d);
    EXPECT_TRUE(pool_exhausted(pool.get())) << "both domains are leased";
  }
  first.reset();
  // Both free again; the next lease takes the one not handed out most recently.
  DomainLease third(1, pool.get());
  EXPECT_EQ(third.domain(), d);
}

TEST(DomainLeaseTest, AChildProcessKeepsTheDomainUntilItExits) {
  PrivatePool pool(1);
  std::optional<DomainLease> lease(std::in_place, 1, pool.get());
  ChildProcess child({"/bin/sleep", "600"});
  lease.reset();
  EXPECT_TRUE(pool_exhausted(pool.get())) << "the child inherited the lease";
  child.stop();
  EXPECT_FALSE(pool_exhausted(pool.get())) << "free once the child has exited";
}

TEST(DomainLeaseTest, SkipsADomainWhoseDiscoveryPortIsBound) {
  PrivatePool pool(1);
  const int d = pool.get().first;
  EXPECT_FALSE(domain_ports_in_use(d));
  // A program outside the scheme on domain d: here a socket on its discovery multicast port.
  const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(s, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(7400 + 250 * d));
  ASSERT_EQ(::bind(s, reinterpret_cast<const sockaddr*>(&a), sizeof a), 0);
  EXPECT_TRUE(domain_ports_in_use(d));
  EXPECT_TRUE(pool_exhausted(pool.get()));
  ::close(s);
  EXPECT_FALSE(pool_exhausted(pool.get()));
}

TEST(DomainLeaseTest, StartsWithoutTheSharedMemoryPortsAKilledParticipantLeft) {
  PrivatePool pool(2);
  // Stand-ins for what participants killed on both domains leave behind.
  auto left_on = [](int domain) {
    const std::string port = std::to_string(7400 + 250 * domain + 10);
    return std::vector<std::string>{"/dev/shm/fastrtps_port" + port, "/dev/shm/sem.fastrtps_port" + port + "_mutex",
                                    "/dev/shm/fastrtps_port" + std::to_string(7400 + 250 * domain + 249)};
  };
  // Whatever happens below, no made-up file stays for a participant to open.
  struct RemoveAtExit {
    std::vector<std::string> files;
    ~RemoveAtExit() {
      for (const std::string& f : files) std::filesystem::remove(f);
    }
  } made;
  for (int d : {pool.get().first, pool.get().last})
    for (const std::string& f : left_on(d)) {
      made.files.push_back(f);
      std::ofstream(f) << "stale";
    }
  DomainLease lease(1, pool.get());
  const int other = lease.domain() == pool.get().first ? pool.get().last : pool.get().first;
  for (const std::string& f : left_on(lease.domain())) EXPECT_FALSE(std::filesystem::exists(f)) << f;
  for (const std::string& f : left_on(other)) EXPECT_TRUE(std::filesystem::exists(f)) << f << ": not the lease's";
}

TEST(DomainLeaseTest, SkipsADomainWhoseSharedMemoryDiscoveryPortIsLocked) {
  PrivatePool pool(1);
  const int d = pool.get().first;
  // A program outside the scheme on domain d over shared memory: it holds a shared lock on the
  // file beside the domain's discovery port, as Fast DDS's shared-memory transport does.
  const std::string path = "/dev/shm/fastrtps_port" + std::to_string(7400 + 250 * d) + "_sl";
  const int fd = ::open(path.c_str(), O_RDONLY | O_CREAT, 0666);
  ASSERT_GE(fd, 0) << path;
  EXPECT_FALSE(domain_ports_in_use(d)) << "a file nobody locks is not a participant";
  ASSERT_EQ(::flock(fd, LOCK_SH | LOCK_NB), 0);
  EXPECT_TRUE(domain_ports_in_use(d));
  EXPECT_TRUE(pool_exhausted(pool.get()));
  ::close(fd);
  EXPECT_FALSE(pool_exhausted(pool.get()));
  std::filesystem::remove(path);
}

TEST(DomainLeaseTest, SeesAFastDdsParticipantOnTheDomain) {
  const DomainLease lease;
  for (const char* profile : {"loopback", "shm", "udp"}) {
    EXPECT_FALSE(domain_ports_in_use(lease.domain())) << profile;
    {
      idl::DdsParticipant participant(lease.domain(), profile);
      EXPECT_TRUE(domain_ports_in_use(lease.domain())) << "the " << profile << " profile's ports were not seen";
    }
    EXPECT_FALSE(domain_ports_in_use(lease.domain())) << profile;
  }
}

// A telegrasp-test-domain-probe process (domain_probe_main.cc) and what it has printed so far.
class Probe {
 public:
  explicit Probe(std::vector<std::string> args) {
    args.insert(args.begin(), TELEGRASP_DOMAIN_PROBE);
    process_.start(args, "", /*pipe_stdout=*/true);
  }
  // Reads what the probe has printed since the last call.
  void poll() {
    char buffer[4096];
    for (ssize_t n; (n = ::read(process_.stdout_fd(), buffer, sizeof buffer)) > 0;) pending_.append(buffer, n);
    for (std::size_t end; (end = pending_.find('\n')) != std::string::npos; pending_.erase(0, end + 1)) {
      std::istringstream line(pending_.substr(0, end));
      std::string what;
      long value = 0;
      line >> what >> value;
      if (what == "domain") domain = static_cast<int>(value);
      if (what == "own") own = value;
      if (what == "foreign") {
        ++foreign;
        if (own_at_first_foreign < 0) own_at_first_foreign = own;
      }
    }
  }
  bool running() { return process_.running(); }
  int stop() { return process_.stop(); }

  int domain = -1;
  long own = 0, foreign = 0, own_at_first_foreign = -1;

 private:
  ChildProcess process_;
  std::string pending_;
};

// Polls both probes every 10 ms until `done` holds (true) or kGuard passes or one exits (false).
bool wait_for(std::array<Probe, 2>& probes, const std::function<bool()>& done) {
  const auto end = std::chrono::steady_clock::now() + kGuard;
  while (std::chrono::steady_clock::now() < end) {
    for (Probe& p : probes) {
      p.poll();
      if (!p.running()) return false;
    }
    if (done()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

// Two stand-in test runs started at the same time, each taking its own lease as every test does,
// get disjoint domains and never receive a sample of the other. The control first puts two on one
// domain to show that they do meet there, and how many of its own samples a probe reads before the
// other's first arrives; the real pair is watched for twice that many and more.
TEST(TwoTestRunsTest, StartedTogetherTheyGetDisjointDomainsAndNeverMeet) {
  long meet_after = 0;
  {
    const DomainLease shared;
    const std::string d = std::to_string(shared.domain());
    std::array<Probe, 2> control{Probe({"--domain", d}), Probe({"--domain", d})};
    ASSERT_TRUE(wait_for(control, [&] { return control[0].foreign > 0 && control[1].foreign > 0; }))
        << "two probes on one domain (" << d << ") never saw each other: the check below could not fail";
    meet_after = std::max(control[0].own_at_first_foreign, control[1].own_at_first_foreign);
    for (Probe& p : control) EXPECT_EQ(p.stop(), 0);
  }
  const long watch = 2 * meet_after + 50;
  std::cout << "[ measured ] on one domain the probes met after " << meet_after << " own samples; watching " << watch
            << "\n";

  std::array<Probe, 2> runs{Probe({}), Probe({})};
  ASSERT_TRUE(wait_for(runs, [&] { return runs[0].own >= watch && runs[1].own >= watch; }))
      << "a probe stopped or stalled (own samples " << runs[0].own << ", " << runs[1].own << ")";
  EXPECT_NE(runs[0].domain, -1);
  EXPECT_NE(runs[0].domain, runs[1].domain) << "both leased domain " << runs[0].domain;
  EXPECT_EQ(runs[0].foreign, 0) << "run 0 (domain " << runs[0].domain << ") received the other run's samples";
  EXPECT_EQ(runs[1].foreign, 0) << "run 1 (domain " << runs[1].domain << ") received the other run's samples";
  for (Probe& p : runs) EXPECT_EQ(p.stop(), 0);
}

}  // namespace
}  // namespace telegrasp::testing
