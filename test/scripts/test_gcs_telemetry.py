#!/usr/bin/python3
"""Ground-station telemetry from the simulator node with the built-in controller
(~gcs_udp): HEARTBEAT, ATTITUDE and GLOBAL_POSITION_INT over UDP, every datagram decoded by the
independent decoder (mavlink_judge.py, python3-crcmod) and compared with /uav/odom:

  * every datagram is exactly one valid frame (no stray byte, no bad CRC);
  * HEARTBEAT once a sim second (quadrotor, generic autopilot), armed once the UAV flies;
  * ATTITUDE and GLOBAL_POSITION_INT at 10 Hz of sim time;
  * relative_alt equals the odometry height and lat/lon the odometry position from the origin
    (the local radii of curvature of the WGS84 ellipsoid at the origin, a flat-Earth
    approximation independent of the simulator's ECEF code, within 0.1 m at these distances),
    while the UAV climbs to 5 m on a pose setpoint.
"""
import math
import os
import socket
import subprocess
import sys
import threading
import time

import rospy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mavlink_judge as mj  # noqa: E402
from fault_util import BIN, SCENARIO, Checks  # noqa: E402
from graph_util import (private_master_port, start_master, stop_master,  # noqa: E402
                        stop_process)

PORT = private_master_port(30000)
ORIGIN = (42.4851, -71.1873, 40.0)
check = Checks()


def main():
    gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    gcs.bind(("127.0.0.1", 0))
    gcs.settimeout(0.2)
    gcs_port = gcs.getsockname()[1]
    core = start_master(PORT)
    sim = None
    try:
        sim = subprocess.Popen(
            [os.path.join(BIN, "simulator"), "__name:=simulator",
             "_sim_config:=%s/sim_config.json" % SCENARIO, "_cameras:=false",
             "_real_time_factor:=4", "_duration:=100000", "_gcs_udp:=127.0.0.1:%d" % gcs_port],
            stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
        rospy.init_node("gcs_telemetry_test", anonymous=True, disable_signals=True)
        odom = {}
        lock = threading.Lock()

        def on_odom(m):
            with lock:
                odom[round(m.header.stamp.to_sec() * 1000)] = (
                    m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z)
        rospy.Subscriber("/uav/odom", Odometry, on_odom, queue_size=1000)
        pub = rospy.Publisher("/uav/cmd_pose", PoseStamped, queue_size=1, latch=True)
        decoder = mj.Decoder()
        got = []
        datagrams = 0
        start = time.time()
        sent_pose = False
        while time.time() - start < 60:
            try:
                data = gcs.recv(65536)
            except socket.timeout:
                continue
            datagrams += 1
            frames = decoder.feed(data)
            check(len(frames) == 1, "a datagram with %d frames" % len(frames))
            got += frames
            atts = [f for f in got if f[0] == "ATTITUDE"]
            if atts and not sent_pose and atts[-1][4]["time_boot_ms"] > 1000:
                with lock:
                    x, y, _ = odom[max(odom)] if odom else (0, 0, 0)
                p = PoseStamped()
                p.header.frame_id = "map"
                p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, 5.0
                p.pose.orientation.w = 1.0
                pub.publish(p)
                sent_pose = True
            if atts and atts[-1][4]["time_boot_ms"] > 12000:
                break
        names = {}
        for f in got:
            names[f[0]] = names.get(f[0], 0) + 1
        span = max(f[4]["time_boot_ms"] for f in got if f[0] == "ATTITUDE") / 1000.0
        print("received %d datagrams over %.1f sim s: %s; judge: stray %d, bad CRC %d" % (
            datagrams, span, names, decoder.stray, decoder.bad_crc))
        check(decoder.stray == 0 and decoder.bad_crc == 0 and decoder.unknown == 0,
              "the judge rejected bytes")
        check(abs(names.get("HEARTBEAT", 0) - span) <= 2, "HEARTBEAT count %s" % names.get("HEARTBEAT"))
        for n in ("ATTITUDE", "GLOBAL_POSITION_INT"):
            check(abs(names.get(n, 0) / span - 10.0) < 0.5, "%s rate %.2f Hz" % (n, names.get(n, 0) / span))
        hbs = [f[4] for f in got if f[0] == "HEARTBEAT"]
        check(all(h["type"] == 2 and h["autopilot"] == 0 for h in hbs), "HEARTBEAT type/autopilot")
        armed = [bool(h["base_mode"] & 128) for h in hbs]
        print("heartbeats armed: %d of %d (the pose setpoint at sim ~1 s)" % (sum(armed), len(armed)))
        check(not armed[0] and armed[-1], "the armed flag does not follow the flight")
        worst_alt = worst_pos = 0.0
        matched = 0
        top = 0.0
        lat0, lon0 = math.radians(ORIGIN[0]), math.radians(ORIGIN[1])
        for f in got:
            if f[0] != "GLOBAL_POSITION_INT":
                continue
            p = f[4]
            with lock:
                o = odom.get(p["time_boot_ms"])
            if o is None:
                continue
            matched += 1
            worst_alt = max(worst_alt, abs(p["relative_alt"] / 1000.0 - o[2]))
            a, e2 = 6378137.0, 6.69437999014e-3
            w = 1 - e2 * math.sin(lat0) ** 2
            north = (math.radians(p["lat"] * 1e-7) - lat0) * a * (1 - e2) / w ** 1.5
            east = (math.radians(p["lon"] * 1e-7) - lon0) * a / math.sqrt(w) * math.cos(lat0)
            worst_pos = max(worst_pos, math.hypot(east - o[0], north - o[1]))
            top = max(top, o[2])
        print("GLOBAL_POSITION_INT vs /uav/odom: %d matched, worst height %.4f m, worst "
              "horizontal %.3f m, top height %.2f m" % (matched, worst_alt, worst_pos, top))
        check(matched >= 50, "only %d positions matched odometry" % matched)
        check(worst_alt <= 0.001, "relative_alt differs by %.4f m" % worst_alt)
        check(worst_pos <= 0.1, "lat/lon differ by %.3f m" % worst_pos)
        check(top > 4.0, "the UAV did not climb (top %.2f m)" % top)
    finally:
        stop_process(sim)
        stop_master(core)
    return check.summary("(nothing kept)")


if __name__ == "__main__":
    sys.exit(main())
