// LiveFeed: the running server's clock and input source for the ServerLoop: steady_clock, waits
// on the InputMailbox (woken by each accepted sample, each command and wake()), the mailbox's
// samples and the commands the DDS node received.
#pragma once

#include "input_mailbox.h"
#include "server_loop.h"

#include <functional>
#include <utility>
#include <vector>

namespace telegrasp::server {

class LiveFeed final : public LoopClock, public LoopSource {
 public:
  /// `take_commands`: the commands received since its last call (DdsNode::take_commands).
  LiveFeed(InputMailbox& mailbox, std::function<std::vector<msg::SceneCommand>()> take_commands)
      : mailbox_(mailbox), take_commands_(std::move(take_commands)) {}

  time_point now() override { return std::chrono::steady_clock::now(); }
  void wait_until(time_point deadline) override { mailbox_.wait(deadline); }
  void wake() override { mailbox_.wake(); }
  std::vector<InputSample> take_inputs() override { return mailbox_.drain(); }
  std::vector<msg::SceneCommand> take_commands() override { return take_commands_(); }

 private:
  InputMailbox& mailbox_;
  std::function<std::vector<msg::SceneCommand>()> take_commands_;
};

}  // namespace telegrasp::server
