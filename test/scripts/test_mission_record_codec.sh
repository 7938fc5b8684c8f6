#!/bin/bash
# The compact recording's image codecs, end to end with outside decoders: the simulator with every
# frame in the compact stream (record_codec.launch) records the 16UC1 depth, the noise-free colour
# image and the PNG CompressedImage streams beside the full-rate 32FC1 depth and noisy colour
# image of the same stamps; Python rosbag reads them back, OpenCV's PNG decoder decodes the PNGs.
# Checks: 16UC1 millimetres = the rendered 32FC1 metres to 0.5 mm (0 = no return, 65535 =
# 65.5345 m or farther); each PNG has the compressed_image_transport format string and decodes to
# the raw image bit for bit; the noisy image = the noise-free one + zero-mean noise of the
# scenario's gaussian_std (salt-and-pepper pixels aside).
source "$(dirname "$0")/cli_lib.sh" record_codec
set -eo pipefail
export PATH="/usr/bin:/bin:$PATH" ROS_MASTER_URI="http://localhost:$((14000 + $$ % 2000))"
limit=4
if ! timeout 300 roslaunch -p "${ROS_MASTER_URI##*:}" "$SRC/test/scripts/record_codec.launch" output:="$T/codec.bag" \
     limit:=$limit >"$T/launch.log" 2>&1; then
  echo "FAIL: roslaunch exited non-zero or timed out"; tail -40 "$T/launch.log"; exit 1
fi
/usr/bin/python3 - "$T/codec.bag" "$SRC" "$limit" <<'PY'
import collections, json, os, sys
import cv2
import numpy as np
import rosbag
bag_path, src, limit = sys.argv[1], sys.argv[2], int(sys.argv[3])
cfg = json.load(open(os.path.join(src, "scenarios/default/sim_config.json")))
sigma = cfg["perturbations"]["camera_noise"]["gaussian_std"] * 255.0
fails = []
checks = collections.Counter()
totals = collections.Counter()
msgs = {}
for topic, msg, _ in rosbag.Bag(bag_path).read_messages():
    msgs[(topic, msg.header.stamp.to_nsec())] = msg

def image(msg):
    dtype = {"rgb8": np.uint8, "mono8": np.uint8, "16UC1": np.uint16, "32FC1": np.float32}[msg.encoding]
    a = np.frombuffer(msg.data, dtype)
    return a.reshape(msg.height, msg.width, -1) if msg.encoding == "rgb8" else a.reshape(msg.height, msg.width)

plugin_format = {"rgb8": "rgb8; png compressed bgr8", "mono8": "mono8; png compressed ",
                 "16UC1": "16UC1; png compressed "}
for cam in ["front", "down"]:
    base = "/uav/camera/%s/" % cam
    stamps = sorted(s for t, s in msgs if t == base + "depth")
    if len(stamps) != limit:
        fails.append("%sdepth: %d messages, expected %d" % (base, len(stamps), limit))
    no_return = saturated = hits = 0
    for s in stamps:
        get = lambda t: msgs.get((base + t, s))
        missing = [t for t in ["depth", "image_raw"] + ["decimated/%s%s" % (m, c) for m in
                   ["image_raw", "depth", "segmentation", "instances"] for c in ["", "/compressed"]]
                   if get(t) is None]
        if missing:
            fails.append("%s stamp %d: no %s" % (cam, s, missing)); continue
        # Depth: 16UC1 millimetres against the rendered 32FC1 metres of the same frame.
        dm, mm = get("depth"), get("decimated/depth")
        if dm.encoding != "32FC1" or mm.encoding != "16UC1":
            fails.append("%s depth encodings %s / %s" % (cam, dm.encoding, mm.encoding)); continue
        d = image(dm).astype(np.float64); z = image(mm).astype(np.int64)
        finite = np.isfinite(d) & (d > 0)
        inrange = finite & (d < 65.5345)
        err = np.abs(z[inrange] / 1000.0 - d[inrange])
        if err.size and err.max() > 0.0005 + 1e-6:
            fails.append("%s depth: |mm - rendered| up to %.6f m" % (cam, err.max()))
        if np.any(z[~finite] != 0):
            fails.append("%s depth: a no-return pixel is not 0" % cam)
        if np.any(z[finite & (d >= 65.5345)] != 65535):
            fails.append("%s depth: a pixel beyond 65.5345 m is not 65535" % cam)
        if np.any(z[inrange] == 0):
            fails.append("%s depth: a hit decoded as no return" % cam)
        hits += int(inrange.sum()); no_return += int((~finite).sum()); saturated += int((finite & ~inrange).sum())
        checks["depth frames"] += 1
        # PNG streams: plugin format strings, decoded by OpenCV = the raw images bit for bit.
        for m in ["image_raw", "depth", "segmentation", "instances"]:
            raw, png = get("decimated/" + m), get("decimated/%s/compressed" % m)
            if png.format != plugin_format.get(raw.encoding):
                fails.append("%s %s/compressed format %r for %s" % (cam, m, png.format, raw.encoding)); continue
            dec = cv2.imdecode(np.frombuffer(png.data, np.uint8), cv2.IMREAD_UNCHANGED)
            if raw.encoding == "rgb8":
                dec = dec[:, :, ::-1]
            if dec is None or dec.shape != image(raw).shape or dec.dtype != image(raw).dtype or \
                    not np.array_equal(dec, image(raw)):
                fails.append("%s %s/compressed does not decode to the raw image" % (cam, m))
            checks["png images"] += 1
        # Colour: the full-rate image is the compact stream's noise-free one plus the noise.
        noisy = image(get("image_raw")).astype(np.int32); clean = image(get("decimated/image_raw")).astype(np.int32)
        salt = np.all((noisy == 0) | (noisy == 255), axis=2)
        keep = ~salt[..., None] & (clean > 40) & (clean < 215)
        diff = (noisy - clean)[keep]
        if np.array_equal(noisy, clean) or abs(diff.mean()) > 0.5 or not (0.8 * sigma < diff.std() < 1.2 * sigma):
            fails.append("%s colour: noisy - noise-free has mean %.2f, std %.2f (gaussian_std %.2f levels)"
                         % (cam, diff.mean(), diff.std(), sigma))
        checks["colour frames"] += 1
    print("%s: %d depth pixels within 0.5 mm, %d no return (0), %d saturated (65535)" % (cam, hits, no_return, saturated))
    totals.update(hits=hits, no_return=no_return, saturated=saturated)
# On the ground at the start the front camera sees terrain, far terrain and sky (the down one,
# at the ground, nothing): every rule of the encoding is exercised.
if min(totals["hits"], totals["no_return"], totals["saturated"]) == 0:
    fails.append("depth pixels compared: %s; expected some of each kind" % dict(totals))
print(dict(checks))
if checks["depth frames"] != 2 * limit or checks["png images"] != 8 * limit or checks["colour frames"] != 2 * limit:
    fails.append("checked %s, expected %d frames per camera" % (dict(checks), limit))
if fails:
    print("FAIL:\n  " + "\n  ".join(fails)); sys.exit(1)
print("PASS: 16UC1 depth within 0.5 mm, PNG streams lossless with the plugin's formats, noise-free colour = noisy - noise")
PY
