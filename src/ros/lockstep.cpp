#include "hameritt/ros/lockstep.h"

#include <ros/master.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include "hameritt/scenario/error.h"

namespace hameritt::ros_wrappers {

namespace {

constexpr const char* kTurnTopic = "/lockstep/turn";
constexpr const char* kAckTopic = "/lockstep/ack";

std::string describe(const std::vector<sim::StreamCount>& streams) {
  std::string out;
  for (const auto& s : streams) {
    if (!out.empty()) out += ", ";
    out += std::to_string(s.count) + " on " + s.topic + " from " + s.publisher;
  }
  return out;
}

// The master's view: nodes publishing and subscribing, by topic. False when it cannot be asked.
bool systemState(std::map<std::string, std::set<std::string>>* publishers,
                 std::map<std::string, std::set<std::string>>* subscribers) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", args, result, payload, false)) return false;
  auto read = [](XmlRpc::XmlRpcValue& list, std::map<std::string, std::set<std::string>>* out) {
    for (int i = 0; i < list.size(); ++i) {
      XmlRpc::XmlRpcValue& entry = list[i];
      std::set<std::string>& nodes = (*out)[static_cast<std::string>(entry[0])];
      for (int j = 0; j < entry[1].size(); ++j) nodes.insert(static_cast<std::string>(entry[1][j]));
    }
  };
  read(payload[0], publishers);
  read(payload[1], subscribers);
  return true;
}

}  // namespace

LockstepGate::LockstepGate(ros::NodeHandle& nh, ros::NodeHandle& pnh, Role role) : role_(role) {
  // The private parameters override the launch-wide /lockstep and /lockstep_timeout.
  pnh.param("lockstep", enabled_, ros::param::param("/lockstep", false));
  pnh.param("lockstep_timeout", timeout_, ros::param::param("/lockstep_timeout", timeout_));
  if (!(timeout_ > 0 && std::isfinite(timeout_))) {
    throw scenario::ConfigError("~lockstep_timeout: expected wall seconds > 0, got " +
                                std::to_string(timeout_));
  }
  if (!enabled_) return;
  name_ = ros::this_node::getName();
  if (role_ == Role::kParticipant) {
    ros::SubscribeOptions ops;
    ops.init<hameritt::LockstepTurn>(
        kTurnTopic, 100, [this](const hameritt::LockstepTurn::ConstPtr& m) { onTurnMsg(m); });
    ops.callback_queue = &recv_queue_;
    ops.transport_hints = ros::TransportHints().tcpNoDelay();
    turn_sub_ = nh.subscribe(ops);
    ack_pub_ = nh.advertise<hameritt::LockstepAck>(kAckTopic, 100);
  } else {
    turn_pub_ = nh.advertise<hameritt::LockstepTurn>(kTurnTopic, 100);
    ros::SubscribeOptions ops;
    ops.init<hameritt::LockstepAck>(kAckTopic, 1000,
                                    [this](const hameritt::LockstepAck::ConstPtr& m) { onAck(m); });
    ops.callback_queue = &recv_queue_;
    ops.transport_hints = ros::TransportHints().tcpNoDelay();
    ack_sub_ = nh.subscribe(ops);
  }
  recv_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &recv_queue_);
  recv_spinner_->start();
  ROS_INFO("%s: lock-step %s", name_.c_str(),
           role_ == Role::kParticipant ? "participant: waiting for turns" : "coordinator");
}

LockstepGate::~LockstepGate() {
  if (recv_spinner_) recv_spinner_->stop();
}

void LockstepGate::watch(const ros::Publisher& p) {
  if (!enabled_ || !p) return;
  watched_.push_back({p.getTopic(), true, [p] { return static_cast<int>(p.getNumSubscribers()); }});
}

void LockstepGate::count(const std::string& topic, std::uint64_t n) {
  if (enabled_) published_.add(topic, n);
}

void LockstepGate::every(ros::NodeHandle& nh, double period, std::function<void()> fn, bool wall) {
  if (enabled_) {
    periodic_.push_back({sim::PeriodicSchedule(period), std::move(fn)});
  } else if (wall) {
    wall_timers_.push_back(
        nh.createWallTimer(ros::WallDuration(period), [fn](const ros::WallTimerEvent&) { fn(); }));
  } else {
    timers_.push_back(
        nh.createTimer(ros::Duration(period), [fn](const ros::TimerEvent&) { fn(); }));
  }
}

void LockstepGate::onTurn(std::function<void(const ros::Time&)> fn) {
  turn_hooks_.push_back(std::move(fn));
}

// ---------------------------------------------------------------------------------------------
// Participant

void LockstepGate::onTurnMsg(const hameritt::LockstepTurn::ConstPtr& msg) {
  if (msg->node != name_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_turn_ = *msg;
  }
  cv_.notify_all();
}

void LockstepGate::sendAck(std::uint8_t state, std::uint64_t cycle) {
  hameritt::LockstepAck a;
  a.state = state;
  a.cycle = cycle;
  a.node = name_;
  for (const auto& [topic, n] : published_.counts()) {
    a.topics.push_back(topic);
    a.counts.push_back(n);
  }
  ack_pub_.publish(a);
}

void LockstepGate::spinOnce(double timeout) {
  ros::CallbackQueue* global = ros::getGlobalCallbackQueue();
  if (!enabled_ || role_ != Role::kParticipant) {
    global->callAvailable(ros::WallDuration(timeout));
    return;
  }
  if (!done_cycle_ && !left_ && (ros::WallTime::now() - last_join_).toSec() >= 0.5) {
    last_join_ = ros::WallTime::now();
    sendAck(hameritt::LockstepAck::JOINED, 0);
  }
  std::optional<hameritt::LockstepTurn> turn;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, std::chrono::duration<double>(timeout),
                 [this] { return pending_turn_.has_value(); });
    turn.swap(pending_turn_);
  }
  if (turn) runTurn(*turn);
  global->callAvailable(ros::WallDuration(0));
}

void LockstepGate::spin() {
  while (ros::ok()) spinOnce(enabled_ ? 0.05 : 0.1);
  leave();
}

void LockstepGate::leave() {
  if (!enabled_ || role_ != Role::kParticipant || left_) return;
  left_ = true;
  sendAck(hameritt::LockstepAck::LEAVING, done_cycle_.value_or(0));
  // The ack goes out on roscpp's own threads: give it a moment before the node goes down.
  ros::WallDuration(0.2).sleep();
}

void LockstepGate::runTurn(const hameritt::LockstepTurn& turn) {
  if (done_cycle_ && turn.cycle <= *done_cycle_) {
    sendAck(hameritt::LockstepAck::DONE, *done_cycle_);  // a turn sent again: answer again
    return;
  }
  if (turn.cycle == 0) {
    waitForConnections();
    done_cycle_ = 0;
    sendAck(hameritt::LockstepAck::DONE, 0);
    return;
  }
  if (ros::Time::isSimTime()) {
    // The clock of the cycle was published before the turn; roscpp takes it on its own thread.
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_);
    while (ros::ok() && ros::Time::now() < turn.stamp) {
      if (ros::WallTime::now() > deadline) {
        ROS_ERROR("%s: lock-step turn %llu: the clock is still at %.6f s, not %.6f s, after %.0f s",
                  name_.c_str(), static_cast<unsigned long long>(turn.cycle),
                  ros::Time::now().toSec(), turn.stamp.toSec(), timeout_);
        break;
      }
      ros::WallDuration(0.0002).sleep();
    }
  }
  std::vector<sim::StreamCount> totals;
  for (std::size_t i = 0;
       i < turn.topics.size() && i < turn.publishers.size() && i < turn.counts.size(); ++i) {
    totals.push_back({turn.topics[i], turn.publishers[i], turn.counts[i]});
  }
  waitForInbox(totals, "turn " + std::to_string(turn.cycle));
  for (const auto& hook : turn_hooks_) hook(turn.stamp);
  for (auto& deliver : inbox_.take(turn.order)) deliver();
  const double t = turn.stamp.toSec();
  for (auto& p : periodic_) {
    if (p.schedule.due(t)) p.fn();
  }
  done_cycle_ = turn.cycle;
  sendAck(hameritt::LockstepAck::DONE, turn.cycle);
}

void LockstepGate::waitForConnections() {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_);
  while (ros::ok()) {
    std::map<std::string, std::set<std::string>> pubs, subs;
    std::string missing;
    if (systemState(&pubs, &subs)) {
      for (const auto& w : watched_) {
        const std::size_t expected = w.publisher ? subs[w.topic].size() : pubs[w.topic].size();
        const int have = w.connections();
        if (have < static_cast<int>(expected)) {
          missing += (missing.empty() ? "" : ", ") + w.topic + " (" + std::to_string(have) +
                     " of " + std::to_string(expected) +
                     (w.publisher ? " subscribers)" : " publishers)");
        }
      }
      if (missing.empty()) return;
    } else {
      missing = "(the master does not answer)";
    }
    if (ros::WallTime::now() > deadline) {
      ROS_ERROR(
          "%s: lock-step: still not connected after %.0f s: %s; going on (messages sent "
          "before a connection are lost: the run may not be reproducible)",
          name_.c_str(), timeout_, missing.c_str());
      return;
    }
    ros::WallDuration(0.05).sleep();
  }
}

bool LockstepGate::waitForInbox(const std::vector<sim::StreamCount>& totals,
                                const std::string& what) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_);
  while (true) {
    const std::vector<sim::StreamCount> missing = inbox_.missing(totals);
    if (missing.empty()) return true;
    if (!ros::ok()) return false;
    if (ros::WallTime::now() > deadline) {
      ROS_ERROR(
          "%s: lock-step %s: still missing after %.0f s: %s; going on without them (the run "
          "is no longer reproducible)",
          name_.c_str(), what.c_str(), timeout_, describe(missing).c_str());
      return false;
    }
    ros::WallDuration(0.0001).sleep();
  }
}

// ---------------------------------------------------------------------------------------------
// Coordinator

void LockstepGate::onAck(const hameritt::LockstepAck::ConstPtr& msg) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    hameritt::LockstepAck& last = acks_[msg->node];
    // A LEAVING stays; a JOINED sent before a DONE never overtakes it (one connection, in order).
    if (last.state == hameritt::LockstepAck::LEAVING && !last.node.empty()) return;
    last = *msg;
  }
  cv_.notify_all();
}

std::vector<std::string> LockstepGate::participants() const { return order_; }

bool LockstepGate::waitForAck(const std::string& node, std::uint64_t cycle, double timeout,
                              bool& left) {
  auto answered = [&] {
    const auto it = acks_.find(node);
    if (it == acks_.end()) return false;
    const auto& a = it->second;
    return a.state == hameritt::LockstepAck::LEAVING ||
           (a.state == hameritt::LockstepAck::DONE && a.cycle >= cycle);
  };
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
  std::unique_lock<std::mutex> lock(mutex_);
  // In slices, so that a shutdown is noticed.
  while (!answered()) {
    const double rest = (deadline - ros::WallTime::now()).toSec();
    if (rest <= 0 || !ros::ok()) return false;
    cv_.wait_for(lock, std::chrono::duration<double>(std::min(rest, 0.1)));
  }
  const hameritt::LockstepAck a = acks_[node];
  lock.unlock();
  left = a.state == hameritt::LockstepAck::LEAVING;
  std::vector<std::pair<std::string, std::uint64_t>> counts;
  for (std::size_t i = 0; i < a.topics.size() && i < a.counts.size(); ++i) {
    counts.emplace_back(a.topics[i], a.counts[i]);
  }
  try {
    tally_.update(node, counts);
  } catch (const std::exception& e) {
    ROS_ERROR("%s: lock-step: %s", name_.c_str(), e.what());
  }
  return true;
}

bool LockstepGate::giveTurn(std::uint64_t cycle, const ros::Time& stamp, const std::string& node,
                            bool resend) {
  hameritt::LockstepTurn m;
  m.cycle = cycle;
  m.stamp = stamp;
  m.node = node;
  m.order.push_back(name_);
  m.order.insert(m.order.end(), order_.begin(), order_.end());
  for (const auto& s : tally_.streams()) {
    m.topics.push_back(s.topic);
    m.publishers.push_back(s.publisher);
    m.counts.push_back(s.count);
  }
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_);
  while (ros::ok()) {
    turn_pub_.publish(m);
    const double left_s = (deadline - ros::WallTime::now()).toSec();
    if (left_s <= 0) break;
    bool left = false;
    if (waitForAck(node, cycle, resend ? std::min(0.5, left_s) : left_s, left)) {
      if (left) {
        ROS_INFO("%s: lock-step: %s left the mission at cycle %llu", name_.c_str(), node.c_str(),
                 static_cast<unsigned long long>(cycle));
        order_.erase(std::remove(order_.begin(), order_.end(), node), order_.end());
      }
      return true;
    }
    if (!resend) break;
  }
  if (!ros::ok()) return false;
  ROS_ERROR(
      "%s: lock-step: %s did not answer turn %llu within %.0f s: taken out of the turn "
      "order (the run is no longer reproducible)",
      name_.c_str(), node.c_str(), static_cast<unsigned long long>(cycle), timeout_);
  order_.erase(std::remove(order_.begin(), order_.end(), node), order_.end());
  return false;
}

bool LockstepGate::start(const std::vector<std::string>& participants) {
  order_.clear();
  for (const auto& p : participants) {
    if (std::find(order_.begin(), order_.end(), p) == order_.end()) order_.push_back(p);
  }
  // Join: every participant constructed (all its publishers and subscriptions made).
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_);
  {
    std::unique_lock<std::mutex> lock(mutex_);
    while (ros::ok()) {
      std::string missing;
      for (const auto& p : order_) {
        if (!acks_.count(p)) missing += (missing.empty() ? "" : ", ") + p;
      }
      if (missing.empty()) break;
      if (ros::WallTime::now() > deadline) {
        ROS_ERROR("%s: lock-step: %s did not join within %.0f s: going on without them",
                  name_.c_str(), missing.c_str(), timeout_);
        order_.erase(std::remove_if(order_.begin(), order_.end(),
                                    [this](const std::string& p) { return !acks_.count(p); }),
                     order_.end());
        break;
      }
      cv_.wait_for(lock, std::chrono::milliseconds(50));
    }
  }
  if (!ros::ok()) return false;
  std::string joined;
  for (const auto& p : order_) joined += (joined.empty() ? "" : ", ") + p;
  ROS_INFO("%s: lock-step: turn order %s; connecting", name_.c_str(), joined.c_str());
  // Connect: each participant, then the coordinator, waits for its connections.
  for (const auto& p : std::vector<std::string>(order_)) giveTurn(0, ros::Time(0), p, true);
  waitForConnections();
  tally_.update(name_, published_.counts());
  ROS_INFO("%s: lock-step: connected, %zu participants", name_.c_str(), order_.size());
  return ros::ok();
}

void LockstepGate::beforeCycle() {
  waitForInbox(tally_.streams(), "the simulator's inputs");
  std::vector<std::string> order{name_};
  order.insert(order.end(), order_.begin(), order_.end());
  for (auto& deliver : inbox_.take(order)) deliver();
}

bool LockstepGate::afterCycle(std::uint64_t cycle, const ros::Time& stamp) {
  tally_.update(name_, published_.counts());
  for (const auto& p : std::vector<std::string>(order_)) {
    giveTurn(cycle, stamp, p, false);
    if (!ros::ok()) return false;
  }
  return ros::ok();
}

}  // namespace hameritt::ros_wrappers
