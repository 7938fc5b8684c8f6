// The city's signalised traffic and crowd, judged on generated scenarios from the written
// trajectories and signal plan alone: cars never overlap and keep the model's standstill gap,
// no car enters an intersection box on red, pedestrians at the crosswalks are on the crossed
// carriageway only while its traffic is red, the densities are met and the jaywalking share is
// the configured probability. Every checker runs on a deliberately broken input first (the
// negative controls) to show it can fail.

#include "hameritt/scenario/city_traffic.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "../sanitized.h"
#include "hameritt/generation/batch.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/trajectory.h"
#include "hameritt/scenario/validation.h"
#include "test_util.h"

namespace hameritt::scenario {
namespace {

using geometry::OrientedBox;
using geometry::Vec2;
using testing::shippedConfig;

const World& cityWorld() { return testing::shippedCityWorld(); }

GeneratorConfig quickConfig() {
  GeneratorConfig c = shippedConfig();
  c.perception_paths = false;
  return c;
}

// A generated city scenario whose sim config is read back from its written sim_config.json, so
// that every check below judges what the file holds (rounding and all).
const Scenario& cityScenario() {
  static const Scenario s = [] {
    Scenario g = generateScenario(cityWorld(), quickConfig(), ScenarioClass::kAreaSearch, 7);
    g.sim = parseSimConfig(simConfigJson(g.sim), "sim_config.json");
    return g;
  }();
  return s;
}

std::vector<const ScenarioEntity*> withRole(const Scenario& s, const std::string& role) {
  std::vector<const ScenarioEntity*> out;
  for (const auto& se : s.sim.entities) {
    if (se.role == role) out.push_back(&se);
  }
  return out;
}

OrientedBox boxAt(const ScenarioEntity& se, double t) {
  if (se.trajectory.empty()) return se.entity.box;
  return poseBox(se.entity.box, sampleTrajectory(se.trajectory, t));
}

bool insideTile(const World& w, const Vec2& p) { return w.bounds().contains(p); }

Vec2 unitOf(double a) { return {std::cos(a), std::sin(a)}; }

struct OverlapReport {
  int overlaps = 0;
  int close_pairs = 0;   // same-lane pairs checked for the gap
  double min_gap = 1e9;  // smallest bumper gap of a same-lane pair
};

// Overlaps of the cars' footprints, sampled every `dt`, and the smallest gap between cars of
// one lane that follow each other (same heading, less than a metre apart across it).
OverlapReport checkCars(const std::vector<ScenarioEntity>& cars, double duration, double dt) {
  OverlapReport r;
  std::vector<OrientedBox> boxes(cars.size());
  for (double t = 0.0; t <= duration; t += dt) {
    std::map<std::pair<int, int>, std::vector<int>> grid;
    for (std::size_t i = 0; i < cars.size(); ++i) {
      boxes[i] = boxAt(cars[i], t);
      grid[{static_cast<int>(std::floor(boxes[i].center.x() / 10.0)),
            static_cast<int>(std::floor(boxes[i].center.y() / 10.0))}]
          .push_back(static_cast<int>(i));
    }
    for (const auto& [cell, members] : grid) {
      for (int i : members) {
        for (int dx = -1; dx <= 1; ++dx) {
          for (int dy = -1; dy <= 1; ++dy) {
            const auto it = grid.find({cell.first + dx, cell.second + dy});
            if (it == grid.end()) continue;
            for (int j : it->second) {
              if (j <= i) continue;
              const OrientedBox &a = boxes[i], &b = boxes[j];
              if (geometry::footprintsOverlap(a, b)) {
                ++r.overlaps;
                continue;
              }
              // One lane: the same heading, the centres less than a metre apart across it.
              const Vec2 d = b.center2() - a.center2();
              const bool same_lane =
                  std::abs(std::cos(a.yaw) * d.y() - std::sin(a.yaw) * d.x()) < 1.0;
              if (same_lane && std::cos(a.yaw - b.yaw) > 0.95) {
                ++r.close_pairs;
                r.min_gap = std::min(r.min_gap, geometry::footprintDistance(a, b));
              }
            }
          }
        }
      }
    }
  }
  return r;
}

// Where a point stands relative to intersection i for `axis`: along that axis' street from the
// node and across it.
void localCoords(const SignalizedIntersection& i, int axis, const Vec2& p, double* along,
                 double* across) {
  const Vec2 u = unitOf(i.heading[axis]), d = p - i.position;
  *along = d.dot(u);
  *across = u.x() * d.y() - u.y() * d.x();
}

struct EntryReport {
  int entries = 0;
  int turns = 0;   // entries of cars that turn in the box
  int on_red = 0;  // entries against the signal
};

// Whether `front` lies in intersection si's box of `axis` (its carriageway, from the far side of
// the crosswalk before the cross street to that after it).
bool inBox(const SignalizedIntersection& si, const SignalPlan& plan, int axis, const Vec2& front) {
  double along = 0, across = 0;
  localCoords(si, axis, front, &along, &across);
  return std::abs(along) < 0.5 * si.width[1 - axis] + plan.sidewalk &&
         std::abs(across) < 0.5 * si.width[axis];
}

// Entries of a car's front into an intersection box from outside both streets' boxes, running
// along the axis, with the signal shown to the car's axis at that moment. A car whose heading
// has turned by more than 45 degrees when its front leaves the box turns: it may enter on the
// left arrow only (a right turn: on either street's arrow); a car going straight on enters on
// green or yellow. judge_turns = false judges
// every entry as straight on (a negative control).
EntryReport checkEntries(const std::vector<ScenarioEntity>& cars, const SignalPlan& plan,
                         double duration, double dt, bool judge_turns = true) {
  EntryReport r;
  for (const auto& car : cars) {
    const double half = 0.5 * car.entity.box.size.x();
    auto frontAt = [&](double t, double* yaw) -> Vec2 {
      const TrajectoryPoint q = sampleTrajectory(car.trajectory, t);
      *yaw = q.yaw;
      return Vec2(q.x, q.y) + half * unitOf(q.yaw);
    };
    std::vector<char> was_in(plan.intersections.size(), 0);
    for (double t = 0.0; t <= duration; t += dt) {
      double yaw = 0;
      const Vec2 front = frontAt(t, &yaw);
      for (std::size_t k = 0; k < plan.intersections.size(); ++k) {
        const auto& si = plan.intersections[k];
        if ((front - si.position).squaredNorm() > 60.0 * 60.0) {
          was_in[k] = 0;
          continue;
        }
        const bool in0 = inBox(si, plan, 0, front), in1 = inBox(si, plan, 1, front);
        if (!was_in[k]) {
          for (int axis = 0; axis < 2; ++axis) {
            if (!(axis == 0 ? in0 : in1) || std::abs(std::cos(yaw - si.heading[axis])) < 0.9)
              continue;
            // The heading when the front leaves the box again. An entry of a car still moving
            // in the box when the judged span ends is not judged (whether it turns is unknown).
            double yaw_out = yaw;
            bool left = false;
            for (double u = t + dt; u <= duration; u += dt) {
              const Vec2 f = frontAt(u, &yaw_out);
              left = !inBox(si, plan, 0, f) && !inBox(si, plan, 1, f);
              if (left) break;
            }
            if (!left && car.trajectory.back().t >= duration - 1e-6) continue;
            const double turned = geometry::wrapPi(yaw_out - yaw);
            const bool turning = judge_turns && std::abs(turned) > 0.25 * geometry::kPi;
            ++r.entries;
            r.turns += turning;
            const SignalState st = plan.state(si, axis, t);
            const bool arrow = st == SignalState::kLeftArrow;
            const bool cross_arrow = plan.state(si, 1 - axis, t) == SignalState::kLeftArrow;
            if (!turning) {
              r.on_red += st != SignalState::kGreen && st != SignalState::kYellow;
            } else if (turned > 0) {
              r.on_red += !arrow;  // left
            } else {
              r.on_red += !arrow && !cross_arrow;  // right: on either street's arrow
            }
          }
        }
        was_in[k] = in0 || in1;
      }
    }
  }
  return r;
}

// Samples at which a pedestrian crossing at a signal stands on a signalised carriageway next to
// the node while that carriageway's axis is not red.
int crossingsOffRed(const std::vector<const ScenarioEntity*>& peds, const SignalPlan& plan,
                    double duration, double dt, int* checked) {
  int bad = 0;
  for (const auto* p : peds) {
    if (p->entity.attributes.str("activity") != "crossing") continue;
    for (double t = 0.0; t <= duration; t += dt) {
      const TrajectoryPoint q = sampleTrajectory(p->trajectory, t);
      for (const auto& si : plan.intersections) {
        if ((Vec2(q.x, q.y) - si.position).squaredNorm() > 50.0 * 50.0) continue;
        for (int axis = 0; axis < 2; ++axis) {
          double along = 0, across = 0;
          localCoords(si, axis, Vec2(q.x, q.y), &along, &across);
          if (std::abs(across) < 0.5 * si.width[axis] &&
              std::abs(along) < 0.5 * si.width[1 - axis] + plan.sidewalk &&
              std::abs(along) > 0.5 * si.width[1 - axis]) {
            ++*checked;
            if (plan.state(si, axis, t) != SignalState::kRed) ++bad;
          }
        }
      }
    }
  }
  return bad;
}

SignalPlan shiftedHalfACycle(SignalPlan plan) {
  for (auto& i : plan.intersections)
    i.offset = std::fmod(i.offset + 0.5 * plan.cycle(), plan.cycle());
  return plan;
}

std::vector<ScenarioEntity> copies(const std::vector<const ScenarioEntity*>& v) {
  std::vector<ScenarioEntity> out;
  for (const auto* p : v) out.push_back(*p);
  return out;
}

TEST(CityTraffic, SignalPhasesFollowTheCycle) {
  SignalPlan plan;
  SignalizedIntersection i;
  i.offset = 10.0;
  EXPECT_DOUBLE_EQ(plan.cycle(), 56.0);
  EXPECT_EQ(plan.state(i, 0, 10.0), SignalState::kLeftArrow);
  EXPECT_EQ(plan.state(i, 0, 17.0), SignalState::kGreen);
  EXPECT_EQ(plan.state(i, 0, 32.0), SignalState::kYellow);
  EXPECT_EQ(plan.state(i, 0, 36.0), SignalState::kRed);  // all-red
  EXPECT_EQ(plan.state(i, 1, 36.0), SignalState::kRed);
  EXPECT_EQ(plan.state(i, 1, 38.0), SignalState::kLeftArrow);
  EXPECT_EQ(plan.state(i, 1, 45.0), SignalState::kGreen);
  EXPECT_EQ(plan.state(i, 0, 45.0), SignalState::kRed);
  EXPECT_EQ(plan.state(i, 0, 66.0), SignalState::kLeftArrow);  // the next cycle
  EXPECT_EQ(plan.state(i, 0, 9.0), SignalState::kRed);         // before the offset
}

TEST(CityTraffic, CarsNeverOverlapAndKeepTheStandstillGap) {
  const Scenario& s = cityScenario();
  const auto traffic = copies(withRole(s, "traffic"));
  ASSERT_GE(traffic.size(), 100u);
  const IdmParams idm;
  // Negative control: one car three seconds late is run into by the car behind it.
  std::vector<ScenarioEntity> late = traffic;
  for (auto& p : late[0].trajectory) p.t += 3.0;
  late[0].trajectory.insert(late[0].trajectory.begin(), late[0].trajectory.front());
  late[0].trajectory.front().t = 0.0;
  EXPECT_GT(checkCars(late, s.sim.duration, sanitizedCount(1, 4) * 0.05).overlaps, 0);

  // Negative control on a curve: a copy of a turning car 0.4 s behind it, present only over the
  // turn (10 km away otherwise), overlaps it.
  std::vector<ScenarioEntity> turn_copy = traffic;
  bool found_turn = false;
  for (std::size_t i = 0; i < traffic.size() && !found_turn; ++i) {
    const Trajectory& tr = traffic[i].trajectory;
    for (double t = 3.0; t + 8.0 <= s.sim.duration && !found_turn; t += 1.0) {
      const TrajectoryPoint a = sampleTrajectory(tr, t), b = sampleTrajectory(tr, t + 6.0);
      if (!insideTile(cityWorld(), Vec2(a.x, a.y)) ||
          std::abs(geometry::wrapPi(b.yaw - a.yaw)) < 1.2)
        continue;
      ScenarioEntity copy = traffic[i];
      copy.entity.id += "_copy";
      Trajectory ct;
      TrajectoryPoint away = tr.front();
      away.x += 1e4;
      away.t = 0.0;
      ct.push_back(away);
      away.t = t - 2.001;
      ct.push_back(away);
      for (double u = t - 2.0; u <= t + 8.0 + 1e-9; u += 0.05) {
        TrajectoryPoint p = sampleTrajectory(tr, u - 0.4);
        p.t = u;
        ct.push_back(p);
      }
      away.t = t + 8.1;
      ct.push_back(away);
      copy.trajectory = ct;
      turn_copy.push_back(copy);
      found_turn = true;
    }
  }
  ASSERT_TRUE(found_turn);
  // Under a sanitizer every fourth sample (sanitized.h).
  const double dt = sanitizedCount(1, 4) * 0.05;
  EXPECT_GT(checkCars(turn_copy, s.sim.duration, dt).overlaps, 0);

  const OverlapReport r = checkCars(traffic, s.sim.duration, dt);
  EXPECT_EQ(r.overlaps, 0);
  EXPECT_GT(r.close_pairs, 1000 / sanitizedCount(1, 4));
  // The bumper gap of followers: the model's standstill gap, less the written trajectories'
  // interpolation tolerance (positions within 0.1 m of the simulated ones, for each car).
  EXPECT_GE(r.min_gap, idm.min_gap - 0.25);
  std::printf("cars %zu over %.0f s: overlaps %d, same-lane pairs %d, smallest gap %.3f m\n",
              traffic.size(), s.sim.duration, r.overlaps, r.close_pairs, r.min_gap);
}

TEST(CityTraffic, NoCarEntersAnIntersectionOnRed) {
  const Scenario& s = cityScenario();
  ASSERT_TRUE(s.sim.signals.has_value());
  const SignalPlan& plan = *s.sim.signals;
  const auto traffic = copies(withRole(s, "traffic"));
  // Negative control: the same cars judged against the plan shifted by half a cycle.
  const EntryReport wrong = checkEntries(traffic, shiftedHalfACycle(plan), s.sim.duration, 0.05);
  EXPECT_GT(wrong.on_red, wrong.entries / 4);
  const EntryReport r = checkEntries(traffic, plan, s.sim.duration, 0.05);
  EXPECT_GE(plan.intersections.size(), 20u);
  EXPECT_GT(r.entries, 500);
  EXPECT_GT(r.turns, 20);
  EXPECT_EQ(r.on_red, 0);
  // Negative controls of the turns: judged as going straight on, the turning cars enter on the
  // arrow; with the plan moved on by the arrow's length, they enter on green.
  const EntryReport straight = checkEntries(traffic, plan, s.sim.duration, 0.05, false);
  EXPECT_EQ(straight.turns, 0);
  EXPECT_GE(straight.on_red, r.turns);
  SignalPlan early = plan;
  for (auto& i : early.intersections)
    i.offset = std::fmod(i.offset - plan.left + plan.cycle(), plan.cycle());
  const EntryReport off_arrow = checkEntries(traffic, early, s.sim.duration, 0.05);
  EXPECT_EQ(off_arrow.turns, r.turns);
  EXPECT_GE(off_arrow.on_red, r.turns);
  std::printf(
      "intersections %zu, entries %d (turning %d), against the signal %d (shifted plan: %d of "
      "%d; turns judged straight: %d; plan moved on by the arrow: %d)\n",
      plan.intersections.size(), r.entries, r.turns, r.on_red, wrong.on_red, wrong.entries,
      straight.on_red, off_arrow.on_red);
}

// `traj` with every wait after it has set off (two samples at one pose) cut out: the car drives
// on at once. A wait before it sets off (at the kerb, behind the convoy's lead) stays.
Trajectory withoutWaits(const Trajectory& traj) {
  Trajectory out;
  double cut = 0.0;
  for (std::size_t k = 0; k < traj.size(); ++k) {
    if (k > 1 && traj[k].x == traj[k - 1].x && traj[k].y == traj[k - 1].y &&
        traj[k].yaw == traj[k - 1].yaw) {
      cut += traj[k].t - traj[k - 1].t;
      continue;
    }
    TrajectoryPoint q = traj[k];
    q.t -= cut;
    out.push_back(q);
  }
  return out;
}

// The mission's own cars (the targets of route searches, pursuits, follows and tracks, the avoid
// class' hostile vehicle) of city scenarios over many seeds, judged from the written files like
// the ambient cars: none enters an intersection box against its signal. Negative controls: the
// same cars against the plan shifted by half a cycle, and with their waits cut out (driving on
// as before they obeyed the signals); the validator reports both and accepts the generated file.
TEST(CityTraffic, MissionVehiclesObeyTheSignals) {
  const std::string schema = defaultConfigDir() + "/schema";
  constexpr int kSeeds = sanitizedCount(15, 3);
  int scenarios = 0, cars = 0, waiting = 0, validator_shifted = 0;
  EntryReport r, shifted, unwaited;
  for (ScenarioClass cls : {ScenarioClass::kRouteSearch, ScenarioClass::kPursuit,
                            ScenarioClass::kFollow, ScenarioClass::kTrack, ScenarioClass::kAvoid}) {
    for (std::uint64_t seed = 1; seed <= kSeeds; ++seed) {
      SCOPED_TRACE(std::string(toString(cls)) + " seed " + std::to_string(seed));
      Scenario g = generateScenario(cityWorld(), quickConfig(), cls, seed);
      const std::string text = simConfigJson(g.sim);
      g.sim = parseSimConfig(text, "sim_config.json");
      ASSERT_TRUE(g.sim.signals.has_value());
      const SignalPlan& plan = *g.sim.signals;
      std::vector<ScenarioEntity> mission, bare;
      for (const auto& se : g.sim.entities) {
        if (se.entity.cls != EntityClass::kCar || se.role == "traffic" || se.trajectory.empty())
          continue;
        mission.push_back(se);
        bare.push_back(se);
        bare.back().trajectory = withoutWaits(se.trajectory);
        waiting += bare.back().trajectory.size() < se.trajectory.size();
      }
      ++scenarios;
      cars += static_cast<int>(mission.size());
      const double horizon = g.sim.duration + 120.0;  // a retimed car may arrive after the limit
      const EntryReport a = checkEntries(mission, plan, horizon, 0.05);
      EXPECT_EQ(a.on_red, 0);
      r.entries += a.entries;
      r.turns += a.turns;
      r.on_red += a.on_red;
      const EntryReport b = checkEntries(mission, shiftedHalfACycle(plan), horizon, 0.05);
      shifted.entries += b.entries;
      shifted.on_red += b.on_red;
      const EntryReport c = checkEntries(bare, plan, horizon, 0.05);
      unwaited.entries += c.entries;
      unwaited.on_red += c.on_red;
      if (seed <= 5) {
        for (const auto& i :
             validateDocument(nlohmann::json::parse(text), "sim_config.json", schema)) {
          ADD_FAILURE() << formatIssue(i);
        }
        // The validator's negative control: the plan shifted by half a cycle in the file.
        if (a.entries > 0) {
          nlohmann::ordered_json doc = nlohmann::ordered_json::parse(text);
          for (auto& i : doc["signals"]["intersections"])
            i["offset"] = std::fmod(i["offset"].get<double>() + 0.5 * plan.cycle(), plan.cycle());
          for (const auto& i :
               validateDocument(nlohmann::json::parse(doc.dump()), "sim_config.json", schema)) {
            validator_shifted += i.rule == "signal";
          }
        }
      }
    }
  }
  std::printf(
      "%d city scenarios, %d mission cars (%d of them wait on the way), %d entries (turning "
      "%d), against the signal %d; plan shifted by half a cycle: %d of %d; waits cut out: %d of "
      "%d; the validator on the shifted plans: %d\n",
      scenarios, cars, waiting, r.entries, r.turns, r.on_red, shifted.on_red, shifted.entries,
      unwaited.on_red, unwaited.entries, validator_shifted);
  EXPECT_EQ(scenarios, 5 * kSeeds);
  EXPECT_GE(cars, scenarios);
  EXPECT_GT(waiting, cars / 4);
  EXPECT_GT(r.entries, 2 * scenarios);
  EXPECT_GT(r.turns, 0);
  EXPECT_EQ(r.on_red, 0);
  EXPECT_GT(shifted.on_red, shifted.entries / 4);
  EXPECT_GT(unwaited.on_red, unwaited.entries / 5);
  EXPECT_GT(validator_shifted, 0);
}

TEST(CityTraffic, PedestriansCrossOnTheSignalsAndNeverUnderACar) {
  const Scenario& s = cityScenario();
  const SignalPlan& plan = *s.sim.signals;
  const auto peds = withRole(s, "pedestrian");
  int checked_wrong = 0, checked = 0;
  EXPECT_GT(crossingsOffRed(peds, shiftedHalfACycle(plan), s.sim.duration, 0.1, &checked_wrong), 0);
  EXPECT_EQ(crossingsOffRed(peds, plan, s.sim.duration, 0.1, &checked), 0);
  EXPECT_GT(checked, 1000);
  // No traffic car's footprint ever overlaps a pedestrian's.
  const auto cars = withRole(s, "traffic");
  int hits = 0;
  for (double t = 0.0; t <= s.sim.duration; t += 0.2) {
    std::map<std::pair<int, int>, std::vector<OrientedBox>> grid;
    for (const auto* c : cars) {
      const OrientedBox b = boxAt(*c, t);
      grid[{static_cast<int>(std::floor(b.center.x() / 10)),
            static_cast<int>(std::floor(b.center.y() / 10))}]
          .push_back(b);
    }
    for (const auto* p : peds) {
      const OrientedBox b = boxAt(*p, t);
      const int cx = static_cast<int>(std::floor(b.center.x() / 10)),
                cy = static_cast<int>(std::floor(b.center.y() / 10));
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          const auto it = grid.find({cx + dx, cy + dy});
          if (it == grid.end()) continue;
          for (const auto& cb : it->second) hits += geometry::footprintsOverlap(cb, b) ? 1 : 0;
        }
      }
    }
  }
  EXPECT_EQ(hits, 0);
  std::printf("crosswalk samples on a carriageway %d (shifted plan: %d off red)\n", checked,
              checked_wrong);
}

TEST(CityTraffic, DensitiesJaywalkingAndBusQueues) {
  const Scenario& s = cityScenario();
  const World& w = cityWorld();
  const CityParams& cp = w.params().city;
  const auto b = w.bounds();
  const double km2 = (b.max.x() - b.min.x()) * (b.max.y() - b.min.y()) / 1e6;
  const auto cars = withRole(s, "traffic");
  const auto peds = withRole(s, "pedestrian");
  double moving_sum = 0, present_min = 1e9, ped_min = 1e9;
  int samples = 0;
  for (double t = 0.0; t + 1.0 <= s.sim.duration; t += 5.0) {
    int present = 0, moving = 0, ped_in = 0;
    for (const auto* c : cars) {
      const TrajectoryPoint a = sampleTrajectory(c->trajectory, t),
                            z = sampleTrajectory(c->trajectory, t + 1.0);
      if (!insideTile(w, Vec2(a.x, a.y))) continue;
      ++present;
      if (std::hypot(z.x - a.x, z.y - a.y) > 0.5) ++moving;
    }
    for (const auto* p : peds) {
      const TrajectoryPoint a =
          p->trajectory.empty()
              ? TrajectoryPoint{0, p->entity.box.center.x(), p->entity.box.center.y(), 0, 0}
              : sampleTrajectory(p->trajectory, t);
      if (insideTile(w, Vec2(a.x, a.y))) ++ped_in;
    }
    moving_sum += moving;
    present_min = std::min(present_min, static_cast<double>(present));
    ped_min = std::min(ped_min, static_cast<double>(ped_in));
    ++samples;
  }
  const double moving_mean = moving_sum / samples / km2;
  EXPECT_GE(moving_mean, 100.0);
  EXPECT_GE(present_min / km2, 100.0);
  EXPECT_GE(ped_min / km2, 300.0);

  // Jaywalking: the share of street crossings made mid-block, within three standard deviations
  // of the configured probability; every jaywalker crosses at least 15 m from a street node.
  int crossings = 0, jay = 0, queuing = 0, near_node = 0, far_from_stop = 0;
  int jaywalkers_seen = 0, jaywalkers_crossing = 0;
  std::vector<Vec2> stops;
  for (const auto& e : w.entities()) {
    if (e.cls == EntityClass::kBusStop) stops.push_back(e.box.center2());
  }
  for (const auto* p : peds) {
    const std::string act = p->entity.attributes.str("activity");
    if (act == "crossing" || act == "jaywalking") ++crossings;
    if (act == "jaywalking") {
      ++jay;
      // The crossings: keyframe steps across a street, centred on its centreline and square to
      // it. A jaywalker crosses back and forth, each time at least 15 m from a street node.
      const auto& tr = p->trajectory;
      int crossed = 0;
      for (std::size_t k = 0; k + 1 < tr.size(); ++k) {
        const Vec2 a(tr[k].x, tr[k].y), c(tr[k + 1].x, tr[k + 1].y);
        if ((c - a).norm() < 1.0) continue;
        const Vec2 mid = 0.5 * (a + c);
        for (const auto& e : w.edges()) {
          const Vec2 pa = w.nodes()[e.a].position, pb = w.nodes()[e.b].position;
          const Vec2 ue = (pb - pa).normalized();
          const double along = (mid - pa).dot(ue);
          if (along < 0 || along > (pb - pa).norm()) continue;
          if ((mid - pa - along * ue).norm() > 0.05) continue;
          if (std::abs((c - a).normalized().dot(ue)) > 0.1) continue;
          ++crossed;
          for (const auto& n : w.nodes()) near_node += (n.position - mid).norm() < 15.0 ? 1 : 0;
        }
      }
      ++jaywalkers_seen;
      jaywalkers_crossing += crossed > 0 ? 1 : 0;
    }
    if (act == "queuing") {
      ++queuing;
      EXPECT_TRUE(p->trajectory.empty());
      double best = 1e9;
      for (const auto& st : stops) best = std::min(best, (st - p->entity.box.center2()).norm());
      far_from_stop += best > 8.5 ? 1 : 0;
    }
  }
  // The share over the crowds of all the world's episodes: a scenario's crowd is one episode's
  // (about 120 crossers, too few to tell the probability from twice it).
  int all_crossings = 0, all_jay = 0;
  for (int k = 0; k < static_cast<int>(cp.traffic_episodes); ++k) {
    for (const auto& p : cityTrafficEpisode(w, k)->episode.pedestrians) {
      all_crossings += p.activity == "crossing" || p.activity == "jaywalking" ? 1 : 0;
      all_jay += p.activity == "jaywalking" ? 1 : 0;
    }
  }
  const double pj = cp.jaywalk_probability;
  const double sigma = std::sqrt(pj * (1 - pj) / all_crossings);
  const double share = static_cast<double>(all_jay) / all_crossings;
  EXPECT_GT(crossings, 50);
  EXPECT_GT(jay, 0);
  EXPECT_GT(all_crossings, 8 * 50);
  EXPECT_LE(std::abs(share - pj), 3 * sigma);
  // Negative control: the same count judged against a probability twice as high fails.
  EXPECT_GT(std::abs(share - 2 * pj), 3 * std::sqrt(2 * pj * (1 - 2 * pj) / all_crossings));
  EXPECT_EQ(near_node, 0);
  EXPECT_GT(jaywalkers_seen, 0);
  EXPECT_EQ(jaywalkers_crossing, jaywalkers_seen);
  EXPECT_GT(queuing, 0);
  EXPECT_EQ(far_from_stop, 0);
  std::printf(
      "per km^2: moving cars %.1f (mean), cars present %.1f (min), pedestrians %.1f (min); "
      "crossers %d, jaywalking %d (%d crossing in the scenario), queuing %d; over the %d "
      "episodes: crossers %d, jaywalking %d (share %.3f, p %.2f, 3 sigma %.3f)\n",
      moving_mean, present_min / km2, ped_min / km2, crossings, jay, jaywalkers_crossing, queuing,
      static_cast<int>(cp.traffic_episodes), all_crossings, all_jay, share, pj, 3 * sigma);
}

TEST(CityTraffic, DeterministicAndWrittenWithItsSignalPlan) {
  const Scenario& s = cityScenario();
  const Scenario again =
      generateScenario(cityWorld(), quickConfig(), ScenarioClass::kAreaSearch, 7);
  const std::string text = simConfigJson(s.sim);
  EXPECT_EQ(text, simConfigJson(again.sim));
  const SimConfig back = parseSimConfig(text, "sim_config.json");
  ASSERT_TRUE(back.signals.has_value());
  EXPECT_EQ(back.signals->intersections.size(), s.sim.signals->intersections.size());
  EXPECT_EQ(simConfigJson(back), text);
  // A cycle that disagrees with its phases is refused, naming the field.
  std::string bad = text;
  const auto at = bad.find("\"cycle\": ");
  ASSERT_NE(at, std::string::npos);
  bad.replace(at, 10, "\"cycle\": 9");
  EXPECT_NE(
      testing::messageOf([&] { parseSimConfig(bad, "sim_config.json"); }).find("signals.cycle"),
      std::string::npos);
  // The suburb writes no signal plan.
  const Scenario suburb =
      generateScenario(testing::shippedWorld(), quickConfig(), ScenarioClass::kAreaSearch, 7);
  EXPECT_FALSE(suburb.sim.signals.has_value());
  EXPECT_EQ(simConfigJson(suburb.sim).find("\"signals\""), std::string::npos);
}

}  // namespace
}  // namespace hameritt::scenario

namespace hameritt::scenario {
namespace {

void writeText(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr) << path;
  std::fwrite(text.data(), 1, text.size(), f);
  std::fclose(f);
}

// Every regular file under `dir` (relative name -> bytes).
std::map<std::string, std::string> treeOf(const std::string& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) {
      out[std::filesystem::relative(e.path(), dir).string()] = testing::slurp(e.path().string());
    }
  }
  return out;
}

// A batch's scenario (generated to be written by reference) builds none of the episode's cars
// and walking pedestrians, only their ids: it writes the same files as the whole scenario, keeps
// the pedestrians who stand (occluders, members of their block's group), and refuses to be
// written inline.
TEST(CityTrafficEpisode, ALeanScenarioWritesWhatTheWholeOneWrites) {
  const World& world = testing::shippedCityWorld();
  const std::vector<ScenarioClass> classes = {
      ScenarioClass::kAreaSearch, ScenarioClass::kRouteSearch, ScenarioClass::kPursuit,
      ScenarioClass::kAvoid,      ScenarioClass::kFollow,      ScenarioClass::kTrack};
  std::size_t left_out = 0, standing = 0;
  const int seeds = sanitizedCount(12, 6);
  for (int k = 0; k < seeds; ++k) {
    const ScenarioClass cls = classes[static_cast<std::size_t>(k) % classes.size()];
    const std::uint64_t seed = batchSeed(11, static_cast<std::uint64_t>(k));
    const Scenario lean = generateScenario(world, quickConfig(), cls, seed, nullptr, true);
    const Scenario whole = generateScenario(world, quickConfig(), cls, seed, nullptr, false);
    ASSERT_TRUE(lean.sim.traffic && lean.sim.traffic->lean) << seed;
    ASSERT_TRUE(whole.sim.traffic && !whole.sim.traffic->lean) << seed;
    EXPECT_EQ(missionJson(lean.mission), missionJson(whole.mission)) << seed;
    EXPECT_EQ(simConfigJson(lean.sim, true), simConfigJson(whole.sim, true)) << seed;
    // What the lean scenario keeps: the whole one's entities but the walking crowd and the cars.
    std::vector<std::string> kept;
    for (const auto& se : whole.sim.entities) {
      const bool moving_traffic =
          se.role == "traffic" || (se.role == "pedestrian" && !se.trajectory.empty());
      if (!moving_traffic) kept.push_back(se.entity.id);
    }
    std::vector<std::string> ids;
    for (const auto& se : lean.sim.entities) ids.push_back(se.entity.id);
    EXPECT_EQ(ids, kept) << seed;
    left_out += whole.sim.entities.size() - lean.sim.entities.size();
    standing += *lean.sim.traffic->lean;
    EXPECT_EQ(lean.sim.groups.size(), whole.sim.groups.size()) << seed;
    std::string inline_error = "(no error)";
    try {
      simConfigJson(lean.sim);
    } catch (const std::logic_error& e) {
      inline_error = e.what();
    }
    EXPECT_NE(inline_error.find("written by reference written inline"), std::string::npos)
        << inline_error;
  }
  EXPECT_GT(left_out, 400u * static_cast<std::size_t>(seeds));
  EXPECT_GT(standing, 0u);
  std::printf("entities not built: %zu over %d scenarios (standing pedestrians kept: %zu)\n",
              left_out, seeds, standing);
}

// A batch's episode is not parsed back from its file: in memory it is what the file reads back
// to, every number bit for bit (the sign of zero included), so that the scenarios it generates
// are the ones a reader of the file gets.
TEST(CityTrafficEpisode, TheEpisodeInMemoryIsTheOneItsFileReadsBack) {
  const World& world = testing::shippedCityWorld();
  std::size_t numbers = 0, differ = 0;
  std::string first_difference;
  auto same = [&](double a, double b, const std::string& what) {
    ++numbers;
    if (std::memcmp(&a, &b, sizeof(double)) == 0) return;
    if (differ++ == 0) first_difference = what;
  };
  const int episodes = sanitizedCount(3, 1);
  for (int index = 0; index < episodes; ++index) {
    const auto shared = cityTrafficEpisode(world, index);
    ASSERT_TRUE(shared && shared->text);
    const TrafficEpisode& m = shared->episode;
    const TrafficEpisode f = parseTrafficEpisode(*shared->text, trafficEpisodeFileName(index));
    const std::string ep = "episode " + std::to_string(index) + " ";
    EXPECT_EQ(m.index, f.index);
    EXPECT_EQ(m.world_fingerprint, f.world_fingerprint);
    same(m.length, f.length, ep + "length");
    for (auto [a, b] : {std::pair{m.plan.left, f.plan.left}, {m.plan.green, f.plan.green},
                        {m.plan.yellow, f.plan.yellow}, {m.plan.all_red, f.plan.all_red},
                        {m.plan.sidewalk, f.plan.sidewalk}}) {
      same(a, b, ep + "signal timing");
    }
    ASSERT_EQ(m.plan.intersections.size(), f.plan.intersections.size());
    for (std::size_t i = 0; i < m.plan.intersections.size(); ++i) {
      const auto &a = m.plan.intersections[i], &b = f.plan.intersections[i];
      EXPECT_EQ(a.id, b.id);
      const std::string w = ep + "intersection " + a.id;
      same(a.position.x(), b.position.x(), w);
      same(a.position.y(), b.position.y(), w);
      same(a.offset, b.offset, w);
      for (int k = 0; k < 2; ++k) {
        same(a.heading[k], b.heading[k], w);
        same(a.width[k], b.width[k], w);
      }
    }
    ASSERT_EQ(m.lanes.size(), f.lanes.size());
    for (std::size_t i = 0; i < m.lanes.size(); ++i) {
      EXPECT_EQ(m.lanes[i].name, f.lanes[i].name);
      ASSERT_EQ(m.lanes[i].points.size(), f.lanes[i].points.size());
      for (std::size_t k = 0; k < m.lanes[i].points.size(); ++k) {
        same(m.lanes[i].points[k].x(), f.lanes[i].points[k].x(), ep + "lane " + m.lanes[i].name);
        same(m.lanes[i].points[k].y(), f.lanes[i].points[k].y(), ep + "lane " + m.lanes[i].name);
      }
    }
    ASSERT_EQ(m.cars.size(), f.cars.size());
    for (std::size_t i = 0; i < m.cars.size(); ++i) {
      const auto &a = m.cars[i], &b = f.cars[i];
      const std::string w = ep + "car " + std::to_string(i);
      EXPECT_EQ(a.path, b.path) << w;
      EXPECT_EQ(a.vehicle_class + a.make + a.model + a.color,
                b.vehicle_class + b.make + b.model + b.color)
          << w;
      for (int k = 0; k < 3; ++k) same(a.size[k], b.size[k], w + " size");
      ASSERT_EQ(a.knots.size(), b.knots.size()) << w;
      for (std::size_t k = 0; k < a.knots.size(); ++k) same(a.knots[k], b.knots[k], w + " knots");
    }
    ASSERT_EQ(m.pedestrians.size(), f.pedestrians.size());
    for (std::size_t i = 0; i < m.pedestrians.size(); ++i) {
      const auto &a = m.pedestrians[i], &b = f.pedestrians[i];
      const std::string w = ep + "pedestrian " + std::to_string(i);
      EXPECT_EQ(a.activity + a.clothing_color, b.activity + b.clothing_color) << w;
      same(a.height, b.height, w + " height");
      ASSERT_EQ(a.trajectory.size(), b.trajectory.size()) << w;
      std::vector<std::pair<const TrajectoryPoint*, const TrajectoryPoint*>> points = {
          {&a.pose, &b.pose}};
      for (std::size_t k = 0; k < a.trajectory.size(); ++k) {
        points.emplace_back(&a.trajectory[k], &b.trajectory[k]);
      }
      for (const auto& [p, q] : points) {
        for (auto [u, v] : {std::pair{p->t, q->t}, {p->x, q->x}, {p->y, q->y}, {p->z, q->z},
                            {p->yaw, q->yaw}}) {
          same(u, v, w + " pose or keyframe");
        }
      }
    }
  }
  EXPECT_EQ(differ, 0u) << "first: " << first_difference;
  EXPECT_GT(numbers, 100000u);
  std::printf("numbers compared: %zu over %d episodes, %zu differ\n", numbers, episodes, differ);
}

TEST(CityTrafficEpisode, Sha256KnownAnswers) {
  // FIPS 180-4 examples; the outside judge (test_city_traffic.py) also checks written files
  // with Python's hashlib.
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256Hex(std::string(1000, 'a')),
            "41edece42d63e8d9bf515a9ba6932e1c20cbc9f5a5d134645adb5db1b9737ea3");
  EXPECT_NE(sha256Hex("abd"), sha256Hex("abc"));
}

// A batch writes each used episode once beside world.json and a reference in every
// sim_config.json; the reader resolves it into exactly the scenario the generator built (the
// same bytes as the self-contained file), the same whatever the thread count. The reader
// refuses a changed episode file, a missing one, a window beyond the episode and a wrong count
// of car ids, naming the field.
TEST(CityTrafficEpisode, BatchReferencesReadBackAsTheGeneratedScenario) {
  const std::string dir = testing::freshTempDir("episode_batch");
  BatchRequest req;
  req.classes = parseClassList("area_search,route_search,pursuit");
  req.count = 4;
  req.seed = 5;
  req.share_traffic = true;
  req.jobs = 1;
  req.out_dir = dir + "/j1";
  const std::vector<ManifestEntry> entries = generateBatch(cityWorld(), quickConfig(), req);
  req.jobs = 2;
  req.out_dir = dir + "/j2";
  generateBatch(cityWorld(), quickConfig(), req);
  const auto tree1 = treeOf(dir + "/j1");
  EXPECT_TRUE(tree1 == treeOf(dir + "/j2")) << "--jobs 1 and 2 differ";
  int episode_files = 0;
  for (const auto& [name, bytes] : tree1) {
    if (name.rfind("traffic_episode_", 0) == 0) ++episode_files;
  }
  EXPECT_GE(episode_files, 1);
  EXPECT_LE(episode_files, 4);

  std::string first_path, first_text;
  for (const auto& e : entries) {
    const std::string path = dir + "/j1/" + e.id + "/sim_config.json";
    const std::string text = testing::slurp(path);
    ASSERT_NE(text.find("\"traffic\""), std::string::npos) << path;
    const SimConfig back = loadSimConfig(path);
    ASSERT_TRUE(back.traffic.has_value());
    EXPECT_GE(back.traffic->car_ids.size(), 100u);
    EXPECT_GE(back.traffic->pedestrian_ids.size(), 300u);
    // The crowd is not inline: only the mission's own entities are listed.
    EXPECT_EQ(text.find("jaywalking"), std::string::npos) << path;
    const Scenario again = generateScenario(cityWorld(), quickConfig(), e.cls, e.seed);
    EXPECT_EQ(simConfigJson(back), simConfigJson(again.sim)) << path;
    EXPECT_EQ(simConfigJson(again.sim, true), text);
    if (first_path.empty()) {
      first_path = path;
      first_text = text;
    }
  }
  auto failure = [&](const std::string& text) {
    writeText(first_path, text);
    return testing::messageOf([&] { loadSimConfig(first_path); });
  };
  nlohmann::json j = nlohmann::json::parse(first_text);
  const std::string episode =
      (std::filesystem::path(first_path).parent_path() / j["traffic"]["file"].get<std::string>())
          .string();
  const std::string episode_bytes = testing::slurp(episode);
  ASSERT_FALSE(episode_bytes.empty()) << episode;
  // A changed byte in the episode file.
  std::string changed = episode_bytes;
  changed[changed.size() / 2] = changed[changed.size() / 2] == '1' ? '2' : '1';
  writeText(episode, changed);
  const std::string sha_message = failure(first_text);
  EXPECT_NE(sha_message.find("traffic.sha256: expected the SHA-256"), std::string::npos)
      << sha_message;
  writeText(episode, episode_bytes);
  EXPECT_EQ(failure(first_text), "(no error)");  // restored: read again
  // A missing file, a window past the episode's end, one car id short.
  nlohmann::json k = j;
  k["traffic"]["file"] = "../no_such_episode.json";
  EXPECT_NE(failure(k.dump()).find("traffic.file"), std::string::npos);
  k = j;
  k["traffic"]["offset"] = kTrafficEpisodeLength - j["duration"].get<double>() + 1.0;
  EXPECT_NE(failure(k.dump()).find("traffic.offset: expected the window"), std::string::npos);
  k = j;
  k["traffic"]["cars"].erase(k["traffic"]["cars"].size() - 1);
  EXPECT_NE(failure(k.dump()).find("traffic.cars: expected"), std::string::npos);
  k = j;
  ASSERT_GE(k["traffic"]["pedestrians"].size(), 300u);
  k["traffic"]["pedestrians"].erase(k["traffic"]["pedestrians"].size() - 1);
  EXPECT_NE(failure(k.dump()).find("traffic.pedestrians: expected"), std::string::npos);
  // A withheld car leaves the scenario for every reader of the file; an id that is not one of
  // the episode's cars, or one named twice, is refused naming the field.
  writeText(first_path, first_text);
  const SimConfig all = loadSimConfig(first_path);
  nlohmann::json held = j["traffic"].value("withheld", nlohmann::json::array());
  std::string kept;
  for (const auto& id : j["traffic"]["cars"]) {
    if (std::find(held.begin(), held.end(), id) == held.end()) kept = id.get<std::string>();
  }
  ASSERT_FALSE(kept.empty());
  k = j;
  k["traffic"]["withheld"] = held;
  k["traffic"]["withheld"].push_back(kept);
  writeText(first_path, k.dump());
  const SimConfig fewer = loadSimConfig(first_path);
  EXPECT_EQ(fewer.entities.size() + 1, all.entities.size());
  EXPECT_EQ(fewer.traffic->entityCount() + 1, all.traffic->entityCount());
  for (const auto& se : fewer.entities) EXPECT_NE(se.entity.id, kept);
  k["traffic"]["withheld"].push_back("car_999999");
  const std::string unknown = failure(k.dump());
  EXPECT_NE(unknown.find("traffic.withheld[" + std::to_string(held.size() + 1) +
                         "]: expected one of traffic.cars, got \"car_999999\""),
            std::string::npos)
      << unknown;
  k["traffic"]["withheld"].back() = kept;
  EXPECT_NE(failure(k.dump()).find("duplicate id"), std::string::npos);
  // A signal plan not shifted with the offset.
  k = j;
  const double t0 = j["traffic"]["offset"].get<double>();
  k["traffic"]["offset"] = t0 >= 1.0 ? t0 - 1.0 : t0 + 1.0;
  EXPECT_NE(failure(k.dump()).find("signals: expected the signal plan"), std::string::npos);
  writeText(first_path, first_text);
}

TEST(CityTrafficEpisode, EpisodeCountIsRangeChecked) {
  WorldParams p = cityWorld().params();
  for (double bad : {0.0, 65.0, 2.5}) {
    p.city.traffic_episodes = bad;
    EXPECT_NE(testing::messageOf([&] { p.city.validate(); }).find("world.city.traffic_episodes"),
              std::string::npos)
        << bad;
  }
  p.city.traffic_episodes = 64;
  EXPECT_EQ(testing::messageOf([&] { p.city.validate(); }), "(no error)");
}

}  // namespace
}  // namespace hameritt::scenario
