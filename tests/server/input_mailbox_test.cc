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

// A mailbox for five-finger hands under `limits`, its log quiet, keeping the refusals it notifies in
// `told`.
struct ToldMailbox {
  explicit ToldMailbox(const InputLimits& limits) : box({5, 5}, limits, [](const std::string&) {}) {
    box.set_notifier([this](const Refusal& r) { told.push_back(r); });
  }
  std::vector<Refusal> told;
  InputMailbox box;
};

// A hand flooding at 5 kHz for 2 s gets its rate (250/s) plus one burst (a second's worth) through; the rest are
// counted as rate_limited, and the client is told at most once a second.
TEST(MailboxLimitsTest, AFloodingHandIsRateLimitedAndTold) {
  InputLimits limits;
  limits.max_input_rate_hz = 250;
  ToldMailbox mailbox(limits);
  auto& [told, box] = mailbox;
  int accepted = 0;
  const std::int64_t period_ns = 200'000;  // 5 kHz
  for (int i = 0; i < 10'000; ++i) accepted += box.offer(sample("flood", 1, i + 1), kAlicePc, i * period_ns);
  const int expected = 250 * 2 + 250;  // rate x duration + burst (one second's worth)
  EXPECT_NEAR(accepted, expected, 2);
  EXPECT_EQ(box.rejected()[static_cast<int>(RejectReason::kRateLimited)], 10'000u - accepted);
  ASSERT_EQ(told.size(), 2u);  // at t = 0.05 s and again one second later
  EXPECT_GT(told[1].count, told[0].count);
  EXPECT_EQ(told[0].client_id, "flood");
  EXPECT_EQ(told[0].reason, "rate_limited");
  EXPECT_EQ(told[0].kind, msg::NOTICE_INPUT_REJECTED);
  // A 90 Hz client beside it is never limited.
  for (int i = 0; i < 180; ++i) EXPECT_TRUE(box.offer(sample("calm", 1, i + 1), kMallory, i * 11'111'111LL));
}

// One participant minting fresh client ids fills at most its share of hand slots: another
// participant still gets in, and the flooder's ids are counted, not accepted.
TEST(MailboxLimitsTest, AParticipantMintingClientIdsCannotLockOthersOut) {
  InputLimits limits;
  limits.max_hands = 256;
  limits.max_hands_per_participant = 16;
  InputMailbox box({5, 5}, limits, [](const std::string&) {});
  int accepted = 0;
  for (int i = 0; i < 4500; ++i) accepted += box.offer(sample("id-" + std::to_string(i), 1, 1), kMallory, i);
  EXPECT_EQ(accepted, 16);
  EXPECT_EQ(box.rejected()[static_cast<int>(RejectReason::kTooManyHandsForParticipant)], 4500u - 16);
  EXPECT_TRUE(box.offer(sample("alice", 1, 1), kAlicePc, 0));
  // The flooder leaves: its ids and hand slots are free again.
  box.forget_participant(kMallory);
  EXPECT_TRUE(box.offer(sample("id-0", 1, 1), kAlicePc, 0));
}

// A relay holds its whole prefix: up to its own hand limit (not the per-participant one), while
// nobody else drives or commands an id under the prefix, even one the relay never used; ids
// outside it follow the usual rules. The prefix is free again once the relay leaves.
TEST(MailboxLimitsTest, ARelayOwnsItsPrefixUpToItsOwnLimit) {
  const ParticipantKey kBridge{7, 7, 7};
  InputLimits limits;
  limits.max_hands_per_participant = 2;
  limits.relays = {{"xr-", 5}};
  ToldMailbox mailbox(limits);
  auto& [told, box] = mailbox;
  int accepted = 0;
  for (int i = 0; i < 8; ++i) accepted += box.offer(sample("xr-" + std::to_string(i), 1, 1), kBridge, i);
  EXPECT_EQ(accepted, 5);  // the relay's limit, above the participant limit of 2
  EXPECT_EQ(box.rejected()[static_cast<int>(RejectReason::kTooManyHandsForParticipant)], 3u);
  ASSERT_FALSE(told.empty());
  EXPECT_NE(told.back().detail.find("relay 'xr-' may drive at most 5 hands"), std::string::npos) << told.back().detail;
  // Another participant: not an id under the prefix, used or not, by input or command.
  EXPECT_FALSE(box.offer(sample("xr-0", 1, 2), kMallory, 10));
  EXPECT_FALSE(box.offer(sample("xr-99", 0, 1), kMallory, 10));
  msg::SceneCommand c;
  c.client_id("xr-98");
  EXPECT_EQ(box.admit_command(c, kMallory, 0), "client_id_owned_by_another_participant");
  EXPECT_EQ(box.rejected()[static_cast<int>(RejectReason::kClientIdOwnedByAnotherParticipant)], 2u);
  // Outside the prefix both are ordinary participants: the relay's hands there count against 2.
  EXPECT_TRUE(box.offer(sample("mallory", 1, 1), kMallory, 10));
  EXPECT_TRUE(box.offer(sample("bridge-a", 1, 1), kBridge, 10));
  EXPECT_TRUE(box.offer(sample("bridge-b", 1, 1), kBridge, 10));
  EXPECT_FALSE(box.offer(sample("bridge-c", 1, 1), kBridge, 10));
  // A hand that leaves frees its slot under the relay's limit; the prefix stays the relay's.
  box.forget_hand({"xr-0", 1});
  EXPECT_FALSE(box.offer(sample("xr-0", 1, 5), kMallory, 20));
  EXPECT_TRUE(box.offer(sample("xr-7", 1, 1), kBridge, 20));
  // The relay leaves the domain: the prefix goes to whoever drives under it first.
  box.forget_participant(kBridge);
  EXPECT_TRUE(box.offer(sample("xr-0", 1, 6), kMallory, 30));
  EXPECT_FALSE(box.offer(sample("xr-1", 1, 7), kBridge, 30));
}

// Commands: the client id belongs to its first participant (inputs and commands alike), and each
// client gets max_command_rate_hz; every refusal is counted per reason.
TEST(MailboxLimitsTest, CommandsAreAdmittedByOwnerAndRate) {
  InputLimits limits;
  limits.max_command_rate_hz = 20;
  ToldMailbox mailbox(limits);
  auto& [told, box] = mailbox;
  msg::SceneCommand c;
  c.client_id("alice");
  EXPECT_TRUE(box.offer(sample("alice", 1, 1), kAlicePc, 0));
  c.command_id(7);
  EXPECT_EQ(box.admit_command(c, kMallory, 0), "client_id_owned_by_another_participant");
  ASSERT_EQ(told.size(), 1u);
  EXPECT_EQ(told[0].command_id, 7u);
  EXPECT_EQ(told[0].kind, msg::NOTICE_COMMAND_REJECTED);
  int admitted = 0;
  for (int i = 0; i < 100; ++i) admitted += box.admit_command(c, kAlicePc, i * 1'000'000LL).empty();  // 1 kHz
  EXPECT_NEAR(admitted, 20 + 2, 1);  // the burst (a second's worth: 20) plus 20/s over 0.1 s
  const auto by_reason = box.commands_rejected();
  EXPECT_EQ(by_reason.at("client_id_owned_by_another_participant"), 1u);
  EXPECT_EQ(by_reason.at("rate_limited"), 100u - admitted);
  c.client_id("");
  EXPECT_EQ(box.admit_command(c, kAlicePc, 0), "empty_client_id");
}

}  // namespace
}  // namespace telegrasp::server
