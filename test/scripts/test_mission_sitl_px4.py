#!/usr/bin/python3
"""PX4 software-in-the-loop through the simulator node (autopilot:=px4), flown by the stand-in
autopilot (px4_standin.py), whose every received frame is decoded by the independent decoder
(mavlink_judge.py, python3-crcmod):

  * the stand-in arms, climbs to 10 m and holds 10 +- 0.5 m for 30 s of sim time, lands and
    disarms (heights judged on the simulator's ground truth, /uav/odom; the stand-in flies on
    its sensors only), and every HIL_SENSOR passed its checks (masks, one sensor period per
    message, at rest -9.81 m/s^2 and the origin's standard-atmosphere pressure);
  * while it stalls for 2 wall seconds during the hold, /clock does not advance;
  * bad input before arming (garbage bytes, a bad-CRC frame, a frame cut short, a NaN actuator
    message, a second client that is refused) is ignored: the flight goes on, and the
    simulator's counters (~autopilot_counters) equal what the judge counts replaying the same
    byte stream;
  * after the stand-in disconnects /clock keeps advancing; a client that connects and says
    nothing is dropped and counted; a new stand-in connects and is served in lock-step;
  * every frame the simulator sent decodes (no stray byte, no bad CRC), and each message kind
    came at its rate (HIL_GPS at 10 Hz of sim time, HIL_STATE_QUATERNION as asked);
  * mission.launch autopilot:=px4 px4_port:= instance:= hands the simulator those parameters.
Negative controls run here: the judge rejects a corrupted frame; the hold check rejects a
trace that leaves the band.
"""
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

import rospy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mavlink_judge as mj  # noqa: E402
import px4_standin  # noqa: E402
from fault_util import BIN, SCENARIO, Checks  # noqa: E402
from graph_util import (private_master_port, start_master, stop_master,  # noqa: E402
                        stop_process, wait_for)

PORT = private_master_port(26000)
SIM_PORT = 34560 + os.getpid() % 1000
check = Checks()


class Watch:
    """What the test sees of the simulator through ROS."""

    def __init__(self):
        self.lock = threading.Lock()
        self.clock = []  # (wall, sim)
        self.odom = []   # (sim, z)
        self.counters = {}
        rospy.Subscriber("/clock", Clock, self.on_clock, queue_size=1000, tcp_nodelay=True)
        rospy.Subscriber("/uav/odom", Odometry, self.on_odom, queue_size=1000)
        rospy.Subscriber("/simulator/autopilot_counters", String, self.on_counters)

    def on_clock(self, m):
        with self.lock:
            self.clock.append((time.time(), m.clock.to_sec()))

    def on_odom(self, m):
        with self.lock:
            self.odom.append((m.header.stamp.to_sec(), m.pose.pose.position.z))

    def on_counters(self, m):
        self.counters = json.loads(m.data)

    def sim_time(self):
        with self.lock:
            return self.clock[-1][1] if self.clock else 0.0


def holds(trace, start, span, target, tol):
    """Whether every (t, z) sample in [start, start + span] is within tol of target, and the
    samples cover the span."""
    window = [z for t, z in trace if start <= t <= start + span]
    if len(window) < span * 10:
        return False, "only %d samples in the window" % len(window)
    worst = max(abs(z - target) for z in window)
    return worst <= tol, "worst deviation %.3f m over %d samples" % (worst, len(window))


def dump_params(tmp):
    out = subprocess.run(
        ["roslaunch", "--dump-params", "hameritt", "mission.launch", "autopilot:=px4",
         "px4_port:=4570", "instance:=2"], capture_output=True, text=True, timeout=120)
    got = out.stdout
    ok = all(s in got for s in ("/simulator/autopilot: px4", "/simulator/px4_port: 4570",
                                "/simulator/instance: 2"))
    print("mission.launch autopilot:=px4 px4_port:=4570 instance:=2 -> simulator params: %s" % (
        "as given" if ok else "MISSING: " + got[-500:]))
    check(ok, "mission.launch does not hand autopilot/px4_port/instance to the simulator")


def bad_input(ap, hooks):
    """Sent by the stand-in just before it arms. Returns the byte chunks for the judge's replay
    (a truncated frame is followed by 0.3 s of silence, which the simulator treats as
    abandoned)."""
    garbage = bytes([0x01, 0x02, 0x55, 0xAA, 0x10, 0x20, 0x30])
    ap.send_raw(garbage)
    bad = bytearray(mj.encode("HEARTBEAT", 9, 1, 1, type=2, autopilot=12, mavlink_version=3))
    bad[-1] ^= 0xFF
    ap.send_raw(bytes(bad))
    cut = mj.encode("HEARTBEAT", 10, 1, 1, type=2, autopilot=12, mavlink_version=3)[:7]
    ap.send_raw(cut)
    hooks["cut_at"] = len(ap.sent)
    time.sleep(0.3)
    ap.send("HIL_ACTUATOR_CONTROLS", controls=[float("nan")] * 4 + [0.0] * 12, mode=128, flags=1)
    # A second client while the stand-in is connected: refused.
    extra = socket.create_connection(("127.0.0.1", SIM_PORT), timeout=5)
    time.sleep(0.1)
    extra.close()


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_sitl_px4.")
    core = start_master(PORT)
    sim = None
    log = os.path.join(tmp, "simulator.log")
    try:
        assert mj.self_check() == 10
        dump_params(tmp)
        sim = subprocess.Popen(
            [os.path.join(BIN, "simulator"), "__name:=simulator",
             "_sim_config:=%s/sim_config.json" % SCENARIO, "_cameras:=false",
             "_autopilot:=px4", "_px4_port:=%d" % (SIM_PORT - 1), "_instance:=1",
             "_real_time_factor:=0", "_duration:=100000", "_sitl_timeout:=5",
             "_sitl_silent_timeout:=1.5"],
            stdout=open(log, "w"), stderr=subprocess.STDOUT,
            env=dict(os.environ, ROSCONSOLE_STDOUT_LINE_BUFFERED="1"))
        rospy.init_node("sitl_px4_test", anonymous=True, disable_signals=True)
        watch = Watch()
        wait_for(lambda: "waiting for PX4 on TCP 127.0.0.1:%d" % SIM_PORT in open(log).read(),
                 60, "the simulator's PX4 port")
        wait_for(lambda: watch.sim_time() > 0.5, 60, "the free-wheeling clock")

        # The ADK's setpoints are not applied while PX4 flies: one sent now must be ignored.
        pose_pub = rospy.Publisher("/uav/cmd_pose", PoseStamped, queue_size=1, latch=True)
        pose = PoseStamped()
        pose.header.frame_id = "map"
        pose.pose.position.z = 30.0
        pose.pose.orientation.w = 1.0
        pose_pub.publish(pose)

        # ---- Flight 1: bad input, arm, climb, hold (with a stall), land, disarm.
        hooks = {}
        ap = px4_standin.Autopilot(SIM_PORT, stall_at_s=None, before_arm=lambda a: bad_input(a, hooks))
        # The stall comes 10 s into the hold (sim time relative to the connection).
        t_connect = watch.sim_time()
        stall = {}
        orig_controls = ap.controls

        def controls(dt, t):
            c = orig_controls(dt, t)
            if ap.phase == "hold" and "wall" not in stall and t - ap.hold_start > 10.0:
                stall["sim"] = t
                stall["wall"] = time.time()
                time.sleep(2.0)
                stall["end"] = time.time()
            return c
        ap.controls = controls
        t_end = ap.run(max_wall_s=240)
        ap.close()
        print("flight: connected at sim ~%.1f s, ended at sim %.3f s; stand-in checks: %s" % (
            t_connect, t_end, "; ".join(ap.problems) or "all passed"))
        check(ap.done, "the stand-in did not land and disarm")
        check(ap.was_armed, "the stand-in never armed")
        check(not ap.problems, "HIL_SENSOR checks: %s" % ap.problems)

        with watch.lock:
            odom = list(watch.odom)
            clock = list(watch.clock)
        z0 = [z for t, z in odom if t <= t_connect + 0.5]
        z0 = z0[-1] if z0 else odom[0][1]
        trace = [(t, z - z0) for t, z in odom]
        ok, why = holds(trace, ap.hold_start + 2.0, 30.0, 10.0, 0.5)
        print("hold: 30 s from sim %.1f s at 10 +- 0.5 m: %s (%s)" % (ap.hold_start + 2.0,
                                                                     "held" if ok else "NOT held", why))
        check(ok, "the hold at 10 +- 0.5 m for 30 s: " + why)
        bad_trace = [(t, z + (0.8 if abs(t - ap.hold_start - 12) < 0.1 else 0)) for t, z in trace]
        check(not holds(bad_trace, ap.hold_start + 2.0, 30.0, 10.0, 0.5)[0],
              "negative control: a 0.8 m excursion passes the hold check")
        peak = max(z for t, z in trace)
        final = [z for t, z in trace if t >= t_end - 0.5]
        print("peak height %.2f m, final height %.3f m" % (peak, final[-1] if final else -1))
        check(10.0 <= peak < 10.5, "peak height %.2f m" % peak)
        check(final and abs(final[-1]) < 0.1, "the UAV is not back on the ground")

        # The stall: no /clock advance while the stand-in slept.
        during = [s for w, s in clock if stall["wall"] + 0.1 <= w <= stall["end"] - 0.05]
        before = [s for w, s in clock if w <= stall["wall"]]
        advance = (max(during) - before[-1]) if during and before else 0.0
        print("stall: %.1f wall s at sim %.3f s; /clock messages during it %d, advance %.6f s" % (
            stall["end"] - stall["wall"], stall["sim"], len(during), advance))
        check(advance == 0.0 and not during, "sim time advanced %.6f s (%d /clock messages) "
              "during the stall" % (advance, len(during)))

        ignored = "uav/cmd_pose ignored: the px4 autopilot flies the UAV" in open(log).read()
        print("the ADK's pose setpoint (30 m) while PX4 flies: %s" % (
            "ignored (logged)" if ignored else "NOT reported as ignored"))
        check(ignored, "the simulator did not report ignoring uav/cmd_pose")

        # ---- Every received frame decoded by the judge.
        d = ap.decoder
        print("judge: %d frames from the simulator %s; stray %d, bad CRC %d, unknown %d" % (
            d.frames, dict(sorted(d.by_name.items())), d.stray, d.bad_crc, d.unknown))
        check(d.stray == 0 and d.bad_crc == 0 and d.unknown == 0, "the judge rejected bytes")
        for name in ("HEARTBEAT", "SYSTEM_TIME", "HIL_SENSOR", "HIL_GPS", "HIL_STATE_QUATERNION",
                     "COMMAND_ACK"):
            check(d.by_name.get(name, 0) > 0, "no %s received" % name)
        span = (ap.last_t - ap.first_t) * 1e-6
        sensors = d.by_name.get("HIL_SENSOR", 0)
        gps_rate = d.by_name.get("HIL_GPS", 0) / max(span, 1e-9)
        state_rate = d.by_name.get("HIL_STATE_QUATERNION", 0) / max(span, 1e-9)
        print("rates over %.1f sim s: HIL_SENSOR %.1f Hz, HIL_GPS %.2f Hz, HIL_STATE_QUATERNION "
              "%.2f Hz (asked 50 Hz)" % (span, sensors / span, gps_rate, state_rate))
        check(abs(sensors / span - 250) < 2, "HIL_SENSOR rate")
        check(abs(gps_rate - 10) < 0.2, "HIL_GPS rate %.2f Hz" % gps_rate)
        check(abs(state_rate - 50) < 1, "HIL_STATE_QUATERNION rate %.2f Hz" % state_rate)

        # ---- After the disconnect: free-wheeling, a silent client, a new stand-in.
        t0 = watch.sim_time()
        time.sleep(0.5)
        t1 = watch.sim_time()
        print("after the disconnect: /clock %.3f -> %.3f s in 0.5 wall s" % (t0, t1))
        check(t1 > t0, "/clock stopped after the autopilot disconnected")
        silent = socket.create_connection(("127.0.0.1", SIM_PORT), timeout=5)
        silent.settimeout(5)
        closed_after = None
        start = time.time()
        try:
            while True:
                if not silent.recv(65536):
                    closed_after = time.time() - start
                    break
        except socket.timeout:
            pass
        silent.close()
        print("silent client: dropped after %s wall s" % (
            "%.1f" % closed_after if closed_after is not None else "NEVER"))
        check(closed_after is not None, "the silent client was not dropped")

        ap2 = px4_standin.Autopilot(SIM_PORT, idle_s=1e9)
        ap2.connect_handshake()
        n = 0
        last = None
        steps_ok = True
        while n < 100:
            for name, _, _, _, f in ap2.frames():
                if name == "HIL_SENSOR":
                    if last is not None and f["time_usec"] - last != 4000:
                        steps_ok = False
                    last = f["time_usec"]
                    ap2.send("HIL_ACTUATOR_CONTROLS", time_usec=f["time_usec"], controls=[0.0] * 16,
                             mode=0, flags=1)
                    n += 1
        time.sleep(0.6)  # a counters message after the last exchange
        ap2.close()
        print("reconnected stand-in: %d lock-step exchanges, one sensor period each: %s" % (
            n, steps_ok))
        check(n == 100 and steps_ok, "the reconnected stand-in was not served in lock-step")
        time.sleep(0.6)

        # ---- Counters against the judge's replay of the bytes the clients sent.
        replay = mj.Decoder()
        replay.feed(bytes(ap.sent[:hooks["cut_at"]]))
        replay.drop_partial()
        replay.feed(bytes(ap.sent[hooks["cut_at"]:]))
        c = watch.counters
        print("simulator counters: %s" % json.dumps(c, sort_keys=True))
        print("judge replay of the stand-in's bytes: stray %d, bad CRC %d, truncated %d" % (
            replay.stray, replay.bad_crc, replay.truncated))
        check(c.get("stray_bytes") == replay.stray, "stray_bytes %s vs judge %d" % (
            c.get("stray_bytes"), replay.stray))
        check(c.get("bad_crc") == replay.bad_crc, "bad_crc %s vs judge %d" % (c.get("bad_crc"), replay.bad_crc))
        check(c.get("truncated") == replay.truncated == 1, "truncated %s vs judge %d" % (
            c.get("truncated"), replay.truncated))
        check(replay.bad_crc >= 1 and replay.stray >= 7, "the bad input did not reach the judge")
        check(c.get("nan_actuators") == 1, "nan_actuators %s" % c.get("nan_actuators"))
        check(c.get("refused_connections") == 1, "refused_connections %s" % c.get("refused_connections"))
        check(c.get("silent_clients") == 1, "silent_clients %s" % c.get("silent_clients"))
        check(c.get("connections") == 3, "connections %s (stand-in, silent, stand-in)" % c.get("connections"))
        check(c.get("disconnects") == 3, "disconnects %s" % c.get("disconnects"))
        check(c.get("stalls") == 0, "stalls %s (the 2 s stall is under the 5 s timeout)" % c.get("stalls"))
        check(c.get("unknown_messages") == 0 and c.get("bad_length") == 0, "unknown/bad_length")
        expected_steps = ap.sensors + n
        check(c.get("actuator_messages") == ap.sensors + n,
              "actuator_messages %s, the stand-ins sent %d valid ones" % (c.get("actuator_messages"), ap.sensors + n))
        # Each connection may end with the answers to the sensor messages still in flight
        # (one or two: the lock-step began while the stand-in answered real-time free-wheeling)
        # received but not yet simulated.
        lost = expected_steps - c.get("lockstep_steps", 0)
        print("lock-step steps %s of %d valid actuator messages (%d lost with their "
              "connections)" % (c.get("lockstep_steps"), expected_steps, lost))
        check(0 <= lost <= 10, "lockstep_steps %s vs %d" % (c.get("lockstep_steps"), expected_steps))
        check(c.get("sensor_messages", 0) >= sensors + n, "sensor_messages %s" % c.get("sensor_messages"))
        # Both stand-ins asked for HIL_STATE_QUATERNION.
        got_gps = d.by_name.get("HIL_GPS", 0) + ap2.decoder.by_name.get("HIL_GPS", 0)
        got_state = (d.by_name.get("HIL_STATE_QUATERNION", 0) +
                     ap2.decoder.by_name.get("HIL_STATE_QUATERNION", 0))
        check(c.get("gps_messages", 0) >= got_gps, "gps_messages %s" % c.get("gps_messages"))
        check(got_state <= c.get("state_messages", 0) <= got_state + 5,
              "state_messages %s, the stand-ins received %d" % (c.get("state_messages"), got_state))
        check(c.get("overflows") == 0 and c.get("out_of_range_actuators") == 0,
              "overflows %s, out_of_range_actuators %s" % (c.get("overflows"),
                                                          c.get("out_of_range_actuators")))

        # ---- The judge's own negative control on a frame from this run.
        frame = bytearray(mj.encode("HIL_SENSOR", 0, 1, 51, time_usec=4000, fields_updated=0x1BFF))
        frame[12] ^= 0x40
        neg = mj.Decoder()
        check(not neg.feed(bytes(frame)) and neg.bad_crc == 1,
              "negative control: the judge accepts a corrupted HIL_SENSOR")
    finally:
        stop_process(sim)
        stop_master(core)
        if not check.fails:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary(tmp)


if __name__ == "__main__":
    sys.exit(main())
