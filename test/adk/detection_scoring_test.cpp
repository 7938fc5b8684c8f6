#include "hameritt/adk/detection_scoring.h"

#include <gtest/gtest.h>

#include <limits>

#include "adk_test_util.h"
#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

using namespace testing;  // NOLINT

std::vector<EntityTruth> truthAt(double t) {
  std::vector<EntityTruth> out;
  for (const auto& e : shippedSimConfig().entities) out.push_back(scenarioEntityAt(e, t));
  return out;
}

const EntityTruth& find(const std::vector<EntityTruth>& v, const std::string& role) {
  for (const auto& e : v) {
    if (e.role == role) return e;
  }
  throw std::runtime_error("no " + role);
}

DetectionClaim claimAt(const Vec3& p, const std::string& cls = "car", double stamp = 10.0) {
  DetectionClaim c;
  c.stamp = stamp;
  c.entity_class = cls;
  c.position = p;
  return c;
}

TEST(DetectionScorer, TargetConfuserOtherAndNone) {
  DetectionScorer scorer(shippedMission(), shippedSimConfig().entities);
  ASSERT_EQ(scorer.targets(), std::vector<std::string>{"car_706"});
  const auto truth = truthAt(10.0);
  const EntityTruth& target = find(truth, "target");
  ASSERT_EQ(target.id, "car_706");

  auto v = scorer.score(claimAt(target.position + Vec3(3, 4, 7)), truth);
  EXPECT_EQ(v.verdict, Verdict::kTarget);
  EXPECT_EQ(v.entity_id, "car_706");
  EXPECT_EQ(v.role, "target");
  EXPECT_NEAR(v.position_error, 5.0, 1e-9);  // horizontal: z is ignored
  EXPECT_TRUE(v.first_correct);
  v = scorer.score(claimAt(target.position), truth);
  EXPECT_EQ(v.verdict, Verdict::kTarget);
  EXPECT_FALSE(v.first_correct);

  const EntityTruth& confuser = find(truth, "confuser");
  v = scorer.score(claimAt(confuser.position + Vec3(1, 0, 0)), truth);
  EXPECT_EQ(v.verdict, Verdict::kConfuser);
  EXPECT_EQ(v.entity_id, confuser.id);
  EXPECT_NEAR(v.position_error, 1.0, 1e-9);
  EXPECT_FALSE(v.first_correct);

  const EntityTruth& traffic = find(truth, "traffic");
  v = scorer.score(claimAt(traffic.position), truth);
  EXPECT_EQ(v.verdict, Verdict::kOther);
  EXPECT_EQ(v.entity_id, traffic.id);

  v = scorer.score(claimAt(Vec3(2000, 2000, 0)), truth);
  EXPECT_EQ(v.verdict, Verdict::kNone);
  EXPECT_EQ(v.entity_id, "");
  EXPECT_STREQ(toString(v.verdict), "none");
}

TEST(DetectionScorer, GatesAndClassesAndWorldCars) {
  const Vec3 at(100, 100, 0);
  std::vector<EntityTruth> truth = {
      {"car_706", "car", "target", at, 0.0},
      {"ped_1", "pedestrian", "pedestrian", at + Vec3(0, 20, 0), 0.0},
      {"car_3", "car", "world", at + Vec3(0, -20, 0), 0.0},
  };
  DetectionScorer scorer(shippedMission(), shippedSimConfig().entities);
  EXPECT_EQ(scorer.score(claimAt(at + Vec3(5.99, 0, 0)), truth).verdict, Verdict::kTarget);
  EXPECT_EQ(scorer.score(claimAt(at + Vec3(6.01, 0, 0)), truth).verdict, Verdict::kNone);
  // A pedestrian claim at the car matches no pedestrian; an unclassified claim matches the car.
  EXPECT_EQ(scorer.score(claimAt(at, "pedestrian"), truth).verdict, Verdict::kNone);
  EXPECT_EQ(scorer.score(claimAt(at, ""), truth).verdict, Verdict::kTarget);
  EXPECT_EQ(scorer.score(claimAt(at + Vec3(0, 22.9, 0), "pedestrian"), truth).verdict,
            Verdict::kOther);
  EXPECT_EQ(scorer.score(claimAt(at + Vec3(0, 23.1, 0), "pedestrian"), truth).verdict,
            Verdict::kNone);
  const auto w = scorer.score(claimAt(at + Vec3(0, -19, 0)), truth);
  EXPECT_EQ(w.verdict, Verdict::kOther);
  EXPECT_EQ(w.role, "world");
  // Nearest wins.
  truth.push_back({"car_721", "car", "confuser", at + Vec3(4, 0, 0), 0.0});
  EXPECT_EQ(scorer.score(claimAt(at + Vec3(2.5, 0, 0)), truth).verdict, Verdict::kConfuser);
  EXPECT_THROW(scorer.score(claimAt(Vec3(std::nan(""), 0, 0)), truth), InputError);
}

TEST(DetectionScorer, RejectsAMissionWhoseTargetIsNotInTheSimConfig) {
  scenario::Mission m = shippedMission();
  m.objective.targets[0].id = "car_99999";
  try {
    DetectionScorer s(m, shippedSimConfig().entities);
    FAIL();
  } catch (const scenario::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("car_99999"), std::string::npos);
  }
  ScoringSettings bad;
  bad.car_gate = 0;
  EXPECT_THROW(DetectionScorer(shippedMission(), shippedSimConfig().entities, bad),
               scenario::ConfigError);
}

TEST(GroundTruthHistory, RefusesASnapshotWithANonFiniteEntity) {
  GroundTruthHistory h(5.0);
  EntityTruth ok{"car_1", "car", "target", {1, 2, 0}, 0.5};
  h.add(1.0, {ok});
  EntityTruth bad = ok;
  bad.id = "car_2";
  bad.position.y() = std::numeric_limits<double>::quiet_NaN();
  try {
    h.add(2.0, {ok, bad});
    FAIL() << "accepted a NaN position";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "ground truth: entities[1] 'car_2': expected a finite position and yaw");
  }
  bad.position.y() = 0;
  bad.yaw = std::numeric_limits<double>::infinity();
  EXPECT_THROW(h.add(2.0, {bad}), InputError);
  ASSERT_EQ(h.at(2.0).size(), 1u);  // the good snapshot is kept
  EXPECT_EQ(h.at(2.0)[0].position, ok.position);
}

TEST(GroundTruthHistory, InterpolatesBetweenSnapshotsAndHoldsOutside) {
  GroundTruthHistory h(5.0);
  EXPECT_TRUE(h.at(1.0).empty());
  h.add(1.0,
        {{"a", "car", "traffic", Vec3(0, 0, 0), 3.0}, {"b", "car", "traffic", Vec3(9, 9, 0), 0}});
  h.add(2.0, {{"a", "car", "traffic", Vec3(10, 0, 0), -3.0}});
  auto at = h.at(1.25);
  ASSERT_EQ(at.size(), 2u);
  EXPECT_EQ(at[0].id, "a");
  EXPECT_NEAR((at[0].position - Vec3(2.5, 0, 0)).norm(), 0, 1e-12);
  // Yaw along the shorter arc: 3 -> -3 passes through pi.
  EXPECT_NEAR(std::fabs(at[0].yaw), 3.0 + 0.25 * (2 * geometry::kPi - 6.0), 1e-12);
  EXPECT_EQ(at[1].id, "b");  // only in the earlier snapshot
  EXPECT_EQ(h.at(0.0)[0].position, Vec3(0, 0, 0));
  EXPECT_EQ(h.at(9.0)[0].position, Vec3(10, 0, 0));
  // Old snapshots fall out of the horizon; a clock that goes back clears the history.
  h.add(8.0, {{"a", "car", "traffic", Vec3(20, 0, 0), 0}});
  EXPECT_EQ(h.at(1.5)[0].position, Vec3(20, 0, 0));
  h.add(0.5, {{"a", "car", "traffic", Vec3(-1, 0, 0), 0}});
  EXPECT_EQ(h.newestTime(), 0.5);
  EXPECT_EQ(h.at(8.0)[0].position, Vec3(-1, 0, 0));
}

TEST(ScenarioEntityAt, FollowsTrajectoriesAndHoldsParkedPoses) {
  for (const auto& e : shippedSimConfig().entities) {
    const EntityTruth t0 = scenarioEntityAt(e, 0.0);
    EXPECT_EQ(t0.id, e.entity.id);
    EXPECT_EQ(t0.role, e.role);
    if (e.trajectory.empty()) {
      EXPECT_EQ(t0.position, e.entity.position());
    } else {
      const auto& last = e.trajectory.back();
      EXPECT_EQ(scenarioEntityAt(e, last.t + 100).position, Vec3(last.x, last.y, last.z));
    }
  }
}

}  // namespace
}  // namespace hameritt::adk
