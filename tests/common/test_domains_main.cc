// telegrasp-test-domains: leases DDS domains (test_domain.h) for a test that is not a C++
// program, such as a shell or CMake script, and runs it with the lease held.
#include "test_domain.h"

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

namespace {

const char* kUsage = R"(Usage: telegrasp-test-domains [--count N] COMMAND [ARG...]

Leases N (default 1) consecutive DDS domains that no other test process on this machine holds
(lock files in /tmp/telegrasp-test-domains; TELEGRASP_TEST_DOMAINS=FIRST-LAST picks the range)
and runs COMMAND with TELEGRASP_TEST_DOMAIN (the first domain) and TELEGRASP_TEST_DOMAIN_COUNT
set. COMMAND and every process it starts hold the lease until the last of them exits.

Exit status: COMMAND's; 2 for a usage error; 1 if no domains are free or COMMAND cannot run.
)";

}  // namespace

int main(int argc, char** argv) {
  int count = 1;
  int i = 1;
  if (i < argc && std::string(argv[i]) == "--help") {
    std::cout << kUsage;
    return 0;
  }
  if (i < argc && std::string(argv[i]) == "--count") {
    char* end = nullptr;
    count = i + 1 < argc ? static_cast<int>(std::strtol(argv[i + 1], &end, 10)) : 0;
    if (count < 1 || end == nullptr || *end != '\0') {
      std::cerr << "telegrasp-test-domains: --count must be a whole number of at least 1\n" << kUsage;
      return 2;
    }
    i += 2;
  }
  if (i >= argc) {
    std::cerr << "telegrasp-test-domains: no command given\n" << kUsage;
    return 2;
  }
  try {
    // Not destroyed: exec keeps its lock descriptors open for the command.
    auto* lease = new telegrasp::testing::DomainLease(count);
    ::setenv("TELEGRASP_TEST_DOMAIN", std::to_string(lease->domain()).c_str(), 1);
    ::setenv("TELEGRASP_TEST_DOMAIN_COUNT", std::to_string(lease->count()).c_str(), 1);
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-test-domains: " << e.what() << "\n";
    return 1;
  }
  ::execvp(argv[i], argv + i);
  std::cerr << "telegrasp-test-domains: cannot run " << argv[i] << ": " << std::strerror(errno) << "\n";
  return 1;
}
