#include "hameritt/cop/tak_events.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace hameritt::cop {
namespace {

CotPoint toPoint(const EnuFrame& frame, const Eigen::Vector3d& enu, double ce, double le) {
  const Geodetic g = frame.toGeodetic(enu);
  return {g.latitude, g.longitude, g.altitude, ce, le};
}

std::string fixed(double v, int decimals) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// TAK colours: signed 32-bit ARGB.
constexpr int kAoiStroke = static_cast<int>(0xFF00C000u);
constexpr int kAoiFill = static_cast<int>(0x3000C000u);
constexpr int kKozStroke = static_cast<int>(0xFFFF0000u);
constexpr int kKozFill = static_cast<int>(0x40FF0000u);

}  // namespace

void TakEventConfig::validate() const {
  const auto positive = [](double v, const char* field) {
    if (!std::isfinite(v) || v <= 0)
      throw std::invalid_argument(std::string("tak config: ") + field + " = " + std::to_string(v) +
                                  " (expected > 0)");
  };
  positive(stale_s, "stale_s");
  positive(zone_stale_s, "zone_stale_s");
  positive(uav_ce, "uav_ce");
  positive(uav_le, "uav_le");
  if (uid_prefix.empty()) throw std::invalid_argument("tak config: uid_prefix is empty");
}

double courseDegrees(const Eigen::Vector2d& v) {
  double c = std::atan2(v.x(), v.y()) * 180.0 / M_PI;
  if (c < 0) c += 360.0;
  return c >= 360.0 ? 0.0 : c;
}

CotEvent uavEvent(const EnuFrame& frame, const Eigen::Vector3d& position,
                  const Eigen::Vector3d& velocity, double now, const TakEventConfig& config) {
  CotEvent e;
  e.uid = config.uid_prefix + ".uav";
  e.type = "a-f-A-M-F-Q";  // friendly, air, military, fixed... rotary-wing UAV (MIL-STD-2525)
  e.how = "m-g";
  e.time = e.start = now;
  e.stale = now + config.stale_s;
  e.point = toPoint(frame, position, config.uav_ce, config.uav_le);
  e.callsign = config.uav_callsign;
  e.track = std::make_pair(courseDegrees(velocity.head<2>()), velocity.head<2>().norm());
  e.remarks = "hameritt UAV, " + fixed(position.z(), 1) + " m above the map origin";
  return e;
}

CotEvent trackEvent(const EnuFrame& frame, const TrackReport& t, double now,
                    const TakEventConfig& config) {
  CotEvent e;
  e.uid = config.uid_prefix + ".track." + t.id;
  e.type = "a-u-G";
  e.how = "m-f";  // machine, fused
  e.time = e.start = now;
  e.stale = now + config.stale_s;
  e.point = toPoint(frame, t.position, t.ce, t.le);
  e.callsign = t.id + " " + (t.entity_class.empty() ? "unknown" : t.entity_class);
  e.track = std::make_pair(courseDegrees(t.velocity), t.velocity.norm());
  std::string attrs;
  for (const auto& [k, v] : t.attributes) attrs += (attrs.empty() ? "" : ", ") + k + "=" + v;
  e.remarks = t.entity_class + (attrs.empty() ? "" : " (" + attrs + ")") + "; " +
              (t.target_id.empty() ? "no target" : "believed target " + t.target_id) + ", belief " +
              fixed(t.target_belief, 2) + "; " + std::to_string(t.hits) + " reports";
  e.extra = {{"track", t.id},
             {"class", t.entity_class},
             {"target", t.target_id},
             {"belief", fixed(t.target_belief, 3)},
             {"entity", t.entity_id}};
  return e;
}

CotEvent zoneEvent(const EnuFrame& frame, const ZoneReport& z, double now,
                   const TakEventConfig& config) {
  CotEvent e;
  e.uid = config.uid_prefix + (z.keep_out ? ".koz." : ".aoi.") + z.id;
  e.type = "u-d-f";
  e.how = "h-e";
  e.time = e.start = now;
  e.stale = now + config.zone_stale_s;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  CotShape shape;
  for (const Eigen::Vector2d& p : z.polygon) {
    mean += p;
    const Geodetic g = frame.toGeodetic(Eigen::Vector3d(p.x(), p.y(), 0.0));
    shape.vertices.emplace_back(g.latitude, g.longitude);
  }
  if (!z.polygon.empty()) mean /= static_cast<double>(z.polygon.size());
  e.point =
      toPoint(frame, Eigen::Vector3d(mean.x(), mean.y(), 0.0), kCotUnknownError, kCotUnknownError);
  shape.stroke_argb = z.keep_out ? kKozStroke : kAoiStroke;
  shape.fill_argb = z.keep_out ? kKozFill : kAoiFill;
  e.shape = shape;
  e.callsign = (z.keep_out ? "KOZ " : "AOI ") + z.id;
  if (z.keep_out) {
    e.remarks = "keep-out zone (" + z.purpose + "), altitude " +
                (z.alt_min ? fixed(*z.alt_min, 0) : std::string("-inf")) + " to " +
                (z.alt_max ? fixed(*z.alt_max, 0) : std::string("+inf")) + " m above ground";
  } else {
    e.remarks = "area of interest";
  }
  e.extra = {{"zone", z.id}, {"kind", z.keep_out ? "koz" : "aoi"}};
  return e;
}

}  // namespace hameritt::cop
