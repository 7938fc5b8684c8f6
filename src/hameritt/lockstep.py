"""Lock-step missions for rospy clients: the turn protocol of the C++ LockstepGate
(include/hameritt/ros/lockstep.h, msg/LockstepTurn.msg, msg/LockstepAck.msg).

A client makes its subscriptions, publishers and periodic work through a LockstepGate and runs
gate.spin(). Its callbacks then always run one at a time on the spinning thread:

- with the parameter ~lockstep (default: /lockstep) false, as messages arrive (each subscription
  keeps its newest queue_size messages) and periodic work on sim time;
- with it true, only in the node's turns on /lockstep/turn: the gate waits until the sim clock is
  the turn's and every message counted so far on its topics has arrived, hands them to the
  callbacks ordered by publisher (in turn order), subscription, then arrival, runs the periodic
  work that is due, and answers on /lockstep/ack with its own publication counts. The same
  scenario, mode and seed then give the same messages, so two algorithms can be compared on
  identical inputs.

The node must be in the simulator's participant list (mission.launch client_nodes:=/name).
"""

import math
import threading
import time

import rosgraph
import rospy

from hameritt.msg import LockstepAck, LockstepTurn

TURN_TOPIC = "/lockstep/turn"
ACK_TOPIC = "/lockstep/ack"


class PeriodicSchedule:
    """Due at the first check at or after each multiple of the period (sim time), once however
    many multiples were passed; as sim::PeriodicSchedule."""

    def __init__(self, period):
        if not (period > 0 and math.isfinite(period)):
            raise ValueError("periodic work: expected a period > 0 s, got %r" % period)
        self.period = float(period)
        self._next = 1

    def due(self, t):
        eps = 1e-9 * max(1.0, abs(t))
        if not t + eps >= self._next * self.period:
            return False
        self._next = int(math.floor((t + eps) / self.period)) + 1
        return True


class CountedPublisher:
    """A rospy.Publisher whose publications the gate counts (lock-step turns carry the counts)."""

    def __init__(self, gate, publisher):
        self._gate = gate
        self.impl = publisher
        self.resolved_name = publisher.resolved_name

    def publish(self, msg):
        self.impl.publish(msg)
        self._gate.count(self.resolved_name)

    def get_num_connections(self):
        return self.impl.get_num_connections()


class LockstepGate:
    """Participant side of the lock-step protocol; transparent (serial callbacks) when off."""

    def __init__(self):
        self.enabled = bool(rospy.get_param("~lockstep", rospy.get_param("/lockstep", False)))
        self.timeout = float(rospy.get_param("~lockstep_timeout",
                                             rospy.get_param("/lockstep_timeout", 120.0)))
        if not (self.timeout > 0 and math.isfinite(self.timeout)):
            raise ValueError("~lockstep_timeout: expected wall seconds > 0, got %r" % self.timeout)
        self.name = rospy.get_name()
        self._cv = threading.Condition()
        self._subs = []       # [resolved topic, callback, queue_size, {publisher: received}]
        self._buffered = []   # (sub index, publisher, arrival, msg)
        self._arrivals = 0
        self._published = {}  # resolved topic -> count
        self._periodic = []   # (PeriodicSchedule, fn)
        self._watched = []    # (is_publisher, rospy topic object)
        self._pending_turn = None
        self._done_cycle = None
        self._left = False
        self._last_join = 0.0
        if self.enabled:
            self._ack_pub = rospy.Publisher(ACK_TOPIC, LockstepAck, queue_size=100, tcp_nodelay=True)
            self._turn_sub = rospy.Subscriber(TURN_TOPIC, LockstepTurn, self._on_turn,
                                              queue_size=None, tcp_nodelay=True)
            rospy.on_shutdown(self.leave)
            rospy.loginfo("%s: lock-step participant: waiting for turns", self.name)

    # ---- what a client uses
    def subscribe(self, topic, msg_class, callback, queue_size=10):
        """A subscription whose callback runs in spin() (in this node's turns in lock-step)."""
        index = len(self._subs)
        sub = rospy.Subscriber(topic, msg_class, lambda m: self._receive(index, m),
                               queue_size=None, buff_size=1 << 24, tcp_nodelay=True)
        self._subs.append([sub.resolved_name, callback, queue_size, {}])
        self._watched.append((False, sub))
        return sub

    def advertise(self, topic, msg_class, queue_size=10, latch=False):
        """A publisher whose publications are counted; publish only from callbacks and periodic
        work (in lock-step nothing is published between turns)."""
        # In lock-step a message rospy dropped from a full queue would stall the receiver's turn.
        pub = rospy.Publisher(topic, msg_class, queue_size=10000 if self.enabled else queue_size,
                              latch=latch, tcp_nodelay=True)
        self._watched.append((True, pub))
        return CountedPublisher(self, pub)

    def count(self, topic, n=1):
        with self._cv:
            self._published[topic] = self._published.get(topic, 0) + n

    def every(self, period, fn):
        """Runs fn() every `period` s of sim time (at the first turn at or after each multiple)."""
        self._periodic.append((PeriodicSchedule(period), fn))

    def spin(self):
        """Runs callbacks and periodic work until ROS shuts down, then leaves the turn order."""
        while not rospy.is_shutdown():
            self.spin_once(0.05 if self.enabled else 0.005)
        self.leave()

    def spin_once(self, timeout):
        if not self.enabled:
            with self._cv:
                self._cv.wait_for(lambda: self._buffered, timeout)
                msgs, self._buffered = self._buffered, []
            for sub, _, _, msg in msgs:
                self._subs[sub][1](msg)
            self._run_periodic(rospy.get_time())
            return
        if self._done_cycle is None and not self._left and time.time() - self._last_join >= 0.5:
            self._last_join = time.time()
            self._send_ack(LockstepAck.JOINED, 0)
        with self._cv:
            self._cv.wait_for(lambda: self._pending_turn is not None, timeout)
            turn, self._pending_turn = self._pending_turn, None
        if turn is not None:
            self._run_turn(turn)

    def leave(self):
        """Tells the simulator this node is leaving (call it before exiting on your own)."""
        if not self.enabled or self._left:
            return
        self._left = True
        self._send_ack(LockstepAck.LEAVING, self._done_cycle or 0)
        rospy.rostime.wallsleep(0.2)  # the ack goes out on rospy's own threads

    # ---- internals
    def _receive(self, index, msg):
        publisher = getattr(msg, "_connection_header", {}).get("callerid", "")
        with self._cv:
            sub = self._subs[index]
            sub[3][publisher] = sub[3].get(publisher, 0) + 1
            self._buffered.append((index, publisher, self._arrivals, msg))
            self._arrivals += 1
            if not self.enabled and sub[2]:
                mine = [b for b in self._buffered if b[0] == index]
                if len(mine) > sub[2]:  # free running: keep the newest queue_size
                    self._buffered.remove(mine[0])
            self._cv.notify_all()

    def _run_periodic(self, t):
        for schedule, fn in self._periodic:
            if schedule.due(t):
                fn()

    def _on_turn(self, msg):
        if msg.node != self.name:
            return
        with self._cv:
            self._pending_turn = msg
            self._cv.notify_all()

    def _send_ack(self, state, cycle):
        with self._cv:
            counts = sorted(self._published.items())
        try:
            self._ack_pub.publish(LockstepAck(state=state, cycle=cycle, node=self.name,
                                              topics=[t for t, _ in counts],
                                              counts=[n for _, n in counts]))
        except rospy.ROSException:  # shutting down: the simulator drops us after its timeout
            pass

    def _run_turn(self, turn):
        if self._done_cycle is not None and turn.cycle <= self._done_cycle:
            self._send_ack(LockstepAck.DONE, self._done_cycle)  # a turn sent again
            return
        if turn.cycle == 0:
            self._wait_for_connections()
            self._done_cycle = 0
            self._send_ack(LockstepAck.DONE, 0)
            return
        self._wait(lambda: rospy.get_rostime() >= turn.stamp, "the clock at %.6f s" % turn.stamp.to_sec())
        totals = list(zip(turn.topics, turn.publishers, turn.counts))
        with self._cv:  # _receive notifies
            if not self._cv.wait_for(lambda: not self._missing(totals), self.timeout):
                rospy.logerr("%s: lock-step turn %d: messages still missing after %.0f s; going "
                             "on without them (the run is no longer reproducible)",
                             self.name, turn.cycle, self.timeout)
        with self._cv:
            msgs, self._buffered = self._buffered, []
        rank = {name: i for i, name in enumerate(turn.order)}
        last = len(turn.order)
        msgs.sort(key=lambda b: (rank.get(b[1], last), b[1], b[0], b[2]))
        for sub, _, _, msg in msgs:
            self._subs[sub][1](msg)
        self._run_periodic(turn.stamp.to_sec())
        self._done_cycle = turn.cycle
        if not self._left:  # a callback may have shut the node down (it has said LEAVING)
            self._send_ack(LockstepAck.DONE, turn.cycle)

    def _missing(self, totals):
        for topic, _, _, received in self._subs:
            for t, publisher, n in totals:
                if t == topic and received.get(publisher, 0) < n:
                    return True
        return False

    def _wait(self, done, what, poll=0.0002):
        deadline = time.time() + self.timeout
        while not done():
            if rospy.is_shutdown():
                return False
            if time.time() > deadline:
                rospy.logerr("%s: lock-step: still waiting for %s after %.0f s; going on (the run "
                             "is no longer reproducible)", self.name, what, self.timeout)
                return False
            time.sleep(poll)
        return True

    def _wait_for_connections(self):
        master = rosgraph.Master(self.name)

        def connected():
            try:
                pubs, subs, _ = master.getSystemState()
            except Exception:  # the master does not answer: ask again
                return False
            pubs, subs = dict(pubs), dict(subs)
            for is_pub, obj in self._watched:
                listed = (subs if is_pub else pubs).get(obj.resolved_name, [])
                if obj.get_num_connections() < len(listed):
                    return False
            return True

        self._wait(connected, "the connections of its topics", poll=0.05)
