#pragma once
// The avoid baseline's pilot: flies an avoid mission's goal along the shortest flight clear of
// the static obstacles (by 2.5 m where it can, else the generator's 1 m) and the static
// keep-out zones (scenario::shortestFlight, the generator's own planner), slowing to 3 m/s for
// its corners, and deconflicts from the other aircraft and the moving keep-out zones by
// choosing, every tick, how fast to go along that path (full, slower, wait, back off) and how
// far above or below it to fly. The choice predicts every reported aircraft at constant
// velocity and every moving zone along its published motion over a horizon, and takes the
// fastest candidate that keeps a buffer larger than the mission's separation minimum at every
// predicted instant (ties: the smaller offset, then the one nearest the current one); when
// none does, the one whose first conflict comes latest. The aircraft are known only from
// traffic reports (the ADK's ADS-B-like topic), never from ground truth. ROS-free and
// deterministic.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/geometry/types.h"
#include "hameritt/planning/validity.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::clients {

struct AvoidSettings {
  double horizon = 10.0;           // s: how far ahead aircraft and zones are predicted
  double step = 0.25;              // s between predicted instants
  double horizontal_buffer = 9.0;  // m: aimed-at horizontal separation (the minimum is 5)
  double vertical_buffer = 6.0;    // m: aimed-at vertical separation (the minimum is 3)
  double speed_fraction = 0.6;     // cruise speed as a fraction of the UAV's top speed
  double climb_rate = 2.5;         // m/s at which the vertical offset changes
  double koz_margin = 4.0;         // m around a moving zone
  double lead = 1.0;               // s: the setpoint leads the reference by this
  double max_lag = 6.0;            // m: the reference waits while the UAV lags more than this
  double stale_after = 3.0;        // s: a traffic report older than this is dropped
  // Throws scenario::ConfigError naming "avoid.<field>" for a value out of range.
  void validate() const;
};

// One traffic report: where an aircraft was at t and how fast it flew.
struct TrafficReport {
  std::string id;
  double t = 0.0;
  geometry::Vec3 position{0, 0, 0};
  geometry::Vec3 velocity{0, 0, 0};
};

struct AvoidCommand {
  geometry::Vec3 setpoint{0, 0, 0};
  double yaw = 0.0;
  double speed = 0.0;     // m/s along the path chosen (negative: backing off)
  double offset = 0.0;    // m above (+) or below (-) the path
  bool conflict = false;  // no candidate kept the buffer over the horizon
  bool at_goal = false;   // the reference has reached the goal
  std::string reason;     // what decided the choice, for logs
};

class AvoidPilot {
 public:
  // Throws scenario::ConfigError when the mission has no avoid phase or the settings are bad.
  AvoidPilot(const scenario::World& world, const scenario::Mission& mission,
             const scenario::UavSpec& uav, const AvoidSettings& settings = {});

  // Plans the path from `start` (the UAV on the ground or in the air) to the goal. False (with
  // why()) when no flight exists. `freeze_at`: the moving zones count as static ones where
  // they are at that time (step() replans so after a stall).
  bool plan(const geometry::Vec3& start, std::optional<double> freeze_at = std::nullopt);
  int replans() const { return replans_; }
  bool planned() const { return !path_.empty(); }
  const std::string& why() const { return why_; }
  const std::vector<geometry::Vec3>& path() const { return path_; }
  double pathLength() const { return cumulative_.empty() ? 0.0 : cumulative_.back(); }

  // A traffic report; an older report of the same aircraft than the one held is ignored.
  void observe(const TrafficReport& report);
  std::size_t tracked() const { return traffic_.size(); }

  // The command at mission time t for the UAV at `uav` (plan() first).
  AvoidCommand step(double t, const geometry::Vec3& uav);

  // The point of the path at arc length s (clamped), with the vertical offset applied where
  // the path is in the flight band.
  geometry::Vec3 pointAt(double s, double offset = 0.0) const;

 private:
  struct Candidate {
    double speed = 0.0;
    double offset = 0.0;
    double first_conflict = 0.0;  // s; the horizon when none
    double closest = 0.0;         // smallest normalised separation over the horizon
    bool valid = true;            // the offset path is clear of the static obstacles
  };
  Candidate evaluate(double t, double speed, double offset) const;
  // Normalised separation of p at time t from the traffic and the moving zones: >= 1 keeps the
  // buffer (max of horizontal/buffer and vertical/buffer per aircraft, min over aircraft).
  double separation(const geometry::Vec3& p, double t) const;
  double project(const geometry::Vec3& p, double from) const;

  const scenario::World& world_;
  scenario::AvoidPhaseSpec spec_;
  scenario::UavSpec uav_;
  AvoidSettings settings_;
  std::vector<scenario::KeepOutZone> static_kozs_, moving_kozs_;
  planning::WorldValidity band_, tight_;
  std::vector<geometry::Vec3> path_;
  std::vector<double> corners_;  // arc lengths of the path's corners
  std::vector<double> cumulative_;
  std::string why_;
  std::map<std::string, TrafficReport> traffic_;
  double s_ = 0.0;       // the reference's arc length
  double offset_ = 0.0;  // the current vertical offset command
  double last_t_ = 0.0;
  std::optional<double> stalled_since_;
  int replans_ = 0;
  bool started_ = false;
};

}  // namespace hameritt::clients
