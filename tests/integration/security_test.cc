// Integration tests of DDS Security (the `secure` profile): a real telegrasp-server with the
// identity "server" and telegrasp::client participants in this process, each joining with its own
// identity from a folder deploy/security/make-certs.sh makes at start: watcher and bob (clients),
// alice (operator), old (expired certificate), mallory (a complete set from another CA). Asserts
// who sees the scene, who moves hands and who commands the scene. Runs on a leased DDS domain,
// inside `unshare -n` when ctest runs it (tests/integration/CMakeLists.txt). Times only guard
// against hangs.
#include "process.h"
#include "telegrasp/client/client.h"
#include "test_domain.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
using client::Client;
using client::ClientOptions;

constexpr auto kEventGuard = 20s;  // something that follows from what the test just did
// How long an unauthorized participant is given to get anything through: several times what an
// authorized one needs on this machine (about 1 s to authenticate and match).
constexpr auto kRefusedWindow = 4s;
constexpr double kPoseTolerance = 1e-3;  // m: a tracked palm "at" a published pose

Eigen::Isometry3d palm_at(double x, double y, double z) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(x, y, z);
  return X;
}

// One server for every test: certificates are made once and client ids stay bound to their
// identity for the server's life, so each test uses client ids of its own.
class SecurityTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    certs_ = new std::string(work_path("certs"));
    const std::string make = std::string(TELEGRASP_MAKE_CERTS) + " " + *certs_ +
                             " watcher bob --operator alice --expired old --foreign mallory > " +
                             work_path("make_certs.log") + " 2>&1";
    ASSERT_EQ(std::system(make.c_str()), 0) << make;
    lease_ = new DomainLease();
    server_ = new ChildProcess({bin("telegrasp-server"), "--domain", std::to_string(lease_->domain()), "--profile",
                                "secure", "--security", *certs_, "--identity", "server"},
                               work_path("security_server.log"));
  }
  static void TearDownTestSuite() {
    delete server_;
    delete lease_;
    delete certs_;
  }

  // A participant joining as `identity` ("" = no security folder at all) with `profile`.
  static std::unique_ptr<Client> join(const std::string& identity, const std::string& client_id,
                                      const std::string& profile = "secure") {
    if (identity.empty()) {
      unsetenv("TELEGRASP_SECURITY_DIR");
      unsetenv("TELEGRASP_IDENTITY");
    } else {
      setenv("TELEGRASP_SECURITY_DIR", certs_->c_str(), 1);
      setenv("TELEGRASP_IDENTITY", identity.c_str(), 1);
    }
    ClientOptions o = client_options(client_id, lease_->domain());
    o.profile = profile;
    return std::make_unique<Client>(o);
  }

  // A watcher (client role) that has seen the server: the reference for what reached the scene.
  static std::unique_ptr<Client> watcher() {
    auto w = join("watcher", "watcher");
    EXPECT_TRUE(w->wait_for_server(kStartGuard)) << "the watcher never saw the secure server; server log:\n"
                                                 << server_->log_tail(20);
    return w;
  }

  // Publishes right-hand samples at `X_WorldPalm` at about 90 Hz for `duration`.
  static void drive(Client& c, const Eigen::Isometry3d& X_WorldPalm, std::chrono::milliseconds duration) {
    client::ControllerSample s;
    s.X_WorldPalm = X_WorldPalm;
    const auto end = std::chrono::steady_clock::now() + duration;
    while (std::chrono::steady_clock::now() < end) {
      c.publish(s);
      std::this_thread::sleep_for(11ms);
    }
  }

  // Drives `c` (as `client_id`) at `X_WorldPalm` for `duration`, meanwhile waiting up to
  // kEventGuard for `w` to see that hand there; whether it did.
  static bool seen_while_driving(const Client& w, Client& c, const std::string& client_id,
                                 const Eigen::Isometry3d& X_WorldPalm, std::chrono::milliseconds duration) {
    std::thread driver([&] { drive(c, X_WorldPalm, duration); });
    const bool seen = eventually([&] { return sees_hand_at(w, client_id, X_WorldPalm); }, kEventGuard);
    driver.join();
    return seen;
  }

  // Whether `w` currently sees the right hand of `client_id` tracked at `X_WorldPalm`.
  static bool sees_hand_at(const Client& w, const std::string& client_id, const Eigen::Isometry3d& X_WorldPalm) {
    for (const client::HandSkeleton& s : w.latest_hand_skeletons())
      if (s.hand.client_id == client_id &&
          (s.X_WorldTracked.translation() - X_WorldPalm.translation()).norm() < kPoseTolerance)
        return true;
    return false;
  }
  static bool sees_client(const Client& w, const std::string& client_id) {
    for (const client::HandSkeleton& s : w.latest_hand_skeletons())
      if (s.hand.client_id == client_id) return true;
    return false;
  }
  static std::uint64_t owned_rejections(const Client& w) {
    const std::optional<client::ServerStatus> s = w.latest_server_status();
    if (!s) return 0;
    const auto it = s->rejected.find("client_id_owned_by_another_participant");
    return it == s->rejected.end() ? 0 : it->second;
  }

  static std::string* certs_;
  static DomainLease* lease_;
  static ChildProcess* server_;
};

std::string* SecurityTest::certs_ = nullptr;
DomainLease* SecurityTest::lease_ = nullptr;
ChildProcess* SecurityTest::server_ = nullptr;

TEST_F(SecurityTest, ParticipantWithoutCertificateNeitherSeesTheSceneNorMovesAHand) {
  // 1. An authenticated watcher sees the scene: the server is up and secure traffic flows.
  auto w = watcher();
  ASSERT_TRUE(eventually([&] { return w->latest_scene_state().has_value(); }, kEventGuard));

  // 2. The secure profile with no security folder does not start at all, and says what is missing.
  try {
    join("", "intruder");
    ADD_FAILURE() << "a secure participant started without certificates";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("TELEGRASP_SECURITY_DIR"), std::string::npos) << e.what();
  }

  // 3. A participant without DDS Security (the loopback profile) finds no server, receives
  //    nothing, and its samples move no hand.
  auto intruder = join("", "intruder", "loopback");
  EXPECT_FALSE(intruder->wait_for_server(kRefusedWindow));
  drive(*intruder, palm_at(0.3, 0.0, 1.1), 2s);
  EXPECT_FALSE(intruder->latest_scene_state().has_value());
  EXPECT_FALSE(intruder->latest_server_status().has_value());
  EXPECT_TRUE(intruder->latest_hand_skeletons().empty());
  EXPECT_FALSE(sees_client(*w, "intruder"));

  // 4. The same samples from an authenticated client do move a hand (the check above can fail).
  auto bob = join("bob", "bob-hands");
  ASSERT_TRUE(bob->wait_for_server(kStartGuard));
  const Eigen::Isometry3d X = palm_at(0.3, 0.0, 1.1);
  EXPECT_TRUE(seen_while_driving(*w, *bob, "bob-hands", X, 3s));
}

TEST_F(SecurityTest, OnlyAnOperatorSpawnsRemovesOrResets) {
  auto w = watcher();
  std::optional<client::SceneState> scene;
  ASSERT_TRUE(eventually([&] { return (scene = w->latest_scene_state()) && !scene->objects.empty(); }, kEventGuard));
  const std::size_t objects = scene->objects.size();
  const std::optional<client::ServerStatus> status = w->latest_server_status();
  ASSERT_TRUE(status && !status->models.empty());

  // 1. bob (no operator role) may not write SceneCommand: spawn, remove and reset are refused at
  //    his end, and nothing reaches the server.
  auto bob = join("bob", "bob-commands");
  ASSERT_TRUE(bob->wait_for_server(kStartGuard));
  client::SceneCommand spawn;
  spawn.kind = client::SceneCommand::Kind::kSpawn;
  spawn.model = status->models.front();
  client::SceneCommand remove;
  remove.kind = client::SceneCommand::Kind::kRemove;
  remove.object_id = scene->objects.front().id;
  client::SceneCommand reset;
  reset.kind = client::SceneCommand::Kind::kReset;
  for (const client::SceneCommand& c : {spawn, remove, reset}) EXPECT_THROW(bob->send_command(c), std::runtime_error);
  std::this_thread::sleep_for(kRefusedWindow);
  scene = w->latest_scene_state();
  ASSERT_TRUE(scene);
  EXPECT_EQ(scene->objects.size(), objects) << "a command of bob changed the scene";

  // 2. alice (operator) spawns and removes: the scene follows, so the check above can fail.
  auto alice = join("alice", "alice-commands");
  ASSERT_TRUE(alice->wait_for_server(kStartGuard));
  alice->send_command(spawn);
  ASSERT_TRUE(eventually([&] { return (scene = w->latest_scene_state()) && scene->objects.size() == objects + 1; },
                         kEventGuard))
      << "alice's spawn never showed";
  remove.object_id = scene->objects.back().id;
  alice->send_command(remove);
  EXPECT_TRUE(
      eventually([&] { return (scene = w->latest_scene_state()) && scene->objects.size() == objects; }, kEventGuard))
      << "alice's remove never showed";
}

TEST_F(SecurityTest, ClientIdBelongsToTheIdentityThatDroveItFirst) {
  auto w = watcher();
  const std::string id = "alice-hands";

  // 1. alice drives her client id: the watcher sees the hand where she put it. She leaves, and the
  //    server forgets her hand (remove_after_s).
  const Eigen::Isometry3d X_alice = palm_at(0.3, 0.1, 1.1);
  {
    auto alice = join("alice", id);
    ASSERT_TRUE(alice->wait_for_server(kStartGuard));
    EXPECT_TRUE(seen_while_driving(*w, *alice, id, X_alice, 2s));
  }
  ASSERT_TRUE(eventually([&] { return !sees_client(*w, id); }, kEventGuard)) << "alice's hand was never removed";

  // 2. bob, with a valid certificate, publishes under alice's client id: refused and counted,
  //    although no participant drives that id any more (binding by GUID alone would accept him).
  const std::uint64_t refused_before = owned_rejections(*w);
  const Eigen::Isometry3d X_bob = palm_at(0.3, -0.1, 1.1);
  {
    auto bob = join("bob", id);
    ASSERT_TRUE(bob->wait_for_server(kStartGuard));
    drive(*bob, X_bob, 2s);
    EXPECT_FALSE(sees_client(*w, id)) << "bob drove alice's hand";
  }
  EXPECT_TRUE(eventually([&] { return owned_rejections(*w) > refused_before; }, kEventGuard))
      << "bob's samples were not counted as rejected";

  // 3. alice comes back from a new participant (a new GUID): her client id is still hers.
  const Eigen::Isometry3d X_back = palm_at(0.3, 0.05, 1.15);
  auto alice = join("alice", id);
  ASSERT_TRUE(alice->wait_for_server(kStartGuard));
  EXPECT_TRUE(seen_while_driving(*w, *alice, id, X_back, 3s));
}

TEST_F(SecurityTest, ExpiredOrForeignCertificateIsRefused) {
  auto w = watcher();

  // 1. An expired certificate: Fast DDS refuses to start the participant, and the error names it.
  try {
    join("old", "old-hands");
    ADD_FAILURE() << "a participant started with an expired certificate";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'old'"), std::string::npos) << e.what();
  }

  // 2. mallory's certificate, permissions and governance all come from another CA: the participant
  //    starts (its own CA vouches for it) but the server never authenticates it, so it sees
  //    nothing and moves nothing.
  auto mallory = join("mallory", "mallory-hands");
  EXPECT_FALSE(mallory->wait_for_server(kRefusedWindow));
  drive(*mallory, palm_at(0.3, 0.0, 1.2), 2s);
  EXPECT_FALSE(mallory->latest_scene_state().has_value());
  EXPECT_FALSE(sees_client(*w, "mallory-hands"));
}

}  // namespace
}  // namespace telegrasp::testing
