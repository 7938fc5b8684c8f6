#include "hameritt/cop/operational_picture.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <tuple>

namespace hameritt::cop {
namespace {

void require(bool ok, const char* field, double value, const char* expected) {
  if (!ok)
    throw std::invalid_argument(std::string("cop config: ") + field + " = " +
                                std::to_string(value) + " (expected " + expected + ")");
}

// Likelihood factors of one described attribute (see OperationalPicture::belief).
constexpr double kUnknownAttribute = 0.5;
constexpr double kMismatchedAttribute = 0.02;

bool classesCompatible(const std::string& a, const std::string& b) {
  return a.empty() || b.empty() || a == b;
}

// A track's ground position and its covariance predicted to `stamp` (the CV model's position
// block, without copying the track).
void predictPosition(const Track& t, double stamp, double accel_sigma, Eigen::Vector2d* pos,
                     Eigen::Matrix2d* cov) {
  const double dt = std::max(0.0, stamp - t.last_seen);
  const Eigen::Matrix2d pp = t.covariance.topLeftCorner<2, 2>();
  const Eigen::Matrix2d pv = t.covariance.topRightCorner<2, 2>();
  const Eigen::Matrix2d vv = t.covariance.bottomRightCorner<2, 2>();
  *pos = t.state.head<2>() + dt * t.state.tail<2>();
  const double q = accel_sigma * accel_sigma * dt * dt * dt / 3.0;
  *cov = pp + dt * (pv + pv.transpose()) + dt * dt * vv + q * Eigen::Matrix2d::Identity();
}

}  // namespace

void CopConfig::validate() const {
  require(std::isfinite(process_accel_sigma) && process_accel_sigma >= 0, "process_accel_sigma",
          process_accel_sigma, ">= 0 m/s^2");
  require(std::isfinite(height_walk_sigma) && height_walk_sigma >= 0, "height_walk_sigma",
          height_walk_sigma, ">= 0");
  require(std::isfinite(gate_chi2) && gate_chi2 > 0, "gate_chi2", gate_chi2, "> 0");
  require(std::isfinite(merge_chi2) && merge_chi2 >= 0, "merge_chi2", merge_chi2, ">= 0");
  require(std::isfinite(initial_speed_sigma) && initial_speed_sigma > 0, "initial_speed_sigma",
          initial_speed_sigma, "> 0 m/s");
  require(confirm_hits >= 1, "confirm_hits", confirm_hits, ">= 1");
  require(std::isfinite(tentative_timeout) && tentative_timeout > 0, "tentative_timeout",
          tentative_timeout, "> 0 s");
  require(std::isfinite(confirmed_timeout) && confirmed_timeout > 0, "confirmed_timeout",
          confirmed_timeout, "> 0 s");
  require(belief_threshold >= 0 && belief_threshold <= 1, "belief_threshold", belief_threshold,
          "in [0, 1]");
}

std::map<std::string, std::string> Track::attributes() const {
  std::map<std::string, std::string> out;
  for (const auto& [key, votes] : attribute_votes) {
    const std::string* best = nullptr;
    double best_w = -1.0;
    for (const auto& [value, w] : votes)  // ordered: the first of equal weights wins
      if (w > best_w) best_w = w, best = &value;
    if (best) out[key] = *best;
  }
  return out;
}

Eigen::Matrix3d Track::positionCovariance() const {
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  c.topLeftCorner<2, 2>() = covariance.topLeftCorner<2, 2>();
  c(2, 2) = z_variance;
  return c;
}

OperationalPicture::OperationalPicture(const CopConfig& config) : config_(config) {
  config_.validate();
}

void OperationalPicture::setTargets(std::vector<TargetSpec> targets) {
  targets_ = std::move(targets);
  refreshBeliefs();
}

void OperationalPicture::predict(Track& t, double stamp) const {
  const double dt = std::max(0.0, stamp - t.last_seen);
  if (dt <= 0.0) return;
  Eigen::Matrix4d f = Eigen::Matrix4d::Identity();
  f(0, 2) = f(1, 3) = dt;
  const double q = config_.process_accel_sigma * config_.process_accel_sigma;
  Eigen::Matrix4d qm = Eigen::Matrix4d::Zero();
  for (int i = 0; i < 2; ++i) {
    qm(i, i) = q * dt * dt * dt / 3.0;
    qm(i, i + 2) = qm(i + 2, i) = q * dt * dt / 2.0;
    qm(i + 2, i + 2) = q * dt;
  }
  t.state = f * t.state;
  t.covariance = f * t.covariance * f.transpose() + qm;
  t.z_variance += config_.height_walk_sigma * config_.height_walk_sigma * dt;
  t.last_seen = stamp;
}

void OperationalPicture::correct(Track& t, const Observation& o) {
  const double r = o.sigma * o.sigma;
  const Eigen::Matrix2d s = t.covariance.topLeftCorner<2, 2>() + r * Eigen::Matrix2d::Identity();
  const Eigen::Matrix<double, 4, 2> k = t.covariance.leftCols<2>() * s.inverse();
  const Eigen::Vector2d nu = o.position.head<2>() - t.state.head<2>();
  t.state += k * nu;
  Eigen::Matrix<double, 2, 4> h = Eigen::Matrix<double, 2, 4>::Zero();
  h(0, 0) = h(1, 1) = 1.0;
  // Joseph form: stays symmetric positive definite.
  const Eigen::Matrix4d ikh = Eigen::Matrix4d::Identity() - k * h;
  t.covariance = ikh * t.covariance * ikh.transpose() + k * r * k.transpose();
  const double kz = t.z_variance / (t.z_variance + r);
  t.z += kz * (o.position.z() - t.z);
  t.z_variance *= 1.0 - kz;
  t.hits++;
  t.last_report = reports_;
  t.confirmed = t.confirmed || t.hits >= config_.confirm_hits;
  const double c = std::clamp(o.confidence, 0.0, 1.0);
  t.miss_probability *= 1.0 - c;
  if (t.entity_class.empty()) t.entity_class = o.entity_class;
  for (const auto& [key, value] : o.attributes)
    if (!value.empty()) t.attribute_votes[key][value] += std::max(c, 1e-3);
  if (!o.entity_id.empty()) t.entity_id = o.entity_id;
  t.sources[o.source]++;
}

Track OperationalPicture::create(const Observation& o) {
  Track t;
  char id[32];
  std::snprintf(id, sizeof id, "T%04llu", static_cast<unsigned long long>(next_id_++));
  t.id = id;
  t.state << o.position.x(), o.position.y(), 0.0, 0.0;
  const double v = config_.initial_speed_sigma * config_.initial_speed_sigma;
  t.covariance = Eigen::Vector4d(1e6, 1e6, v, v).asDiagonal();  // position set by correct()
  t.z = o.position.z();
  t.z_variance = 1e6;
  t.first_seen = t.last_seen = o.stamp;
  correct(t, o);
  stats_.created++;
  return t;
}

void OperationalPicture::update(const std::vector<Observation>& observations) {
  reports_++;
  // Candidate pairs inside the gate, then global nearest neighbour by greedy assignment in
  // (distance, observation, track id) order: deterministic and one-to-one.
  std::vector<std::tuple<double, size_t, std::string>> pairs;
  for (size_t i = 0; i < observations.size(); ++i) {
    const Observation& o = observations[i];
    for (const auto& [id, track] : tracks_) {
      if (!classesCompatible(track.entity_class, o.entity_class)) continue;
      Eigen::Vector2d pos;
      Eigen::Matrix2d cov;
      predictPosition(track, o.stamp, config_.process_accel_sigma, &pos, &cov);
      const Eigen::Matrix2d s = cov + o.sigma * o.sigma * Eigen::Matrix2d::Identity();
      const Eigen::Vector2d nu = o.position.head<2>() - pos;
      const double d2 = nu.dot(s.ldlt().solve(nu));
      if (d2 <= config_.gate_chi2) pairs.emplace_back(d2, i, id);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<bool> used_obs(observations.size(), false);
  std::map<std::string, bool> used_track;
  for (const auto& [d2, i, id] : pairs) {
    if (used_obs[i] || used_track[id]) continue;
    used_obs[i] = used_track[id] = true;
    Track& t = tracks_.at(id);
    predict(t, observations[i].stamp);
    correct(t, observations[i]);
    stats_.associated++;
  }
  for (size_t i = 0; i < observations.size(); ++i) {
    stats_.observations++;
    if (used_obs[i]) continue;
    Track t = create(observations[i]);
    tracks_.emplace(t.id, std::move(t));
  }
  mergeDuplicates();
  refreshBeliefs();
}

void OperationalPicture::mergeDuplicates() {
  if (config_.merge_chi2 <= 0.0) return;
  for (auto a = tracks_.begin(); a != tracks_.end(); ++a) {
    for (auto b = std::next(a); b != tracks_.end();) {
      Track& older = a->second;
      const Track& newer = b->second;
      bool same = classesCompatible(older.entity_class, newer.entity_class) &&
                  older.last_report != newer.last_report;
      if (same) {
        // Both at the later time, then the distance of the positions.
        const double t = std::max(older.last_seen, newer.last_seen);
        Eigen::Vector2d pa, pb;
        Eigen::Matrix2d ca, cb;
        predictPosition(older, t, config_.process_accel_sigma, &pa, &ca);
        predictPosition(newer, t, config_.process_accel_sigma, &pb, &cb);
        const Eigen::Matrix2d s = ca + cb;
        const Eigen::Vector2d d = pa - pb;
        same = d.dot(s.ldlt().solve(d)) <= config_.merge_chi2;
      }
      if (!same) {
        ++b;
        continue;
      }
      // The older track keeps its id and takes the newer one's evidence, and its state when that
      // is more recent.
      if (newer.last_seen > older.last_seen) {
        older.state = newer.state;
        older.covariance = newer.covariance;
        older.z = newer.z;
        older.z_variance = newer.z_variance;
        older.last_seen = newer.last_seen;
        older.last_report = newer.last_report;
        if (!newer.entity_id.empty()) older.entity_id = newer.entity_id;
      }
      older.first_seen = std::min(older.first_seen, newer.first_seen);
      older.hits += newer.hits;
      older.confirmed = older.confirmed || newer.confirmed || older.hits >= config_.confirm_hits;
      older.miss_probability *= newer.miss_probability;
      if (older.entity_class.empty()) older.entity_class = newer.entity_class;
      if (older.entity_id.empty()) older.entity_id = newer.entity_id;
      for (const auto& [key, votes] : newer.attribute_votes)
        for (const auto& [value, w] : votes) older.attribute_votes[key][value] += w;
      for (const auto& [source, n] : newer.sources) older.sources[source] += n;
      b = tracks_.erase(b);
      stats_.merged++;
    }
  }
}

std::vector<std::string> OperationalPicture::prune(double now) {
  std::vector<std::string> gone;
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    const double limit =
        it->second.confirmed ? config_.confirmed_timeout : config_.tentative_timeout;
    if (now - it->second.last_seen > limit) {
      gone.push_back(it->first);
      it = tracks_.erase(it);
      stats_.deleted++;
    } else {
      ++it;
    }
  }
  return gone;
}

double OperationalPicture::belief(const Track& track, const TargetSpec& target) {
  if (!target.entity_class.empty() && track.entity_class != target.entity_class) return 0.0;
  const std::map<std::string, std::string> attrs = track.attributes();
  double agreement = 1.0;
  for (const auto& [key, value] : target.attributes) {
    const auto it = attrs.find(key);
    agreement *=
        it == attrs.end() ? kUnknownAttribute : (it->second == value ? 1.0 : kMismatchedAttribute);
  }
  return agreement * (1.0 - track.miss_probability);
}

void OperationalPicture::refreshBeliefs() {
  for (auto& [id, t] : tracks_) {
    t.target_id.clear();
    t.target_belief = 0.0;
    for (const TargetSpec& target : targets_) {  // the first of equal beliefs wins
      const double b = belief(t, target);
      if (b > t.target_belief) {
        t.target_belief = b;
        if (b >= config_.belief_threshold) t.target_id = target.id;
      }
    }
  }
}

}  // namespace hameritt::cop
