#include "hameritt/clients/claims.h"

#include <algorithm>
#include <cmath>

#include "hameritt/scenario/error.h"

namespace hameritt::clients {

ClaimLedger::ClaimLedger(double radius, double hold) : radius_(radius), hold_(hold) {
  if (!(radius >= 0) || !std::isfinite(radius)) {
    throw scenario::ConfigError("claims.radius: expected metres >= 0, got " +
                                scenario::formatNumber(radius));
  }
  if (std::isnan(hold)) throw scenario::ConfigError("claims.hold: expected seconds, got nan");
}

bool ClaimLedger::isRepeat(const geometry::Vec3& p, double t) const {
  for (const auto& c : claims_) {
    const bool near = (c.p - p).head<2>().norm() <= radius_;
    const bool fresh = hold_ <= 0 || t - c.t < hold_;
    if (near && fresh) return true;
  }
  return false;
}

bool ClaimLedger::claim(const geometry::Vec3& p, double t) {
  if (isRepeat(p, t)) return false;
  claims_.push_back({p, t});
  bool known = false;
  for (const auto& q : places_) known |= (q - p).head<2>().norm() <= radius_;
  if (!known) places_.push_back(p);
  return true;
}

std::size_t ClaimLedger::locations() const { return places_.size(); }

StandingSightings::StandingSightings(double radius, double hold, double keep)
    : radius_(radius), hold_(hold), keep_(keep) {
  if (!(radius >= 0) || !std::isfinite(radius)) {
    throw scenario::ConfigError("standing.radius: expected metres >= 0, got " +
                                scenario::formatNumber(radius));
  }
  if (!(hold >= 0) || !std::isfinite(hold) || !(keep > hold) || !std::isfinite(keep)) {
    throw scenario::ConfigError("standing: expected 0 <= hold < keep seconds, got hold " +
                                scenario::formatNumber(hold) + ", keep " +
                                scenario::formatNumber(keep));
  }
}

bool StandingSightings::observe(const std::string& key, const geometry::Vec3& p, double t) {
  std::vector<Sighting>& v = seen_[key];
  std::size_t old = 0;
  while (old < v.size() && t - v[old].t > keep_) ++old;
  v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(old));
  bool standing = false;
  for (const auto& s : v) {
    if (t - s.t < hold_) break;  // in time order: the rest are more recent
    standing |= (s.p - p).head<2>().norm() <= radius_;
  }
  v.push_back({p, t});
  return standing;
}

ConvoySightings::ConvoySightings(double radius, double window)
    : radius_(radius), window_(window) {
  if (!(radius >= 0) || !std::isfinite(radius) || !(window > 0) || !std::isfinite(window)) {
    throw scenario::ConfigError("convoy: expected radius >= 0 m and window > 0 s, got " +
                                scenario::formatNumber(radius) + " m, " +
                                scenario::formatNumber(window) + " s");
  }
}

void ConvoySightings::observe(const std::string& key, const geometry::Vec3& p, double t) {
  while (!seen_.empty() && seen_.front().t < t - window_) seen_.pop_front();
  seen_.push_back({key, p.head<2>(), t});
}

bool ConvoySightings::besideAnother(const std::string& key, const geometry::Vec3& p,
                                    double t) const {
  return std::any_of(seen_.begin(), seen_.end(), [&](const Sighting& s) {
    return s.key != key && s.t >= t - window_ && (s.p - p.head<2>()).norm() <= radius_;
  });
}

FalseLeads::FalseLeads(double reach, double after, double radius)
    : reach_(reach), after_(after), radius_(radius) {
  if (!(reach > 0) || !std::isfinite(reach) || !(after >= 0) || !std::isfinite(after) ||
      !(radius >= 0) || !std::isfinite(radius)) {
    throw scenario::ConfigError("false leads: expected reach > 0 m, after >= 0 s and radius >= 0 "
                                "m, got " + scenario::formatNumber(reach) + " m, " +
                                scenario::formatNumber(after) + " s, " +
                                scenario::formatNumber(radius) + " m");
  }
}

bool FalseLeads::giveUp(double t, bool lost, bool confirmed, const geometry::Vec2& uav,
                        const geometry::Vec2& prediction, double confirm_by) {
  if (!confirmed && t > confirm_by) return true;
  if (!lost || confirmed || !((uav - prediction).norm() <= reach_)) {
    reached_at_ = -1.0;
    return false;
  }
  if (reached_at_ < 0) reached_at_ = t;
  return t - reached_at_ > after_;
}

void FalseLeads::setAside(const geometry::Vec2& p) {
  leads_.push_back(p);
  reached_at_ = -1.0;
}

bool FalseLeads::near(const geometry::Vec2& p) const {
  return std::any_of(leads_.begin(), leads_.end(),
                     [&](const geometry::Vec2& q) { return (q - p).norm() <= radius_; });
}

void FalseLeads::clear() {
  leads_.clear();
  reached_at_ = -1.0;
}

}  // namespace hameritt::clients
