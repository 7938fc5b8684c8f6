#include "hameritt/ros/adk_conversions.h"

#include <algorithm>
#include <cmath>
#include <variant>

#include "hameritt/ros/mission_conversions.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::ros_wrappers {

namespace {

constexpr const char* kMap = "map";

geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

std::vector<geometry_msgs::Point> points(const std::vector<geometry::Vec2>& v, double z = 0.0) {
  std::vector<geometry_msgs::Point> out;
  out.reserve(v.size());
  for (const auto& p : v) out.push_back(point(p.x(), p.y(), z));
  return out;
}

std_msgs::ColorRGBA color(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

visualization_msgs::Marker marker(const std::string& ns, int id, int type, const ros::Time& stamp) {
  visualization_msgs::Marker m;
  m.header.frame_id = kMap;
  m.header.stamp = stamp;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = m.scale.y = m.scale.z = 1.0;
  m.frame_locked = false;
  return m;
}

std::string windowText(const geometry::TimeWindow& w) {
  if (w.unbounded()) return "always";
  std::string s;
  if (w.net) s += "from " + scenario::formatNumber(*w.net) + " s";
  if (w.nlt)
    s += std::string(s.empty() ? "" : " ") + "until " + scenario::formatNumber(*w.nlt) + " s";
  return s;
}

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

}  // namespace

hameritt::Mission toMsg(const scenario::Mission& m, const ros::Time& stamp) {
  // One conversion for the ADK and the clients (mission_conversions.cpp); the ADK stamps it.
  hameritt::Mission msg = toMsg(m);
  msg.header.stamp = stamp;
  msg.header.frame_id = kMap;
  return msg;
}

visualization_msgs::MarkerArray missionMarkers(const scenario::Mission& m, double open_top,
                                               const ros::Time& stamp) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray out;
  int label_id = 0;
  auto label = [&](const std::string& text, const geometry::Vec2& at, double z) {
    Marker t = marker("label", label_id++, Marker::TEXT_VIEW_FACING, stamp);
    t.pose.position = point(at.x(), at.y(), z);
    t.scale.z = 6.0;
    t.color = color(1, 1, 1, 0.9f);
    t.text = text;
    out.markers.push_back(t);
  };
  auto closedRing = [](const std::vector<geometry::Vec2>& v, double z) {
    std::vector<geometry_msgs::Point> pts = points(v, z);
    if (!pts.empty()) pts.push_back(pts.front());
    return pts;
  };
  for (std::size_t i = 0; i < m.aois.size(); ++i) {
    const auto& a = m.aois[i];
    Marker l = marker("aoi", static_cast<int>(i), Marker::LINE_STRIP, stamp);
    l.scale.x = 1.0;
    l.color = color(0.2f, 0.6f, 1.0f, 1.0f);
    l.points = closedRing(a.polygon.vertices(), 0.3);
    out.markers.push_back(l);
    label(a.id + " (" + windowText(a.window) + ")", a.polygon.centroid(), 5.0);
  }
  for (std::size_t i = 0; i < m.kozs.size(); ++i) {
    const auto& k = m.kozs[i];
    const double lo = k.alt_min.value_or(0.0), hi = k.alt_max.value_or(open_top);
    const auto& v = k.polygon.vertices();
    Marker e = marker("koz", static_cast<int>(i), Marker::LINE_LIST, stamp);
    e.scale.x = 0.6;
    e.color = color(1.0f, 0.15f, 0.1f, 1.0f);
    Marker w = marker("koz_walls", static_cast<int>(i), Marker::TRIANGLE_LIST, stamp);
    w.color = color(1.0f, 0.15f, 0.1f, k.window.unbounded() ? 0.3f : 0.15f);
    for (std::size_t j = 0; j < v.size(); ++j) {
      const auto& p = v[j];
      const auto& q = v[(j + 1) % v.size()];
      for (double z : {lo, hi}) {
        e.points.push_back(point(p.x(), p.y(), z));
        e.points.push_back(point(q.x(), q.y(), z));
      }
      e.points.push_back(point(p.x(), p.y(), lo));
      e.points.push_back(point(p.x(), p.y(), hi));
      const auto a0 = point(p.x(), p.y(), lo), a1 = point(q.x(), q.y(), lo);
      const auto b0 = point(p.x(), p.y(), hi), b1 = point(q.x(), q.y(), hi);
      w.points.insert(w.points.end(), {a0, a1, b1, a0, b1, b0});
    }
    out.markers.push_back(e);
    out.markers.push_back(w);
    label(k.id + " " + k.purpose + " (" + windowText(k.window) + ")", k.polygon.centroid(),
          hi + 3.0);
  }
  int prior_id = 0;
  for (const auto& p : m.priors) {
    double pmax = 0.0;
    for (const auto& c : p.cells) pmax = std::max(pmax, c.probability);
    for (const auto& c : p.cells) {
      // Prior cells are convex quadrilaterals (sub-quadrants of an AOI): a fan covers them.
      Marker t = marker("prior", prior_id++, Marker::TRIANGLE_LIST, stamp);
      const float share = pmax > 0 ? static_cast<float>(c.probability / pmax) : 0.0f;
      t.color = color(1.0f, 0.6f, 0.0f, 0.1f + 0.6f * share);
      const auto& v = c.polygon.vertices();
      for (std::size_t j = 1; j + 1 < v.size(); ++j) {
        t.points.push_back(point(v[0].x(), v[0].y(), 0.15));
        t.points.push_back(point(v[j].x(), v[j].y(), 0.15));
        t.points.push_back(point(v[j + 1].x(), v[j + 1].y(), 0.15));
      }
      out.markers.push_back(t);
    }
  }
  for (std::size_t i = 0; i < m.routes.size(); ++i) {
    const auto& r = m.routes[i];
    Marker l = marker("route", static_cast<int>(i), Marker::LINE_STRIP, stamp);
    l.scale.x = 1.0;
    l.color = color(0.1f, 0.9f, 0.3f, 1.0f);
    l.points = points(r.polyline, 0.4);
    out.markers.push_back(l);
    Marker b = marker("route_band", static_cast<int>(i), Marker::LINE_STRIP, stamp);
    b.scale.x = 0.5;
    b.color = color(0.1f, 0.9f, 0.3f, 0.6f);
    b.points = closedRing(r.band.vertices(), 0.35);
    out.markers.push_back(b);
    if (!r.polyline.empty()) label(r.id, r.polyline.front(), 5.0);
  }
  return out;
}

hameritt::KozViolation toMsg(const adk::Violation& v) {
  hameritt::KozViolation m;
  m.zone_id = v.zone_id;
  m.purpose = v.purpose;
  m.t_enter = v.t_enter;
  m.t_exit = v.t_exit;
  m.duration = v.duration();
  m.ongoing = v.ongoing;
  return m;
}

hameritt::ConstraintStatus toMsg(const adk::ConstraintMonitor& monitor, const ros::Time& stamp) {
  hameritt::ConstraintStatus s;
  s.header.stamp = stamp;
  s.header.frame_id = kMap;
  for (const auto& z : monitor.zones()) {
    hameritt::ZoneStatus m;
    m.id = z.id;
    m.purpose = z.purpose;
    m.inside = z.inside;
    m.active = z.active;
    m.violating = z.violating;
    s.keep_out_zones.push_back(m);
  }
  for (const auto& v : monitor.violations()) {
    s.violations.push_back(toMsg(v));
    if (v.ongoing) s.active_violations.push_back(toMsg(v));
  }
  s.violation_count = static_cast<std::uint32_t>(monitor.violationCount());
  s.violation_duration = monitor.violationDuration();
  for (const auto& a : monitor.areas()) {
    hameritt::AoiStatus m;
    m.id = a.id;
    m.inside = a.inside;
    m.active = a.active;
    m.time_inside = a.time_inside;
    m.time_inside_active = a.time_inside_active;
    m.entries = static_cast<std::uint32_t>(a.entries);
    s.areas_of_interest.push_back(m);
  }
  return s;
}

hameritt::ConstraintEvent toMsg(const adk::ConstraintEvent& e) {
  hameritt::ConstraintEvent m;
  m.header.stamp.fromSec(std::max(0.0, e.t));
  m.header.frame_id = kMap;
  m.area_type = e.keep_out_zone ? "keep_out_zone" : "area_of_interest";
  m.id = e.id;
  m.purpose = e.purpose;
  m.event = adk::toString(e.kind);
  m.active = e.active;
  m.position = point(e.position.x(), e.position.y(), e.position.z());
  return m;
}

hameritt::MissionMetrics toMsg(const adk::MissionMetrics& m, const std::string& metrics_file,
                               const ros::Time& stamp) {
  hameritt::MissionMetrics msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = kMap;
  msg.scenario_id = m.scenario_id;
  msg.mode = m.mode;
  msg.outcome = adk::toString(m.outcome);
  msg.reason = m.reason;
  msg.start_time = m.start_time;
  msg.end_time = m.end_time;
  msg.time_limit = m.time_limit;
  for (const auto& t : m.targets) {
    hameritt::TargetMetrics tm;
    tm.id = t.id;
    tm.found = t.found;
    tm.has_first_correct_time = t.first_correct_time.has_value();
    tm.first_correct_time = t.first_correct_time.value_or(0.0);
    tm.has_first_seen_time = t.first_seen_time.has_value();
    tm.first_seen_time = t.first_seen_time.value_or(0.0);
    tm.in_view_time = t.in_view_time;
    msg.targets.push_back(tm);
  }
  msg.has_time_to_first_correct = m.time_to_first_correct.has_value();
  msg.time_to_first_correct = m.time_to_first_correct.value_or(0.0);
  msg.has_time_to_all_found = m.time_to_all_found.has_value();
  msg.time_to_all_found = m.time_to_all_found.value_or(0.0);
  msg.detections = static_cast<std::uint32_t>(m.detections.total);
  msg.correct_detections = static_cast<std::uint32_t>(m.detections.correct);
  msg.false_on_confusers = static_cast<std::uint32_t>(m.detections.false_on_confusers);
  msg.false_on_other_entities = static_cast<std::uint32_t>(m.detections.false_on_other_entities);
  msg.false_on_nothing = static_cast<std::uint32_t>(m.detections.false_on_nothing);
  msg.koz_violation_count = static_cast<std::uint32_t>(m.violations.size());
  msg.koz_violation_duration = m.violation_duration;
  for (const auto& v : m.violations) msg.koz_violations.push_back(toMsg(v));
  msg.path_length = m.flight.path_length;
  msg.flight_time = m.flight.flight_time;
  msg.energy = m.flight.energy;
  msg.max_speed = m.flight.max_speed;
  msg.coverage_cell_size = m.coverage_cell_size;
  for (std::size_t i = 0; i < m.coverage.size(); ++i) {
    const auto& c = m.coverage[i];
    hameritt::AoiCoverage cm;
    cm.id = c.aoi_id;
    cm.cells = static_cast<std::uint32_t>(c.cells);
    cm.covered = static_cast<std::uint32_t>(c.covered);
    cm.fraction = c.fraction;
    cm.has_prior = c.has_prior;
    cm.prior_weighted = c.prior_weighted;
    if (i < m.aoi_time.size()) {
      cm.time_inside = m.aoi_time[i].time_inside;
      cm.time_inside_active = m.aoi_time[i].time_inside_active;
      cm.entries = static_cast<std::uint32_t>(m.aoi_time[i].entries);
    }
    msg.coverage.push_back(cm);
  }
  msg.prior_weighted_coverage = m.prior_weighted_coverage;
  msg.metrics_file = metrics_file;
  return msg;
}

adk::DetectionClaim fromMsg(const hameritt::Detection& d) {
  adk::DetectionClaim c;
  c.stamp = d.header.stamp.toSec();
  c.entity_class = d.entity_class;
  c.position = Eigen::Vector3d(d.position.x, d.position.y, d.position.z);
  c.confidence = d.confidence;
  return c;
}

std::vector<adk::EntityTruth> fromMsg(const hameritt::EntityStateArray& a) {
  std::vector<adk::EntityTruth> out;
  out.reserve(a.entities.size());
  for (const auto& e : a.entities) {
    adk::EntityTruth t;
    t.id = e.id;
    t.cls = e.entity_class;
    t.role = e.role;
    t.position = Eigen::Vector3d(e.pose.position.x, e.pose.position.y, e.pose.position.z);
    t.yaw = yawOf(e.pose.orientation);
    out.push_back(t);
  }
  return out;
}

Eigen::Isometry3d poseOf(const nav_msgs::Odometry& o) {
  const auto& p = o.pose.pose.position;
  const auto& q = o.pose.pose.orientation;
  Eigen::Quaterniond quat(q.w, q.x, q.y, q.z);
  if (!(quat.norm() > 0.0)) quat = Eigen::Quaterniond::Identity();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = quat.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.x, p.y, p.z);
  return T;
}

Eigen::Vector3d worldVelocityOf(const nav_msgs::Odometry& o) {
  const auto& v = o.twist.twist.linear;
  return poseOf(o).linear() * Eigen::Vector3d(v.x, v.y, v.z);
}

}  // namespace hameritt::ros_wrappers
