#pragma once
// Lock-step bookkeeping without ROS (README "Lock-step missions"). In a lock-step mission the
// simulator steps the physics one cycle at a time and then gives each participant node (ADK,
// clients, planner) a turn, in a fixed order. A turn carries how many messages every publisher
// has put on every lock-step topic so far; the participant waits until it has received all of
// those on the topics it subscribes to, handles them in a canonical order, runs the periodic
// work due at the cycle's sim time, and answers with its own publication counts. What a node
// sees, and when, then no longer depends on thread or network timing: the same scenario, mode
// and seed give the same messages.

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace hameritt::sim {

// How many messages one publisher (node name) has put on one topic (resolved name).
struct StreamCount {
  std::string topic;
  std::string publisher;
  std::uint64_t count = 0;
};

// Cumulative publication counts per topic, safe to update from any thread (render threads
// publish camera frames).
class PublicationCounter {
 public:
  // Notes n more messages on `topic`.
  void add(const std::string& topic, std::uint64_t n = 1);
  // Every topic with its count, sorted by topic.
  std::vector<std::pair<std::string, std::uint64_t>> counts() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::uint64_t> counts_;
};

// The coordinator's running totals over every participant and itself.
class LockstepTally {
 public:
  // Takes `publisher`'s cumulative counts. Counts never go back: a smaller count than one taken
  // before throws std::invalid_argument naming the topic.
  void update(const std::string& publisher,
              const std::vector<std::pair<std::string, std::uint64_t>>& counts);
  // Every stream, sorted by topic, then publisher.
  std::vector<StreamCount> streams() const;

 private:
  std::map<std::pair<std::string, std::string>, std::uint64_t> totals_;
};

// A participant's messages received between its turns. receive() may be called from any
// thread; take() hands them out in the canonical order: by the rank of the publisher (its
// position in the turn order, unlisted publishers after every listed one, by name), then by the
// order in which the subscriptions were added, then by arrival (one publisher's messages on one
// topic arrive in the order it published them).
class LockstepInbox {
 public:
  // Adds a subscription to `topic` (resolved name) and returns its index.
  std::size_t addSubscription(const std::string& topic);
  // Buffers one message of subscription `sub` from `publisher`; `deliver` runs the node's
  // callback on it when taken.
  void receive(std::size_t sub, const std::string& publisher, std::function<void()> deliver);
  // The streams of `totals` on this inbox's topics of which fewer messages have arrived than
  // were published (count = how many are still missing): empty when the turn can start.
  std::vector<StreamCount> missing(const std::vector<StreamCount>& totals) const;
  // Every buffered message, in the canonical order for the turn order `order`.
  std::vector<std::function<void()>> take(const std::vector<std::string>& order);
  // Messages buffered now.
  std::size_t pending() const;

 private:
  struct Subscription {
    std::string topic;
    std::map<std::string, std::uint64_t> received;  // by publisher
  };
  struct Message {
    std::size_t sub = 0;
    std::string publisher;
    std::uint64_t arrival = 0;
    std::function<void()> deliver;
  };
  mutable std::mutex mutex_;
  std::vector<Subscription> subs_;
  std::vector<Message> buffered_;
  std::uint64_t arrivals_ = 0;
};

// Periodic work on sim time, as a sim-time timer of this period started at t = 0 would run it:
// due at the first turn at or after each multiple of the period, once however many were passed.
class PeriodicSchedule {
 public:
  // Throws std::invalid_argument unless period > 0 and finite.
  explicit PeriodicSchedule(double period);
  // True when the work is due at sim time t; the next is then the first multiple after t.
  bool due(double t);
  double period() const { return period_; }

 private:
  double period_;
  std::uint64_t next_ = 1;  // the next multiple of the period due
};

}  // namespace hameritt::sim
