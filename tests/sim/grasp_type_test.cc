// Tests grasp types: the choice from shape class, width and pose (analytic boxes), the rig data
// that closes each type, and each type closing on its primitive with the opposable-thumb rig.
#include "telegrasp/sim/grasp_type.h"

#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/hand_kinematics.h"
#include "test_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <numbers>
#include <sstream>

namespace telegrasp::sim {
namespace {

constexpr double kPi = std::numbers::pi;

ObjectShape shape(ShapeClass c, const Eigen::Vector3d& half, int axis = -1,
                  const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
  ObjectShape s;
  s.shape = c;
  s.half_extent = half;
  s.axis = axis;
  s.X_ObjectBox.linear() = R;
  return s;
}

// The palm at the object's origin turned by R (palm +x across, -z the palm normal).
Eigen::Isometry3d palm(const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = R;
  return X;
}

TEST(GraspTypeTest, NamesReadBack) {
  for (int i = 0; i < kGraspTypeCount; ++i) {
    const auto t = static_cast<GraspType>(i);
    EXPECT_EQ(parse_grasp_type(grasp_type_name(t)), t) << i;
  }
  EXPECT_FALSE(parse_grasp_type("pinch").has_value());
}

// Width along d of a box with half extents h and axes R: 2 sum h_i |R_i . d|; along a box axis, its side.
TEST(GraspTypeTest, BoxWidthIsTheSupportWidth) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(kPi / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const ObjectShape s = shape(ShapeClass::kBox, {0.01, 0.02, 0.03}, -1, R);
  EXPECT_NEAR(box_width_along(s, R.col(1)), 0.04, 1e-15);
  EXPECT_NEAR(box_width_along(s, Eigen::Vector3d::UnitX()), 2 * (0.01 * std::cos(kPi / 6) + 0.02 * std::sin(kPi / 6)),
              1e-15);
}

// Across the shortest side: the palm's +x within 45 degrees of the box's x axis (and of the sides
// as short as it), either sign.
TEST(GraspTypeTest, ClosingAcrossTheShortestSide) {
  const ObjectShape s = shape(ShapeClass::kBox, {0.01, 0.02, 0.03});
  const auto turned = [](double deg) { return palm(Eigen::AngleAxisd(deg * kPi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix()); };
  EXPECT_TRUE(closes_across_shortest_side(s, turned(0)));
  EXPECT_TRUE(closes_across_shortest_side(s, turned(44)));
  EXPECT_FALSE(closes_across_shortest_side(s, turned(46)));
  EXPECT_TRUE(closes_across_shortest_side(s, turned(180)));
  EXPECT_FALSE(closes_across_shortest_side(s, turned(90)));
  // Sides as short as the shortest (shorter / longer >= 0.88, the round ratio) count with it: a
  // standing can is closed across from any side, not along its axis; a ball whatever the turn.
  const auto tilted = [](double deg) {  // +x turned from the x axis toward z
    return palm(Eigen::AngleAxisd(-deg * kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix());
  };
  const ObjectShape can = shape(ShapeClass::kCylinder, {0.03, 0.03, 0.06}, 2);
  for (double deg : {0.0, 30.0, 45.0, 60.0, 90.0, 135.0}) EXPECT_TRUE(closes_across_shortest_side(can, turned(deg))) << deg;
  EXPECT_TRUE(closes_across_shortest_side(can, tilted(44)));
  EXPECT_FALSE(closes_across_shortest_side(can, tilted(46)));
  EXPECT_FALSE(closes_across_shortest_side(can, tilted(90)));
  const ObjectShape ball = shape(ShapeClass::kSphere, {0.04, 0.04, 0.04});
  for (double deg : {0.0, 45.0, 90.0}) {
    EXPECT_TRUE(closes_across_shortest_side(ball, turned(deg))) << deg;
    EXPECT_TRUE(closes_across_shortest_side(ball, tilted(deg))) << deg;
  }
  // The ratio's edge: 0.02 / 0.0227 = 0.881 ties, 0.02 / 0.0228 = 0.877 does not.
  EXPECT_TRUE(closes_across_shortest_side(shape(ShapeClass::kBox, {0.02, 0.0227, 0.05}), turned(90)));
  EXPECT_FALSE(closes_across_shortest_side(shape(ShapeClass::kBox, {0.02, 0.0228, 0.05}), turned(90)));
  // Between two tied sides at 45 degrees: fully in their span.
  EXPECT_TRUE(closes_across_shortest_side(shape(ShapeClass::kBox, {0.02, 0.021, 0.05}), turned(45)));
}

// On a table, the smallest dimension is the smallest a hand can close across there: a side within
// 45 degrees of the table's normal does not count unless it is as long as that one.
TEST(GraspTypeTest, OnATableTheShortestSideIsTheShortestAHandCanReach) {
  const auto along = [](const Eigen::Vector3d& d) {  // palm +x along d
    return palm(Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), d).toRotationMatrix());
  };
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  // A knife lying flat: its 2 mm thickness (box x) upright, 2 cm width (y), 20 cm length (z).
  const ObjectShape knife = shape(ShapeClass::kThin, {0.001, 0.01, 0.1});
  EXPECT_TRUE(closes_across_shortest_side(knife, along(y), {}, x));
  EXPECT_FALSE(closes_across_shortest_side(knife, along(y)));  // without the table: not its thickness
  EXPECT_FALSE(closes_across_shortest_side(knife, along(x), {}, x));  // through the table
  EXPECT_TRUE(closes_across_shortest_side(knife, along(x)));
  EXPECT_FALSE(closes_across_shortest_side(knife, along(z), {}, x));
  // Standing on its end (length upright) nothing changes: the thickness is horizontal.
  EXPECT_TRUE(closes_across_shortest_side(knife, along(x), {}, z));
  EXPECT_FALSE(closes_across_shortest_side(knife, along(y), {}, z));
  // The 45-degree edge: the normal 44 degrees from the thickness takes it out, 46 leaves it.
  const auto normal_at = [&](double deg) {
    return Eigen::Vector3d(std::cos(deg * kPi / 180), std::sin(deg * kPi / 180), 0);
  };
  EXPECT_FALSE(closes_across_shortest_side(knife, along(x), {}, normal_at(44)));
  EXPECT_TRUE(closes_across_shortest_side(knife, along(y), {}, normal_at(44)));
  EXPECT_TRUE(closes_across_shortest_side(knife, along(x), {}, normal_at(46)));
  EXPECT_FALSE(closes_across_shortest_side(knife, along(y), {}, normal_at(46)));
  // A ball: the upright side is as long as the reachable ones, so every direction still counts.
  const ObjectShape ball = shape(ShapeClass::kSphere, {0.04, 0.04, 0.04});
  for (const Eigen::Vector3d& d : {x, y, z, Eigen::Vector3d(1, 1, 1).normalized()})
    EXPECT_TRUE(closes_across_shortest_side(ball, along(d), {}, z)) << d.transpose();
  // A can lying on its side (axis z horizontal, a round side x upright): across the other round
  // side or upright, never along the axis.
  const ObjectShape can = shape(ShapeClass::kCylinder, {0.03, 0.03, 0.06}, 2);
  EXPECT_TRUE(closes_across_shortest_side(can, along(y), {}, x));
  EXPECT_TRUE(closes_across_shortest_side(can, along(x), {}, x));
  EXPECT_FALSE(closes_across_shortest_side(can, along(z), {}, x));
}

// Miller's rules with Feix's widths: balls by their width, cylinders by diameter and whether the
// palm faces their end, boxes, thin objects, anything else.
TEST(GraspTypeTest, ChoiceFollowsShapeWidthAndPose) {
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kSphere, {0.02, 0.02, 0.02}), palm()), GraspType::kTripod);
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kSphere, {0.04, 0.04, 0.04}), palm()), GraspType::kPowerSphere);
  // A rod along object z, 2.4, 5 and 9 cm across, the palm's normal (-z) along object -x.
  const Eigen::Matrix3d side = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kCylinder, {0.012, 0.012, 0.1}, 2), palm(side)), GraspType::kSmallWrap);
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kCylinder, {0.025, 0.025, 0.1}, 2), palm(side)),
            GraspType::kMediumWrap);
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kCylinder, {0.045, 0.045, 0.1}, 2), palm(side)), GraspType::kLargeWrap);
  // The palm normal along the axis: a disk grasp; 40 degrees off still, 50 not.
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kCylinder, {0.025, 0.025, 0.1}, 2), palm()), GraspType::kDisk);
  const auto tilted = [](double deg) { return Eigen::AngleAxisd(deg * kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix(); };
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kCylinder, {0.025, 0.025, 0.1}, 2), palm(tilted(40))), GraspType::kDisk);
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kCylinder, {0.025, 0.025, 0.1}, 2), palm(tilted(50))),
            GraspType::kMediumWrap);
  // A flat can (its axis the box's shortest side, x) seen from its end, and its diameter.
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kCylinder, {0.02, 0.05, 0.05}, 0), palm(side)), GraspType::kDisk);
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kCylinder, {0.02, 0.05, 0.05}, 0), palm()), GraspType::kLargeWrap);
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kBox, {0.02, 0.05, 0.08}), palm()), GraspType::kPrismatic);
  // A thin object closed across its thickness (box x): a lateral pinch, still 40 degrees off it;
  // 50 degrees off and across its width, as one lying flat on a table is closed: prismatic.
  const ObjectShape thin = shape(ShapeClass::kThin, {0.003, 0.02, 0.1});
  const auto about_z = [](double deg) { return Eigen::AngleAxisd(deg * kPi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix(); };
  EXPECT_EQ(choose_grasp_type(thin, palm()), GraspType::kLateralPinch);
  EXPECT_EQ(choose_grasp_type(thin, palm(about_z(40))), GraspType::kLateralPinch);
  EXPECT_EQ(choose_grasp_type(thin, palm(about_z(50))), GraspType::kPrismatic);
  EXPECT_EQ(choose_grasp_type(thin, palm(about_z(90))), GraspType::kPrismatic);
  EXPECT_EQ(choose_grasp_type(shape(ShapeClass::kOther, {0.02, 0.05, 0.08}), palm()), GraspType::kOther);
}

std::shared_ptr<const HandRig> opposable() {
  return std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right_opposable")));
}

// The rig data: a type replaces the closing of the joints it names, keeps the others', and may
// have its own rule; types the rig does not list close as the rig does.
TEST(GraspTypeTest, RigTypesReplaceTheJointsTheyName) {
  const auto rig = opposable();
  const PhalanxId ring = rig->find("ring_prox"), index = rig->find("index_prox");
  EXPECT_NEAR(rig->phalanges(GraspType::kTripod)[ring.value].closed, 5 * kPi / 180, 1e-15);
  EXPECT_EQ(rig->phalanges(GraspType::kTripod)[index.value].closed, rig->phalanges()[index.value].closed);
  EXPECT_EQ(rig->grasp_rule(GraspType::kTripod).size(), 2u);
  for (const auto& group : rig->grasp_rule(GraspType::kTripod))
    for (const GraspTerm& t : group) EXPECT_FALSE(t.palm);
  EXPECT_EQ(&rig->grasp_rule(GraspType::kPowerSphere), &rig->grasp_rule());
  const HandRig planar = HandRig::load(HandRig::builtin_path("human_right"));
  EXPECT_FALSE(planar.has_grasp_types());
  EXPECT_FALSE(planar.has_grasp_type(GraspType::kTripod));
  EXPECT_TRUE(planar.has_grasp_type(GraspType::kOther));
  EXPECT_EQ(&planar.phalanges(GraspType::kTripod), &planar.phalanges());
  // The mirror keeps the types, on mirrored phalanges.
  const HandRig left = rig->mirrored();
  EXPECT_TRUE(left.has_grasp_type(GraspType::kTripod));
  EXPECT_EQ(left.phalanges(GraspType::kTripod)[ring.value].closed, rig->phalanges(GraspType::kTripod)[ring.value].closed);
  EXPECT_EQ(left.phalanges(GraspType::kTripod)[ring.value].X_ParentJoint.translation().y(),
            -rig->phalanges()[ring.value].X_ParentJoint.translation().y());
}

std::string read_builtin(const std::string& name) {
  std::ifstream in(HandRig::builtin_path(name));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string error_of(const std::string& extra) {
  try {
    HandRig::parse(read_builtin("human_right") + extra, "bad.textproto");
  } catch (const RigError& e) {
    return e.what();
  }
  return "";
}

TEST(GraspTypeTest, BadTypesAreNamed) {
  EXPECT_EQ(error_of("grasp_types { type: \"tripod\" }"), "");
  EXPECT_NE(error_of("grasp_types { type: \"pinch\" }").find("grasp_types[0].type"), std::string::npos);
  EXPECT_NE(error_of("grasp_types { type: \"other\" }").find("grasp_types[0].type"), std::string::npos);
  EXPECT_NE(error_of("grasp_types { type: \"disk\" } grasp_types { type: \"disk\" }").find("listed twice"),
            std::string::npos);
  EXPECT_NE(error_of("grasp_types { type: \"disk\" joints { phalanx: \"index_nail\" } }").find("unknown phalanx 'index_nail'"),
            std::string::npos);
  EXPECT_NE(error_of("grasp_types { type: \"disk\" joints { phalanx: \"index_prox\" closed_deg: 120 } }")
                .find("grasp_types[0].joints[0].closed_deg"),
            std::string::npos);
  EXPECT_NE(error_of("grasp_types { type: \"disk\" joints { phalanx: \"index_prox\" closes_from: 1 } }")
                .find("grasp_types[0].joints[0].closes_from/closes_until"),
            std::string::npos);
  EXPECT_NE(error_of("grasp_types { type: \"disk\" grasp_rule { members: [\"index_prox\"] } }")
                .find("grasp_types[0].grasp_rule[0].members"),
            std::string::npos);
}

// One primitive under the palm (top 3 mm below it, centred under the grasp centre), the hand
// at the world origin, the trigger squeezed over 2/3 s after 0.2 s.
struct Closing {
  GraspType type_at_rest = GraspType::kOther;  // before the trigger moves
  HandController hand;
};
Closing close_on(const std::shared_ptr<const HandRig>& rig, const ObjectModel& model, const Eigen::Isometry3d& X) {
  const ObjectView view{ObjectId(1), X, &model};
  Closing out{GraspType::kOther, HandController(rig, {})};
  for (int t = 0; t < 160; ++t) {
    ControllerInput in;
    in.trigger = std::clamp((t - 18) / 60.0, 0.0, 1.0);
    out.hand.tick(in, 1.0 / 90.0, {&view, 1});
    if (t == 17) out.type_at_rest = out.hand.state().grasp_type;
  }
  return out;
}

// The object turned by R under the rig's grasp centre, its top `gap` below the palm.
Eigen::Isometry3d under_palm(const HandRig& rig, const ObjectModel& model, const Eigen::Matrix3d& R,
                             double gap = 0.003) {
  double top = -1e9;
  for (const Eigen::Vector3d& v : model.mesh.vertices) top = std::max(top, (R * v).z());
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = R;
  X.translation() = rig.p_PalmGraspCenter();
  X.translation().z() = -rig.palm_half_extent().z() - gap - top;
  return X;
}

// Each type on its primitive: chosen while the hand is still open, grasped, every contact on the
// primitive's surface (analytic distance within the tessellation's and the contact tolerance),
// and the fingers the type uses: the tripod leaves ring and little out.
TEST(GraspTypeTest, EachTypeClosesOnItsPrimitive) {
  const auto rig = opposable();
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d side = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();  // axis -> palm y
  struct Case {
    const char* name;
    TriangleMesh mesh;
    Eigen::Matrix3d R;
    GraspType type;
    // Distance from a point (object frame) to the primitive's surface.
    std::function<double(const Eigen::Vector3d&)> surface;
    double gap = 0.003;  // from the palm down to the object's top
  };
  const auto sphere = [](double r) { return [r](const Eigen::Vector3d& p) { return std::abs(p.norm() - r); }; };
  const auto cylinder = [](double r, double hz) {
    return [r, hz](const Eigen::Vector3d& p) {
      const double radial = std::hypot(p.x(), p.y()) - r, axial = std::abs(p.z()) - hz;
      return radial > 0 || axial > 0 ? std::hypot(std::max(radial, 0.0), std::max(axial, 0.0))
                                     : std::abs(std::max(radial, axial));
    };
  };
  const auto box = [](const Eigen::Vector3d& h) {
    return [h](const Eigen::Vector3d& p) {
      const Eigen::Vector3d d = p.cwiseAbs() - h;
      return d.maxCoeff() > 0 ? d.cwiseMax(0.0).norm() : -d.maxCoeff();
    };
  };
  std::vector<Case> cases;
  cases.push_back({"4 cm ball", testing::uv_sphere_mesh(0.02, 60, 120), I, GraspType::kTripod, sphere(0.02)});
  cases.push_back({"8 cm ball", testing::uv_sphere_mesh(0.04, 60, 120), I, GraspType::kPowerSphere, sphere(0.04)});
  cases.push_back({"2.5 cm rod", testing::cylinder_mesh(0.0125, 0.08, 96), side, GraspType::kSmallWrap,
                   cylinder(0.0125, 0.08)});
  cases.push_back({"5 cm can", testing::cylinder_mesh(0.025, 0.06, 96), side, GraspType::kMediumWrap,
                   cylinder(0.025, 0.06)});
  cases.push_back({"9 cm can", testing::cylinder_mesh(0.045, 0.07, 96), side, GraspType::kLargeWrap,
                   cylinder(0.045, 0.07)});
  cases.push_back({"6 cm can from its end", testing::cylinder_mesh(0.03, 0.05, 96), I, GraspType::kDisk,
                   cylinder(0.03, 0.05)});
  cases.push_back({"box", testing::box_mesh({0.03, 0.075, 0.04}), I, GraspType::kPrismatic,
                   box({0.03, 0.075, 0.04})});
  // A 6 mm diamond plate (diagonals 4 and 12 cm: thin, half its box), lying flat under the palm
  // with its short diagonal across the hand; then standing on its edge, its thickness across.
  // 25 mm under the palm, where the fingertips (not the knuckles) reach something this thin.
  const std::vector<Eigen::Vector2d> diamond = {{0.02, 0}, {0, 0.06}, {-0.02, 0}, {0, -0.06}};
  const auto diamond_plate = [](const Eigen::Vector3d& p) {
    const double edge = (std::abs(p.x()) / 0.02 + std::abs(p.y()) / 0.06 - 1) / std::hypot(1 / 0.02, 1 / 0.06);
    return std::abs(std::max(edge, std::abs(p.z()) - 0.003));
  };
  const Eigen::Matrix3d on_edge = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();  // z -> palm x
  const TriangleMesh plate = testing::prism_mesh(diamond, 0.003);
  ASSERT_EQ(make_object_model("diamond", plate, 0.2, "test")->shape.shape, ShapeClass::kThin);
  cases.push_back({"plate lying flat", plate, I, GraspType::kPrismatic, diamond_plate, 0.025});
  cases.push_back({"plate on its edge", plate, on_edge, GraspType::kLateralPinch, diamond_plate, 0.025});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const ObjectModelPtr model = make_object_model(c.name, c.mesh, 0.2, "test");
    const Eigen::Isometry3d X = under_palm(*rig, *model, c.R, c.gap);
    const Closing closing = close_on(rig, *model, X);
    EXPECT_EQ(closing.type_at_rest, c.type) << grasp_type_name(closing.type_at_rest);
    const HandController& hand = closing.hand;
    EXPECT_EQ(hand.state().grasp_type, c.type) << grasp_type_name(hand.state().grasp_type);
    ASSERT_TRUE(hand.state().grasped.valid());
    const std::vector<Contact> contacts = hand.contacts();
    EXPECT_GE(contacts.size(), 3u);
    // The mesh model is recentred on its centre of mass, which for these is the primitive's centre.
    for (const Contact& k : contacts) EXPECT_LT(c.surface(k.p_ObjectContact), 1e-3) << k.p_ObjectContact.transpose();
    if (c.type != GraspType::kTripod) continue;
    for (const Contact& k : contacts) {
      if (k.phalanx.valid()) {
        EXPECT_LE(rig->phalanges()[k.phalanx.value].finger, 2) << rig->phalanges()[k.phalanx.value].name;
      }
    }
  }
}

// The type follows the hand's pose while nothing is blocked, and is chosen again after release:
// a can under the palm from its side (medium wrap), from its end after turning the hand.
TEST(GraspTypeTest, TypeFollowsThePoseUntilAPhalanxBlocksAndAgainAfterRelease) {
  const auto rig = opposable();
  const ObjectModelPtr model = make_object_model("can", testing::cylinder_mesh(0.025, 0.06, 96), 0.2, "test");
  const Eigen::Matrix3d side = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Isometry3d X = under_palm(*rig, *model, side);
  const ObjectView view{ObjectId(1), X, model.get()};
  HandController hand(rig, {});
  ControllerInput in;
  hand.tick(in, 1.0 / 90.0, {&view, 1});
  EXPECT_EQ(hand.state().grasp_type, GraspType::kMediumWrap);
  // The hand turned so its palm faces the can's end (the palm normal along the can's axis, palm y).
  ControllerInput turned;
  turned.X_WorldPalm.linear() = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  turned.X_WorldPalm.translation() = X.translation() - turned.X_WorldPalm.linear() * Eigen::Vector3d(0.05, 0, -0.04);
  hand.tick(turned, 1.0 / 90.0, {&view, 1});
  EXPECT_EQ(hand.state().grasp_type, GraspType::kDisk);
  // Back and closed: grasped as a wrap, which it stays while held.
  for (int t = 0; t < 150; ++t) {
    in.trigger = std::min(1.0, t / 60.0);
    hand.tick(in, 1.0 / 90.0, {&view, 1});
  }
  ASSERT_TRUE(hand.state().grasped.valid());
  EXPECT_EQ(hand.state().grasp_type, GraspType::kMediumWrap);
  // Opened and turned away: released, and chosen afresh.
  in.trigger = 0;
  for (int t = 0; t < 60; ++t) hand.tick(in, 1.0 / 90.0, {&view, 1});
  EXPECT_FALSE(hand.state().grasped.valid());
  hand.tick(turned, 1.0 / 90.0, {&view, 1});
  EXPECT_EQ(hand.state().grasp_type, GraspType::kDisk);
}

}  // namespace
}  // namespace telegrasp::sim
