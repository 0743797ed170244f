// Tests telegrasp-view's model and Foxglove messages (client_lib/tools/view/view_model.h,
// foxglove_json.h): capsule primitives against the segment they draw, /scene sent only when an
// entity looks different, deletions when a hand goes, /tf carrying only what moved.
#include "foxglove_json.h"
#include "right_hand_model.h"

#include <gtest/gtest.h>

#include <memory>
#include <set>

namespace telegrasp::view {
namespace {

constexpr double kTolerance = 1e-12;

Eigen::Vector3d vec(const Json& j) { return {j["x"].get<double>(), j["y"].get<double>(), j["z"].get<double>()}; }
Eigen::Quaterniond quat(const Json& j) {
  return Eigen::Quaterniond(j["w"].get<double>(), j["x"].get<double>(), j["y"].get<double>(), j["z"].get<double>());
}

TEST(FoxgloveJsonTest, CapsuleIsCylinderAlongSegmentWithSphereCaps) {
  // A capsule from A to B of radius 1 cm, drawn in some frame.
  const Eigen::Vector3d A(0.01, -0.02, 0.03), B(0.05, 0.01, 0.0);
  Json e = scene_entity("e", "f", 0);
  add_capsule(e, A, B, 0.01, colours::kSkin);
  ASSERT_EQ(e["cylinders"].size(), 1u);
  ASSERT_EQ(e["spheres"].size(), 2u);
  const Json& c = e["cylinders"][0];
  // The cylinder's centre is the midpoint and its local z (foxglove's cylinder axis) maps onto A-B.
  EXPECT_LT((vec(c["pose"]["position"]) - 0.5 * (A + B)).norm(), kTolerance);
  const Eigen::Vector3d axis = quat(c["pose"]["orientation"]) * Eigen::Vector3d::UnitZ();
  EXPECT_LT((axis - (B - A).normalized()).norm(), 1e-9);
  EXPECT_NEAR(vec(c["size"]).z(), (B - A).norm(), kTolerance);
  EXPECT_NEAR(vec(c["size"]).x(), 0.02, kTolerance);
  // The caps: spheres of diameter 2r at both ends.
  EXPECT_LT((vec(e["spheres"][0]["pose"]["position"]) - A).norm(), kTolerance);
  EXPECT_LT((vec(e["spheres"][1]["pose"]["position"]) - B).norm(), kTolerance);
  EXPECT_NEAR(vec(e["spheres"][1]["size"]).y(), 0.02, kTolerance);
}

TEST(FoxgloveJsonTest, ArrowPointsAlongTheNormal) {
  Json e = scene_entity("e", "f", 0);
  const Eigen::Vector3d n = Eigen::Vector3d(0, -1, 1).normalized();
  add_arrow(e, Eigen::Vector3d(1, 2, 3), n, 0.02, colours::kContact);
  const Json& a = e["arrows"][0];
  // A foxglove arrow points along its local +x; shaft and head add up to the length.
  EXPECT_LT((quat(a["pose"]["orientation"]) * Eigen::Vector3d::UnitX() - n).norm(), 1e-9);
  EXPECT_NEAR(a["shaft_length"].get<double>() + a["head_length"].get<double>(), 0.02, kTolerance);
}

// A model of one right hand (the shipped rig) and, optionally, one object.
class ViewModelTest : public RightHandModelTest {
 protected:
  ViewModelTest() {
    for (std::size_t i = 0; i < rig_->phalanges().size(); ++i) {
      Eigen::Isometry3d X = skeleton_.X_WorldPalm;
      X.translation() += Eigen::Vector3d(0.02 * static_cast<double>(i), 0.01, 0);
      skeleton_.X_WorldPhalanx.push_back(X);
    }
    state_.hand = skeleton_.hand;
    state_.blocked.assign(rig_->phalanges().size(), false);
  }

  ClientSnapshot snapshot() const {
    ClientSnapshot s;
    s.skeletons = {skeleton_};
    s.grasp_states[skeleton_.hand] = state_;
    return s;
  }

  static std::set<std::string> entity_ids(const Json& update) {
    std::set<std::string> ids;
    for (const Json& e : update["entities"]) ids.insert(e["id"].get<std::string>());
    return ids;
  }

  client::GraspState state_;
};

TEST_F(ViewModelTest, SendsEntitiesOnceAndAgainOnlyWhenTheyLookDifferent) {
  // First update: the palm entity and one entity per capsule, in their own frames.
  const ViewUpdate first = model_.update(snapshot(), 1);
  ASSERT_TRUE(first.scene);
  const std::set<std::string> ids = entity_ids(*first.scene);
  EXPECT_TRUE(ids.contains("hand/c1/right"));
  EXPECT_EQ(ids.size(), 1 + rig_->capsule_phalanges().size());
  EXPECT_EQ(first.grasp_states.size(), 1u);

  // The same input again: nothing to send.
  const ViewUpdate same = model_.update(snapshot(), 2);
  EXPECT_FALSE(same.scene);
  EXPECT_TRUE(same.grasp_states.empty());

  // One phalanx blocks (a new grasp state): only that phalanx's entity is re-sent, now red.
  const auto p = static_cast<std::size_t>(rig_->capsule_phalanges().front().value);
  state_.tick = 7;
  state_.blocked[p] = true;
  const ViewUpdate blocked = model_.update(snapshot(), 3);
  ASSERT_TRUE(blocked.scene);
  ASSERT_EQ((*blocked.scene)["entities"].size(), 1u);
  const Json& entity = (*blocked.scene)["entities"][0];
  EXPECT_EQ(entity["id"], "hand/c1/right/" + rig_->phalanges()[p].name);
  EXPECT_DOUBLE_EQ(entity["cylinders"][0]["color"]["r"].get<double>(), colours::kBlocked.r);

  // The hand goes: every one of its entities is deleted, and a late joiner sees none.
  const ViewUpdate gone = model_.update(ClientSnapshot{}, 4);
  ASSERT_TRUE(gone.scene);
  std::set<std::string> deleted;
  for (const Json& d : (*gone.scene)["deletions"]) deleted.insert(d["id"].get<std::string>());
  EXPECT_EQ(deleted, ids);
  EXPECT_TRUE(model_.scene_full(5)["entities"].empty());
}

TEST_F(ViewModelTest, TransformsCarryOnlyTheFramesThatMoved) {
  const ViewUpdate first = model_.update(snapshot(), 1);
  ASSERT_TRUE(first.transforms);
  EXPECT_EQ((*first.transforms)["transforms"].size(), 1 + skeleton_.X_WorldPhalanx.size());

  // The whole hand moves 1 cm: the palm frame moves, the phalanges keep their pose in the palm.
  const Eigen::Vector3d step(0.01, 0, 0);
  skeleton_.X_WorldPalm.translation() += step;
  for (Eigen::Isometry3d& X : skeleton_.X_WorldPhalanx) X.translation() += step;
  const ViewUpdate moved = model_.update(snapshot(), 2);
  ASSERT_TRUE(moved.transforms);
  ASSERT_EQ((*moved.transforms)["transforms"].size(), 1u);
  const Json& palm = (*moved.transforms)["transforms"][0];
  EXPECT_EQ(palm["child_frame_id"], "c1/right/palm");
  EXPECT_EQ(palm["parent_frame_id"], "world");
  EXPECT_NEAR(palm["translation"]["x"].get<double>(), 0.41, 1e-7);

  // Nothing moves: no /tf; a viewer that missed one gets every frame from transforms_full.
  EXPECT_FALSE(model_.update(snapshot(), 3).transforms);
  EXPECT_EQ((*model_.transforms_full(4))["transforms"].size(), 1 + skeleton_.X_WorldPhalanx.size());

  // After kFullTransformsEveryNs every frame goes out again, moved or not.
  const ViewUpdate keyframe = model_.update(snapshot(), 1 + ViewModel::kFullTransformsEveryNs);
  ASSERT_TRUE(keyframe.transforms);
  EXPECT_TRUE(keyframe.transforms_complete);
  EXPECT_EQ((*keyframe.transforms)["transforms"].size(), 1 + skeleton_.X_WorldPhalanx.size());
}

TEST_F(ViewModelTest, HeldObjectTakesItsHoldersColourAndGrowsToItsContacts) {
  client::SceneState scene;
  scene.tick = 1;
  client::ObjectState object;
  object.id = 3;
  object.name = "box";
  scene.objects = {object};
  ClientSnapshot s = snapshot();
  s.scene = scene;
  model_.update(s, 1);

  // Held by the hand, with a contact 5 cm out along x in the object frame.
  s.scene->tick = 2;
  s.scene->objects[0].held = true;
  s.scene->objects[0].holder = skeleton_.hand;
  client::ContactSet contacts;
  contacts.hand = skeleton_.hand;
  contacts.object_id = 3;
  client::ContactPoint c;
  c.phalanx = 2;
  c.p_ObjectContact = Eigen::Vector3d(0.05, 0, 0);
  c.n_Object = Eigen::Vector3d::UnitX();
  contacts.contacts = {c};
  s.contact_sets[skeleton_.hand] = contacts;
  s.grasp_states[skeleton_.hand].grasped_object = 3;
  s.grasp_states[skeleton_.hand].tick = 2;
  const ViewUpdate held = model_.update(s, 2);
  ASSERT_TRUE(held.scene);
  Json box, arrows;
  for (const Json& e : (*held.scene)["entities"]) {
    if (e["id"] == "object/3") box = e;
    if (e["id"] == "contacts/c1/right") arrows = e;
  }
  ASSERT_FALSE(box.is_null());
  EXPECT_DOUBLE_EQ(box["cubes"][0]["color"]["b"].get<double>(), colours::hand_colour(0).b);
  EXPECT_NEAR(vec(box["cubes"][0]["size"]).x(), 0.10, kTolerance);  // encloses the contact
  EXPECT_NEAR(vec(box["cubes"][0]["size"]).y(), 0.04, kTolerance);  // the 2 cm minimum half extent
  ASSERT_FALSE(arrows.is_null());
  EXPECT_EQ(arrows["frame_id"], "object/3");
  EXPECT_EQ(arrows["arrows"].size(), 1u);
}

}  // namespace
}  // namespace telegrasp::view
