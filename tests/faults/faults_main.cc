// The fault tests' main: the whole process, and every server, bot and subscriber it starts, runs in
// a network namespace of its own (loopback only), so packet loss added with iptables touches
// nothing else on the machine and no test traffic leaves it.
#include "fault_env.h"

#include <gtest/gtest.h>

#include <iostream>
#include <string>

int main(int argc, char** argv) {
  std::string why;
  // Before any thread starts (unshare(CLONE_NEWNET) applies to the calling thread only).
  if (!telegrasp::testing::enter_private_network(why)) std::cerr << "fault tests: " << why << ": skipped\n";
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
