// What the integration tests share about the programs they start: where they are, where their
// files go, and ChildProcess (client_lib/tools/common) to run them.
#pragma once

#include "child_process.h"
#include "telegrasp/client/client.h"

#include <chrono>
#include <string>
#include <thread>

namespace telegrasp::testing {

using tools::ChildProcess;

/// How long a test waits, against a hang only (never asserted), for its start: a server
/// answering, a client (secure or not) matched with it, a bot started.
inline constexpr std::chrono::seconds kStartGuard{60};

/// Options for a client `id` on `domain` subscribed to `topics` (bits of client::Topics), every
/// other option at its default.
inline client::ClientOptions client_options(const std::string& id, int domain, unsigned topics = client::kAllTopics) {
  client::ClientOptions o;
  o.client_id = id;
  o.domain = domain;
  o.topics = topics;
  return o;
}

/// The path of the tool `name`, built next to the test program (build/bin).
std::string bin(const std::string& name);

/// The path of `name` in this test process's own scratch folder, made on first use
/// ($TMPDIR/telegrasp_integration.XXXXXX, so concurrent runs never share one): configurations,
/// logs and results of the programs a test starts. The folder is removed at exit when every test
/// passed and kept, its path printed, when one failed.
std::string work_path(const std::string& name);

/// Polls `done` every 10 ms until it returns true or `timeout` passes; its last answer.
template <typename F>
bool eventually(F done, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

}  // namespace telegrasp::testing
