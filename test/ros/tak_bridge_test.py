#!/usr/bin/python3
"""rostest: the cop and tak_bridge nodes (launch/cop.launch) end to end.

The test publishes a latched mission (origin, one target, an AOI and a KOZ), UAV odometry,
perfect-perception reports and client claims of a known car, listens on a free loopback UDP
port, and starts cop.launch with tak:=udp://127.0.0.1:<port>,tcp://127.0.0.1:<closed port>.
Every datagram is parsed as XML (xml.etree) and checked against the CoT 2.0 event schema's
required fields; the UAV, the known car's track and the zone vertices are converted back to the
map frame with an independent closed-form WGS84 -> ECEF -> ENU conversion and compared with
the published positions (0.5 m). The unreachable TCP endpoint must not stop anything: the bridge
logs its reconnect back-off, UDP keeps flowing and new odometry reaches TAK; then
a TCP server comes up on that port and receives the events streamed back to back.
Only 127.0.0.1 is ever sent to.
"""
import math
import os
import re
import select
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest
import xml.etree.ElementTree as ET
from datetime import datetime, timezone

import rospy
import rostest
from geometry_msgs.msg import Point
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Log

from hameritt.msg import (AreaOfInterest, CopTrackArray, Detection, KeepOutZone, KeyValue,
                          Mission, PerceivedEntity, PerceptionReport, TargetDescription)

ORIGIN = (42.4851, -71.1873, 40.0)
UAV = (120.0, -80.0, 55.0)
UAV2 = (130.0, -60.0, 70.0)
CAR = (-250.0, 300.0, 0.0)
CONFUSER = (60.0, 40.0, 0.0)
AOI = [(-300.0, 250.0), (-200.0, 250.0), (-200.0, 350.0), (-300.0, 350.0)]
KOZ = [(0.0, 0.0), (50.0, 0.0), (50.0, 40.0), (0.0, 40.0)]
ATTRS = {"vehicle_class": "suv", "make": "Toyota", "model": "RAV4", "color": "white"}
ISO = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$")

# WGS84 (NIMA TR8350.2), written out here independently of the library.
A = 6378137.0
F = 1.0 / 298.257223563
E2 = F * (2.0 - F)


def ecef(lat, lon, h):
    la, lo = math.radians(lat), math.radians(lon)
    n = A / math.sqrt(1.0 - E2 * math.sin(la) ** 2)
    return ((n + h) * math.cos(la) * math.cos(lo), (n + h) * math.cos(la) * math.sin(lo),
            (n * (1.0 - E2) + h) * math.sin(la))


def to_enu(lat, lon, h):
    """Geodetic -> map frame (ENU at ORIGIN) by rotating the ECEF difference."""
    x0, y0, z0 = ecef(*ORIGIN)
    x, y, z = ecef(lat, lon, h)
    dx, dy, dz = x - x0, y - y0, z - z0
    la, lo = math.radians(ORIGIN[0]), math.radians(ORIGIN[1])
    e = -math.sin(lo) * dx + math.cos(lo) * dy
    nn = (-math.sin(la) * math.cos(lo) * dx - math.sin(la) * math.sin(lo) * dy +
          math.cos(la) * dz)
    u = math.cos(la) * math.cos(lo) * dx + math.cos(la) * math.sin(lo) * dy + math.sin(la) * dz
    return e, nn, u


def parse_time(s):
    return datetime.strptime(s, "%Y-%m-%dT%H:%M:%S.%fZ").replace(tzinfo=timezone.utc).timestamp()


def free_port(kind):
    s = socket.socket(socket.AF_INET, kind)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    return s, port


def make_mission():
    m = Mission()
    m.header.frame_id = "map"
    m.scenario_id = "tak_bridge_test"
    m.scenario_class = "area_search"
    m.origin_latitude, m.origin_longitude, m.origin_altitude = ORIGIN
    m.time_limit = 600
    t = TargetDescription(id="car_706", entity_class="car", vehicle_class="suv", make="Toyota",
                          model="RAV4", color="white")
    m.objective.type = "find"
    m.objective.text = "Find the white Toyota RAV4 (suv)."
    m.objective.targets = [t]
    m.areas_of_interest = [AreaOfInterest(id="aoi_1", polygon=[Point(x, y, 0) for x, y in AOI])]
    koz = KeepOutZone(id="koz_1", purpose="vantage_denial",
                      polygon=[Point(x, y, 0) for x, y in KOZ])
    koz.has_alt_min, koz.alt_min, koz.has_alt_max, koz.alt_max = True, 0.0, True, 96.0
    m.keep_out_zones = [koz]
    return m


class TakBridgeTest(unittest.TestCase):
    def setUp(self):
        rospy.init_node("tak_bridge_test")
        self.udp, self.udp_port = free_port(socket.SOCK_DGRAM)
        closed, self.tcp_port = free_port(socket.SOCK_STREAM)
        closed.close()  # nothing listens there yet
        self.logs = []
        self.uav = UAV
        self.tracks = []
        rospy.Subscriber("/rosout", Log, lambda m: self.logs.append(m))
        rospy.Subscriber("/cop/tracks", CopTrackArray, lambda m: self.tracks.append(m))
        self.mission_pub = rospy.Publisher("/mission", Mission, queue_size=1, latch=True)
        self.odom_pub = rospy.Publisher("/uav/odom", Odometry, queue_size=10)
        self.pp_pub = rospy.Publisher("/adk/perfect_perception", PerceptionReport, queue_size=10)
        self.det_pub = rospy.Publisher("/perception/detections", Detection, queue_size=10)
        self.mission_pub.publish(make_mission())
        # A copy of config/tak.yaml with fast ticks and a short back-off cap for the test.
        self.cfg = tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False)
        with open(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                               "../../config/tak.yaml")) as f:
            self.cfg.write(f.read())
        self.cfg.write("\nreconnect_max_s: 1.0\n")
        self.cfg.close()
        self.launch_log = tempfile.TemporaryFile("w+")
        tak = "udp://127.0.0.1:%d,tcp://127.0.0.1:%d" % (self.udp_port, self.tcp_port)
        self.launch = subprocess.Popen(
            ["roslaunch", "hameritt", "cop.launch", "tak:=" + tak, "tak_rate_hz:=5",
             "tak_zone_period_s:=1", "cop_rate_hz:=5", "tak_config:=" + self.cfg.name],
            stdout=self.launch_log, stderr=subprocess.STDOUT, start_new_session=True)

    def launch_output(self):
        self.launch_log.flush()
        self.launch_log.seek(0)
        text = self.launch_log.read()
        self.launch_log.seek(0, os.SEEK_END)
        return text[-4000:]

    def tearDown(self):
        if self.launch.poll() is None:
            os.killpg(self.launch.pid, signal.SIGINT)
            try:
                self.launch.wait(15)
            except subprocess.TimeoutExpired:
                os.killpg(self.launch.pid, signal.SIGKILL)
        self.udp.close()
        os.unlink(self.cfg.name)
        # The nodes' output (their end-of-run summaries) in the test's log.
        self.launch_log.seek(0)
        sys.stderr.write(self.launch_log.read()[-6000:])
        self.launch_log.close()

    def publish_world(self, t):
        now = rospy.Time.now()
        o = Odometry()
        o.header.stamp, o.header.frame_id, o.child_frame_id = now, "map", "uav/base_link"
        o.pose.pose.position = Point(*self.uav)
        o.pose.pose.orientation.z = math.sin(math.pi / 4)  # yaw 90 deg: nose north
        o.pose.pose.orientation.w = math.cos(math.pi / 4)
        o.twist.twist.linear.x = 3.0  # forward = north in the map frame
        self.odom_pub.publish(o)
        r = PerceptionReport()
        r.header.stamp, r.header.frame_id, r.camera = now, "uav/camera/down_optical", "down"
        kv = [KeyValue(key=k, value=v) for k, v in sorted(ATTRS.items())]
        r.entities = [
            PerceivedEntity(entity_id="car_706", entity_class="car", role="target",
                            attributes=kv, position=Point(*CAR)),
            PerceivedEntity(entity_id="car_12", entity_class="car", role="confuser",
                            attributes=[KeyValue(key="color", value="red")],
                            position=Point(*CONFUSER))]
        self.pp_pub.publish(r)
        d = Detection()
        d.header.stamp, d.header.frame_id = now, "map"
        d.client, d.description, d.entity_class = "test_client", "white Toyota RAV4", "car"
        d.attributes, d.confidence = kv, 0.8
        d.position = Point(CAR[0] + 0.3, CAR[1] - 0.2, 0.0)
        self.det_pub.publish(d)

    def collect(self, seconds, datagrams):
        end = time.time() + seconds
        next_pub = 0.0
        while time.time() < end and not rospy.is_shutdown():
            if time.time() >= next_pub:
                self.publish_world(time.time())
                next_pub = time.time() + 0.1
            ready, _, _ = select.select([self.udp], [], [], 0.05)
            if ready:
                data, addr = self.udp.recvfrom(65536)
                datagrams.append((time.time(), data))

    def check_event(self, ev, received, max_age=5.0):
        self.assertEqual(ev.tag, "event")
        self.assertEqual(ev.get("version"), "2.0")
        for a in ("uid", "type", "how", "time", "start", "stale"):
            self.assertTrue(ev.get(a), "event without %s" % a)
        for a in ("time", "start", "stale"):
            self.assertRegex(ev.get(a), ISO)
        t, start, stale = (parse_time(ev.get(a)) for a in ("time", "start", "stale"))
        self.assertLessEqual(start, t + 1e-3)
        self.assertGreater(stale, t)
        self.assertLess(abs(t - received), max_age, "event time is not the wall clock")
        pt = ev.find("point")
        self.assertIsNotNone(pt)
        vals = {k: float(pt.get(k)) for k in ("lat", "lon", "hae", "ce", "le")}
        self.assertTrue(-90 <= vals["lat"] <= 90 and -180 <= vals["lon"] <= 180)
        self.assertGreaterEqual(vals["ce"], 0)
        self.assertIsNotNone(ev.find("detail"))
        return vals, stale - t

    def test_cot_over_udp_and_unreachable_tcp(self):
        # The first datagram (roslaunch and the nodes start), then 5 s of events.
        first = []
        end = time.time() + 30
        while not first and time.time() < end and self.launch.poll() is None:
            self.collect(0.2, first)
        self.assertTrue(first, "no CoT datagram on udp://127.0.0.1:%d; launch output:\n%s" %
                        (self.udp_port, self.launch_output()))
        datagrams = []
        self.collect(5.0, datagrams)
        self.assertGreater(len(datagrams), 20, "too few CoT datagrams on udp://127.0.0.1")
        by_type = {}
        for received, data in datagrams:
            ev = ET.fromstring(data.decode("utf-8"))  # every datagram is one XML document
            vals, life = self.check_event(ev, received)
            by_type.setdefault(ev.get("type"), []).append((ev, vals, life))

        # The UAV: friendly rotary-wing UAV at its odometry position, heading north at 3 m/s.
        uav = by_type.get("a-f-A-M-F-Q")
        self.assertTrue(uav, "no UAV event; types: %s" % sorted(by_type))
        ev, vals, life = uav[-1]
        e, n, u = to_enu(vals["lat"], vals["lon"], vals["hae"])
        self.assertLess(math.dist((e, n, u), UAV), 0.5)
        self.assertAlmostEqual(life, 30.0, delta=0.01)
        self.assertEqual(ev.find("detail/contact").get("callsign"), "HAMERITT-UAV")
        self.assertAlmostEqual(float(ev.find("detail/track").get("course")), 0.0, delta=0.5)
        self.assertAlmostEqual(float(ev.find("detail/track").get("speed")), 3.0, delta=0.05)

        # Tracks: unknown ground; the known car believed to be the target, at its position.
        tracks = by_type.get("a-u-G", [])
        target = [t for t in tracks if t[0].find("detail/hameritt").get("target") == "car_706"]
        self.assertTrue(target, "no track believed to be car_706")
        ev, vals, life = target[-1]
        e, n, _ = to_enu(vals["lat"], vals["lon"], vals["hae"])
        self.assertLess(math.hypot(e - CAR[0], n - CAR[1]), 0.5)
        self.assertEqual(ev.find("detail/hameritt").get("entity"), "car_706")
        self.assertGreaterEqual(float(ev.find("detail/hameritt").get("belief")), 0.5)
        self.assertAlmostEqual(life, 30.0, delta=0.01)
        self.assertTrue(ev.get("uid").startswith("hameritt.track.T"))
        confuser = [t for t in tracks if t[0].find("detail/hameritt").get("entity") == "car_12"]
        self.assertTrue(confuser)
        self.assertEqual(confuser[-1][0].find("detail/hameritt").get("target"), "")
        e, n, _ = to_enu(confuser[-1][1]["lat"], confuser[-1][1]["lon"], 0.0)
        self.assertLess(math.hypot(e - CONFUSER[0], n - CONFUSER[1]), 0.5)

        # Zones: closed u-d-f shapes whose link points are the polygons' vertices.
        zones = {z[0].get("uid"): z for z in by_type.get("u-d-f", [])}
        self.assertEqual(sorted(zones), ["hameritt.aoi.aoi_1", "hameritt.koz.koz_1"])
        for uid, poly in (("hameritt.aoi.aoi_1", AOI), ("hameritt.koz.koz_1", KOZ)):
            ev, vals, life = zones[uid]
            self.assertAlmostEqual(life, 600.0, delta=0.01)
            links = [tuple(map(float, l.get("point").split(","))) for l in ev.findall("detail/link")]
            self.assertEqual(len(links), len(poly) + 1)
            self.assertEqual(links[0], links[-1])
            for (lat, lon), (x, y) in zip(links, poly):
                e, n, _ = to_enu(lat, lon, ORIGIN[2])
                self.assertLess(math.hypot(e - x, n - y), 0.5, uid)
            self.assertIsNotNone(ev.find("detail/strokeColor"))

        # cop/tracks: the target's track carries the ground-truth entity and the belief.
        self.assertTrue(self.tracks)
        best = [t for t in self.tracks[-1].tracks if t.target_id == "car_706"]
        self.assertEqual(len(best), 1)
        self.assertEqual(best[0].entity_id, "car_706")
        self.assertIn("test_client", best[0].sources)
        self.assertIn("perfect_perception", best[0].sources)

        # The unreachable TCP server: a throttled warning with the back-off, the node alive and
        # its callbacks served (service round trips stay fast), UDP flowing (checked above).
        warnings = [m.msg for m in self.logs if m.name == "/tak_bridge" and m.level >= Log.WARN]
        self.assertTrue(any("tcp://127.0.0.1:%d unreachable" % self.tcp_port in w and
                            "back-off" in w for w in warnings), warnings)
        self.assertLess(len(warnings), 5, "the unreachable warning is not throttled")
        # The reason itself is logged once (an error), however many attempts failed with it.
        reasons = [m.msg for m in self.logs if m.name == "/tak_bridge" and m.level == Log.ERROR
                   and "tcp://127.0.0.1:%d: connect: Connection refused" % self.tcp_port in m.msg]
        self.assertEqual(len(reasons), 1, [m.msg for m in self.logs if m.name == "/tak_bridge"])
        self.assertIsNone(self.launch.poll(), "roslaunch exited")
        # A topic round trip through the bridge's callbacks: the UAV moves, the next UAV event
        # over UDP shows it (a liveness bound, generous for a loaded machine).
        self.uav = UAV2
        got = []
        t0 = time.time()
        while time.time() - t0 < 10 and not got:
            batch = []
            self.collect(0.2, batch)
            for _, data in batch:
                ev = ET.fromstring(data.decode("utf-8"))
                if ev.get("type") == "a-f-A-M-F-Q":
                    p = ev.find("point")
                    pos = to_enu(float(p.get("lat")), float(p.get("lon")), float(p.get("hae")))
                    if math.dist(pos, UAV2) < 0.5:
                        got.append(time.time() - t0)
        self.assertTrue(got, "odometry no longer reaches the bridge while TCP is down")
        self.assertLess(got[0], 5.0)

        # The TAK server comes up: the bridge reconnects (back-off capped at 1 s here) and
        # streams events back to back.
        server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        server.bind(("127.0.0.1", self.tcp_port))
        server.listen(1)
        end = time.time() + 10
        conn = None
        while conn is None and time.time() < end:
            self.publish_world(time.time())
            if select.select([server], [], [], 0.1)[0]:
                conn, _ = server.accept()
        self.assertIsNotNone(conn, "the bridge did not reconnect to the TCP server")
        stream = b""
        end = time.time() + 5
        while time.time() < end and stream.count(b"</event>") < 5:
            self.publish_world(time.time())
            if select.select([conn], [], [], 0.1)[0]:
                stream += conn.recv(65536)
        conn.close()
        server.close()
        events = re.findall(rb"<event .*?</event>", stream, re.S)
        self.assertGreaterEqual(len(events), 5)
        # Events queued while the server was down arrive too (up to the bounded queue).
        for data in events:
            self.check_event(ET.fromstring(data.decode("utf-8")), time.time(), max_age=60.0)


if __name__ == "__main__":
    rostest.rosrun("hameritt", "cop_tak_bridge", TakBridgeTest, sys.argv)
