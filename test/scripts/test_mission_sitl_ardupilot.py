#!/usr/bin/python3
"""ArduPilot SITL's JSON interface through the simulator node (autopilot:=ardupilot), flown by
the stand-in (ardupilot_standin.py: one 40-byte servo packet per frame over UDP, one JSON line
back):

  * the stand-in arms, climbs to 10 m and holds 10 +- 0.5 m for 30 s of sim time, lands and
    disarms (judged on /uav/odom); each JSON line is one line with one sensor period more;
  * a stall of 2 wall seconds advances no /clock;
  * frame counts: a repeated one is answered with the same line and no step (duplicates), a
    jump over 5 frame counts is counted as 5 missed frames, a count that goes back is a reset; packets of the
    wrong size or magic are ignored; every count equals what the test sent;
  * when the stand-in goes silent the simulator gives up after ~sitl_timeout, /clock runs on,
    and a new stand-in (frame count from 0) is served in lock-step.
Negative control run here: the hold check rejects a trace that leaves the band.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time

import rospy
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ardupilot_standin as ast  # noqa: E402
from fault_util import BIN, SCENARIO, Checks  # noqa: E402
from graph_util import (private_master_port, start_master, stop_master,  # noqa: E402
                        stop_process, wait_for)

PORT = private_master_port(28000)
UDP_PORT = 39002 + (os.getpid() % 500) * 10
check = Checks()


class Watch:
    def __init__(self):
        self.lock = threading.Lock()
        self.clock, self.odom, self.counters = [], [], {}
        rospy.Subscriber("/clock", Clock, self.on_clock, queue_size=1000, tcp_nodelay=True)
        rospy.Subscriber("/uav/odom", Odometry, self.on_odom, queue_size=1000)
        rospy.Subscriber("/simulator/autopilot_counters", String,
                         lambda m: setattr(self, "counters", json.loads(m.data)))

    def on_clock(self, m):
        with self.lock:
            self.clock.append((time.time(), m.clock.to_sec()))

    def on_odom(self, m):
        with self.lock:
            self.odom.append((m.header.stamp.to_sec(), m.pose.pose.position.z))

    def sim_time(self):
        with self.lock:
            return self.clock[-1][1] if self.clock else 0.0


def holds(trace, start, span, target, tol):
    window = [z for t, z in trace if start <= t <= start + span]
    if len(window) < span * 10:
        return False, "only %d samples in the window" % len(window)
    worst = max(abs(z - target) for z in window)
    return worst <= tol, "worst deviation %.3f m over %d samples" % (worst, len(window))


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_sitl_ardupilot.")
    core = start_master(PORT)
    sim = None
    log = os.path.join(tmp, "simulator.log")
    try:
        sim = subprocess.Popen(
            [os.path.join(BIN, "simulator"), "__name:=simulator",
             "_sim_config:=%s/sim_config.json" % SCENARIO, "_cameras:=false",
             "_autopilot:=ardupilot", "_ardupilot_port:=%d" % (UDP_PORT - 10), "_instance:=1",
             "_real_time_factor:=0", "_duration:=100000", "_sitl_timeout:=3"],
            stdout=open(log, "w"), stderr=subprocess.STDOUT,
            env=dict(os.environ, ROSCONSOLE_STDOUT_LINE_BUFFERED="1"))
        rospy.init_node("sitl_ardupilot_test", anonymous=True, disable_signals=True)
        watch = Watch()
        wait_for(lambda: "waiting for ArduPilot on UDP 127.0.0.1:%d" % UDP_PORT in open(log).read(),
                 60, "the simulator's ArduPilot port")
        wait_for(lambda: watch.sim_time() > 0.5, 60, "the free-wheeling clock")
        t_connect = watch.sim_time()

        ap = ast.ArduPilotStandin(UDP_PORT)
        sent = {"bad_size": 0, "bad_magic": 0, "duplicates": 0, "missed": 0}
        stall = {}

        def hook(a, t):
            if a.phase == "idle" and a.frame == 100:
                # Bad packets: no reply may come, and nothing changes.
                a.udp.sendto(b"\x1a\x48" + bytes(20), a.addr)
                a.udp.sendto(ast.servo_packet(a.frame, a.pwm, magic=12345), a.addr)
                sent["bad_size"] += 1
                sent["bad_magic"] += 1
                # A duplicate of the last frame: the same line again, no step.
                again = a.exchange(frame=a.frame)
                sent["duplicates"] += 1
                check(again["timestamp"] == t, "the duplicate's reply is not the same state "
                      "(%.6f vs %.6f)" % (again["timestamp"], t))
            if a.phase == "idle" and a.frame == 150:
                a.frame += 5  # the next packet skips 5 frame counts: 5 missed
                sent["missed"] += 5
            if a.phase == "hold" and "wall" not in stall and t - a.hold_start > 10.0:
                stall["sim"], stall["wall"] = t, time.time()
                time.sleep(2.0)
                stall["end"] = time.time()

        t_end = ap.run_udp(stall_hook=hook)
        print("flight: connected at sim ~%.1f s, ended at sim %.3f s; %d JSON lines; stand-in "
              "checks: %s" % (t_connect, t_end, ap.lines, "; ".join(ap.problems) or "all passed"))
        check(ap.done and ap.was_armed, "the stand-in did not arm, land and disarm")
        check(not ap.problems, "stand-in checks: %s" % ap.problems)
        with watch.lock:
            odom, clock = list(watch.odom), list(watch.clock)
        z0 = [z for t, z in odom if t <= ap.t0]
        z0 = z0[-1] if z0 else odom[0][1]
        trace = [(t, z - z0) for t, z in odom]
        ok, why = holds(trace, ap.hold_start + 2.0, 30.0, 10.0, 0.5)
        print("hold: 30 s from sim %.1f s at 10 +- 0.5 m: %s (%s)" % (
            ap.hold_start + 2.0, "held" if ok else "NOT held", why))
        check(ok, "the hold: " + why)
        bad = [(t, z + (0.8 if abs(t - ap.hold_start - 12) < 0.1 else 0)) for t, z in trace]
        check(not holds(bad, ap.hold_start + 2.0, 30.0, 10.0, 0.5)[0],
              "negative control: a 0.8 m excursion passes the hold check")
        final = [z for t, z in trace if t >= t_end - 0.5]
        print("final height %.3f m" % (final[-1] if final else -1))
        check(final and abs(final[-1]) < 0.1, "the UAV is not back on the ground")
        during = [s for w, s in clock if stall["wall"] + 0.1 <= w <= stall["end"] - 0.05]
        before = [s for w, s in clock if w <= stall["wall"]]
        advance = (max(during) - before[-1]) if during and before else 0.0
        print("stall: %.1f wall s at sim %.3f s; /clock messages during it %d, advance %.6f s" % (
            stall["end"] - stall["wall"], stall["sim"], len(during), advance))
        check(advance == 0.0 and not during, "sim time advanced during the stall")

        # A reset: the frame count goes back (ArduPilot restarted), answered and stepped.
        r = ap.exchange(frame=3)
        check(abs(r["timestamp"] - t_end - 0.004) < 1e-9, "a reset frame was not stepped")
        # Silent: the simulator gives up after ~sitl_timeout and runs on.
        wait_for(lambda: "no servo packet for 3 wall s" in open(log).read(), 20,
                 "the simulator to give up on the silent stand-in")
        t0 = watch.sim_time()
        time.sleep(0.5)
        t1 = watch.sim_time()
        print("after the stand-in went silent: /clock %.3f -> %.3f s in 0.5 wall s" % (t0, t1))
        check(t1 > t0, "/clock stopped after the stand-in went silent")
        ap2 = ast.ArduPilotStandin(UDP_PORT)
        stamps = [ap2.exchange(frame=i)["timestamp"] for i in range(100)]
        steps = {round(b - a, 9) for a, b in zip(stamps, stamps[1:])}
        print("new stand-in: %d lock-step exchanges, timestamp steps %s" % (len(stamps), steps))
        check(steps == {0.004}, "the new stand-in was not served in lock-step")
        time.sleep(1.2)

        c = watch.counters
        print("simulator counters: %s" % json.dumps(c, sort_keys=True))
        valid = ap.sensors + sent["duplicates"] + 1 + 100  # flight, duplicate, reset, new stand-in
        check(c.get("bad_size") == sent["bad_size"], "bad_size %s" % c.get("bad_size"))
        check(c.get("bad_magic") == sent["bad_magic"], "bad_magic %s" % c.get("bad_magic"))
        check(c.get("duplicates") == sent["duplicates"], "duplicates %s" % c.get("duplicates"))
        check(c.get("missed_frames") == sent["missed"], "missed_frames %s" % c.get("missed_frames"))
        check(c.get("resets") == 1, "resets %s" % c.get("resets"))
        check(c.get("stalls") == 1, "stalls %s (the silent stand-in)" % c.get("stalls"))
        check(c.get("packets") == valid, "packets %s, sent %d valid" % (c.get("packets"), valid))
        check(c.get("lockstep_steps") == valid - sent["duplicates"],
              "lockstep_steps %s" % c.get("lockstep_steps"))
        check(c.get("state_messages") == valid, "state_messages %s" % c.get("state_messages"))
        check(c.get("out_of_range_pwm") == 0, "out_of_range_pwm %s" % c.get("out_of_range_pwm"))
    finally:
        stop_process(sim)
        stop_master(core)
        if not check.fails:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary(tmp)


if __name__ == "__main__":
    sys.exit(main())
