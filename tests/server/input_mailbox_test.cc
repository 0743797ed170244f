// Tests server/src/input_mailbox: newest sample per hand, order and ownership checks, counts,
// one log line per client and reason, and waits ended by a sample or wake().
#include "input_mailbox.h"

#include <gtest/gtest.h>

#include <thread>

namespace telegrasp::server {
namespace {

const ParticipantKey kAlicePc{1, 2, 3};
const ParticipantKey kMallory{9, 9, 9};

msg::ControllerState sample(const std::string& client, std::uint8_t side, std::uint64_t seq, double trigger = 0.5) {
  msg::ControllerState s;
  s.client_id(client);
  s.hand_side(side);
  s.sequence_number(seq);
  s.palm().orientation().w(1);
  s.trigger(trigger);
  return s;
}

struct MailboxTest : ::testing::Test {
  std::vector<std::string> log;
  InputMailbox box{{5, 5}, 3, [this](const std::string& line) { log.push_back(line); }};
  std::uint64_t rejected(RejectReason r) const { return box.rejected()[static_cast<int>(r)]; }
};

TEST_F(MailboxTest, KeepsTheNewestSamplePerHand) {
  EXPECT_TRUE(box.offer(sample("alice", 1, 1, 0.1), kAlicePc, 10));
  EXPECT_TRUE(box.offer(sample("alice", 1, 2, 0.2), kAlicePc, 20));
  EXPECT_TRUE(box.offer(sample("alice", 0, 1, 0.3), kAlicePc, 30));
  const auto out = box.drain();
  ASSERT_EQ(out.size(), 2u);  // one per hand, in hand order: left (0) then right (1)
  EXPECT_EQ(out[0].hand, (HandAddress{"alice", 0}));
  EXPECT_EQ(out[1].hand, (HandAddress{"alice", 1}));
  EXPECT_EQ(out[1].state.sequence_number(), 2u);
  EXPECT_EQ(out[1].received_ns, 20);
  EXPECT_TRUE(box.drain().empty());
  EXPECT_EQ(box.accepted(), 3u);
}

TEST_F(MailboxTest, DropsStaleAndRepeatedSequenceNumbers) {
  EXPECT_TRUE(box.offer(sample("alice", 1, 5), kAlicePc, 0));
  EXPECT_FALSE(box.offer(sample("alice", 1, 5), kAlicePc, 0));  // repeated
  EXPECT_FALSE(box.offer(sample("alice", 1, 3), kAlicePc, 0));  // out of order
  EXPECT_TRUE(box.offer(sample("alice", 1, 6), kAlicePc, 0));
  EXPECT_EQ(rejected(RejectReason::kStaleSequence), 2u);
  ASSERT_EQ(box.drain().at(0).state.sequence_number(), 6u);
}

// A client id belongs to the participant that first drove it: another participant claiming it
// cannot move its hands, until all of the owner's hands are gone.
TEST_F(MailboxTest, ASpoofedClientIdCannotDriveAnotherClientsHands) {
  EXPECT_TRUE(box.offer(sample("alice", 1, 1), kAlicePc, 0));
  EXPECT_FALSE(box.offer(sample("alice", 1, 100), kMallory, 0));
  EXPECT_FALSE(box.offer(sample("alice", 0, 1), kMallory, 0));  // nor add a hand to it
  EXPECT_EQ(rejected(RejectReason::kClientIdOwnedByAnotherParticipant), 2u);
  ASSERT_EQ(box.drain().size(), 1u);
  box.forget_hand({"alice", 1});
  EXPECT_TRUE(box.offer(sample("alice", 1, 1), kMallory, 0));  // free again, sequence restarts
}

TEST_F(MailboxTest, CountsEveryDropAndLogsOncePerClientAndReason) {
  msg::ControllerState bad = sample("alice", 1, 1);
  bad.trigger(2);
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(box.offer(bad, kAlicePc, 0));
  bad.client_id("bob");
  EXPECT_FALSE(box.offer(bad, kAlicePc, 0));
  EXPECT_EQ(rejected(RejectReason::kTriggerOutOfRange), 6u);
  ASSERT_EQ(log.size(), 2u);
  EXPECT_NE(log[0].find("alice"), std::string::npos);
  EXPECT_NE(log[0].find("trigger_out_of_range"), std::string::npos);
  EXPECT_NE(log[1].find("bob"), std::string::npos);
  EXPECT_TRUE(box.drain().empty());
}

TEST_F(MailboxTest, RefusesHandsBeyondTheLimit) {
  EXPECT_TRUE(box.offer(sample("a", 0, 1), kAlicePc, 0));
  EXPECT_TRUE(box.offer(sample("a", 1, 1), kAlicePc, 0));
  EXPECT_TRUE(box.offer(sample("b", 1, 1), kMallory, 0));
  EXPECT_FALSE(box.offer(sample("c", 1, 1), ParticipantKey{7}, 0));
  EXPECT_EQ(rejected(RejectReason::kTooManyHands), 1u);
  EXPECT_TRUE(box.offer(sample("a", 1, 2), kAlicePc, 0));  // known hands go on
}

// The waits below end by being woken, long before their guard deadline; wait() says which it was,
// so a broken wake-up fails the test (after the guard) instead of passing late. The other thread
// acts after a pause, so the waiter is most likely blocked by then, not about to start waiting.
constexpr auto kGuard = std::chrono::seconds(3);
constexpr auto kPause = std::chrono::milliseconds(50);

TEST_F(MailboxTest, ASampleWakesAWaiter) {
  std::thread producer([&] {
    std::this_thread::sleep_for(kPause);
    box.offer(sample("alice", 1, 1), kAlicePc, 0);
  });
  const bool woken = box.wait(std::chrono::steady_clock::now() + kGuard);
  producer.join();
  EXPECT_TRUE(woken) << "the wait ran to its guard deadline: offer() did not wake it";
  EXPECT_EQ(box.drain().size(), 1u);
}

TEST_F(MailboxTest, WakeWakesAWaiter) {
  std::thread waker([&] {
    std::this_thread::sleep_for(kPause);
    box.wake();
  });
  const bool woken = box.wait(std::chrono::steady_clock::now() + kGuard);
  waker.join();
  EXPECT_TRUE(woken) << "the wait ran to its guard deadline: wake() did not wake it";
  EXPECT_TRUE(box.drain().empty());
}

// A wake() with nobody waiting ends the next wait at once, and only that one.
TEST_F(MailboxTest, AWakeBeforeTheWaitIsKeptForIt) {
  box.wake();
  EXPECT_TRUE(box.wait(std::chrono::steady_clock::now() + kGuard));
  EXPECT_FALSE(box.wait(std::chrono::steady_clock::now() + std::chrono::milliseconds(1))) << "the wake-up was used up";
}

TEST_F(MailboxTest, WaitReturnsFalseAtTheDeadline) {
  EXPECT_FALSE(box.wait(std::chrono::steady_clock::now() + std::chrono::milliseconds(1)));
  EXPECT_FALSE(box.wait(std::chrono::steady_clock::now() - std::chrono::seconds(1)))
      << "a past deadline returns at once";
}

}  // namespace
}  // namespace telegrasp::server
