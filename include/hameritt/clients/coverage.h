#pragma once
// Prior-weighted coverage search, the maneuver half of the baseline clients: which areas of
// interest (and route bands) to search, in which order, and the lawnmower waypoints that sweep
// the down camera's ground footprint over them while keeping out of the keep-out zones. ROS-free
// and deterministic; the coverage_search_client node sends the legs to the planner's follower.
//
// Only the mission (what a client is told) and the UAV's own specification (altitude band, speed,
// cameras) go in: never a target's position.

#include <set>
#include <string>
#include <vector>

#include "hameritt/geometry/polygon.h"
#include "hameritt/geometry/time_window.h"
#include "hameritt/geometry/types.h"
#include "hameritt/planning/validity.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::clients {

// Ground footprint of a nadir camera at some height: `across` is the image-width side (across
// the track: the down camera's image x axis points to the UAV's right), `along` the image-height
// side. Pinhole, square pixels: fx = (width / 2) / tan(hfov / 2).
struct Footprint {
  double across = 0.0;
  double along = 0.0;
};
Footprint groundFootprint(const scenario::CameraSpec& camera, double height);

// Highest flight over the ground at which an object of `size` metres still spans `pixels`
// pixels in the camera (the default search altitude keeps a car's width >= 25 px).
double heightForPixels(const scenario::CameraSpec& camera, double size, double pixels);

// Coverage settings. validate() throws scenario::ConfigError naming "coverage.<field>".
struct CoverageSettings {
  double altitude = 0.0;          // flight altitude, m above ground (z); must be inside the band
  Footprint footprint;            // of the search camera at `altitude`
  double overlap = 0.2;           // of neighbouring swaths, [0, 0.9]
  double max_speed = 12.0;        // m/s, for arrival-time estimates (the planner's limits:
  double accel = 2.0;             // m/s^2  it stops at each waypoint, trapezoidal profile)
  double climb_rate = 3.0;        // m/s
  double detour_factor = 1.15;    // transits are longer than straight lines (obstacles, zones)
  double koz_margin = 3.0;        // waypoints stay this far (m) outside active keep-out zones
  double koz_time_slack = 20.0;   // a zone counts as active if it is at any instant of
                                  // [eta - slack, eta + slack]: estimates are not exact
  double sample_step = 1.0;       // m, resolution of the line clipping against zones
  double min_line = 2.0;          // m, shorter free pieces of a line are dropped
  double window_margin = 10.0;    // s: when the estimated arrival is less than this after a
                                  // region's window opens, wait outside it (estimates are not
                                  // exact: the UAV must not enter before the window opens)
  int max_leg_waypoints = 12;     // a cell's pattern is sent in legs of at most this many
  bool cover_zero_cells = false;  // also sweep prior cells of probability 0 (last)
  void validate() const;
};

// Fills `altitude` (when <= 0: the height that keeps `min_car_pixels` across a car of
// `car_width` m, clamped into the band minus `band_margin`) and `footprint` from the search
// camera. Throws ConfigError for an altitude outside the band.
CoverageSettings coverageSettingsFor(const scenario::UavSpec& uav, const std::string& camera,
                                     double altitude = 0.0, double min_car_pixels = 25.0,
                                     double car_width = 1.8, double band_margin = 2.0);

// One waypoint of the search, with the time the plan expects the UAV there.
struct SearchWaypoint {
  geometry::Vec3 position{0, 0, 0};
  double eta = 0.0;
};

// What a leg does.
enum class LegKind {
  kStage,  // fly to the edge of a region and wait there for its window to open
  kCover,  // sweep (part of) one cell
};

// A chunk of waypoints for the follower. The client sends a leg, waits for the follower's
// "done", then plans again from where the UAV is (planSearch is cheap and deterministic).
struct SearchLeg {
  LegKind kind = LegKind::kCover;
  std::string region_id;  // AOI or route id
  std::string cell_id;    // prior cell id (the region id for regions without priors)
  double probability = 0.0;
  double not_before = 0.0;     // do not send before this mission time (the window opening, after a
                               // stage leg)
  bool completes_cell = true;  // the cell is covered once this leg is done
  std::vector<SearchWaypoint> waypoints;
};

// What the UAV has done so far: cells already swept, and where it is.
struct SearchProgress {
  geometry::Vec3 position{0, 0, 0};
  double time = 0.0;
  std::set<std::string> covered_cells;
};

struct SearchPlan {
  std::vector<SearchLeg> legs;
  // Cells left out and why ("aoi_2_r0c0: window closes before arrival"), for logs.
  std::vector<std::string> skipped;
  // Swath spacing used, m.
  double line_spacing = 0.0;
};

// Plans the rest of the search from `progress`.
//
// Regions are the areas of interest (their prior cells; an AOI without a prior is one cell of
// probability 1) and the route bands (one cell each, swept with lines parallel to the route).
// Region order: the region whose search can start first (max(arrival, window opening)) among
// those that can still be reached before their window closes; ties by earlier closing, then by
// document order. Regions whose window has closed, and the mission time limit, end the plan.
// Inside a region, cells go greedily by probability gathered per metre:
// p / (transit from here to the cell's nearest pattern entry + length of its pattern), ties by
// higher p, then cell id; cells of probability 0 are skipped unless cover_zero_cells.
// A cell's pattern is a lawnmower over its polygon: lines parallel to its longest edge, spaced
// at most footprint.across * (1 - overlap) apart and centred so that the swaths (each line's
// Minkowski sum with the footprint rectangle) cover the cell; each line is cut where it comes
// within koz_margin of a keep-out zone active around the time it would be flown (and inside the
// zone's altitude band), so no waypoint lies in one; the planner finds the way around.
// Waypoints expected after the region's window closes (or the time limit) are dropped.
SearchPlan planSearch(const scenario::Mission& mission, const CoverageSettings& settings,
                      const SearchProgress& progress);

// The sweep flies at one altitude; in the city a rooftop can stand above it. Each waypoint of
// `plan` that `validity` finds invalid (inside an obstacle box inflated by its margin) is lifted
// in 1 m steps until it is valid, then `above` metres more; a waypoint that cannot be lifted
// inside the altitude band (a tower, or a point outside the bounds) is dropped, and a leg left
// without waypoints with it. Returns how many were lifted and dropped.
struct WaypointRepairs {
  int lifted = 0;
  int dropped = 0;
};
WaypointRepairs clearWaypoints(SearchPlan* plan, const planning::WorldValidity& validity,
                               double above = 1.0);

// The lawnmower lines (pairs of endpoints, in flying order, alternating direction, at z = 0)
// whose swaths cover `polygon`; exposed for tests and tools.
std::vector<std::pair<geometry::Vec2, geometry::Vec2>> lawnmowerLines(
    const geometry::Polygon& polygon, const Footprint& footprint, double overlap);

// Seconds to fly `distance` metres from rest to rest with this speed and acceleration
// (trapezoidal profile).
double flightTime(double distance, double max_speed, double accel);

}  // namespace hameritt::clients
