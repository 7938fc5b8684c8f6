#pragma once
// Lock-step missions over ROS (README "Lock-step missions"; bookkeeping in sim/lockstep.h).
//
// Every node of a mission makes its subscriptions, publishers and periodic work through a
// LockstepGate. With ~lockstep false (the default) the gate is transparent: plain
// subscriptions, plain publishing, sim-time (or wall) timers, ros::spin(). With ~lockstep true:
//   - subscriptions buffer their messages in an inbox instead of calling the node;
//   - the node's publications are counted per topic;
//   - a participant (ADK, clients, planner, path player) runs its callbacks and periodic work
//     only in its turns (/lockstep/turn): it waits until every message counted so far on its
//     topics has arrived and the sim time is the turn's, handles them in the canonical order,
//     runs what is due, and answers on /lockstep/ack with its counts;
//   - the coordinator (the simulator) waits for the participants to join, connects everyone
//     (cycle 0), and then for each cycle handles its own inputs (setpoints) as they were counted,
//     steps the physics, and gives each participant its turn in ~lockstep_participants order.
// A node that does not answer within ~lockstep_timeout wall seconds is taken out of the turn
// order with an error (the run is then no longer reproducible), so nothing hangs.

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <ros/spinner.h>

#include <boost/function.hpp>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/LockstepAck.h"
#include "hameritt/LockstepTurn.h"
#include "hameritt/sim/lockstep.h"

namespace hameritt::ros_wrappers {

class LockstepGate {
 public:
  enum class Role { kParticipant, kCoordinator };

  // Reads ~lockstep (bool; default: the parameter /lockstep, else false) and ~lockstep_timeout
  // (wall s; default: /lockstep_timeout, else 120). Throws
  // scenario::ConfigError for a timeout that is not > 0.
  LockstepGate(ros::NodeHandle& nh, ros::NodeHandle& pnh, Role role = Role::kParticipant);
  ~LockstepGate();
  LockstepGate(const LockstepGate&) = delete;
  LockstepGate& operator=(const LockstepGate&) = delete;

  bool enabled() const { return enabled_; }
  // Wall seconds a turn, an ack or a connection is waited for.
  double timeout() const { return timeout_; }

  // A subscription whose callback runs at once (off) or in this node's turns (lock-step).
  template <class M>
  ros::Subscriber subscribe(ros::NodeHandle& nh, const std::string& topic, std::uint32_t queue,
                            std::function<void(const boost::shared_ptr<M const>&)> fn);
  template <class M, class T>
  ros::Subscriber subscribe(ros::NodeHandle& nh, const std::string& topic, std::uint32_t queue,
                            void (T::*fn)(const boost::shared_ptr<M const>&), T* obj) {
    return subscribe<M>(nh, topic, queue,
                        std::function<void(const boost::shared_ptr<M const>&)>(
                            [obj, fn](const boost::shared_ptr<M const>& m) { (obj->*fn)(m); }));
  }

  // A publisher whose subscribers the connect phase waits for.
  template <class M>
  ros::Publisher advertise(ros::NodeHandle& nh, const std::string& topic, std::uint32_t queue,
                           bool latch = false) {
    ros::Publisher p = nh.advertise<M>(topic, queue, latch);
    watch(p);
    return p;
  }
  // Also waits for the subscribers of a publisher made elsewhere (same topic, same node).
  void watch(const ros::Publisher& p);
  // Publishes and counts the message.
  template <class M>
  void publish(const ros::Publisher& p, const M& msg) {
    p.publish(msg);
    count(p.getTopic());
  }
  // Counts n messages published on `topic` (resolved) some other way (tf broadcasters, render
  // threads). Thread-safe.
  void count(const std::string& topic, std::uint64_t n = 1);

  // Periodic work every `period` s: a sim-time timer (a wall timer with `wall`) when off; in
  // lock-step, run in the turns at which a multiple of the period of sim time is reached.
  void every(ros::NodeHandle& nh, double period, std::function<void()> fn, bool wall = false);
  // Lock-step only: work at the start of each turn, before its messages, with the turn's time.
  void onTurn(std::function<void(const ros::Time&)> fn);

  // Participant: handles callbacks for up to `timeout` wall seconds (the global queue and, in
  // lock-step, a turn that has come).
  void spinOnce(double timeout);
  // Participant: spinOnce until ROS shuts down; then leave().
  void spin();
  // Participant: tells the coordinator this node is leaving (before ros::shutdown()).
  void leave();

  // Coordinator: waits until every participant (resolved node names, in turn order) has joined
  // and runs the connect phase. Returns false when ROS shut down meanwhile.
  bool start(const std::vector<std::string>& participants);
  // Coordinator: before the physics of a cycle, handles the coordinator's own inputs exactly as
  // counted so far.
  void beforeCycle();
  // Coordinator: after the physics of cycle `cycle` (ending at `stamp`, everything published),
  // gives each participant its turn. Returns false when ROS shut down meanwhile.
  bool afterCycle(std::uint64_t cycle, const ros::Time& stamp);
  // Coordinator: the participants still in the turn order.
  std::vector<std::string> participants() const;

 private:
  struct Periodic {
    sim::PeriodicSchedule schedule;
    std::function<void()> fn;
  };
  struct Watched {
    std::string topic;
    bool publisher = false;            // a publisher (else a subscription)
    std::function<int()> connections;  // subscribers of a publisher, publishers of a subscriber
  };

  void onTurnMsg(const hameritt::LockstepTurn::ConstPtr& msg);
  void onAck(const hameritt::LockstepAck::ConstPtr& msg);
  void runTurn(const hameritt::LockstepTurn& turn);
  void sendAck(std::uint8_t state, std::uint64_t cycle);
  // Waits (up to the timeout) until every watched publisher and subscription is connected to
  // every node the master lists on its topic.
  void waitForConnections();
  // Waits until the inbox holds every counted message of `totals`; false on timeout.
  bool waitForInbox(const std::vector<sim::StreamCount>& totals, const std::string& what);
  // Coordinator: publishes the turn (again every 0.5 s while `resend`) until `node` answers
  // for `cycle`. False on timeout or shutdown.
  bool giveTurn(std::uint64_t cycle, const ros::Time& stamp, const std::string& node, bool resend);
  bool waitForAck(const std::string& node, std::uint64_t cycle, double timeout, bool& left);

  bool enabled_ = false;
  Role role_;
  double timeout_ = 120.0;
  std::string name_;
  sim::LockstepInbox inbox_;
  sim::PublicationCounter published_;
  std::vector<Periodic> periodic_;
  std::vector<std::function<void(const ros::Time&)>> turn_hooks_;
  std::vector<Watched> watched_;
  std::vector<ros::Timer> timers_;
  std::vector<ros::WallTimer> wall_timers_;

  ros::CallbackQueue recv_queue_;
  std::unique_ptr<ros::AsyncSpinner> recv_spinner_;
  ros::Publisher turn_pub_, ack_pub_;
  ros::Subscriber turn_sub_, ack_sub_;

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  // Participant: the turn waiting to run; the last cycle done.
  std::optional<hameritt::LockstepTurn> pending_turn_;
  std::optional<std::uint64_t> done_cycle_;
  bool left_ = false;
  ros::WallTime last_join_;
  // Coordinator: the turn order, the totals, and the last ack of each node.
  std::vector<std::string> order_;
  sim::LockstepTally tally_;
  std::map<std::string, hameritt::LockstepAck> acks_;
};

template <class M>
ros::Subscriber LockstepGate::subscribe(ros::NodeHandle& nh, const std::string& topic,
                                        std::uint32_t queue,
                                        std::function<void(const boost::shared_ptr<M const>&)> fn) {
  if (!enabled_) {
    return nh.subscribe<M>(topic, queue,
                           boost::function<void(const boost::shared_ptr<M const>&)>(fn));
  }
  const std::size_t index = inbox_.addSubscription(nh.resolveName(topic));
  ros::SubscribeOptions ops;
  // Messages wait in the inbox, not in roscpp's queue: a deep queue never drops one.
  ops.initByFullCallbackType<const ros::MessageEvent<M const>&>(
      topic, std::max<std::uint32_t>(queue, 10000),
      [this, index, fn](const ros::MessageEvent<M const>& ev) {
        boost::shared_ptr<M const> msg = ev.getConstMessage();
        inbox_.receive(index, ev.getPublisherName(), [fn, msg] { fn(msg); });
      });
  ops.callback_queue = &recv_queue_;
  // Small messages go out at once (no Nagle delay): every turn waits for them.
  ops.transport_hints = ros::TransportHints().tcpNoDelay();
  ros::Subscriber s = nh.subscribe(ops);
  watched_.push_back({s.getTopic(), false, [s] { return static_cast<int>(s.getNumPublishers()); }});
  return s;
}

}  // namespace hameritt::ros_wrappers
