#pragma once
// Standoff pursuit of a ground vehicle after its find: the vehicle's motion predicted at constant
// speed along the street graph from its last sightings, and a viewpoint a standoff behind and
// above it from which a payload camera sees it with a clear line of sight past the world's
// buildings and trees. The baseline maneuver client flies it so that a pursuit target stays in
// view after it drives off. ROS-free.

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "hameritt/geometry/types.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::clients {

struct PursuitSettings {
  double standoff = 8.0;         // m behind the vehicle (against its heading), horizontally
  double height = 20.0;          // m above the vehicle's ground point
  double lead = 1.0;             // s: the viewpoint of where the vehicle will be (the autopilot's
                                 // position loop lags about 1 / 0.95 s behind a moving setpoint)
  double predict_horizon = 8.0;  // s: after the last sighting the prediction moves this long
  double clearance = 4.0;        // m above the tallest occluder near the UAV and the viewpoint
  double margin_px = 20.0;       // the vehicle's centre projects this far inside the image
  double speed_window = 1.0;     // s of sightings that estimate the speed
  // Following an envelope (a follow phase): viewpoints only within envelope_radius
  // (horizontally) of the point `standoff` behind the vehicle and within envelope_height of
  // `height`, the centre when none of them sees the vehicle. 0: any viewpoint that sees it.
  double envelope_radius = 0.0;
  double envelope_height = 0.0;
  // The camera that must see the vehicle (a track phase scores one camera's frames): only its
  // view counts for the viewpoint choice. Empty: any payload camera.
  std::string camera;
  // Throws scenario::ConfigError naming "pursuit.<field>" and the bad value.
  void validate() const;
};

// A vehicle's state as a detector (or the perfect-perception report) gives it.
struct VehicleState {
  double t = 0.0;
  geometry::Vec3 position{0, 0, 0};  // bottom centre, map frame
  double yaw = 0.0;                  // heading
  double speed = 0.0;                // m/s along the heading (estimated)
};

// Constant-speed prediction along the street graph: the vehicle keeps its speed along the
// street it drives on and goes straight on (the smallest turn) at each intersection; it stops
// moving predict_horizon seconds after its last sighting.
class StreetPredictor {
 public:
  StreetPredictor(const scenario::World& world, const PursuitSettings& settings);
  // A sighting; sightings at or before the last one are ignored (false).
  bool observe(double t, const geometry::Vec3& position, double yaw);
  // A sighting with its speed along the heading known (a tracker's or the ADK's ground-truth
  // target state): the speed is taken as given, not estimated from the sightings.
  bool observe(double t, const geometry::Vec3& position, double yaw, double speed);
  // A sighting without a heading (a detection claim): the heading of the displacement from the
  // last sighting when it moved more than 2 m, else the last heading.
  bool observe(double t, const geometry::Vec3& position);
  bool tracking() const { return !recent_.empty(); }
  // The last sighting (with its estimated speed); requires tracking().
  const VehicleState& last() const { return last_; }
  // The predicted state at time t (>= the last sighting).
  VehicleState predict(double t) const;
  // Every way it may have gone by time t: each branch at each intersection (no U-turns), at
  // most 64; the straight-on prediction first.
  std::vector<VehicleState> hypotheses(double t) const;
  // The prediction, held at the next intersection where the vehicle has a choice: where a
  // lost vehicle is sure to pass (or to have passed).
  VehicleState predictToJunction(double t) const;

 private:
  enum class Branches { kStraight, kEvery, kStopAtJunction };
  std::vector<VehicleState> walk(double t, Branches branches) const;
  const scenario::World& world_;
  PursuitSettings settings_;
  std::deque<VehicleState> recent_;
  VehicleState last_;
};

// Several vehicles held in one camera's image at once (a track phase's convoy): the point to
// look at and how high.
struct GroupView {
  VehicleState centre;  // the vehicles' midpoint; yaw across their line, so that the image's
                        // wider axis (a level camera's width) lies along it
  double height = 0.0;  // m above the vehicles that fits them all across the image's width with
                        // `margin` m to spare at each end
};
// The view of `vehicles` (at least one) from straight above with the nadir camera `camera`
// (pitched down): their midpoint and the height; one vehicle: itself, height 0.
GroupView groupView(const std::vector<VehicleState>& vehicles, const scenario::CameraSpec& camera,
                    double margin);

// The farthest a point `height` m below a level nadir camera `camera` can lie, horizontally, and
// still be in its image: half the image's diagonal on the ground. A sighting farther than this
// came while the UAV was tilted (a manoeuvre's glimpse), not from a camera that holds it.
double levelReach(const scenario::CameraSpec& camera, double height);

// Where a camera's optical axis meets the ground `height` m below it, tilted with the UAV's
// attitude (`attitude`: body FLU to world, unit), less where it meets it when the UAV is level
// with the same heading (horizontal, world frame). A quadrotor tilts into its flight: at 9 m/s
// against its drag the Sentinel pitches about 15 degrees nose down, so a nadir camera then looks
// 6 m behind the point below it from 22 m up, and 15 m behind it in a headwind of 8 m/s: the
// pursuit aims the axis, not the UAV, at the target by flying this much ahead of it. Zero when
// the tilted axis does not look down at least 10 degrees below the horizon.
geometry::Vec2 tiltedAxisShift(const scenario::CameraSpec& camera, const Eigen::Quaterniond& attitude,
                               double height);

// The running average of tiltedAxisShift that the pursuit flies ahead by. It takes a sample only
// while the UAV keeps station: within `station_radius` (horizontally) of its station (where it is
// sent, less the autopilot's lag behind a moving setpoint) and moving with the vehicle (their
// horizontal velocities within `steady_speed`). The tilt of catching up, of braking or of
// circling is not the steady tilt against drag and wind; averaged in, it moves the viewpoint,
// which tilts the UAV again, and from 40 m up (a viewpoint above the roofs beside a tower) the
// loop held a UAV circling a standing car at 34 degrees of tilt with the car out of the nadir
// camera's image half of the time. Outside station the average holds.
class TiltAverage {
 public:
  TiltAverage(double rate = 0.025, double station_radius = 8.0, double steady_speed = 1.5);
  void reset() { shift_.setZero(); }
  // One tick: the UAV's horizontal position and velocity, its station, the vehicle's
  // horizontal velocity and the shift the UAV's attitude gives now. Returns shift().
  const geometry::Vec2& update(const geometry::Vec2& uav, const geometry::Vec2& uav_velocity,
                               const geometry::Vec2& station,
                               const geometry::Vec2& vehicle_velocity,
                               const geometry::Vec2& measured);
  const geometry::Vec2& shift() const { return shift_; }

 private:
  double rate_, station_radius_, steady_speed_;
  geometry::Vec2 shift_{0.0, 0.0};
};

// A place to look from.
struct PursuitView {
  geometry::Vec3 position{0, 0, 0};
  double yaw = 0.0;
  bool visible = false;  // some camera sees the vehicle's centre with a clear line of sight
  std::string camera;    // which one (empty when none)
};

// Chooses the viewpoint: the preferred one (standoff behind, height above, facing the vehicle's
// heading), else the nearest of a ring of candidates around the vehicle (12 bearings x 4
// standoffs x 2 heights, nadir included) from which a camera sees it; candidates inside a
// keep-out zone active at t whose band holds the altitude are skipped. With an envelope
// (PursuitSettings::envelope_radius), the candidates lie inside it (8 bearings at 0.6 of its
// radius x 3 heights) and its centre is kept when none sees the vehicle; the ring only when
// the whole envelope is in a keep-out zone. All candidates are clamped into the altitude band
// and kept `clearance` above nearby occluders; one that this lifts above the band (a tower
// beside the vehicle in the city) is skipped like one in a keep-out zone.
class ViewpointChooser {
 public:
  ViewpointChooser(const scenario::World& world, const scenario::UavSpec& uav,
                   const std::vector<scenario::KeepOutZone>& kozs, const PursuitSettings& settings);
  // `climb`: metres added to the height (a wider view while the vehicle is lost; with an
  // envelope at most 0.4 of its height tolerance). When no
  // candidate sees the vehicle, the nearest one outside the keep-out zones (visible false).
  PursuitView choose(const VehicleState& vehicle, const geometry::Vec3& uav, double t,
                     double climb = 0.0) const;
  // The camera (by name; only PursuitSettings::camera when set) that sees the point `target`
  // from a UAV at `position` with `yaw` with a clear line of sight, or nullopt.
  std::optional<std::string> seenBy(const geometry::Vec3& position, double yaw,
                                    const geometry::Vec3& target) const;
  // True when the straight flight a -> b at time t stays out of every keep-out zone active then
  // whose altitude band reaches the flight's altitudes.
  bool kozClear(const geometry::Vec3& a, const geometry::Vec3& b, double t) const;

 private:
  double safeAltitude(const geometry::Vec2& p, double wanted) const;
  bool inKoz(const geometry::Vec3& p, double t) const;
  // Inside the altitude band (less 1.5 m) and outside the keep-out zones active at t.
  bool usable(const geometry::Vec3& p, double t) const;

  const scenario::World& world_;
  scenario::UavSpec uav_;
  std::vector<scenario::KeepOutZone> kozs_;
  PursuitSettings settings_;
};

}  // namespace hameritt::clients
