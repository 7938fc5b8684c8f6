#pragma once
// The COP as Cursor-on-Target events: the UAV's own position (a-f-A-M-F-Q), one event per track
// (a-u-G, unknown ground), and the mission's areas of interest and keep-out zones as freeform
// shapes (u-d-f). Map (ENU) coordinates become WGS84 through the EnuFrame at the geodetic origin.

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/cop/cot.h"
#include "hameritt/cop/geodetic.h"

namespace hameritt::cop {

// Event naming and lifetimes.
struct TakEventConfig {
  std::string uid_prefix = "hameritt";
  std::string uav_callsign = "HAMERITT-UAV";
  double stale_s = 30.0;        // UAV and tracks: stale = time + stale_s
  double zone_stale_s = 600.0;  // zones
  double uav_ce = 1.0;          // the UAV's own position error (m, 1-sigma)
  double uav_le = 1.0;

  // Throws std::invalid_argument naming the field.
  void validate() const;
};

// A track as the bridge sends it.
struct TrackReport {
  std::string id;
  std::string entity_class;
  std::map<std::string, std::string> attributes;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // map frame
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  // east, north m/s
  double ce = kCotUnknownError;                        // horizontal 1-sigma (m)
  double le = kCotUnknownError;                        // vertical 1-sigma (m)
  std::string target_id;
  double target_belief = 0.0;
  std::string entity_id;
  unsigned hits = 0;
};

// An area of interest or keep-out zone.
struct ZoneReport {
  std::string id;
  bool keep_out = false;
  std::string purpose;                   // keep-out zones: vantage_denial, ...
  std::vector<Eigen::Vector2d> polygon;  // map frame, counter-clockwise
  std::optional<double> alt_min, alt_max;
};

// Course in degrees clockwise from true north, [0, 360), of an (east, north) velocity.
double courseDegrees(const Eigen::Vector2d& velocity_en);

// The UAV at `position` (map frame) moving with `velocity` (map frame), at wall time `now`.
CotEvent uavEvent(const EnuFrame& frame, const Eigen::Vector3d& position,
                  const Eigen::Vector3d& velocity, double now, const TakEventConfig& config);

// One track.
CotEvent trackEvent(const EnuFrame& frame, const TrackReport& track, double now,
                    const TakEventConfig& config);

// One zone: a closed u-d-f shape at ground level, its point the vertices' mean.
CotEvent zoneEvent(const EnuFrame& frame, const ZoneReport& zone, double now,
                   const TakEventConfig& config);

}  // namespace hameritt::cop
