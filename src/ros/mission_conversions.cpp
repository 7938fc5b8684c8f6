#include "hameritt/ros/mission_conversions.h"

#include <cmath>
#include <cstdlib>
#include <utility>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::ros_wrappers {

namespace {

geometry_msgs::Point point(const geometry::Vec2& v) {
  geometry_msgs::Point p;
  p.x = v.x();
  p.y = v.y();
  return p;
}

std::vector<geometry_msgs::Point> points(const std::vector<geometry::Vec2>& v) {
  std::vector<geometry_msgs::Point> out;
  out.reserve(v.size());
  for (const auto& p : v) out.push_back(point(p));
  return out;
}

std::vector<geometry::Vec2> vecs(const std::vector<geometry_msgs::Point>& v) {
  std::vector<geometry::Vec2> out;
  out.reserve(v.size());
  for (const auto& p : v) out.emplace_back(p.x, p.y);
  return out;
}

geometry::Polygon polygon(const std::vector<geometry_msgs::Point>& v, const std::string& field) {
  if (v.size() < 3) {
    throw scenario::ConfigError("mission message: " + field +
                                ": expected a polygon of 3 or more "
                                "points, got " +
                                std::to_string(v.size()));
  }
  return geometry::Polygon(vecs(v));
}

hameritt::TimeWindow toMsg(const geometry::TimeWindow& w) {
  hameritt::TimeWindow m;
  m.has_net = w.net.has_value();
  m.net = w.net.value_or(0.0);
  m.has_nlt = w.nlt.has_value();
  m.nlt = w.nlt.value_or(0.0);
  return m;
}

geometry::TimeWindow fromMsg(const hameritt::TimeWindow& m) {
  geometry::TimeWindow w;
  if (m.has_net) w.net = m.net;
  if (m.has_nlt) w.nlt = m.nlt;
  return w;
}

std::string attributeString(const scenario::AttributeValue& v) {
  if (const auto* s = std::get_if<std::string>(&v)) return *s;
  return std::to_string(std::get<std::int64_t>(v));
}

// Integers travel as their decimal text and come back as integers ("storeys": 2).
scenario::AttributeValue attributeValue(const std::string& s) {
  const bool digits = !s.empty() && s.size() < 19 &&
                      s.find_first_not_of("0123456789", s[0] == '-' ? 1 : 0) == std::string::npos &&
                      s != "-" && !(s.size() > 1 && s[s[0] == '-' ? 1 : 0] == '0');
  if (digits) return static_cast<std::int64_t>(std::strtoll(s.c_str(), nullptr, 10));
  return s;
}

}  // namespace

std::vector<hameritt::KeyValue> toKeyValues(const scenario::Attributes& a) {
  std::vector<hameritt::KeyValue> out;
  out.reserve(a.items.size());
  for (const auto& [k, v] : a.items) {
    hameritt::KeyValue kv;
    kv.key = k;
    kv.value = attributeString(v);
    out.push_back(std::move(kv));
  }
  return out;
}

hameritt::Mission toMsg(const scenario::Mission& mission) {
  hameritt::Mission m;
  m.header.frame_id = "map";
  m.scenario_id = mission.scenario_id;
  m.scenario_class = scenario::toString(mission.cls);
  m.seed = mission.seed;
  m.origin_latitude = mission.origin.latitude;
  m.origin_longitude = mission.origin.longitude;
  m.origin_altitude = mission.origin.altitude;
  m.time_limit = mission.time_limit;
  m.objective.type = mission.objective.type;
  m.objective.text = mission.objective.text;
  for (const auto& t : mission.objective.targets) {
    hameritt::TargetDescription d;
    d.id = t.id;
    d.entity_class = t.cls;
    d.vehicle_class = t.vehicle_class;
    d.make = t.make;
    d.model = t.model;
    d.color = t.color;
    m.objective.targets.push_back(d);
  }
  for (const auto& a : mission.aois) {
    hameritt::AreaOfInterest x;
    x.id = a.id;
    x.polygon = points(a.polygon.vertices());
    x.window = toMsg(a.window);
    m.areas_of_interest.push_back(x);
  }
  for (const auto& k : mission.kozs) {
    hameritt::KeepOutZone x;
    x.id = k.id;
    x.purpose = k.purpose;
    x.polygon = points(k.polygon.vertices());
    x.has_alt_min = k.alt_min.has_value();
    x.alt_min = k.alt_min.value_or(0.0);
    x.has_alt_max = k.alt_max.has_value();
    x.alt_max = k.alt_max.value_or(0.0);
    x.window = toMsg(k.window);
    for (const auto& q : k.motion) {
      x.motion_t.push_back(q.t);
      geometry_msgs::Point pt;
      pt.x = q.x;
      pt.y = q.y;
      x.motion.push_back(pt);
    }
    m.keep_out_zones.push_back(x);
  }
  for (const auto& p : mission.priors) {
    hameritt::AreaPrior x;
    x.aoi_id = p.aoi_id;
    x.depth = p.depth;
    for (const auto& c : p.cells) {
      hameritt::PriorCell cell;
      cell.id = c.id;
      cell.row = c.row;
      cell.col = c.col;
      cell.polygon = points(c.polygon.vertices());
      cell.probability = c.probability;
      x.cells.push_back(cell);
    }
    m.area_priors.push_back(x);
  }
  for (const auto& r : mission.routes) {
    hameritt::RouteOfInterest x;
    x.id = r.id;
    x.polyline = points(r.polyline);
    x.streets = r.streets;
    x.band_width = r.band_width;
    x.band = points(r.band.vertices());
    m.routes.push_back(x);
  }
  for (const auto& r : mission.relations) {
    hameritt::SceneRelation x;
    x.target_id = r.target_id;
    x.op = scenario::toString(r.op, false);
    x.eventually = r.eventually;
    x.related_id = r.related_id;
    x.related_class = r.related_class;
    x.related_attributes = toKeyValues(r.related_attributes);
    x.distance = r.distance;
    x.bearing_deg = r.bearing_deg;
    x.dz = r.dz;
    x.line_of_sight = r.line_of_sight;
    x.has_time = r.time.has_value();
    x.time = r.time.value_or(0.0);
    x.text = scenario::relationText(r);
    m.relations.push_back(x);
  }
  for (const auto& p : mission.phases) {
    hameritt::MissionPhase x;
    x.id = p.id;
    x.type = scenario::toString(p.type);
    x.targets = p.targets;
    x.duration = p.duration.value_or(0.0);
    x.follow_distance = p.follow.distance;
    x.follow_distance_tolerance = p.follow.distance_tolerance;
    x.follow_height = p.follow.height;
    x.follow_height_tolerance = p.follow.height_tolerance;
    x.follow_min_inside_fraction = p.follow.min_inside_fraction;
    x.follow_max_outside_s = p.follow.max_outside_s;
    x.follow_approach_s = p.follow.approach_s;
    x.track_min_visible_fraction = p.track.min_visible_fraction;
    x.track_min_box_area = p.track.min_box_area;
    x.track_min_tracked_fraction = p.track.min_tracked_fraction;
    x.track_max_reacquire_s = p.track.max_reacquire_s;
    x.avoid_goal.x = p.avoid.goal.x();
    x.avoid_goal.y = p.avoid.goal.y();
    x.avoid_goal.z = p.avoid.goal.z();
    x.avoid_goal_radius = p.avoid.goal_radius;
    x.avoid_shortest_path = p.avoid.shortest_path_m;
    x.avoid_min_horizontal_separation = p.avoid.min_horizontal_separation;
    x.avoid_min_vertical_separation = p.avoid.min_vertical_separation;
    m.phases.push_back(x);
  }
  return m;
}

scenario::Mission fromMsg(const hameritt::Mission& m) {
  scenario::Mission mission;
  mission.scenario_id = m.scenario_id;
  if (!scenario::parseScenarioClass(m.scenario_class, &mission.cls)) {
    throw scenario::ConfigError(
        "mission message: scenario_class: expected area_search, "
        "route_search or pursuit, got '" +
        m.scenario_class + "'");
  }
  mission.seed = m.seed;
  mission.origin.latitude = m.origin_latitude;
  mission.origin.longitude = m.origin_longitude;
  mission.origin.altitude = m.origin_altitude;
  mission.time_limit = m.time_limit;
  mission.objective.type = m.objective.type;
  mission.objective.text = m.objective.text;
  for (const auto& d : m.objective.targets) {
    scenario::TargetDescription t;
    t.id = d.id;
    t.cls = d.entity_class;
    t.vehicle_class = d.vehicle_class;
    t.make = d.make;
    t.model = d.model;
    t.color = d.color;
    mission.objective.targets.push_back(t);
  }
  for (std::size_t i = 0; i < m.areas_of_interest.size(); ++i) {
    const auto& a = m.areas_of_interest[i];
    mission.aois.push_back({a.id,
                            polygon(a.polygon, "areas_of_interest[" + std::to_string(i) + "]"),
                            fromMsg(a.window)});
  }
  for (std::size_t i = 0; i < m.keep_out_zones.size(); ++i) {
    const auto& k = m.keep_out_zones[i];
    scenario::KeepOutZone z;
    z.id = k.id;
    z.purpose = k.purpose;
    z.polygon = polygon(k.polygon, "keep_out_zones[" + std::to_string(i) + "]");
    if (k.has_alt_min) z.alt_min = k.alt_min;
    if (k.has_alt_max) z.alt_max = k.alt_max;
    z.window = fromMsg(k.window);
    if (k.motion.size() != k.motion_t.size()) {
      throw scenario::ConfigError("mission message: keep_out_zones[" + std::to_string(i) +
                                  "]: " + std::to_string(k.motion.size()) + " motion points but " +
                                  std::to_string(k.motion_t.size()) + " motion_t stamps");
    }
    for (std::size_t j = 0; j < k.motion.size(); ++j) {
      z.motion.push_back({k.motion_t[j], k.motion[j].x, k.motion[j].y, 0.0, 0.0});
    }
    mission.kozs.push_back(z);
  }
  for (const auto& p : m.area_priors) {
    scenario::AreaPrior prior;
    prior.aoi_id = p.aoi_id;
    prior.depth = p.depth;
    for (const auto& c : p.cells) {
      prior.cells.push_back(
          {c.id, c.row, c.col, polygon(c.polygon, "area_priors." + c.id), c.probability});
    }
    mission.priors.push_back(prior);
  }
  for (const auto& r : m.routes) {
    scenario::RouteOfInterest route;
    route.id = r.id;
    route.polyline = vecs(r.polyline);
    route.streets = r.streets;
    route.band_width = r.band_width;
    route.band = polygon(r.band, "routes." + r.id + ".band");
    mission.routes.push_back(route);
  }
  for (std::size_t i = 0; i < m.relations.size(); ++i) {
    const auto& x = m.relations[i];
    scenario::SceneRelation r;
    bool eventually = false;
    if (!scenario::parseRelationOp(x.op, &r.op, &eventually)) {
      throw scenario::ConfigError("mission message: relations[" + std::to_string(i) +
                                  "].op: unknown operator '" + x.op + "'");
    }
    r.eventually = x.eventually || eventually;
    r.target_id = x.target_id;
    r.related_id = x.related_id;
    r.related_class = x.related_class;
    for (const auto& kv : x.related_attributes) {
      r.related_attributes.set(kv.key, attributeValue(kv.value));
    }
    r.distance = x.distance;
    r.bearing_deg = x.bearing_deg;
    r.dz = x.dz;
    r.line_of_sight = x.line_of_sight;
    if (x.has_time) r.time = x.time;
    mission.relations.push_back(r);
  }
  for (std::size_t i = 0; i < m.phases.size(); ++i) {
    const auto& x = m.phases[i];
    scenario::MissionPhase p;
    p.id = x.id;
    if (!scenario::parsePhaseType(x.type, &p.type)) {
      throw scenario::ConfigError("mission message: phases[" + std::to_string(i) +
                                  "].type: expected search, follow, track or avoid, got '" +
                                  x.type + "'");
    }
    p.targets = x.targets;
    if (p.type == scenario::PhaseType::kFollow || p.type == scenario::PhaseType::kTrack) {
      p.duration = x.duration;
    }
    p.follow.distance = x.follow_distance;
    p.follow.distance_tolerance = x.follow_distance_tolerance;
    p.follow.height = x.follow_height;
    p.follow.height_tolerance = x.follow_height_tolerance;
    p.follow.min_inside_fraction = x.follow_min_inside_fraction;
    p.follow.max_outside_s = x.follow_max_outside_s;
    p.follow.approach_s = x.follow_approach_s;
    p.track.min_visible_fraction = x.track_min_visible_fraction;
    p.track.min_box_area = x.track_min_box_area;
    p.track.min_tracked_fraction = x.track_min_tracked_fraction;
    p.track.max_reacquire_s = x.track_max_reacquire_s;
    p.avoid.goal = geometry::Vec3(x.avoid_goal.x, x.avoid_goal.y, x.avoid_goal.z);
    p.avoid.goal_radius = x.avoid_goal_radius;
    p.avoid.shortest_path_m = x.avoid_shortest_path;
    p.avoid.min_horizontal_separation = x.avoid_min_horizontal_separation;
    p.avoid.min_vertical_separation = x.avoid_min_vertical_separation;
    mission.phases.push_back(p);
  }
  return mission;
}

hameritt::UavSpec toMsg(const scenario::UavSpec& uav, const std::string& scenario_id) {
  hameritt::UavSpec m;
  m.header.frame_id = "map";
  m.scenario_id = scenario_id;
  m.model = uav.model;
  m.altitude_min = uav.altitude_min;
  m.altitude_max = uav.altitude_max;
  m.max_speed = uav.max_speed;
  m.start.x = uav.start.x;
  m.start.y = uav.start.y;
  m.start.z = uav.start.z;
  m.start_yaw = uav.start.yaw;
  for (const auto& c : uav.cameras) {
    hameritt::CameraSpec cm;
    cm.name = c.name;
    cm.frame_id = "uav/camera_" + c.name + "_optical";
    cm.mount_xyz.x = c.mount_xyz.x();
    cm.mount_xyz.y = c.mount_xyz.y();
    cm.mount_xyz.z = c.mount_xyz.z();
    cm.mount_rpy_deg.x = c.mount_rpy.x();
    cm.mount_rpy_deg.y = c.mount_rpy.y();
    cm.mount_rpy_deg.z = c.mount_rpy.z();
    cm.width = static_cast<std::uint32_t>(c.width);
    cm.height = static_cast<std::uint32_t>(c.height);
    cm.hfov_deg = c.hfov_deg;
    cm.rate_hz = c.rate_hz;
    cm.modalities = c.modalities;
    m.cameras.push_back(std::move(cm));
  }
  return m;
}

scenario::UavSpec fromMsg(const hameritt::UavSpec& m) {
  auto bad = [](const std::string& field, const std::string& what, double v) {
    return scenario::ConfigError("uav message: " + field + ": expected " + what + ", got " +
                                 scenario::formatNumber(v));
  };
  for (const auto& [field, v] : {std::pair<const char*, double>{"altitude_min", m.altitude_min},
                                 {"altitude_max", m.altitude_max},
                                 {"max_speed", m.max_speed},
                                 {"start.x", m.start.x},
                                 {"start.y", m.start.y},
                                 {"start.z", m.start.z},
                                 {"start_yaw", m.start_yaw}}) {
    if (!std::isfinite(v)) throw bad(field, "a finite number", v);
  }
  if (!(m.altitude_min < m.altitude_max)) {
    throw bad("altitude_max",
              "more than altitude_min (" + scenario::formatNumber(m.altitude_min) + ")",
              m.altitude_max);
  }
  if (!(m.max_speed > 0)) throw bad("max_speed", "m/s > 0", m.max_speed);
  scenario::UavSpec u;
  u.model = m.model;
  u.altitude_min = m.altitude_min;
  u.altitude_max = m.altitude_max;
  u.max_speed = m.max_speed;
  u.start = {0.0, m.start.x, m.start.y, m.start.z, m.start_yaw};
  for (std::size_t i = 0; i < m.cameras.size(); ++i) {
    const auto& cm = m.cameras[i];
    const std::string f = "cameras[" + std::to_string(i) + "].";
    if (cm.width == 0) throw bad(f + "width", "pixels > 0", cm.width);
    if (cm.height == 0) throw bad(f + "height", "pixels > 0", cm.height);
    if (!(cm.hfov_deg > 0 && cm.hfov_deg < 180))
      throw bad(f + "hfov_deg", "degrees in (0, 180)", cm.hfov_deg);
    if (!(cm.rate_hz > 0 && std::isfinite(cm.rate_hz)))
      throw bad(f + "rate_hz", "Hz > 0", cm.rate_hz);
    scenario::CameraSpec c;
    c.name = cm.name;
    c.mount_xyz = {cm.mount_xyz.x, cm.mount_xyz.y, cm.mount_xyz.z};
    c.mount_rpy = {cm.mount_rpy_deg.x, cm.mount_rpy_deg.y, cm.mount_rpy_deg.z};
    if (!c.mount_xyz.allFinite() || !c.mount_rpy.allFinite()) {
      throw scenario::ConfigError("uav message: " + f + "mount: expected finite numbers");
    }
    c.width = static_cast<int>(cm.width);
    c.height = static_cast<int>(cm.height);
    c.hfov_deg = cm.hfov_deg;
    c.rate_hz = cm.rate_hz;
    c.modalities = cm.modalities;
    u.cameras.push_back(std::move(c));
  }
  return u;
}

}  // namespace hameritt::ros_wrappers
