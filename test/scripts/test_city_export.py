#!/usr/bin/env python3
"""The city's classes in the dataset export, judged from outside: a small bag written here with
Python rosbag (camera "front", 64 x 48 frames whose instance images hold a building, a lamp
post, a bus stop, a street tree and a car, with their hameritt/BoundingBox metadata) is exported
by hameritt_export as COCO and as YOLO, and the files are read back with Python's json and yaml:
the categories are exactly the table of docs/reference/formats.md (name and id), every
annotation's category is its entity class, its bbox is the numpy extent of its mask, and every
YOLO line's class index names the same class in data.yaml. Negative controls: the same checks
fail on a category table with two ids swapped and on a YOLO name list shifted by one."""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import cv2
import numpy as np
import rosbag
import rospy
import yaml
from hameritt.msg import BoundingBox, BoundingBoxArray

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fault_util import BIN, SRC, Checks  # noqa: E402
from synthetic_bag import image  # noqa: E402

W, H = 64, 48
# (entity id, class, instance id, rectangle x0, y0, x1, y1 inclusive) of every frame.
THINGS = [("building_3", "building", 4, 0, 0, 20, 40), ("lamp_post_9", "lamp_post", 10, 24, 5, 25, 40),
          ("bus_stop_2", "bus_stop", 3, 30, 28, 44, 40), ("street_tree_5", "street_tree", 6, 48, 8, 60, 40),
          ("car_1", "car", 2, 30, 42, 40, 47)]
check = Checks()


def write_bag(path, frames):
    base = "/uav/camera/front/"
    with rosbag.Bag(path, "w") as bag:
        for i in range(frames):
            stamp = rospy.Time(1 + i)
            inst = np.zeros((H, W), np.uint16)
            msg = BoundingBoxArray()
            msg.header.stamp = stamp
            msg.camera = "front"
            for eid, cls, iid, x0, y0, x1, y1 in THINGS:
                inst[y0:y1 + 1, x0 + i:x1 + 1 + i] = iid
            for eid, cls, iid, x0, y0, x1, y1 in THINGS:
                ys, xs = np.nonzero(inst == iid)
                b = BoundingBox()
                b.entity_id, b.entity_class, b.role, b.instance_id = eid, cls, "world", iid
                b.x_min, b.y_min, b.x_max, b.y_max = int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())
                b.visible_pixels = len(xs)
                b.total_pixels = (x1 - x0 + 1) * (y1 - y0 + 1)
                b.occlusion = 1.0 - b.visible_pixels / b.total_pixels
                msg.boxes.append(b)
            rgb = np.zeros((H, W, 3), np.uint8)
            rgb[inst > 0] = (120, 120, 120)
            depth = np.full((H, W), 50.0, np.float32)
            seg = np.zeros((H, W), np.uint8)
            bag.write(base + "boxes", msg, stamp)
            bag.write(base + "image_raw", image(rgb, "bgr8", stamp), stamp)
            bag.write(base + "depth", image(depth, "32FC1", stamp), stamp)
            bag.write(base + "segmentation", image(seg, "mono8", stamp), stamp)
            bag.write(base + "instances", image(inst, "16UC1", stamp), stamp)


def documented_categories():
    """{name: id} of the COCO category table in docs/reference/formats.md."""
    text = open(os.path.join(SRC, "docs", "reference", "formats.md")).read()
    section = text[text.index("COCO category"):]
    rows = re.findall(r"^\| `([a-z_]+)` \| (\d+) \| (\d+) \|", section, re.M)
    return {name: (int(cid), int(yolo)) for name, cid, yolo in rows}


def judge_coco(ds, table):
    """Problems of a COCO export against a documented {name: (id, yolo index)} table."""
    bad = []
    doc = json.load(open(os.path.join(ds, "annotations", "instances_train.json")))
    cats = {c["name"]: c["id"] for c in doc["categories"]}
    if cats != {n: v[0] for n, v in table.items()}:
        bad.append("categories %s differ from the documented table" % cats)
    by_id = {c["id"]: c["name"] for c in doc["categories"]}
    images = {im["id"]: im for im in doc["images"]}
    for a in doc["annotations"]:
        if by_id.get(a["category_id"]) != a["extra"]["entity_class"]:
            bad.append("annotation %d: category %s, class %s" % (a["id"], a["category_id"],
                                                                 a["extra"]["entity_class"]))
        inst = cv2.imread(os.path.join(ds, images[a["image_id"]]["extra"]["instances_file"]), -1)
        ys, xs = np.nonzero(inst == a["extra"]["instance_id"])
        want = [int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)]
        if a["bbox"] != want or a["area"] != len(xs):
            bad.append("annotation %d: bbox %s area %d, mask %s %d" % (a["id"], a["bbox"], a["area"], want, len(xs)))
    return bad, doc


def judge_yolo(ds, table, names=None):
    bad = []
    data = yaml.safe_load(open(os.path.join(ds, "data.yaml")))
    names = names if names is not None else data["names"]
    if isinstance(names, dict):
        names = [names[k] for k in sorted(names)]
    if data["nc"] != len(names) or {n: i for i, n in enumerate(names)} != {n: v[1] for n, v in table.items()}:
        bad.append("data.yaml names %s differ from the documented YOLO indices" % names)
    lines = 0
    label_dir = os.path.join(ds, "labels", "train")
    for f in sorted(os.listdir(label_dir)):
        for line in open(os.path.join(label_dir, f)):
            k, cx, cy, w, h = line.split()
            lines += 1
            cls = names[int(k)]
            # The rectangle of that class, moved one pixel right per frame (3 frames).
            hits = [t for t in THINGS if t[1] == cls]
            if len(hits) != 1:
                bad.append("%s: class %s is none of the frame's" % (f, cls))
                continue
            _, _, _, x0, y0, x1, y1 = hits[0]
            ok = any(abs(float(cx) * W - (x0 + x1 + 1) / 2 - i) < 1e-3 and
                     abs(float(cy) * H - (y0 + y1 + 1) / 2) < 1e-3 and
                     abs(float(w) * W - (x1 - x0 + 1)) < 1e-3 and abs(float(h) * H - (y1 - y0 + 1)) < 1e-3
                     for i in range(3))
            if not ok:
                bad.append("%s: %s %s" % (f, cls, line.strip()))
    return bad, lines


def export(bag, out, fmt):
    r = subprocess.run([os.path.join(BIN, "hameritt_export"), bag, "--format", fmt, "--out", out,
                        "--split", "train=1"], capture_output=True, text=True)
    check(r.returncode == 0, "%s export: %s" % (fmt, r.stderr))


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_city_export.")
    try:
        bag = os.path.join(tmp, "city.bag")
        write_bag(bag, 3)
        table = documented_categories()
        check(len(table) == 18 and table.get("building") == (11, 8) and table.get("street_tree") == (19, 16),
              "documented table %s" % table)
        coco = os.path.join(tmp, "coco")
        export(bag, coco, "coco")
        bad, doc = judge_coco(coco, table)
        check(not bad, "COCO: %s" % bad)
        n = len(doc["annotations"])
        check(n == 3 * len(THINGS), "%d annotations, expected %d" % (n, 3 * len(THINGS)))
        used = sorted({a["category_id"] for a in doc["annotations"]})
        check(used == [8, 11, 15, 17, 19], "category ids used %s" % used)
        print("COCO: %d annotations of %d classes against the documented table" % (n, len(used)))
        # Negative control: building and parking_garage swapped in the table.
        swapped = dict(table)
        swapped["building"], swapped["parking_garage"] = table["parking_garage"], table["building"]
        check(judge_coco(coco, swapped)[0], "a swapped category table passes")

        yolo = os.path.join(tmp, "yolo")
        export(bag, yolo, "yolo")
        bad, lines = judge_yolo(yolo, table)
        check(not bad, "YOLO: %s" % bad)
        check(lines == 3 * len(THINGS), "%d YOLO lines, expected %d" % (lines, 3 * len(THINGS)))
        print("YOLO: %d lines against the documented indices" % lines)
        # Negative control: the names shifted by one.
        names = yaml.safe_load(open(os.path.join(yolo, "data.yaml")))["names"]
        names = [names[k] for k in sorted(names)] if isinstance(names, dict) else list(names)
        check(judge_yolo(yolo, table, names[1:] + names[:1])[0], "shifted YOLO names pass")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    sys.exit(check.summary("nowhere: the temporary directory is removed"))


if __name__ == "__main__":
    main()
