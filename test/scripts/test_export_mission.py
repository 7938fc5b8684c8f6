#!/usr/bin/env python3
"""End to end: record a short mission bag (mission.launch record:=true), export it with
hameritt_export, and judge the dataset with outside readers: Python rosbag reads the bag's
images, a COCO RLE decoder written here (from pycocotools' maskApi.c, independent of the
exporter) decodes every annotation, OpenCV reads the PNGs. Checks: every mask == (instances ==
id) exactly, bbox == mask extent, area == pixel count, categories and context fields, RGB,
segmentation, instances and depth (mm) PNGs against the bag, YOLO labels against the COCO boxes,
determinism (twice, and --jobs 1 vs 3), --every, --cameras, --split, PNG-compressed and 16UC1
depth input, and the error cases (truncated and unindexed bags, a missing file, bad flags,
SIGINT): each exits non-zero with a clear message and leaves no output."""
import filecmp
import json
import os
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time

import cv2
import numpy as np
import rosbag
import yaml

BIN = os.environ["HAMERITT_BIN_DIR"]
SRC = os.environ["HAMERITT_SOURCE_DIR"]
EXPORT = os.path.join(BIN, "hameritt_export")
MODALITIES = ["image_raw", "depth", "segmentation", "instances"]
fails = []
checks = [0]


def check(cond, what):
    checks[0] += 1
    if not cond:
        fails.append(what)
        print("FAIL:", what)
    return cond


def run(args, **kw):
    return subprocess.run([EXPORT] + args, capture_output=True, text=True, **kw)


# ------------------------------------------------------------------ COCO RLE (pycocotools)
def rle_counts(s):
    """rleFrString of pycocotools' maskApi.c."""
    counts, p = [], 0
    while p < len(s):
        x, k, more = 0, 0, True
        while more:
            c = ord(s[p]) - 48
            x |= (c & 0x1F) << (5 * k)
            more = c & 0x20
            p += 1
            k += 1
            if not more and (c & 0x10):
                x |= -1 << (5 * k)
        if len(counts) > 2:
            x += counts[-2]
        counts.append(x)
    return counts


def rle_decode(counts, h, w):
    """rleDecode: runs over the column-major pixels, starting with zeros."""
    flat = np.zeros(h * w, np.uint8)
    pos, v = 0, 0
    for c in counts:
        if c < 0:
            raise ValueError("negative run")
        if v:
            flat[pos:pos + c] = 1
        pos += c
        v ^= 1
    if pos != h * w:
        raise ValueError("runs sum to %d, expected %d" % (pos, h * w))
    return flat.reshape(w, h).T


# ------------------------------------------------------------------ bag contents
def image_array(msg):
    dtype = {"rgb8": np.uint8, "mono8": np.uint8, "16UC1": np.uint16, "32FC1": np.float32}[msg.encoding]
    ch = 3 if msg.encoding == "rgb8" else 1
    item = np.dtype(dtype).itemsize * ch
    a = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.step)[:, :msg.width * item]
    a = a.copy().view(dtype).reshape(msg.height, msg.width, ch)
    return a[:, :, 0] if ch == 1 else a


def read_bag(path):
    """Frame sets {(camera, stamp_ns): {modality: array, 'boxes': [...]}} and the mission."""
    frames, boxes, mission = {}, {}, None
    with rosbag.Bag(path) as bag:
        for topic, msg, _ in bag.read_messages():
            parts = topic.split("/")
            if topic == "/mission":
                mission = msg
            elif len(parts) == 6 and parts[1:3] == ["uav", "camera"] and parts[4] == "decimated" \
                    and parts[5] in MODALITIES:
                key = (parts[3], msg.header.stamp.to_nsec())
                frames.setdefault(key, {})[parts[5]] = image_array(msg)
            elif len(parts) == 5 and parts[1:3] == ["uav", "camera"] and parts[4] == "boxes":
                boxes[(parts[3], msg.header.stamp.to_nsec())] = msg.boxes
    for key, f in frames.items():
        if key in boxes:
            f["boxes"] = boxes[key]
    complete = {k: f for k, f in frames.items() if len(f) == 5}
    return complete, mission


def export(bag, out, *extra):
    r = run([bag, "--out", out, "--quiet"] + list(extra))
    check(r.returncode == 0, "export %s %s: rc %d: %s" % (bag, extra, r.returncode, r.stderr))
    return r


def same_tree(a, b):
    names_a = sorted(os.path.relpath(os.path.join(d, f), a) for d, _, fs in os.walk(a) for f in fs)
    names_b = sorted(os.path.relpath(os.path.join(d, f), b) for d, _, fs in os.walk(b) for f in fs)
    if names_a != names_b:
        return False
    return all(filecmp.cmp(os.path.join(a, n), os.path.join(b, n), shallow=False) for n in names_a)


def no_leftovers(parent, name):
    left = [n for n in os.listdir(parent) if n.startswith(name)]
    return check(not left, "output left behind: %s" % left)


# ------------------------------------------------------------------ the checks
def check_coco(ds, frames, mission, expect_keys=None):
    """Every image and annotation of a COCO dataset against the bag's frame sets."""
    ann_dir = os.path.join(ds, "annotations")
    images, anns, cats = {}, [], None
    for name in sorted(os.listdir(ann_dir)):
        doc = json.load(open(os.path.join(ann_dir, name)))
        split = name[len("instances_"):-len(".json")]
        cats = {c["id"]: c["name"] for c in doc["categories"]}
        for im in doc["images"]:
            check(im["id"] not in images, "image id %d twice" % im["id"])
            check(im["file_name"].startswith("images/%s/" % split),
                  "%s in %s" % (im["file_name"], name))
            images[im["id"]] = im
        anns += doc["annotations"]
    check(set(cats.values()) >= {"car", "pedestrian", "house", "tree", "street"},
          "categories %s" % cats)
    keys = {(im["extra"]["camera"], im["extra"]["stamp_ns"]): im for im in images.values()}
    check(len(keys) == len(images), "two images of one camera frame")
    if expect_keys is not None:
        check(set(keys) == set(expect_keys), "exported frames %d, expected %d" % (len(keys), len(expect_keys)))
    check(len({a["id"] for a in anns}) == len(anns), "duplicate annotation ids")
    by_image = {}
    for a in anns:
        by_image.setdefault(a["image_id"], []).append(a)
    relations = {(r.target_id, r.related_id, r.op) for r in mission.relations}
    targets = {b.entity_id for f in frames.values() for b in f["boxes"] if b.role == "target"}
    n_checked = 0
    for iid, im in images.items():
        key = (im["extra"]["camera"], im["extra"]["stamp_ns"])
        if not check(key in frames, "image %d: no frame set %s in the bag" % (iid, key)):
            continue
        f = frames[key]
        inst = f["instances"]
        h, w = inst.shape
        check((im["width"], im["height"]) == (w, h), "image %d size" % iid)
        check(im["extra"]["scenario_id"] == mission.scenario_id, "image %d scenario id" % iid)
        check(abs(im["extra"]["sim_time"] - key[1] * 1e-9) < 1e-9, "image %d sim_time" % iid)
        # The files against the bag.
        rgb = cv2.imread(os.path.join(ds, im["file_name"]), cv2.IMREAD_UNCHANGED)
        if im["file_name"].endswith(".png"):
            check(rgb is not None and np.array_equal(rgb[:, :, ::-1], f["image_raw"]),
                  "image %d: RGB PNG differs from the bag" % iid)
        seg = cv2.imread(os.path.join(ds, im["extra"]["segmentation_file"]), cv2.IMREAD_UNCHANGED)
        check(seg is not None and np.array_equal(seg, f["segmentation"]), "image %d segmentation" % iid)
        ins = cv2.imread(os.path.join(ds, im["extra"]["instances_file"]), cv2.IMREAD_UNCHANGED)
        check(ins is not None and ins.dtype == np.uint16 and np.array_equal(ins, inst),
              "image %d instances PNG" % iid)
        depth = cv2.imread(os.path.join(ds, im["extra"]["depth_file"]), cv2.IMREAD_UNCHANGED)
        d = f["depth"]
        if d.dtype == np.float32:
            ok = np.isfinite(d) & (d > 0)
            mm = np.where(ok, np.minimum(np.floor(d.astype(np.float64) * 1000 + 0.5), 65535), 0)
            check(depth is not None and depth.dtype == np.uint16 and
                  np.abs(depth.astype(np.int64) - mm.astype(np.int64)).max() <= 1,
                  "image %d depth PNG is not the bag's depth in mm" % iid)
        else:
            check(depth is not None and np.array_equal(depth, d), "image %d 16UC1 depth" % iid)
        # Every box with pixels has exactly one annotation; each mask is exactly its pixels.
        boxes = {b.instance_id: b for b in f["boxes"]}
        present = set(np.unique(inst).tolist()) - {0}
        want = {i for i in boxes if i in present}
        got = {a["extra"]["instance_id"]: a for a in by_image.get(iid, [])}
        check(set(got) == want, "image %d: annotated ids %s, boxes with pixels %s" %
              (iid, sorted(got), sorted(want)))
        for inst_id, a in got.items():
            b = boxes.get(inst_id)
            if not check(b is not None, "annotation %d: no box %d" % (a["id"], inst_id)):
                continue
            seg_rle = a["segmentation"]
            check(seg_rle["size"] == [h, w], "annotation %d size" % a["id"])
            mask = rle_decode(rle_counts(seg_rle["counts"]), h, w)
            truth = (inst == inst_id)
            check(np.array_equal(mask.astype(bool), truth), "annotation %d: mask != instance pixels" % a["id"])
            ys, xs = np.nonzero(truth)
            bbox = [int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)]
            check(a["bbox"] == bbox, "annotation %d bbox %s, mask extent %s" % (a["id"], a["bbox"], bbox))
            check(a["area"] == int(truth.sum()), "annotation %d area" % a["id"])
            check(a["iscrowd"] == 0, "iscrowd")
            check(cats.get(a["category_id"]) == b.entity_class, "annotation %d category" % a["id"])
            ex = a["extra"]
            check(ex["entity_id"] == b.entity_id and ex["role"] == b.role, "annotation %d entity" % a["id"])
            check(abs(a["occlusion"] - b.occlusion) < 1e-6, "annotation %d occlusion" % a["id"])
            check(ex["is_target"] == (b.role == "target"), "annotation %d is_target" % a["id"])
            check(set(ex["target_ids"]) == targets, "annotation %d target ids" % a["id"])
            named = {(r["target_id"], r["related_id"], r["op"]) for r in ex["relations"]}
            expected = {r for r in relations if b.entity_id in (r[0], r[1])}
            check(named == expected, "annotation %d relations %s, expected %s" % (a["id"], named, expected))
            n_checked += 1
    return images, anns, n_checked


def coco_categories(ds):
    """{category id: name} of a COCO export: its own class list, read from its files."""
    cats = {}
    ann_dir = os.path.join(ds, "annotations")
    for name in sorted(os.listdir(ann_dir)):
        cats.update({c["id"]: c["name"] for c in json.load(open(os.path.join(ann_dir, name)))["categories"]})
    return cats


def check_yolo(yolo, images, anns, cat_name):
    """The YOLO labels against the COCO annotations of the same export; cat_name maps the COCO
    category ids to names (the dataset's own class list, not ids written into this test)."""
    data = yaml.safe_load(open(os.path.join(yolo, "data.yaml")))
    names = data["names"]
    if isinstance(names, dict):  # {index: name} form of data.yaml
        names = [names[k] for k in sorted(names)]
    used = {cat_name.get(a["category_id"]) for a in anns}
    check(used and None not in used and used <= set(names),
          "YOLO names %s do not cover the annotated COCO classes %s" % (names, used))
    coco = {}
    for a in anns:
        coco.setdefault(a["image_id"], []).append(a)
    n = 0
    for iid, im in images.items():
        stem = os.path.splitext(os.path.basename(im["file_name"]))[0]
        split = im["file_name"].split("/")[1]
        check(data.get(split) == "images/" + split, "data.yaml %s" % split)
        path = os.path.join(yolo, "labels", split, stem + ".txt")
        if not check(os.path.exists(path), "no YOLO label %s" % path):
            continue
        lines = [l.split() for l in open(path).read().splitlines()]
        boxes = coco.get(iid, [])
        check(len(lines) == len(boxes), "%s: %d lines, %d COCO boxes" % (path, len(lines), len(boxes)))
        for l, a in zip(lines, boxes):
            x, y, w, h = a["bbox"]
            W, H = im["width"], im["height"]
            want = [(x + w / 2) / W, (y + h / 2) / H, w / W, h / H]
            check(names[int(l[0])] == cat_name.get(a["category_id"]), "%s class" % path)
            check(max(abs(float(v) - e) for v, e in zip(l[1:], want)) < 1e-6, "%s: %s vs %s" % (path, l, want))
            n += 1
    return n


def write_compressed_bag(src, dst):
    """The decimated images as compressed_image_transport PNGs (depth as 16UC1 millimetres)."""
    from sensor_msgs.msg import CompressedImage, Image
    with rosbag.Bag(src) as bag, rosbag.Bag(dst, "w") as out:
        for topic, msg, t in bag.read_messages():
            parts = topic.split("/")
            if topic == "/mission" or topic.endswith("/boxes"):
                out.write(topic, msg, t)
            elif "decimated" in parts and parts[-1] in MODALITIES:
                a = image_array(msg)
                if parts[-1] == "depth":
                    ok = np.isfinite(a) & (a > 0)
                    mm = np.where(ok, np.minimum(np.floor(a.astype(np.float64) * 1000 + 0.5), 65535), 0)
                    d = Image(header=msg.header, height=msg.height, width=msg.width, encoding="16UC1",
                              is_bigendian=0, step=msg.width * 2, data=mm.astype(np.uint16).tobytes())
                    out.write(topic, d, t)
                    continue
                c = CompressedImage(header=msg.header)
                if msg.encoding == "rgb8":
                    c.format = "rgb8; png compressed bgr8"
                    a = a[:, :, ::-1]  # the transport converts to bgr8 before cv::imencode
                else:
                    c.format = msg.encoding + "; png compressed "
                c.data = cv2.imencode(".png", np.ascontiguousarray(a))[1].tobytes()
                out.write(topic + "/compressed", c, t)


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_export_e2e.")
    try:
        run_all(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("%d checks" % checks[0])
    if fails:
        print("FAIL: %d of %d checks" % (len(fails), checks[0]))
        sys.exit(1)
    print("PASS: hameritt_export end to end")


def run_all(tmp):
    # A short real mission, recorded as a user does it.
    rec = os.path.join(tmp, "mission")
    port = 13000 + os.getpid() % 2000
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % port)
    t0 = time.time()
    r = subprocess.run(["timeout", "300", "roslaunch", "-p", str(port), "hameritt", "mission.launch",
                        "scenario:=" + os.path.join(SRC, "scenarios/default"), "mode:=end_to_end",
                        "record:=true", "time_limit:=6", "real_time_factor:=0", "output_dir:=" + rec],
                       env=env, capture_output=True, text=True)
    bag = os.path.join(rec, "mission.bag")
    if r.returncode != 0 or not os.path.exists(bag):
        print(r.stdout[-3000:], r.stderr[-3000:])
        check(False, "the mission recording failed (rc %d)" % r.returncode)
        return
    print("recorded %s in %.1f s" % (bag, time.time() - t0))
    frames, mission = read_bag(bag)
    check(mission is not None, "no /mission in the bag")
    check(len(frames) >= 8, "only %d complete frame sets in the bag" % len(frames))

    # COCO, two splits: every annotation against the bag.
    coco = os.path.join(tmp, "coco")
    r = export(bag, coco, "--format", "coco", "--split", "train=0.7,val=0.3", "--seed", "3")
    images, anns, n = check_coco(coco, frames, mission, expect_keys=frames.keys())
    print("COCO: %d images, %d annotations checked pixel for pixel" % (len(images), n))
    check(n >= 20, "only %d annotations" % n)
    check("%d images" % len(images) in r.stdout, "summary: %s" % r.stdout)
    split_n = {s: len(os.listdir(os.path.join(coco, "images", s))) for s in ("train", "val")}
    check(sum(split_n.values()) == len(images) and min(split_n.values()) > 0, "splits %s" % split_n)
    check("splits: train %d val %d" % (split_n["train"], split_n["val"]) in r.stdout, "summary splits")
    # Split by instant: the two cameras of one stamp share a split.
    by_stamp = {}
    for im in images.values():
        by_stamp.setdefault(im["extra"]["stamp_ns"], set()).add(im["file_name"].split("/")[1])
    check(all(len(s) == 1 for s in by_stamp.values()), "one instant in two splits")

    # Deterministic: same flags -> same bytes, whatever the number of threads.
    again = os.path.join(tmp, "coco_again")
    export(bag, again, "--format", "coco", "--split", "train=0.7,val=0.3", "--seed", "3", "--jobs", "1")
    check(same_tree(coco, again), "two exports (--jobs 2 and 1) differ")
    jobs3 = os.path.join(tmp, "coco_jobs3")
    export(bag, jobs3, "--format", "coco", "--split", "train=0.7,val=0.3", "--seed", "3", "--jobs", "3")
    check(same_tree(coco, jobs3), "--jobs 3 differs")
    other = os.path.join(tmp, "coco_seed4")
    export(bag, other, "--format", "coco", "--split", "train=0.7,val=0.3", "--seed", "4")
    check(not same_tree(coco, other), "another seed gives the same split")

    # YOLO cross-checked against the COCO boxes (same flags -> same image ids and names).
    yolo = os.path.join(tmp, "yolo")
    export(bag, yolo, "--format", "yolo", "--split", "train=0.7,val=0.3", "--seed", "3")
    print("YOLO: %d labels cross-checked" % check_yolo(yolo, images, anns, coco_categories(coco)))
    check(not os.path.exists(os.path.join(yolo, "annotations")), "YOLO wrote COCO annotations")

    # --every and --cameras.
    every = os.path.join(tmp, "every")
    export(bag, every, "--format", "coco", "--every", "3", "--cameras", "front")
    front = sorted(k for k in frames if k[0] == "front")
    ev_images, _, _ = check_coco(every, frames, mission, expect_keys=front[::3])
    check(len(ev_images) == len(front[::3]), "--every 3: %d images of %d front frames" % (len(ev_images), len(front)))

    # JPEG RGB.
    jpg = os.path.join(tmp, "jpg")
    export(bag, jpg, "--format", "coco", "--image-format", "jpg", "--cameras", "down")
    j = json.load(open(os.path.join(jpg, "annotations", "instances_train.json")))
    im = cv2.imread(os.path.join(jpg, j["images"][0]["file_name"]))
    check(j["images"][0]["file_name"].endswith(".jpg") and im is not None and im.shape[2] == 3, "JPEG RGB")

    # PNG-compressed images and 16UC1 depth in millimetres: the same dataset.
    cbag = os.path.join(tmp, "compressed.bag")
    write_compressed_bag(bag, cbag)
    cds = os.path.join(tmp, "coco_compressed")
    export(cbag, cds, "--format", "coco", "--split", "train=0.7,val=0.3", "--seed", "3")
    for sub in ("images", "instances", "segmentation"):
        check(same_tree(os.path.join(coco, sub), os.path.join(cds, sub)),
              "compressed input: %s differ from the raw export" % sub)
    a1 = json.load(open(os.path.join(coco, "annotations", "instances_train.json")))["annotations"]
    a2 = json.load(open(os.path.join(cds, "annotations", "instances_train.json")))["annotations"]
    check(a1 == a2, "compressed input: annotations differ")

    # A record_all-like bag (full-rate topic names only): auto picks it, --stream decimated fails.
    fbag = os.path.join(tmp, "full.bag")
    with rosbag.Bag(bag) as src_bag, rosbag.Bag(fbag, "w") as out_bag:
        for topic, msg, t in src_bag.read_messages():
            if topic == "/mission" or topic.endswith("/boxes"):
                out_bag.write(topic, msg, t)
            elif "/decimated/" in topic:
                out_bag.write(topic.replace("/decimated/", "/"), msg, t)
    fds = os.path.join(tmp, "coco_full")
    export(fbag, fds, "--format", "coco", "--split", "train=0.7,val=0.3", "--seed", "3")
    check(same_tree(os.path.join(coco, "annotations"), os.path.join(fds, "annotations")) and
          same_tree(os.path.join(coco, "images"), os.path.join(fds, "images")),
          "full-rate stream: the export differs from the decimated one")
    r = run([fbag, "--format", "coco", "--out", os.path.join(tmp, "bad8"), "--stream", "decimated"])
    check(r.returncode == 5 and "no camera" in r.stderr, "--stream decimated on a full bag: %d %s" %
          (r.returncode, r.stderr))
    no_leftovers(tmp, "bad8")

    # Preview: the project's own drawing of one image.
    pv = os.path.join(tmp, "preview.png")
    r = run(["--preview", coco, "--image-id", "1", "--out", pv])
    p = cv2.imread(pv)
    check(r.returncode == 0 and p is not None and p.shape[:2] == (480, 640), "preview: %s" % r.stderr)
    counts = {i: 0 for i in images}
    for a in anns:
        counts[a["image_id"]] += 1
    most = min(i for i in counts if counts[i] == max(counts.values()))
    r = run(["--preview", coco, "--image-id", "most", "--out", pv])
    check(r.returncode == 0 and ("image %d (%d annotations)" % (most, counts[most])) in r.stdout,
          "preview most: expected image %d: %s" % (most, r.stdout))

    # Error cases: non-zero exit, a message naming the file, no output left.
    def expect_fail(args, code, pattern, out_name):
        r = run(args)
        check(r.returncode == code, "%s: rc %d, expected %d (%s)" % (args, r.returncode, code, r.stderr.strip()))
        check(pattern in r.stderr, "%s: stderr lacks %r: %s" % (args, pattern, r.stderr.strip()))
        no_leftovers(tmp, out_name)

    size = os.path.getsize(bag)
    trunc = os.path.join(tmp, "truncated.bag")
    with open(bag, "rb") as f, open(trunc, "wb") as g:
        g.write(f.read(size // 2))
    expect_fail([trunc, "--format", "coco", "--out", os.path.join(tmp, "bad1")], 3, trunc, "bad1")
    # A recording that did not end (.bag.active): truncated, and no index position in the header.
    active = os.path.join(tmp, "mission.bag.active")
    data = bytearray(open(trunc, "rb").read())
    i = data.find(b"index_pos=")
    check(i > 0, "no index_pos in the bag header")
    data[i + 10:i + 18] = struct.pack("<Q", 0)
    open(active, "wb").write(data)
    expect_fail([active, "--format", "coco", "--out", os.path.join(tmp, "bad2")], 3, "not indexed", "bad2")
    expect_fail([os.path.join(tmp, "nope.bag"), "--format", "coco", "--out", os.path.join(tmp, "bad3")], 3,
                "nope.bag: no such file", "bad3")
    garbage = os.path.join(tmp, "garbage.bag")
    open(garbage, "wb").write(b"#ROSBAG V2.0\n" + os.urandom(5000))
    expect_fail([garbage, "--format", "coco", "--out", os.path.join(tmp, "bad4")], 3, garbage, "bad4")
    for args, pattern in [(["--format", "xml"], "--format"), (["--every", "0"], "--every"),
                          (["--split", "train=0.5"], "sum to"), (["--jobs", "x"], "--jobs"),
                          (["--cameras", "left"], "no camera 'left'"), (["--bogus"], "unknown flag")]:
        base = [bag, "--out", os.path.join(tmp, "bad5")]
        if "--format" not in args:
            base += ["--format", "coco"]
        expect_fail(base + args, 2, pattern, "bad5")
    expect_fail([bag, "--format", "coco"], 2, "--out", "bad6")
    expect_fail([bag, "--format", "coco", "--out", coco], 2, "exists", "coco.tmp")
    # SIGINT while exporting the bag many times over: exit 130, nothing left.
    slow = os.path.join(tmp, "bad7")
    p = subprocess.Popen([EXPORT] + [bag] * 40 + ["--format", "coco", "--out", slow, "--jobs", "1",
                         "--png-level", "9", "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    time.sleep(1.5)
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=60)
    check(p.returncode == 130, "SIGINT: rc %d, expected 130" % p.returncode)
    no_leftovers(tmp, "bad7")
    # --force replaces a dataset atomically.
    r = run([bag, "--format", "coco", "--out", every, "--force", "--quiet", "--cameras", "down"])
    j = json.load(open(os.path.join(every, "annotations", "instances_train.json")))
    check(r.returncode == 0 and all(i["extra"]["camera"] == "down" for i in j["images"]), "--force")
    no_leftovers(tmp, "every.")


if __name__ == "__main__":
    main()
