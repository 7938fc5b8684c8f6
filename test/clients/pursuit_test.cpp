// Standoff pursuit: the street-graph prediction (along the street, round corners, held after
// the horizon) and the viewpoint choice (the preferred standoff when it sees the vehicle, a
// candidate with a clear line of sight when a tree or house hides it, never inside an active
// keep-out zone), on the shipped scenario's world.
#include "hameritt/clients/pursuit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hameritt/clients/public_config.h"
#include "hameritt/geometry/segment.h"
#include "hameritt/planning/look_at.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/sim_config_io.h"
#include "../scenario/test_util.h"

namespace hameritt::clients {
namespace {

using geometry::Vec2;
using geometry::Vec3;

const char* kSimConfig = "scenarios/default/sim_config.json";

const scenario::SimConfig& sim() {
  static const scenario::SimConfig s = loadPublicSimConfig(kSimConfig);
  return s;
}

const scenario::World& world() {
  static const scenario::World w = scenario::generateCheckedWorld(sim(), kSimConfig);
  return w;
}

// Distance from p to the nearest street centreline.
double streetDistance(const Vec2& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& e : world().edges()) {
    best = std::min(best, geometry::pointSegmentDistance(p, world().nodes()[e.a].position,
                                                         world().nodes()[e.b].position));
  }
  return best;
}

// A node with exactly two streets that meet at a right angle (a corner of the outer ring), the
// edge that arrives at it and the one that leaves it.
struct Corner {
  int node = -1, from = -1, to = -1;
};

Corner findCorner() {
  const auto& w = world();
  for (std::size_t n = 0; n < w.nodes().size(); ++n) {
    const auto& adj = w.adjacency()[n];
    if (adj.size() != 2) continue;
    auto other = [&](int ei) {
      const auto& e = w.edges()[static_cast<std::size_t>(ei)];
      return e.a == static_cast<int>(n) ? e.b : e.a;
    };
    const Vec2 c = w.nodes()[n].position;
    const Vec2 d0 = (w.nodes()[static_cast<std::size_t>(other(adj[0]))].position - c).normalized();
    const Vec2 d1 = (w.nodes()[static_cast<std::size_t>(other(adj[1]))].position - c).normalized();
    if (std::abs(d0.dot(d1)) < 0.2) return {static_cast<int>(n), other(adj[0]), other(adj[1])};
  }
  return {};
}

TEST(Pursuit, SettingsNameTheBadField) {
  PursuitSettings s;
  EXPECT_NO_THROW(s.validate());
  s.standoff = -1.0;
  try {
    s.validate();
    FAIL() << "a negative standoff was accepted";
  } catch (const scenario::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("pursuit.standoff"), std::string::npos) << e.what();
  }
  s = PursuitSettings();
  s.height = std::nan("");
  EXPECT_THROW(s.validate(), scenario::ConfigError);
  s = PursuitSettings();
  s.envelope_radius = -1.0;
  EXPECT_THROW(s.validate(), scenario::ConfigError);
}

TEST(Pursuit, PredictionFollowsTheStreetRoundACorner) {
  const Corner c = findCorner();
  ASSERT_GE(c.node, 0) << "no right-angle corner in the shipped world";
  const auto& w = world();
  const Vec2 corner = w.nodes()[static_cast<std::size_t>(c.node)].position;
  const Vec2 from = w.nodes()[static_cast<std::size_t>(c.from)].position;
  const Vec2 to = w.nodes()[static_cast<std::size_t>(c.to)].position;
  const Vec2 in = (corner - from).normalized(), out = (to - corner).normalized();
  const double yaw = std::atan2(in.y(), in.x());
  PursuitSettings settings;
  settings.predict_horizon = 5.0;
  StreetPredictor predictor(w, settings);
  EXPECT_FALSE(predictor.tracking());
  // 10 m/s on the centreline, 20 m before the corner.
  const Vec2 p0 = corner - in * 30.0, p1 = corner - in * 20.0;
  ASSERT_TRUE(predictor.observe(10.0, Vec3(p0.x(), p0.y(), 0), yaw));
  ASSERT_TRUE(predictor.observe(11.0, Vec3(p1.x(), p1.y(), 0), yaw));
  EXPECT_FALSE(predictor.observe(11.0, Vec3(p1.x(), p1.y(), 0), yaw)) << "a repeated stamp";
  EXPECT_NEAR(predictor.last().speed, 10.0, 1e-9);

  // 1 s later: 10 m further along the same street.
  const VehicleState a = predictor.predict(12.0);
  EXPECT_NEAR((a.position.head<2>() - (corner - in * 10.0)).norm(), 0.0, 1e-6);
  // 3 s later: round the corner, 10 m along the leaving street, heading along it.
  const VehicleState b = predictor.predict(14.0);
  EXPECT_NEAR((b.position.head<2>() - (corner + out * 10.0)).norm(), 0.0, 1e-6);
  EXPECT_NEAR(std::cos(b.yaw - std::atan2(out.y(), out.x())), 1.0, 1e-9);
  EXPECT_LT(streetDistance(b.position.head<2>()), 1e-6);
  // Negative control: a straight constant-velocity extrapolation leaves the street there.
  const Vec2 straight = p1 + in * 30.0;
  EXPECT_GT(streetDistance(straight), 5.0);
  // After the horizon the prediction stops.
  const VehicleState c5 = predictor.predict(11.0 + settings.predict_horizon);
  const VehicleState c100 = predictor.predict(111.0);
  EXPECT_NEAR((c5.position - c100.position).norm(), 0.0, 1e-9);
  // A sighting without a heading takes the heading of its displacement.
  StreetPredictor claims(w, settings);
  ASSERT_TRUE(claims.observe(1.0, Vec3(p0.x(), p0.y(), 0)));
  ASSERT_TRUE(claims.observe(2.0, Vec3(p1.x(), p1.y(), 0)));
  EXPECT_NEAR(claims.last().yaw, yaw, 1e-9);
  EXPECT_NEAR(claims.last().speed, 10.0, 1e-9);
}

TEST(Pursuit, HypothesesTakeEveryBranchOfAnIntersection) {
  const auto& w = world();
  // A four-way intersection whose streets are all longer than 30 m.
  int node = -1;
  for (std::size_t n = 0; n < w.nodes().size() && node < 0; ++n) {
    if (w.adjacency()[n].size() != 4) continue;
    bool long_enough = true;
    for (int ei : w.adjacency()[n]) {
      const auto& e = w.edges()[static_cast<std::size_t>(ei)];
      long_enough &= (w.nodes()[e.a].position - w.nodes()[e.b].position).norm() > 30.0;
    }
    if (long_enough) node = static_cast<int>(n);
  }
  ASSERT_GE(node, 0) << "no four-way intersection in the shipped world";
  const Vec2 c = w.nodes()[static_cast<std::size_t>(node)].position;
  const auto& e = w.edges()[static_cast<std::size_t>(w.adjacency()[node][0])];
  const Vec2 from = w.nodes()[static_cast<std::size_t>(e.a == node ? e.b : e.a)].position;
  const Vec2 in = (c - from).normalized();
  const double yaw = std::atan2(in.y(), in.x());
  StreetPredictor predictor(w, PursuitSettings());
  const Vec2 p0 = c - in * 30.0, p1 = c - in * 20.0;
  ASSERT_TRUE(predictor.observe(0.0, Vec3(p0.x(), p0.y(), 0), yaw));
  ASSERT_TRUE(predictor.observe(1.0, Vec3(p1.x(), p1.y(), 0), yaw));
  // 3 s later, 30 m on: 10 m past the intersection on each of the three streets ahead.
  const std::vector<VehicleState> h = predictor.hypotheses(4.0);
  ASSERT_EQ(h.size(), 3u);
  int ahead = 0;
  for (const auto& v : h) {
    EXPECT_NEAR((v.position.head<2>() - c).norm(), 10.0, 1e-6);
    EXPECT_LT(streetDistance(v.position.head<2>()), 1e-6);
    // None goes back the way it came.
    EXPECT_GT((v.position.head<2>() - c).normalized().dot(in), -0.5);
    ahead += (v.position.head<2>() - c).normalized().dot(in) > 0.95;  // (streets bend a little)
  }
  EXPECT_EQ(ahead, 1);
  // The straight-on one first, and it is the single prediction.
  EXPECT_NEAR((h.front().position - predictor.predict(4.0).position).norm(), 0.0, 1e-9);
  // Held at the intersection, where it has a choice.
  EXPECT_NEAR((predictor.predictToJunction(4.0).position.head<2>() - c).norm(), 0.0, 1e-6);
  // Before it reaches it, the same as the prediction.
  EXPECT_NEAR((predictor.predictToJunction(1.5).position - predictor.predict(1.5).position).norm(),
              0.0, 1e-9);
}

TEST(Pursuit, ViewpointSeesTheVehiclePastOccluders) {
  const auto& w = world();
  PursuitSettings settings;
  const ViewpointChooser chooser(w, sim().uav, {}, settings);
  // Vehicles on every street: along each edge every 10 m, both directions.
  int tested = 0, preferred_used = 0;
  for (const auto& e : w.edges()) {
    const Vec2 a = w.nodes()[static_cast<std::size_t>(e.a)].position;
    const Vec2 b = w.nodes()[static_cast<std::size_t>(e.b)].position;
    const double len = (b - a).norm();
    for (double s = 10.0; s < len - 10.0; s += 10.0) {
      for (int dir = 0; dir < 2; ++dir) {
        const Vec2 u = dir ? Vec2((a - b) / len) : Vec2((b - a) / len);
        const Vec2 p = a + (b - a) * (s / len) + Vec2(u.y(), -u.x()) * 2.0;  // right lane
        VehicleState v;
        v.position = Vec3(p.x(), p.y(), 0.0);
        v.yaw = std::atan2(u.y(), u.x());
        const Vec3 uav = v.position + Vec3(0, 0, 30);
        const PursuitView view = chooser.choose(v, uav, 0.0);
        ++tested;
        const Vec3 centre = v.position + Vec3(0, 0, 0.8);
        ASSERT_TRUE(view.visible) << "no viewpoint sees a vehicle at " << p.transpose();
        // The chooser's claim is checked again here: the named camera sees it.
        const auto cam = chooser.seenBy(view.position, view.yaw, centre);
        ASSERT_TRUE(cam.has_value());
        EXPECT_EQ(*cam, view.camera);
        EXPECT_GE(view.position.z(), sim().uav.altitude_min);
        EXPECT_LE(view.position.z(), sim().uav.altitude_max);
        // The preferred viewpoint: standoff behind, height above.
        const Vec2 behind = p - u * settings.standoff;
        preferred_used += (view.position.head<2>() - behind).norm() < 1e-6;
      }
    }
  }
  std::printf("%d street positions, %d seen from the preferred standoff\n", tested, preferred_used);
  EXPECT_GT(tested, 200);
  EXPECT_GT(preferred_used, tested / 2);
}

// A vehicle driving away from each tall occluder (house, garage, canopy), 2.5 m past its edge.
std::vector<VehicleState> pastTallOccluders() {
  std::vector<VehicleState> out;
  const auto& occ = world().occluders();
  for (std::size_t i = 0; i < occ.size(); ++i) {
    const auto& box = occ.box(static_cast<int>(i));
    if (box.maxZ() < 5.0) continue;
    const Vec2 u(std::cos(box.yaw), std::sin(box.yaw));
    const Vec2 p = box.center2() + u * (0.5 * box.size.x() + 2.5);
    VehicleState v;
    v.position = Vec3(p.x(), p.y(), 0.0);
    v.yaw = std::atan2(u.y(), u.x());
    out.push_back(v);
  }
  return out;
}

TEST(Pursuit, ViewpointMovesOffAnOccludedStandoff) {
  // A vehicle driving away from each tall occluder (house, garage, canopy), 2.5 m past its
  // edge: the preferred viewpoint (8 m behind, 20 m above) often looks through the occluder.
  const auto& w = world();
  PursuitSettings settings;
  const ViewpointChooser chooser(w, sim().uav, {}, settings);
  int hidden = 0, recovered = 0;
  for (const VehicleState& v : pastTallOccluders()) {
    const Vec2 p = v.position.head<2>(), u(std::cos(v.yaw), std::sin(v.yaw));
    const Vec3 centre = v.position + Vec3(0, 0, 0.8);
    const Vec2 behind = p - u * settings.standoff;
    const PursuitView view = chooser.choose(v, v.position + Vec3(0, 0, 30), 0.0);
    const Vec3 pref(behind.x(), behind.y(), view.position.z());
    if (chooser.seenBy(pref, v.yaw, centre)) continue;
    ++hidden;
    if (view.visible && chooser.seenBy(view.position, view.yaw, centre)) ++recovered;
    // Never the hidden preferred viewpoint itself.
    EXPECT_GT((view.position.head<2>() - behind).norm(), 1.0);
  }
  std::printf("%d vehicles hidden from the preferred viewpoint, %d seen from another\n", hidden,
              recovered);
  // The case arises (negative control: the preferred viewpoint alone would not see these) ...
  EXPECT_GT(hidden, 10);
  // ... and the chooser finds a viewpoint that sees nearly every one.
  EXPECT_GE(recovered, hidden * 9 / 10);
}

TEST(Pursuit, ViewpointStaysInsideTheEnvelopeWhenFollowing) {
  // The same hidden vehicles, followed with a 10 m standoff and a 5 m envelope: every viewpoint
  // stays within the envelope's radius of the point 10 m behind, and some of the hidden ones
  // are still seen from inside it. Negative control: without the envelope the chooser leaves it.
  const auto& w = world();
  PursuitSettings free_settings;
  free_settings.standoff = 10.0;
  PursuitSettings follow_settings = free_settings;
  follow_settings.envelope_radius = 5.0;
  follow_settings.envelope_height = 5.0;
  const ViewpointChooser free_chooser(w, sim().uav, {}, free_settings);
  const ViewpointChooser follow_chooser(w, sim().uav, {}, follow_settings);
  int hidden = 0, seen_inside = 0, free_outside = 0;
  for (const VehicleState& v : pastTallOccluders()) {
    const Vec2 p = v.position.head<2>(), u(std::cos(v.yaw), std::sin(v.yaw));
    const Vec3 centre = v.position + Vec3(0, 0, 0.8);
    const Vec2 behind = p - u * follow_settings.standoff;
    const Vec3 uav = v.position + Vec3(0, 0, 30);
    const PursuitView view = follow_chooser.choose(v, uav, 0.0);
    EXPECT_LE((view.position.head<2>() - behind).norm(), 5.0 + 1e-9);
    const Vec3 pref(behind.x(), behind.y(), view.position.z());
    if (follow_chooser.seenBy(pref, v.yaw, centre)) continue;
    ++hidden;
    if (view.visible && follow_chooser.seenBy(view.position, view.yaw, centre)) ++seen_inside;
    const PursuitView loose = free_chooser.choose(v, uav, 0.0);
    free_outside += (loose.position.head<2>() - behind).norm() > 5.0;
  }
  std::printf(
      "%d vehicles hidden from 10 m behind: %d seen from inside the envelope, %d "
      "viewpoints outside it without the envelope\n",
      hidden, seen_inside, free_outside);
  EXPECT_GT(hidden, 10);
  EXPECT_GT(seen_inside, 0);
  EXPECT_GT(free_outside, 0);  // the control: the unconstrained choice leaves the envelope
  // Lost, it climbs at most 0.4 H (2 m) above h*, where the free chooser climbs the 15 m asked.
  VehicleState v;
  v.position = Vec3(world().nodes()[0].position.x(), world().nodes()[0].position.y(), 0.0);
  const Vec3 uav = v.position + Vec3(0, 0, 30);
  const double ground = follow_chooser.choose(v, uav, 0.0).position.z();
  EXPECT_LE(follow_chooser.choose(v, uav, 0.0, 15.0).position.z(), ground + 2.0 + 1e-9);
  EXPECT_GT(free_chooser.choose(v, uav, 0.0, 15.0).position.z(),
            free_chooser.choose(v, uav, 0.0).position.z() + 5.0);
}

TEST(Pursuit, ViewpointStaysOutOfActiveKeepOutZones) {
  const auto& w = world();
  PursuitSettings settings;
  const ViewpointChooser open(w, sim().uav, {}, settings);
  // The first street midpoint whose preferred viewpoint sees the vehicle.
  VehicleState v;
  Vec2 p, u;
  bool found = false;
  for (const auto& e : w.edges()) {
    const Vec2 a = w.nodes()[static_cast<std::size_t>(e.a)].position;
    const Vec2 b = w.nodes()[static_cast<std::size_t>(e.b)].position;
    u = (b - a).normalized();
    p = 0.5 * (a + b);
    v.position = Vec3(p.x(), p.y(), 0.0);
    v.yaw = std::atan2(u.y(), u.x());
    const PursuitView view = open.choose(v, v.position + Vec3(0, 0, 30), 0.0);
    if (view.visible && (view.position.head<2>() - (p - u * settings.standoff)).norm() < 1e-6) {
      found = true;
      break;
    }
  }
  ASSERT_TRUE(found);
  // A zone of 24 x 24 m around the preferred viewpoint, active from t = 100 s.
  scenario::KeepOutZone k;
  k.id = "koz_test";
  const Vec2 c = p - u * settings.standoff;
  k.polygon = geometry::rectangle(c - Vec2(12, 12), c + Vec2(12, 12));
  k.window.net = 100.0;
  const ViewpointChooser chooser(w, sim().uav, {k}, settings);
  const Vec3 uav = v.position + Vec3(0, 0, 30);
  const PursuitView before = chooser.choose(v, uav, 50.0);
  const PursuitView during = chooser.choose(v, uav, 150.0);
  // Before the window the preferred viewpoint (inside the zone's polygon) is taken.
  EXPECT_TRUE(k.polygon.contains(before.position.head<2>()));
  // While it is active the view is outside it, and still sees the vehicle.
  EXPECT_FALSE(k.polygon.contains(during.position.head<2>()));
  EXPECT_TRUE(during.visible);
  // The straight flight from inside the zone's far side crosses it only while it is active.
  const Vec3 far(c.x() - 30 * u.x(), c.y() - 30 * u.y(), 25.0);
  EXPECT_TRUE(chooser.kozClear(far, before.position, 50.0));
  EXPECT_FALSE(chooser.kozClear(far, Vec3(p.x(), p.y(), 25.0), 150.0));
}

TEST(Pursuit, AGivenSpeedIsTakenNotEstimated) {
  // One state with its speed (the ADK's ground truth): the prediction moves at once. Negative
  // control: the same single sighting without a speed has none to estimate and stands still.
  const Corner c = findCorner();
  ASSERT_GE(c.node, 0);
  const auto& w = world();
  const Vec2 corner = w.nodes()[static_cast<std::size_t>(c.node)].position;
  const Vec2 from = w.nodes()[static_cast<std::size_t>(c.from)].position;
  const Vec2 in = (corner - from).normalized();
  const double yaw = std::atan2(in.y(), in.x());
  const Vec2 p = corner - in * 20.0;
  PursuitSettings settings;
  StreetPredictor told(w, settings), guessed(w, settings);
  ASSERT_TRUE(told.observe(5.0, Vec3(p.x(), p.y(), 0), yaw, 8.0));
  ASSERT_TRUE(guessed.observe(5.0, Vec3(p.x(), p.y(), 0), yaw));
  EXPECT_NEAR(told.last().speed, 8.0, 1e-12);
  EXPECT_NEAR((told.predict(6.0).position.head<2>() - (corner - in * 12.0)).norm(), 0.0, 1e-6);
  EXPECT_NEAR(guessed.last().speed, 0.0, 1e-12);
  EXPECT_NEAR((guessed.predict(6.0).position.head<2>() - p).norm(), 0.0, 1e-9);
  // The next state's speed is its own, whatever the displacement says (a stop: 0 m/s).
  const Vec2 q = corner - in * 12.0;
  ASSERT_TRUE(told.observe(6.0, Vec3(q.x(), q.y(), 0), yaw, 0.0));
  EXPECT_NEAR(told.last().speed, 0.0, 1e-12);
  ASSERT_TRUE(guessed.observe(6.0, Vec3(q.x(), q.y(), 0), yaw));
  EXPECT_NEAR(guessed.last().speed, 8.0, 1e-9);
  // A bad speed is no sighting.
  EXPECT_FALSE(told.observe(7.0, Vec3(q.x(), q.y(), 0), yaw, -1.0));
  EXPECT_FALSE(told.observe(7.0, Vec3(q.x(), q.y(), 0), yaw, std::nan("")));
  EXPECT_NEAR(told.last().t, 6.0, 1e-12);
}

TEST(Pursuit, ViewpointsForOneCameraAreSeenByIt) {
  // A track phase scores the down camera: with PursuitSettings::camera "down" (straight above
  // the vehicle), every viewpoint that sees a vehicle on the streets sees it in the down
  // camera. Negative control: views that only the front camera has (30 m behind) count for the
  // unrestricted chooser and not for the restricted one.
  const auto& w = world();
  PursuitSettings any;
  PursuitSettings down;
  down.camera = "down";
  down.standoff = 0.0;
  const ViewpointChooser any_chooser(w, sim().uav, {}, any);
  const ViewpointChooser down_chooser(w, sim().uav, {}, down);
  int tested = 0, any_front = 0, down_seen = 0, down_front = 0;
  for (const auto& e : w.edges()) {
    const Vec2 a = w.nodes()[static_cast<std::size_t>(e.a)].position;
    const Vec2 b = w.nodes()[static_cast<std::size_t>(e.b)].position;
    const double len = (b - a).norm();
    for (double s = 10.0; s < len - 10.0; s += 10.0) {
      const Vec2 u = (b - a) / len;
      const Vec2 p = a + u * s + Vec2(u.y(), -u.x()) * 2.0;
      VehicleState v;
      v.position = Vec3(p.x(), p.y(), 0.0);
      v.yaw = std::atan2(u.y(), u.x());
      const Vec3 centre = v.position + Vec3(0, 0, 0.8);
      const Vec3 uav = v.position + Vec3(0, 0, 30);
      ++tested;
      // From 30 m behind and 20 m above, facing the car, the front camera sees it, the down
      // one cannot: the unrestricted chooser counts that view, the restricted one does not.
      const Vec3 far(p.x() - 30.0 * u.x(), p.y() - 30.0 * u.y(), 20.0);
      if (any_chooser.seenBy(far, v.yaw, centre).value_or("") == "front") {
        ++any_front;
        EXPECT_FALSE(down_chooser.seenBy(far, v.yaw, centre).has_value());
      }
      const PursuitView vd = down_chooser.choose(v, uav, 0.0);
      if (!vd.visible) continue;
      ++down_seen;
      down_front += vd.camera != "down";
      // Checked again with the unrestricted chooser: the down camera does see it from there.
      EXPECT_TRUE(any_chooser.seenBy(vd.position, vd.yaw, centre).has_value());
      EXPECT_EQ(down_chooser.seenBy(vd.position, vd.yaw, centre).value_or(""), "down");
    }
  }
  std::printf("%d street positions: %d seen by the front camera alone from 30 m; down camera %d\n",
              tested, any_front, down_seen);
  EXPECT_GT(tested, 100);
  EXPECT_GT(any_front, 0);
  EXPECT_EQ(down_front, 0);
  EXPECT_GT(down_seen, tested * 9 / 10);
}

// A level down camera sees nothing farther (horizontally) than levelReach: no point beyond it
// projects into the image at any bearing or yaw, while points just inside it, towards the
// image's corners, do (so the bound is tight). The track client's claims use it to tell a
// glimpse during a manoeuvre from a camera that holds the target.
TEST(Pursuit, NothingBeyondALevelCamerasReachIsInItsImage) {
  const scenario::CameraSpec* down = nullptr;
  for (const auto& c : sim().uav.cameras) {
    if (c.name == "down") down = &c;
  }
  ASSERT_NE(down, nullptr);
  int beyond_seen = 0, inside_seen = 0, inside = 0;
  for (double h : {10.0, 20.0, 45.0}) {
    const double reach = levelReach(*down, h);
    EXPECT_GT(reach, h * std::tan(0.5 * down->hfov_deg * geometry::kPi / 180.0));
    const Vec3 uav(5.0, -3.0, h);
    for (int y = 0; y < 12; ++y) {
      const double yaw = y * geometry::kPi / 6.0;
      for (int b = 0; b < 720; ++b) {
        const double bearing = b * geometry::kPi / 360.0;
        const Vec3 dir(std::cos(bearing), std::sin(bearing), 0.0);
        beyond_seen +=
            planning::projectToImage(*down, uav, yaw, Vec3(5.0, -3.0, 0.0) + dir * (1.01 * reach))
                .has_value();
        ++inside;
        inside_seen +=
            planning::projectToImage(*down, uav, yaw, Vec3(5.0, -3.0, 0.0) + dir * (0.97 * reach))
                .has_value();
      }
    }
  }
  EXPECT_EQ(beyond_seen, 0);
  EXPECT_GT(inside_seen, 0);  // towards the corners
  EXPECT_LT(inside_seen, inside / 10);
  EXPECT_EQ(levelReach(*down, -5.0), 0.0);
  std::printf("level reach: %d of %d points beyond it seen, %d of %d at 0.97 of it\n",
              beyond_seen, inside, inside_seen, inside);
}

// The tilt shift is averaged only while the UAV keeps station. Circling a standing car 5 m from
// its station at 6 m/s, tilted 30 degrees into the turn from 42.5 m (the city flight whose
// averaged circling tilt held it circling), the shift stays where it was; so does it while the
// UAV brakes into station at 8 m/s, and 9 m off station. Following a car at 9 m/s with the UAV
// at the car's speed, it converges on the steady tilt's shift (300 ticks, 30 s at 10 Hz).
TEST(Pursuit, TheTiltShiftAveragesOnlyTheTiltOfKeepingStation) {
  const double deg = geometry::kPi / 180.0, h = 42.5;
  TiltAverage circling(0.025, 8.0, 1.5);
  const Vec2 station(0.0, 0.0);
  for (int k = 0; k < 300; ++k) {
    const double a = 0.1 * k * 6.0 / 5.0;  // angular position (rad): 6 m/s on a 5 m circle
    const Vec2 at = 5.0 * Vec2(std::cos(a), std::sin(a));
    const Vec2 velocity = 6.0 * Vec2(-std::sin(a), std::cos(a));
    // Tilted towards the centre: the nadir axis looks outwards, h tan 30 = 24.5 m.
    const Vec2 measured = at.normalized() * h * std::tan(30 * deg);
    circling.update(at, velocity, station, Vec2::Zero(), measured);
  }
  EXPECT_EQ(circling.shift(), Vec2::Zero());
  TiltAverage braking(0.025, 8.0, 1.5);
  braking.update(Vec2(5.0, 0.0), Vec2(-8.0, 0.0), station, Vec2::Zero(), Vec2(-20.0, 0.0));
  EXPECT_EQ(braking.shift(), Vec2::Zero());
  TiltAverage away(0.025, 8.0, 1.5);
  away.update(Vec2(9.0, 0.0), Vec2::Zero(), station, Vec2::Zero(), Vec2(-3.0, 0.0));
  EXPECT_EQ(away.shift(), Vec2::Zero());
  // Following east at 9 m/s, 1 m/s of the UAV's speed off the car's: every tick counts.
  TiltAverage following(0.025, 8.0, 1.5);
  const Vec2 steady(-h * std::tan(15 * deg), 0.0);
  for (int k = 0; k < 300; ++k) {
    const Vec2 car(0.9 * k, 0.0);
    following.update(car + Vec2(2.0, 1.0), Vec2(9.0 + (k % 2 ? 1.0 : -1.0), 0.0), car,
                     Vec2(9.0, 0.0), steady);
  }
  EXPECT_NEAR((following.shift() - steady).norm(), 0.0, 1e-3 * steady.norm());
  following.reset();
  EXPECT_EQ(following.shift(), Vec2::Zero());
}

// A quadrotor tilts into its flight, and its nadir camera looks behind the point below it:
// tiltedAxisShift gives where the axis meets the ground less where it meets it level, by hand:
// pitched 15 degrees nose down heading north from 22.5 m, 22.5 tan 15 = 6.03 m south; rolled 10
// degrees (left side up) heading east, 22.5 tan 10 = 3.97 m north (the left); level, or a
// camera that does not look down 10 degrees (the front camera, level), none.
TEST(Pursuit, ATiltedNadirCameraLooksBehindThePointBelowIt) {
  const scenario::CameraSpec *down = nullptr, *front = nullptr;
  for (const auto& c : sim().uav.cameras) {
    if (c.name == "down") down = &c;
    if (c.name == "front") front = &c;
  }
  ASSERT_TRUE(down && front);
  using Eigen::AngleAxisd;
  const double deg = geometry::kPi / 180.0;
  const Eigen::Quaterniond north_nose_down(AngleAxisd(90 * deg, Vec3::UnitZ()) *
                                           AngleAxisd(15 * deg, Vec3::UnitY()));
  const Vec2 a = tiltedAxisShift(*down, north_nose_down, 22.5);
  EXPECT_NEAR(a.x(), 0.0, 1e-9);
  EXPECT_NEAR(a.y(), -22.5 * std::tan(15 * deg), 1e-9);
  const Eigen::Quaterniond east_rolled(AngleAxisd(10 * deg, Vec3::UnitX()));
  const Vec2 b = tiltedAxisShift(*down, east_rolled, 22.5);
  EXPECT_NEAR(b.x(), 0.0, 1e-9);
  EXPECT_NEAR(b.y(), 22.5 * std::tan(10 * deg), 1e-9);
  const Eigen::Quaterniond level(AngleAxisd(1.3, Vec3::UnitZ()));
  EXPECT_NEAR(tiltedAxisShift(*down, level, 40.0).norm(), 0.0, 1e-9);
  EXPECT_EQ(tiltedAxisShift(*front, level, 40.0), Vec2::Zero());  // looks down 6 degrees
  EXPECT_EQ(tiltedAxisShift(*down, north_nose_down, -1.0), Vec2::Zero());
  // The shift, flown ahead, puts the tilted axis where the level axis from the point meets the
  // ground (a check by the camera's own rays, not the formula).
  const Eigen::Matrix3d mount = (AngleAxisd(down->mount_rpy.z() * deg, Vec3::UnitZ()) *
                                 AngleAxisd(down->mount_rpy.y() * deg, Vec3::UnitY()) *
                                 AngleAxisd(down->mount_rpy.x() * deg, Vec3::UnitX()))
                                    .toRotationMatrix();
  const Vec3 ray = north_nose_down * (mount * Vec3::UnitX());
  const Vec3 from(10.0 - a.x(), 20.0 - a.y(), 22.5);
  const Vec3 hit = from + ray * (from.z() / -ray.z());
  const Vec3 level_ray = AngleAxisd(90 * deg, Vec3::UnitZ()) * (mount * Vec3::UnitX());
  const Vec3 level_hit = Vec3(10.0, 20.0, 22.5) + level_ray * (22.5 / -level_ray.z());
  EXPECT_NEAR(hit.x(), level_hit.x(), 1e-9);
  EXPECT_NEAR(hit.y(), level_hit.y(), 1e-9);
  EXPECT_GT(from.y() - 20.0, 6.0);  // flown 6 m ahead (north) of the point
}

TEST(Pursuit, AGroupViewHoldsEveryVehicleInTheDownCamera) {
  // Two cars 25 m apart on a street line: from the group view's height above their midpoint,
  // yawed across their line, the down camera sees both body centres. Negative controls: yawed
  // along their line (the image's narrow axis), or at the single-vehicle height above the first
  // car, it does not.
  const scenario::CameraSpec* down = nullptr;
  for (const auto& c : sim().uav.cameras) {
    if (c.name == "down") down = &c;
  }
  ASSERT_NE(down, nullptr);
  int tested = 0;
  for (double heading : {0.0, 0.7, 2.0, -2.5}) {
    const Vec2 u(std::cos(heading), std::sin(heading));
    VehicleState lead, second;
    lead.position = Vec3(40.0, -10.0, 0.2);
    lead.yaw = heading;
    second = lead;
    second.position = lead.position - Vec3(u.x(), u.y(), 0.0) * 25.0;
    const GroupView g = groupView({lead, second}, *down, 3.0);
    EXPECT_NEAR((g.centre.position - 0.5 * (lead.position + second.position)).norm(), 0.0, 1e-9);
    const Vec3 uav = g.centre.position + Vec3(0, 0, g.height);
    const Vec3 up(0, 0, 0.8);
    for (const VehicleState* v : {&lead, &second}) {
      EXPECT_TRUE(planning::projectToImage(*down, uav, g.centre.yaw, v->position + up))
          << "heading " << heading;
    }
    const bool along =
        planning::projectToImage(*down, uav, heading, lead.position + up).has_value() &&
        planning::projectToImage(*down, uav, heading, second.position + up).has_value();
    EXPECT_FALSE(along) << "heading " << heading;
    const Vec3 single = lead.position + Vec3(0, 0, PursuitSettings().height);
    EXPECT_FALSE(planning::projectToImage(*down, single, heading, second.position + up));
    ++tested;
  }
  EXPECT_EQ(tested, 4);
  // One vehicle: itself, no extra height.
  VehicleState one;
  one.position = Vec3(1, 2, 0);
  one.yaw = 0.3;
  const GroupView g1 = groupView({one}, *down, 3.0);
  EXPECT_EQ(g1.height, 0.0);
  EXPECT_EQ(g1.centre.yaw, 0.3);
}

// In the city a tower beside the vehicle lifts the viewpoints near it above its roof, and so
// above the altitude band: those are skipped, and the view chosen lies inside the band.
TEST(Pursuit, ViewpointsLiftedAboveTheBandByATowerAreSkipped) {
  const scenario::World& city = scenario::testing::shippedCityWorld();
  scenario::UavSpec uav = sim().uav;
  uav.altitude_min = 21.0;
  uav.altitude_max = 62.0;
  const ViewpointChooser chooser(city, uav, {}, PursuitSettings());
  int towers = 0;
  for (const auto& e : city.entities()) {
    if (e.cls != scenario::EntityClass::kBuilding || e.box.maxZ() < 75.0) continue;
    // The vehicle 3 m out from the middle of the tower's long side, driving along it.
    const double c = std::cos(e.box.yaw), s = std::sin(e.box.yaw);
    const Vec2 side(-s, c);
    const Vec2 p = e.box.center2() + (0.5 * e.box.size.y() + 3.0) * side;
    VehicleState v;
    v.position = Vec3(p.x(), p.y(), 0.0);
    v.yaw = e.box.yaw;
    const PursuitView view = chooser.choose(v, v.position + Vec3(0, 0, 40.0), 0.0);
    EXPECT_LE(view.position.z(), uav.altitude_max - 1.5 + 1e-9) << e.id;
    EXPECT_GE(view.position.z(), uav.altitude_min + 1.5 - 1e-9) << e.id;
    if (++towers == 5) break;
  }
  EXPECT_EQ(towers, 5);
}

}  // namespace
}  // namespace hameritt::clients
