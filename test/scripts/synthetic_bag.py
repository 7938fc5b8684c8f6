#!/usr/bin/python3
"""A small mission-like bag for the exporter's fault and full-disk tests, made without a
mission: camera "down", FRAMES frames of 64x48 (bgr8 image, 32FC1 depth, mono8 segmentation,
16UC1 instances with two rectangles) and their boxes, one frame per sim second.
  synthetic_bag.py OUT.bag [FRAMES]
"""
import sys

import numpy as np
import rosbag
import rospy
from hameritt.msg import BoundingBox, BoundingBoxArray
from sensor_msgs.msg import Image

W, H = 64, 48


def image(arr, encoding, stamp):
    m = Image()
    m.header.stamp = stamp
    m.header.frame_id = "down_optical"
    m.height, m.width = arr.shape[:2]
    m.encoding = encoding
    m.is_bigendian = 0
    m.step = arr.strides[0]
    m.data = arr.tobytes()
    return m


def box(entity, cls, role, inst, x0, y0, x1, y1):
    b = BoundingBox()
    b.entity_id, b.entity_class, b.role, b.instance_id = entity, cls, role, inst
    b.x_min, b.y_min, b.x_max, b.y_max = x0, y0, x1, y1
    b.visible_pixels = b.total_pixels = (x1 - x0 + 1) * (y1 - y0 + 1)
    b.occlusion = 0.0
    return b


def main():
    out = sys.argv[1]
    frames = int(sys.argv[2]) if len(sys.argv) > 2 else 6
    base = "/uav/camera/down/"
    with rosbag.Bag(out, "w") as bag:
        for i in range(frames):
            stamp = rospy.Time(1 + i)
            x = 4 + 3 * i
            inst = np.zeros((H, W), np.uint16)
            inst[10:20, x:x + 12] = 1
            inst[30:40, 40:50] = 2
            rgb = np.zeros((H, W, 3), np.uint8)
            rgb[..., 0] = np.arange(W, dtype=np.uint8)[None, :] * 3
            rgb[..., 1] = 40 * i % 256
            rgb[inst > 0] = (200, 30, 30)
            depth = np.full((H, W), 50.0, np.float32)
            depth[inst > 0] = 20.0
            seg = (inst * 60).astype(np.uint8)
            boxes = BoundingBoxArray()
            boxes.header.stamp = stamp
            boxes.camera = "down"
            boxes.boxes = [box("car_1", "car", "target", 1, x, 10, x + 11, 19),
                           box("pedestrian_2", "pedestrian", "confuser", 2, 40, 30, 49, 39)]
            bag.write(base + "boxes", boxes, stamp)
            bag.write(base + "image_raw", image(rgb, "bgr8", stamp), stamp)
            bag.write(base + "depth", image(depth, "32FC1", stamp), stamp)
            bag.write(base + "segmentation", image(seg, "mono8", stamp), stamp)
            bag.write(base + "instances", image(inst, "16UC1", stamp), stamp)


if __name__ == "__main__":
    main()
