#include "hameritt/sim/lockstep.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace hameritt::sim {

void PublicationCounter::add(const std::string& topic, std::uint64_t n) {
  std::lock_guard<std::mutex> lock(mutex_);
  counts_[topic] += n;
}

std::vector<std::pair<std::string, std::uint64_t>> PublicationCounter::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {counts_.begin(), counts_.end()};
}

void LockstepTally::update(const std::string& publisher,
                           const std::vector<std::pair<std::string, std::uint64_t>>& counts) {
  for (const auto& [topic, n] : counts) {
    auto& total = totals_[{topic, publisher}];
    if (n < total) {
      throw std::invalid_argument("lock-step counts of " + publisher + " on " + topic +
                                  " went back from " + std::to_string(total) + " to " +
                                  std::to_string(n));
    }
    total = n;
  }
}

std::vector<StreamCount> LockstepTally::streams() const {
  std::vector<StreamCount> out;
  out.reserve(totals_.size());
  for (const auto& [key, n] : totals_) out.push_back({key.first, key.second, n});
  return out;
}

std::size_t LockstepInbox::addSubscription(const std::string& topic) {
  std::lock_guard<std::mutex> lock(mutex_);
  subs_.push_back({topic, {}});
  return subs_.size() - 1;
}

void LockstepInbox::receive(std::size_t sub, const std::string& publisher,
                            std::function<void()> deliver) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (sub >= subs_.size())
    throw std::out_of_range("lock-step inbox: no subscription " + std::to_string(sub));
  ++subs_[sub].received[publisher];
  buffered_.push_back({sub, publisher, arrivals_++, std::move(deliver)});
}

std::vector<StreamCount> LockstepInbox::missing(const std::vector<StreamCount>& totals) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<StreamCount> out;
  for (const auto& s : subs_) {
    for (const auto& t : totals) {
      if (t.topic != s.topic) continue;
      const auto r = s.received.find(t.publisher);
      const std::uint64_t got = r == s.received.end() ? 0 : r->second;
      if (got < t.count) out.push_back({t.topic, t.publisher, t.count - got});
    }
  }
  return out;
}

std::vector<std::function<void()>> LockstepInbox::take(const std::vector<std::string>& order) {
  std::vector<Message> msgs;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    msgs.swap(buffered_);
  }
  auto rank = [&order](const std::string& publisher) {
    const auto it = std::find(order.begin(), order.end(), publisher);
    return static_cast<std::size_t>(it - order.begin());
  };
  std::vector<std::pair<std::size_t, std::size_t>> keys;  // (rank, index into msgs)
  keys.reserve(msgs.size());
  for (std::size_t i = 0; i < msgs.size(); ++i) keys.emplace_back(rank(msgs[i].publisher), i);
  std::sort(keys.begin(), keys.end(), [&msgs](const auto& a, const auto& b) {
    const Message& x = msgs[a.second];
    const Message& y = msgs[b.second];
    // Unlisted publishers share the last rank and are ordered by name among themselves.
    return std::tie(a.first, x.publisher, x.sub, x.arrival) <
           std::tie(b.first, y.publisher, y.sub, y.arrival);
  });
  std::vector<std::function<void()>> out;
  out.reserve(msgs.size());
  for (const auto& k : keys) out.push_back(std::move(msgs[k.second].deliver));
  return out;
}

std::size_t LockstepInbox::pending() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return buffered_.size();
}

PeriodicSchedule::PeriodicSchedule(double period) : period_(period) {
  if (!(period > 0 && std::isfinite(period))) {
    throw std::invalid_argument("periodic work: expected a period > 0 s, got " +
                                std::to_string(period));
  }
}

bool PeriodicSchedule::due(double t) {
  // A relative tolerance keeps t = k * period (accumulated in steps of dt) on time.
  const double eps = 1e-9 * std::max(1.0, std::abs(t));
  if (!(t + eps >= static_cast<double>(next_) * period_)) return false;
  next_ = static_cast<std::uint64_t>(std::floor((t + eps) / period_)) + 1;
  return true;
}

}  // namespace hameritt::sim
