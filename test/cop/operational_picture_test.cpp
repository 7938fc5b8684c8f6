// Track fusion: association, gating, class compatibility, confirmation, deletion, belief,
// ground-truth entity ids and determinism.
#include "hameritt/cop/operational_picture.h"

#include <gtest/gtest.h>

#include <random>

namespace hameritt::cop {
namespace {

Observation obs(double t, double x, double y, const std::string& cls = "car",
                std::map<std::string, std::string> attrs = {}, double confidence = 0.8,
                const std::string& entity = "") {
  Observation o;
  o.stamp = t;
  o.position = Eigen::Vector3d(x, y, 0.0);
  o.entity_class = cls;
  o.attributes = std::move(attrs);
  o.confidence = confidence;
  o.source = entity.empty() ? "client" : "perfect_perception";
  o.entity_id = entity;
  o.sigma = entity.empty() ? 3.0 : 0.5;
  return o;
}

const TargetSpec kTarget{
    "car_706",
    "car",
    {{"color", "white"}, {"make", "Toyota"}, {"model", "RAV4"}, {"vehicle_class", "suv"}}};
const std::map<std::string, std::string> kTargetAttrs = kTarget.attributes;

TEST(OperationalPicture, AssociatesNearbyReportsAndConfirms) {
  OperationalPicture cop;
  for (int i = 0; i < 3; ++i) cop.update({obs(i, 10 + 0.5 * i, 20, "car")});
  ASSERT_EQ(cop.tracks().size(), 1u);
  const Track& t = cop.tracks().begin()->second;
  EXPECT_EQ(t.id, "T0001");
  EXPECT_EQ(t.hits, 3u);
  EXPECT_TRUE(t.confirmed);
  EXPECT_NEAR(t.state.x(), 11.0, 1.0);
  EXPECT_GT(t.state(2), 0.0);                    // moving east
  EXPECT_LT(t.positionCovariance()(0, 0), 9.0);  // tighter than one report
}

TEST(OperationalPicture, FollowsAMovingTargetWithTheConstantVelocityModel) {
  OperationalPicture cop;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int i = 0; i <= 40; ++i) {
    const double t = 0.5 * i;
    cop.update({obs(t, 5.0 * t + noise(rng), -2.0 * t + noise(rng))});
  }
  ASSERT_EQ(cop.tracks().size(), 1u);
  const Track& tr = cop.tracks().begin()->second;
  EXPECT_NEAR(tr.state(2), 5.0, 0.6);
  EXPECT_NEAR(tr.state(3), -2.0, 0.6);
  EXPECT_NEAR(tr.state.x(), 100.0, 2.0);
}

TEST(OperationalPicture, GatesByMahalanobisDistanceAndClass) {
  OperationalPicture cop;
  cop.update({obs(0, 0, 0, "car")});
  cop.update({obs(0.1, 2, 0, "car")});           // inside the gate: same track
  cop.update({obs(0.2, 40, 0, "car")});          // far: a new track
  cop.update({obs(0.3, 0.5, 0, "pedestrian")});  // near, but another class: a new track
  cop.update({obs(0.4, 1.5, 0.1, "")});  // unknown class: compatible, the nearest track (T0001)
  ASSERT_EQ(cop.tracks().size(), 3u);
  EXPECT_EQ(cop.tracks().at("T0001").hits, 3u);
  EXPECT_EQ(cop.tracks().at("T0002").hits, 1u);
  EXPECT_EQ(cop.tracks().at("T0003").entity_class, "pedestrian");
}

TEST(OperationalPicture, OneReportsEntitiesAreAssociatedOneToOne) {
  OperationalPicture cop;
  cop.update({obs(0, 0, 0, "car", {}, 1, "car_1"), obs(0, 3, 0, "car", {}, 1, "car_2")});
  ASSERT_EQ(cop.tracks().size(), 2u);
  // Both move 0.2 m east: each keeps its own track (global nearest neighbour), ids kept.
  cop.update({obs(0.5, 3.2, 0, "car", {}, 1, "car_2"), obs(0.5, 0.2, 0, "car", {}, 1, "car_1")});
  ASSERT_EQ(cop.tracks().size(), 2u);
  EXPECT_EQ(cop.tracks().at("T0001").entity_id, "car_1");
  EXPECT_EQ(cop.tracks().at("T0002").entity_id, "car_2");
  EXPECT_EQ(cop.tracks().at("T0001").hits, 2u);
  EXPECT_EQ(cop.tracks().at("T0002").hits, 2u);
}

TEST(OperationalPicture, MergesATrackStartedByAReportOutsideTheGate) {
  CopConfig c;
  c.gate_chi2 = 0.5;  // tight: a report 2 m off starts a track of its own
  OperationalPicture cop(c);
  for (int i = 0; i < 3; ++i) cop.update({obs(i * 0.1, 0, 0, "car", {{"color", "white"}})});
  cop.update({obs(0.3, 2, 0, "car", {{"color", "white"}}, 0.8, "car_9")});
  ASSERT_EQ(cop.tracks().size(), 1u);
  const Track& t = cop.tracks().at("T0001");
  EXPECT_EQ(t.hits, 4u);
  EXPECT_EQ(t.entity_id, "car_9");
  EXPECT_EQ(t.sources.at("perfect_perception"), 1u);
  EXPECT_EQ(cop.stats().created, 2u);
  EXPECT_EQ(cop.stats().merged, 1u);
  // Two entities in one report stay two tracks however close.
  OperationalPicture two(c);
  two.update({obs(0, 0, 0), obs(0, 0.5, 0)});
  EXPECT_EQ(two.tracks().size(), 2u);
  EXPECT_EQ(two.stats().merged, 0u);
}

TEST(OperationalPicture, DeletesTentativeTracksSoonerThanConfirmedOnes) {
  CopConfig c;
  c.tentative_timeout = 2.0;
  c.confirmed_timeout = 10.0;
  OperationalPicture cop(c);
  for (int i = 0; i < 3; ++i) cop.update({obs(i * 0.1, 0, 0)});  // confirmed
  cop.update({obs(0.3, 100, 100)});                              // tentative
  EXPECT_TRUE(cop.prune(2.0).empty());
  EXPECT_EQ(cop.prune(2.5), std::vector<std::string>{"T0002"});
  EXPECT_TRUE(cop.prune(10.0).empty());
  EXPECT_EQ(cop.prune(10.5), std::vector<std::string>{"T0001"});
  EXPECT_TRUE(cop.tracks().empty());
  EXPECT_EQ(cop.stats().deleted, 2u);
  // A report after deletion starts a new track with a fresh id.
  cop.update({obs(11, 0, 0)});
  EXPECT_EQ(cop.tracks().begin()->first, "T0003");
}

TEST(OperationalPicture, BeliefFollowsTheTargetDescriptionAndConfidence) {
  OperationalPicture cop;
  cop.setTargets({kTarget});
  cop.update({obs(0, 0, 0, "car", kTargetAttrs, 0.6)});  // matching claim
  cop.update({obs(0, 50, 0, "car", {{"color", "red"}, {"make", "Toyota"}}, 0.9)});
  cop.update({obs(0, 100, 0, "pedestrian", {}, 0.9)});
  cop.update({obs(0, 150, 0, "car", {{"color", "white"}}, 0.9)});  // partial description
  const Track& match = cop.tracks().at("T0001");
  EXPECT_NEAR(match.target_belief, 0.6, 1e-9);
  EXPECT_EQ(match.target_id, "car_706");
  // More agreeing claims raise the belief: 1 - 0.4 * 0.4.
  cop.update({obs(0.5, 0.3, 0, "car", kTargetAttrs, 0.6)});
  EXPECT_NEAR(cop.tracks().at("T0001").target_belief, 0.84, 1e-9);
  // A look-alike of another colour: 0.02 * 1 * 1/2 * 1/2 * 0.9.
  EXPECT_NEAR(cop.tracks().at("T0002").target_belief, 0.0045, 1e-9);
  EXPECT_EQ(cop.tracks().at("T0002").target_id, "");
  EXPECT_EQ(cop.tracks().at("T0003").target_belief, 0.0);  // another class
  // Colour only: 1 * (1/2)^3 * 0.9, not enough to be believed the target.
  EXPECT_NEAR(cop.tracks().at("T0004").target_belief, 0.1125, 1e-9);
  EXPECT_EQ(cop.tracks().at("T0004").target_id, "");
  // The same make, model and class in another colour: a look-alike, not the target.
  cop.update({obs(
      1, 300, 0, "car",
      {{"color", "red"}, {"make", "Toyota"}, {"model", "RAV4"}, {"vehicle_class", "suv"}}, 1.0)});
  EXPECT_NEAR(cop.tracks().at("T0005").target_belief, 0.02, 1e-9);
  EXPECT_EQ(cop.tracks().at("T0005").target_id, "");
}

TEST(OperationalPicture, AttributesAreMergedByAccumulatedConfidence) {
  OperationalPicture cop;
  cop.setTargets({kTarget});
  cop.update({obs(0, 0, 0, "car", {{"color", "silver"}}, 0.3)});
  cop.update({obs(0.2, 0, 0, "car", {{"color", "white"}}, 0.5)});
  const Track& t = cop.tracks().at("T0001");
  EXPECT_EQ(t.attributes().at("color"), "white");
  cop.update({obs(0.4, 0, 0, "car", {{"color", "silver"}}, 0.3)});
  EXPECT_EQ(cop.tracks().at("T0001").attributes().at("color"), "silver");  // 0.6 > 0.5
}

TEST(OperationalPicture, PerfectPerceptionKeepsTheEntityIdAsGroundTruth) {
  OperationalPicture cop;
  cop.setTargets({kTarget});
  for (int i = 0; i < 3; ++i) cop.update({obs(i, 0.1 * i, 0, "car", kTargetAttrs, 1.0, "car_706")});
  const Track& t = cop.tracks().at("T0001");
  EXPECT_EQ(t.entity_id, "car_706");
  EXPECT_EQ(t.target_id, "car_706");
  EXPECT_DOUBLE_EQ(t.target_belief, 1.0);
  EXPECT_EQ(t.sources.at("perfect_perception"), 3u);
}

TEST(OperationalPicture, SameReportsGiveTheSameTracks) {
  const auto run = [] {
    OperationalPicture cop;
    cop.setTargets({kTarget});
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> pos(-200, 200);
    std::normal_distribution<double> noise(0, 1.5);
    std::vector<Eigen::Vector2d> truth(15);
    for (auto& p : truth) p = {pos(rng), pos(rng)};
    for (int k = 0; k < 30; ++k) {
      std::vector<Observation> batch;
      for (size_t i = 0; i < truth.size(); ++i)
        if (rng() % 2)
          batch.push_back(obs(k * 0.5, truth[i].x() + noise(rng), truth[i].y() + noise(rng)));
      cop.update(batch);
      cop.prune(k * 0.5);
    }
    return cop.tracks();
  };
  const auto a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  for (auto ia = a.begin(), ib = b.begin(); ia != a.end(); ++ia, ++ib) {
    EXPECT_EQ(ia->first, ib->first);
    EXPECT_EQ(ia->second.state, ib->second.state);
    EXPECT_EQ(ia->second.hits, ib->second.hits);
  }
  // Well-separated stationary entities: one track each.
  EXPECT_EQ(a.size(), 15u);
}

TEST(OperationalPicture, RejectsBadConfig) {
  CopConfig c;
  c.gate_chi2 = -1;
  EXPECT_THROW(OperationalPicture{c}, std::invalid_argument);
  c = CopConfig{};
  c.confirm_hits = 0;
  try {
    c.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("confirm_hits"), std::string::npos);
  }
}

}  // namespace
}  // namespace hameritt::cop
