#!/usr/bin/env python3
"""A complete hameritt client in Python: the template to copy (docs/tutorials/03-client-algorithm.md).

It reads the mission and the UAV's envelope, flies a simple search (the AOIs' prior cells, most
probable first, skipping keep-out zones), finds the target (perfect perception in maneuver_only,
a colour threshold on the down camera otherwise), claims it with its symbolic context (the AOI
it lies in, while that AOI's window is open), and exits when the ADK says the mission is over.
Run it beside `roslaunch hameritt mission.launch clients:=none client_nodes:=/example_client`.
"""
import math
import re

import cv2
import numpy as np
import rospy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry, Path
from sensor_msgs.msg import Image

from hameritt.lockstep import LockstepGate
from hameritt.msg import (Detection, FollowProgress, KeyValue, Mission, MissionState,
                          PerceptionReport, PriorCell, UavSpec)

# Hue ranges (OpenCV: H 0-179) of saturated colours. White, silver and grey (the brightest 2 %
# of the unsaturated pixels) and black (the darkest 2 %) are told relative to the image: the
# scene's light changes with the hour and the weather.
HUES = {"red": (0, 8), "yellow": (20, 35), "green": (40, 85), "blue": (100, 130)}
ATTRIBUTES = ["vehicle_class", "make", "model", "color"]


def inside(polygon, x, y):
    return cv2.pointPolygonTest(np.float32([(p.x, p.y) for p in polygon]), (x, y), False) >= 0


class ExampleClient:
    def __init__(self):
        self.gate = LockstepGate()  # every subscription, publisher and timer goes through it
        self.mission = self.uav = self.odom = None
        self.plan, self.claims = [], []
        # The mode is also in /adk/state; the launch sets the ADK's parameter before we start.
        self.mode = rospy.get_param("/adk/mode", "end_to_end")
        self.gate.subscribe("/mission", Mission, lambda m: setattr(self, "mission", m))
        self.gate.subscribe("/mission/uav", UavSpec, lambda m: setattr(self, "uav", m))
        self.gate.subscribe("/uav/odom", Odometry, lambda m: setattr(self, "odom", m), queue_size=1)
        self.gate.subscribe("/adk/state", MissionState, self.on_state)
        self.gate.subscribe("/planner/progress", FollowProgress, self.on_progress)
        self.gate.subscribe("/adk/perfect_perception", PerceptionReport, self.on_perfect)
        if self.mode != "maneuver_only":  # a camera no one subscribes to is not rendered
            self.gate.subscribe("/uav/camera/down/image_raw", Image, self.on_image, queue_size=1)
        self.waypoints = self.gate.advertise("/planner/waypoints", Path, latch=True)
        self.detections = self.gate.advertise("/perception/detections", Detection, queue_size=20)
        self.gate.every(1.0, self.start_search)

    def on_state(self, s):
        over = ("succeeded", "timeout", "crashed", "aborted", "ended", "failed")
        if s.state in over and not rospy.is_shutdown():
            rospy.loginfo("example_client: mission %s (%s); exiting", s.state, s.reason)
            rospy.signal_shutdown("mission over")

    def start_search(self):
        """Once: one waypoint over each prior cell's centre; the AOI whose window closes first
        comes first, and within an AOI the most probable cell."""
        if self.plan or None in (self.mission, self.uav, self.odom):
            return
        alt = min(max(40.0, self.uav.altitude_min + 2), self.uav.altitude_max - 2)
        priors = {p.aoi_id: p.cells for p in self.mission.area_priors}
        cells = [(a.window.nlt if a.window.has_nlt else math.inf, -c.probability, c.polygon)
                 for a in self.mission.areas_of_interest
                 for c in priors.get(a.id, [PriorCell(polygon=a.polygon, probability=1.0)])]
        for _, _, polygon in sorted(cells, key=lambda c: c[:2]):
            x, y = np.mean([p.x for p in polygon]), np.mean([p.y for p in polygon])
            # The planner refuses a waypoint inside a keep-out zone: leave those out.
            if not any(inside(k.polygon, x, y) and (not k.has_alt_min or k.alt_min <= alt) and
                       (not k.has_alt_max or alt <= k.alt_max) for k in self.mission.keep_out_zones):
                self.plan.append((x, y, alt))
        self.send(self.plan)

    def send(self, points):
        path = Path()
        path.header.frame_id = "map"
        for x, y, z in points:
            pose = PoseStamped()
            pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = x, y, z
            path.poses.append(pose)
        self.waypoints.publish(path)

    def on_progress(self, p):
        """A failed plan names its leg ("leg 2: ..."): leave that waypoint out and send the rest."""
        leg = re.search(r"leg (\d+)", p.message)
        bad = p.waypoint + int(leg.group(1)) if leg else p.waypoint
        if p.state == "failed" and bad < len(self.plan):
            rospy.logwarn("example_client: %s; dropping waypoint %d", p.message, bad)
            self.plan = self.plan[:bad] + self.plan[bad + 1:]
            self.send(self.plan)

    def on_perfect(self, report):
        """maneuver_only: perfect perception stands in for a detector (class and attributes only)."""
        for e in report.entities:
            seen = {kv.key: kv.value for kv in e.attributes}
            self.claim(e.entity_class, seen, e.position.x, e.position.y, report.header.stamp, 1.0)

    def on_image(self, img):
        if None in (self.mission, self.uav, self.odom) or self.odom.pose.pose.position.z < 10:
            return
        target = self.mission.objective.targets[0]
        rgb = np.frombuffer(img.data, np.uint8).reshape(img.height, img.step // 3, 3)[:, :img.width]
        hsv = cv2.cvtColor(cv2.medianBlur(rgb, 5), cv2.COLOR_RGB2HSV)  # the median removes noise
        v = hsv[:, :, 2]
        if target.color in HUES:
            mask = cv2.inRange(hsv, (HUES[target.color][0], 80, 40), (HUES[target.color][1], 255, 255))
        elif target.color == "black":
            mask = cv2.inRange(hsv, (0, 0, 0), (179, 80, int(np.percentile(v, 2))))
        else:
            mask = cv2.inRange(hsv, (0, 0, int(np.percentile(v, 98))), (179, 50, 255))
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
        cam = next(c for c in self.uav.cameras if c.name == "down")
        f = cam.width / 2 / math.tan(math.radians(cam.hfov_deg) / 2)
        p, q = self.odom.pose.pose.position, self.odom.pose.pose.orientation
        car = (4.6 * f / p.z) * (1.8 * f / p.z)  # a car's expected area in pixels
        n, _, stats, centres = cv2.connectedComponentsWithStats(mask)
        for i in range(1, n):
            if 0.4 * car < stats[i, cv2.CC_STAT_AREA] < 2.5 * car:
                # The down camera looks straight down: pixel offset -> metres on the ground.
                dx, dy = (centres[i] - (cam.width / 2, cam.height / 2)) * p.z / f
                yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
                fwd, left = -dy, -dx  # image up is the UAV's forward, image right its right
                x = p.x + fwd * math.cos(yaw) - left * math.sin(yaw)
                y = p.y + fwd * math.sin(yaw) + left * math.cos(yaw)
                attrs = {k: getattr(target, k) for k in ATTRIBUTES}
                self.claim(target.entity_class, attrs, x, y, img.header.stamp, 0.5)

    def claim(self, cls, seen, x, y, stamp, confidence):
        """Claims a match of the objective's description inside an AOI whose time window is open,
        once per 10 m."""
        for t in self.mission.objective.targets if self.mission else []:
            if cls != t.entity_class or any(getattr(t, k) and seen.get(k) != getattr(t, k)
                                            for k in ATTRIBUTES):
                continue
            t_now, aois = stamp.to_sec(), self.mission.areas_of_interest
            aoi = next((a.id for a in aois if inside(a.polygon, x, y) and  # its window open now
                        (not a.window.has_net or a.window.net <= t_now) and
                        (not a.window.has_nlt or t_now <= a.window.nlt)), "")
            if not aoi or any(math.hypot(x - cx, y - cy) < 10 for cx, cy in self.claims):
                continue
            self.claims.append((x, y))
            d = Detection(client=rospy.get_name(), entity_class=cls, confidence=confidence,
                          description="%s %s %s (%s) in %s" % (t.color, t.make, t.model,
                                                               t.vehicle_class, aoi),
                          attributes=[KeyValue(k, seen[k]) for k in ATTRIBUTES if seen.get(k)])
            d.header.stamp, d.header.frame_id = stamp, "map"
            d.position.x, d.position.y = x, y
            rospy.loginfo("example_client: claim %s at (%.1f, %.1f)", d.description, x, y)
            self.detections.publish(d)


if __name__ == "__main__":
    rospy.init_node("example_client")
    ExampleClient().gate.spin()
