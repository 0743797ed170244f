// Tests of ClientIdentities (server/src/identity.h): client ids bound to certificate subjects.
#include "identity.h"

#include <gtest/gtest.h>

namespace telegrasp::server {
namespace {

ParticipantKey participant(std::uint8_t n) {
  ParticipantKey k{};
  k.fill(n);
  return k;
}

TEST(ClientIdentitiesTest, UnknownParticipantIsRefused) {
  ClientIdentities ids;
  EXPECT_FALSE(ids.admit(participant(1), "alice"));
  ids.participant_discovered(participant(2), "");  // discovered without an identity token
  EXPECT_FALSE(ids.admit(participant(2), "alice"));
}

TEST(ClientIdentitiesTest, ClientIdBelongsToTheFirstSubjectForGood) {
  ClientIdentities ids;
  ids.participant_discovered(participant(1), "CN=alice,O=telegrasp");
  ids.participant_discovered(participant(2), "CN=bob,O=telegrasp");
  // 1. alice claims "alice"; bob cannot drive it, but drives his own id under another key.
  const std::optional<ParticipantKey> alice = ids.admit(participant(1), "alice");
  ASSERT_TRUE(alice);
  EXPECT_FALSE(ids.admit(participant(2), "alice"));
  const std::optional<ParticipantKey> bob = ids.admit(participant(2), "bob");
  ASSERT_TRUE(bob);
  EXPECT_NE(*alice, *bob);
  // 2. alice leaves: her id stays hers.
  ids.participant_left(participant(1));
  EXPECT_FALSE(ids.admit(participant(1), "alice"));  // that participant is gone
  EXPECT_FALSE(ids.admit(participant(2), "alice"));
  EXPECT_EQ(ids.subject_of(participant(1)), "");
  // 3. alice comes back as a new participant: same subject, same owner key, her id again.
  ids.participant_discovered(participant(3), "CN=alice,O=telegrasp");
  const std::optional<ParticipantKey> back = ids.admit(participant(3), "alice");
  ASSERT_TRUE(back);
  EXPECT_EQ(*back, *alice);
  EXPECT_EQ(ids.subject_of(participant(3)), "CN=alice,O=telegrasp");
}

TEST(ClientIdentitiesTest, BindingsAreCapped) {
  ClientIdentities ids;
  ids.participant_discovered(participant(1), "CN=alice,O=telegrasp");
  for (std::size_t i = 0; i < ClientIdentities::kMaxClientIds; ++i)
    ASSERT_TRUE(ids.admit(participant(1), "id-" + std::to_string(i))) << i;
  EXPECT_FALSE(ids.admit(participant(1), "one-more"));
  EXPECT_TRUE(ids.admit(participant(1), "id-0"));  // already bound ids still work
}

}  // namespace
}  // namespace telegrasp::server
