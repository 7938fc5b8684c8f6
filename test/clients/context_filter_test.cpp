// Context filter: description matching, the region gate, scene-relation checks against the
// public map, and the claim ledger; on the shipped scenario, whose confusers must all be told
// apart from its target by the context alone.
#include "hameritt/clients/context_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hameritt/clients/claims.h"
#include "hameritt/clients/public_config.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::clients {
namespace {

using geometry::Vec2;
using geometry::Vec3;

const char* kMission = "scenarios/default/mission.json";
const char* kSimConfig = "scenarios/default/sim_config.json";

class ContextFilterTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    mission_ = new scenario::Mission(scenario::loadMission(kMission));
    world_ = new scenario::World(
        scenario::generateCheckedWorld(loadPublicSimConfig(kSimConfig), kSimConfig));
    // Ground truth, for the test's judgement only.
    truth_ = new scenario::SimConfig(scenario::loadSimConfig(kSimConfig));
  }
  static void TearDownTestSuite() {
    delete truth_;
    delete world_;
    delete mission_;
  }

  // A candidate at an entity's true pose, the heading known only up to pi (as from an image).
  static CandidatePose at(const std::string& id) {
    for (const auto& e : truth_->entities) {
      if (e.entity.id != id) continue;
      CandidatePose c;
      c.position = e.entity.position();
      c.yaw = e.entity.yaw() + geometry::kPi;
      c.size = e.entity.box.size;
      return c;
    }
    ADD_FAILURE() << id;
    return {};
  }

  static const scenario::TargetDescription& target() { return mission_->objective.targets.front(); }

  static scenario::Mission* mission_;
  static scenario::World* world_;
  static scenario::SimConfig* truth_;
};
scenario::Mission* ContextFilterTest::mission_ = nullptr;
scenario::World* ContextFilterTest::world_ = nullptr;
scenario::SimConfig* ContextFilterTest::truth_ = nullptr;

TEST_F(ContextFilterTest, DescriptionsMatchAttributesCaseInsensitively) {
  const Observation rav4{
      "car", {{"vehicle_class", "suv"}, {"make", "Toyota"}, {"model", "RAV4"}, {"color", "White"}}};
  EXPECT_TRUE(matchesDescription(rav4, target()));
  Observation red = rav4;
  red.attributes.back().second = "red";
  EXPECT_FALSE(matchesDescription(red, target()));
  EXPECT_FALSE(matchesDescription({"pedestrian", rav4.attributes}, target()));
  scenario::TargetDescription any_white;
  any_white.color = "white";
  EXPECT_TRUE(matchesDescription(rav4, any_white));  // empty fields are wildcards
  const ContextFilter filter(*mission_, world_);
  EXPECT_EQ(filter.targetsMatching(rav4).size(), 1u);
  EXPECT_TRUE(filter.targetsMatching(red).empty());
  EXPECT_EQ(describe(target()), "white Toyota RAV4 (suv)");
  EXPECT_TRUE(nominalSize(target()).isApprox(Vec3(4.6, 1.855, 1.685)));
  scenario::TargetDescription some_sedan;
  some_sedan.vehicle_class = "sedan";
  EXPECT_NEAR(nominalSize(some_sedan).x(), 4.99, 0.05);
}

TEST_F(ContextFilterTest, TheTargetPassesInsideItsWindowOnly) {
  const ContextFilter filter(*mission_, world_);
  const ContextVerdict v = filter.check(at("car_706"), 100.0, target());
  EXPECT_TRUE(v.accepted) << v.reason;
  EXPECT_EQ(v.region_id, "aoi_1");
  EXPECT_EQ(v.target_id, "car_706");
  EXPECT_EQ(v.relations_checked, 6);  // PART_OF block, ON_TOP_OF, NOT_ON_TOP_OF, ORTHOGONAL_TO,
  EXPECT_EQ(v.relations_skipped, 0);  // NEXT_TO, NOT_NEXT_TO: all on the public map
  EXPECT_FALSE(filter.check(at("car_706"), 40.0, target()).accepted);   // before net 48
  EXPECT_FALSE(filter.check(at("car_706"), 200.0, target()).accepted);  // after nlt 192
  // A position estimate off by half a metre still passes.
  CandidatePose off = at("car_706");
  off.position += Vec3(0.4, -0.3, 0);
  off.yaw += 0.08;
  EXPECT_TRUE(filter.check(off, 100.0, target()).accepted);
}

TEST_F(ContextFilterTest, AMovingTargetPassesWithinReachOfItsAreaPastTheWindow) {
  // The same mission as a track mission: its target may drive off once aoi_1's window closes.
  scenario::Mission track = *mission_;
  track.cls = scenario::ScenarioClass::kTrack;
  track.aois.erase(std::remove_if(track.aois.begin(), track.aois.end(),
                                  [](const auto& a) { return a.id != "aoi_1"; }),
                   track.aois.end());
  ASSERT_EQ(track.aois.size(), 1u);
  const double nlt = track.aois.front().window.nlt.value();  // 192
  ContextSettings reach;
  reach.drive_off_speed = 13.0;
  const ContextFilter filter(track, world_, reach);
  // In the area past its window: accepted, its relations (t = 0) no longer checked.
  const ContextVerdict in = filter.check(at("car_706"), nlt + 8, target());
  EXPECT_TRUE(in.accepted) << in.reason;
  EXPECT_EQ(in.region_id, "aoi_1");
  EXPECT_EQ(in.relations_checked, 0);
  EXPECT_EQ(in.relations_skipped, 6);
  // 50 m outside the area: out of reach 1 s after the window (14.5 m), within it after 5 s.
  CandidatePose away = at("car_706");
  while (track.aois.front().polygon.distance(away.position.head<2>()) < 50.0) {
    away.position.x() += 0.5;
  }
  EXPECT_FALSE(filter.check(away, nlt + 1, target()).accepted);
  EXPECT_TRUE(filter.check(away, nlt + 5, target()).accepted);
  EXPECT_FALSE(filter.check(away, nlt - 1, target()).accepted);  // inside the window: in the area
  // Negative controls: no reach (the default), or a target that does not move (area search).
  EXPECT_FALSE(ContextFilter(track, world_).check(away, nlt + 5, target()).accepted);
  EXPECT_FALSE(ContextFilter(*mission_, world_, reach).check(away, nlt + 5, target()).accepted);
  ContextSettings bad;
  bad.drive_off_speed = -1.0;
  EXPECT_THROW(bad.validate(), scenario::ConfigError);
}

TEST_F(ContextFilterTest, EveryConfuserOfTheScenarioIsRejected) {
  const ContextFilter filter(*mission_, world_);
  int confusers = 0;
  for (const auto& e : truth_->entities) {
    if (e.role != "confuser") continue;
    ++confusers;
    for (double t : {60.0, 150.0, 180.0, 300.0}) {
      const ContextVerdict v = filter.check(at(e.entity.id), t, target());
      EXPECT_FALSE(v.accepted) << e.entity.id << " at t=" << t << ": " << v.reason;
    }
  }
  EXPECT_EQ(confusers, 4);
}

TEST_F(ContextFilterTest, RelationsThatCannotBeCheckedAreSkipped) {
  scenario::Mission m = *mission_;
  // Without the map nothing can be checked: the region gate alone decides.
  {
    const ContextFilter no_map(m, nullptr);
    const ContextVerdict v = no_map.check(at("car_722"), 100.0, target());
    EXPECT_TRUE(v.accepted);
    EXPECT_EQ(v.relations_checked, 0);
    EXPECT_EQ(v.relations_skipped, 6);
  }
  // A relation to a scenario entity (not on the map), an EVENTUALLY_ relation and a convoy group.
  scenario::SceneRelation ped;
  ped.related_id = "pedestrian_3";
  ped.related_class = "pedestrian";
  ped.op = scenario::RelationOp::kNextTo;
  ped.target_id = "car_706";
  scenario::SceneRelation later = ped;
  later.related_id = "tree_638";
  later.related_class = "tree";
  later.eventually = true;
  later.distance = 40.0;
  scenario::SceneRelation convoy = ped;
  convoy.related_id = "convoy_1";
  convoy.related_class = "group";
  convoy.op = scenario::RelationOp::kPartOf;
  m.relations = {ped, later, convoy};
  const ContextFilter filter(m, world_);
  const ContextVerdict v = filter.check(at("car_706"), 100.0, target());
  EXPECT_TRUE(v.accepted) << v.reason;
  EXPECT_EQ(v.relations_skipped, 3);
  // A moving target's relations (route search) describe t = 0 only: skipped.
  scenario::Mission route = *mission_;
  route.cls = scenario::ScenarioClass::kRouteSearch;
  const ContextVerdict r = ContextFilter(route, world_).check(at("car_722"), 100.0, target());
  EXPECT_TRUE(r.accepted) << r.reason;
  EXPECT_EQ(r.relations_checked, 0);
}

TEST_F(ContextFilterTest, DirectionalRelationsUseTheBearingEvidence) {
  // tree_638 is on the target's right (bearing 279.8): a RIGHT_OF relation holds for the target
  // with either heading (ambiguous), a LEFT_OF at the same place holds only ambiguously and fails
  // once the heading is known.
  scenario::Mission m = *mission_;
  scenario::SceneRelation right;
  for (const auto& r : m.relations) {
    if (r.op == scenario::RelationOp::kOrthogonalTo) right = r;
  }
  right.op = scenario::RelationOp::kRightOf;
  scenario::SceneRelation left = right;
  left.op = scenario::RelationOp::kLeftOf;
  left.bearing_deg = geometry::wrapDeg360(right.bearing_deg + 180.0);
  m.relations = {right};
  CandidatePose known = at("car_706");
  known.yaw -= geometry::kPi;  // the true heading
  known.yaw_ambiguous = false;
  EXPECT_TRUE(ContextFilter(m, world_).check(known, 100.0, target()).accepted);
  m.relations = {left};
  EXPECT_FALSE(ContextFilter(m, world_).check(known, 100.0, target()).accepted);
  known.yaw_ambiguous = true;
  EXPECT_TRUE(ContextFilter(m, world_).check(known, 100.0, target()).accepted);
  ContextSettings bad;
  bad.bearing_tolerance_deg = 200;
  EXPECT_THROW(ContextFilter(m, world_, bad), scenario::ConfigError);
}

TEST(ClaimLedger, OneClaimPerPlaceUntilTheHoldExpires) {
  ClaimLedger ledger(4.0, 30.0);
  EXPECT_TRUE(ledger.claim(Vec3(0, 0, 0), 10.0));
  EXPECT_FALSE(ledger.claim(Vec3(3, 0, 0), 12.0));
  EXPECT_TRUE(ledger.isRepeat(Vec3(0, 3.9, 0), 39.0));
  EXPECT_TRUE(ledger.claim(Vec3(5, 0, 0), 12.0));  // another place
  EXPECT_TRUE(ledger.claim(Vec3(0, 0, 0), 40.0));  // the hold has expired
  EXPECT_EQ(ledger.locations(), 2u);
  ClaimLedger forever(4.0, 0.0);
  EXPECT_TRUE(forever.claim(Vec3(0, 0, 0), 0.0));
  EXPECT_FALSE(forever.claim(Vec3(0, 0, 0), 1e6));
  EXPECT_THROW(ClaimLedger(-1.0, 1.0), scenario::ConfigError);
}

// The pursuit of the failed pursuit mission (a look-alike claimed, lost 2 s later, the UAV then at
// its prediction): given up once the UAV has been lost within reach of the prediction for more
// than 10 s, not before; never while the find is confirmed (the ADK's target state), nor while
// the UAV is still on its way, nor when the target was reacquired in between.
TEST(FalseLeads, ALostUnconfirmedPursuitAtItsPredictionIsGivenUpAfterTheWait) {
  const Vec2 lead(175.7, -168.2), here(175.3, -184.2);  // 16 m off: within reach
  FalseLeads leads(20.0, 10.0, 8.0);
  EXPECT_FALSE(leads.giveUp(30.0, true, false, Vec2(108.8, -356.4), lead));  // on its way
  double given_up_at = -1;
  for (int k = 0; k <= 200 && given_up_at < 0; ++k) {
    const double t = 40.0 + 0.1 * k;
    if (leads.giveUp(t, true, false, here, lead)) given_up_at = t;
  }
  EXPECT_GT(given_up_at, 50.0 - 1e-9);  // the first tick more than 10 s after arrival
  EXPECT_LT(given_up_at, 50.1 + 1e-9);
  leads.setAside(lead);
  EXPECT_EQ(leads.size(), 1u);
  EXPECT_TRUE(leads.near(Vec2(175.7, -161.0)));   // the look-alike, 7.2 m on
  EXPECT_FALSE(leads.near(Vec2(175.7, -159.0)));  // 9.2 m: another vehicle
  // Confirmed (or reacquired, or out of reach) on one tick: the count starts again.
  FalseLeads other(20.0, 10.0, 8.0);
  for (int k = 0; k <= 300; ++k) {
    const double t = 0.1 * k;
    EXPECT_FALSE(other.giveUp(t, true, true, here, lead)) << t;  // the ADK's state holds it
  }
  EXPECT_FALSE(other.giveUp(30.0, true, false, here, lead));
  EXPECT_FALSE(other.giveUp(39.0, true, false, here, lead));
  EXPECT_FALSE(other.giveUp(39.5, false, false, here, lead));  // reacquired
  EXPECT_FALSE(other.giveUp(45.0, true, false, here, lead));
  EXPECT_FALSE(other.giveUp(54.0, true, false, here, lead));
  EXPECT_FALSE(other.giveUp(55.0, true, false, Vec2(175.3, -230.0), lead));  // 62 m off
  EXPECT_FALSE(other.giveUp(56.0, true, false, here, lead));
  other.restart();  // a new pursuit
  EXPECT_FALSE(other.giveUp(65.0, true, false, here, lead));
  EXPECT_TRUE(other.giveUp(75.5, true, false, here, lead));
  other.clear();
  EXPECT_FALSE(other.near(lead));
  // maneuver_only: a find is confirmed within 3 s of the claim, or never. The second look-alike
  // of that mission, held in view (not lost) and unconfirmed: given up just past the wait; a
  // confirmed pursuit never is.
  FalseLeads held(20.0, 10.0, 8.0);
  const Vec2 parked(291.7, -125.9), above(291.2, -133.9);
  EXPECT_FALSE(held.giveUp(59.0, false, false, above, parked, 56.4 + 3.0));
  EXPECT_FALSE(held.giveUp(59.4, false, false, above, parked, 56.4 + 3.0));
  EXPECT_TRUE(held.giveUp(59.5, false, false, above, parked, 56.4 + 3.0));
  EXPECT_FALSE(held.giveUp(59.5, false, true, above, parked, 56.4 + 3.0));
  EXPECT_FALSE(held.giveUp(300.0, true, true, above, parked, 56.4 + 3.0));
  EXPECT_THROW(FalseLeads(0.0, 10.0, 8.0), scenario::ConfigError);
  EXPECT_THROW(FalseLeads(20.0, std::nan(""), 8.0), scenario::ConfigError);
}

// A look-alike parked beside the road stands from 3 s after its first sighting on; a car of the
// same description driving past it at 10 m/s, 5 m away, never does. The negative control: the
// driving car stopping at a light stands once it has waited 3 s, and no longer once it drives on.
TEST(StandingSightings, AParkedLookAlikeStandsADrivingCarDoesNot) {
  StandingSightings s(1.0, 3.0, 60.0);
  int parked_standing = 0, driving_standing = 0;
  for (int k = 0; k <= 100; ++k) {  // 10 s at 10 Hz
    const double t = 0.1 * k;
    parked_standing += s.observe("suv", Vec3(50.0, 5.0, 0.0), t) ? 1 : 0;
    driving_standing += s.observe("suv", Vec3(-40.0 + 10.0 * t, 0.0, 0.0), t) ? 1 : 0;
  }
  EXPECT_EQ(parked_standing, 71);  // every frame from t = 3 s on
  EXPECT_EQ(driving_standing, 0);
  // Another description is not compared with this one's sightings.
  EXPECT_FALSE(s.observe("sedan", Vec3(50.0, 5.0, 0.0), 10.1));
  // A car stopped at a light: standing once it has waited 3 s, no longer once it drives on.
  StandingSightings light(1.0, 3.0, 60.0);
  std::vector<bool> flags;
  for (int k = 0; k <= 80; ++k) {
    const double t = 0.1 * k;
    const double x = t < 2.0 ? 10.0 * t : t < 6.0 ? 20.0 : 20.0 + 10.0 * (t - 6.0);
    flags.push_back(light.observe("suv", Vec3(x, 0.0, 0.0), t));
  }
  EXPECT_FALSE(flags[45]);  // stopped 2.5 s
  EXPECT_TRUE(flags[55]);   // stopped 3.5 s
  EXPECT_FALSE(flags[75]);  // 15 m on
  // Old sightings are forgotten after `keep`.
  StandingSightings brief(1.0, 3.0, 5.0);
  brief.observe("suv", Vec3(0, 0, 0), 0.0);
  EXPECT_FALSE(brief.observe("suv", Vec3(0, 0, 0), 6.0));
  EXPECT_THROW(StandingSightings(-1.0, 3.0, 60.0), scenario::ConfigError);
  EXPECT_THROW(StandingSightings(1.0, 3.0, 2.0), scenario::ConfigError);
}

// A convoy (seed 2's track mission): a red sedan with a yellow pickup 12 m behind it, both
// driving at 10 m/s, and a red sedan look-alike driving alone 190 m away. The sedan of the convoy
// is beside a sighting of the pickup; the look-alike is not, nor the convoy's sedan once the
// pickup was last seen more than the window ago, nor a sedan beside another sedan only.
TEST(ConvoySightings, AConvoysCarIsBesideTheOtherTargetALookAlikeAloneIsNot) {
  ConvoySightings c(80.0, 20.0);
  int convoy = 0, alone = 0;
  for (int k = 0; k <= 100; ++k) {  // 10 s at 10 Hz
    const double t = 0.1 * k;
    const Vec3 sedan(10.0 * t, 0.0, 0.0), pickup(10.0 * t - 12.0, 0.0, 0.0);
    const Vec3 look_alike(-190.0, 10.0 * t, 0.0);
    if (k % 3 == 0) c.observe("pickup", pickup, t);  // the front camera's sightings
    convoy += c.besideAnother("sedan", sedan, t) ? 1 : 0;
    alone += c.besideAnother("sedan", look_alike, t) ? 1 : 0;
    c.observe("sedan", sedan, t);
    c.observe("sedan", look_alike, t);
  }
  EXPECT_EQ(convoy, 101);
  EXPECT_EQ(alone, 0);
  // The pickup last sighted at 9.9 s: 20 s later it no longer vouches for the sedan.
  EXPECT_TRUE(c.besideAnother("sedan", Vec3(100.0, 0.0, 0.0), 29.9));
  EXPECT_FALSE(c.besideAnother("sedan", Vec3(100.0, 0.0, 0.0), 30.0));
  // The pickup is beside the sedans' sightings in turn.
  EXPECT_TRUE(c.besideAnother("pickup", Vec3(88.0, 0.0, 0.0), 10.0));
  c.clear();
  EXPECT_FALSE(c.besideAnother("pickup", Vec3(88.0, 0.0, 0.0), 10.0));
  EXPECT_THROW(ConvoySightings(-1.0, 20.0), scenario::ConfigError);
  EXPECT_THROW(ConvoySightings(80.0, 0.0), scenario::ConfigError);
}

TEST(PublicSimConfig, HoldsTheMapAndTheUavButNoEntityOrGroundTruthPath) {
  const scenario::SimConfig pub = loadPublicSimConfig(kSimConfig);
  const scenario::SimConfig full = scenario::loadSimConfig(kSimConfig);
  EXPECT_TRUE(pub.entities.empty());
  EXPECT_TRUE(pub.groups.empty());
  EXPECT_FALSE(pub.uav.perception_path.has_value());
  ASSERT_FALSE(full.entities.empty());
  EXPECT_EQ(pub.world_fingerprint, full.world_fingerprint);
  EXPECT_EQ(pub.uav.cameras.size(), full.uav.cameras.size());
  EXPECT_EQ(pub.uav.altitude_max, full.uav.altitude_max);
  EXPECT_THROW(loadPublicSimConfig("no/such/sim_config.json"), scenario::ConfigError);
  EXPECT_THROW(loadPublicSimConfig(kMission), scenario::ConfigError);
}

}  // namespace
}  // namespace hameritt::clients
