// DomainLease: DDS domains for one test process that no other test process on this machine uses
// at the same time, so that concurrent test runs (two ctest runs, ctest -j, two build trees)
// never see each other's samples.
//
// How: each domain d of the test range has a lock file /tmp/telegrasp-test-domains/<d>.lock; a
// lease holds flock(LOCK_EX) on the files of its domains. The kernel drops the lock when the last
// process holding the file closes it or dies, so a crashed test frees its domains and nothing
// needs cleaning up. The descriptors are inherited by child processes (no close-on-exec): a
// server or bot started by a test keeps the domain taken until it too has exited. As a second
// guard, a domain on which some process that takes no lease (a server started by hand, an older
// test) has bound the domain's discovery ports is skipped. A leased domain starts without the
// shared-memory ports a killed participant left in /dev/shm (remove_shared_memory_ports).
//
// The directory is fixed (not $TMPDIR), so runs with different temporary folders still agree.
// Scripts lease through the program telegrasp-test-domains (test_domains_main.cc).
#pragma once

#include <string>
#include <vector>

namespace telegrasp::testing {

/// Where leases come from: the domains first..last (inclusive) and the folder of their lock
/// files. Processes agree on a domain's owner only if they use the same folder.
struct DomainPool {
  int first = 50;
  int last = 99;
  std::string lock_dir = "/tmp/telegrasp-test-domains";
};

/// The pool of every test: domains 50..99, which keeps clear of the domains people and tools use
/// by default (0, the README's 3..7, the demo's 42, telegrasp-eval's 100..200, the benchmarks'
/// 120/121), or TELEGRASP_TEST_DOMAINS="FIRST-LAST" (within 0..232) if set. Throws
/// std::runtime_error naming the variable if it is malformed.
DomainPool test_domain_pool();

/// `count` consecutive DDS domains held for this object's lifetime (and by any child process
/// started meanwhile until it exits). Two leases, in one process or in two, never share a
/// domain; successive leases in one process do not reuse a domain while others are free, so
/// tests run one after another in one process do not meet either. The udp profile's unicast
/// discovery probes participant ids 0..3 only: keep at most four of its participants on one
/// domain (the loopback profile discovers over shared memory, with no such limit).
class DomainLease {
 public:
  /// Leases `count` >= 1 consecutive free domains of `pool`. Throws std::runtime_error if none
  /// are free (naming the lock folder and the range) or if the lock folder cannot be made.
  explicit DomainLease(int count = 1, const DomainPool& pool = test_domain_pool());
  /// Releases the domains (child processes still running keep them).
  ~DomainLease();
  DomainLease(DomainLease&& other) noexcept;
  DomainLease& operator=(DomainLease&& other) = delete;
  DomainLease(const DomainLease&) = delete;
  DomainLease& operator=(const DomainLease&) = delete;

  /// The first leased domain.
  int domain() const { return first_; }
  /// The i-th leased domain, 0 <= i < count().
  int domain(int i) const;
  int count() const { return static_cast<int>(fds_.size()); }

 private:
  int first_ = -1;
  std::vector<int> fds_;
};

/// Removes the Fast DDS shared-memory port files of `domain` (/dev/shm/fastrtps_port<port> and
/// its semaphore, for the domain's 250 ports). A participant killed with SIGKILL leaves them, and a
/// mutex inside may stay locked: the next participant with the same port then stalls
/// ("Interprocess mutex timeout when locking"). DomainLease calls it once it holds a domain and has
/// seen none of its discovery ports bound, that is with no participant of the domain alive in this
/// network namespace. (A participant in another network namespace that shares /dev/shm, e.g.
/// under a bare `unshare -n`, and takes no lease would lose its ports: keep such runs out of the
/// test range or give them a /dev/shm of their own.)
void remove_shared_memory_ports(int domain);

/// Whether a process outside the lease scheme runs a Fast DDS participant on `domain`: its
/// discovery multicast port (7400 + 250 domain) or participant 0's unicast discovery port is
/// bound (UDP, in this host's network namespace), or a process holds the lock of the domain's
/// shared-memory discovery port (/dev/shm/fastrtps_port<7400 + 250 domain>_sl, the loopback
/// profile).
bool domain_ports_in_use(int domain);

}  // namespace telegrasp::testing
