#include "hameritt/ros/cop_conversions.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace hameritt::ros_wrappers {
namespace {

std::map<std::string, std::string> toMap(const std::vector<hameritt::KeyValue>& kvs) {
  std::map<std::string, std::string> out;
  for (const auto& kv : kvs) out[kv.key] = kv.value;
  return out;
}

}  // namespace

cop::Observation fromMsg(const hameritt::Detection& msg, double sigma) {
  cop::Observation o;
  o.stamp = msg.header.stamp.toSec();
  o.position = Eigen::Vector3d(msg.position.x, msg.position.y, msg.position.z);
  o.entity_class = msg.entity_class;
  o.attributes = toMap(msg.attributes);
  o.confidence = std::clamp(static_cast<double>(msg.confidence), 0.0, 1.0);
  o.source = msg.client.empty() ? "unnamed_client" : msg.client;
  o.sigma = sigma;
  return o;
}

std::vector<cop::Observation> fromMsg(const hameritt::PerceptionReport& msg, double sigma) {
  std::vector<cop::Observation> out;
  for (const auto& e : msg.entities) {
    cop::Observation o;
    o.stamp = msg.header.stamp.toSec();
    o.position = Eigen::Vector3d(e.position.x, e.position.y, e.position.z);
    o.entity_class = e.entity_class;
    o.attributes = toMap(e.attributes);
    o.confidence = 1.0;
    o.source = "perfect_perception";
    o.entity_id = e.entity_id;
    o.sigma = sigma;
    out.push_back(std::move(o));
  }
  return out;
}

std::vector<cop::TargetSpec> targetsOf(const hameritt::Mission& msg) {
  std::vector<cop::TargetSpec> out;
  for (const auto& t : msg.objective.targets) {
    cop::TargetSpec s;
    s.id = t.id;
    s.entity_class = t.entity_class;
    const std::pair<const char*, const std::string*> fields[] = {
        {"vehicle_class", &t.vehicle_class},
        {"make", &t.make},
        {"model", &t.model},
        {"color", &t.color}};
    for (const auto& [key, value] : fields)
      if (!value->empty()) s.attributes[key] = *value;
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<cop::ZoneReport> zonesOf(const hameritt::Mission& msg) {
  std::vector<cop::ZoneReport> out;
  for (const auto& a : msg.areas_of_interest) {
    cop::ZoneReport z;
    z.id = a.id;
    for (const auto& p : a.polygon) z.polygon.emplace_back(p.x, p.y);
    out.push_back(std::move(z));
  }
  for (const auto& k : msg.keep_out_zones) {
    cop::ZoneReport z;
    z.id = k.id;
    z.keep_out = true;
    z.purpose = k.purpose;
    for (const auto& p : k.polygon) z.polygon.emplace_back(p.x, p.y);
    if (k.has_alt_min) z.alt_min = k.alt_min;
    if (k.has_alt_max) z.alt_max = k.alt_max;
    out.push_back(std::move(z));
  }
  return out;
}

hameritt::CopTrack toMsg(const cop::Track& t) {
  hameritt::CopTrack m;
  m.id = t.id;
  m.entity_class = t.entity_class;
  for (const auto& [k, v] : t.attributes()) {
    hameritt::KeyValue kv;
    kv.key = k;
    kv.value = v;
    m.attributes.push_back(kv);
  }
  m.position.x = t.state.x();
  m.position.y = t.state.y();
  m.position.z = t.z;
  m.velocity.x = t.state(2);
  m.velocity.y = t.state(3);
  const Eigen::Matrix3d c = t.positionCovariance();
  for (int i = 0; i < 9; ++i) m.position_covariance[i] = c(i / 3, i % 3);
  m.first_seen = ros::Time(std::max(0.0, t.first_seen));
  m.last_seen = ros::Time(std::max(0.0, t.last_seen));
  m.hits = t.hits;
  m.confirmed = t.confirmed;
  m.entity_id = t.entity_id;
  m.target_id = t.target_id;
  m.target_belief = t.target_belief;
  for (const auto& [source, n] : t.sources) m.sources.push_back(source);
  return m;
}

cop::TrackReport toTrackReport(const hameritt::CopTrack& m) {
  cop::TrackReport r;
  r.id = m.id;
  r.entity_class = m.entity_class;
  r.attributes = toMap(m.attributes);
  r.position = Eigen::Vector3d(m.position.x, m.position.y, m.position.z);
  r.velocity = Eigen::Vector2d(m.velocity.x, m.velocity.y);
  Eigen::Matrix2d h;
  h << m.position_covariance[0], m.position_covariance[1], m.position_covariance[3],
      m.position_covariance[4];
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(h).eigenvalues().maxCoeff();
  r.ce = std::sqrt(std::max(0.0, largest));
  r.le = std::sqrt(std::max(0.0, m.position_covariance[8]));
  r.target_id = m.target_id;
  r.target_belief = m.target_belief;
  r.entity_id = m.entity_id;
  r.hits = m.hits;
  return r;
}

}  // namespace hameritt::ros_wrappers
