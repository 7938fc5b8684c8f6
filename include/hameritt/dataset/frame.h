#pragma once
// One exported camera frame: the annotations of its instances, built from the instance image
// (mask, box = mask extent, area = pixel count) and the simulator's per-box metadata (entity,
// class, role, occlusion), plus the depth conversion and the split assignment.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hameritt/dataset/rle.h"

namespace hameritt::dataset {

// What the simulator says about one instance in one frame (hameritt/BoundingBox, ROS-free).
struct BoxMeta {
  std::string entity_id;
  std::string entity_class;
  std::string role;
  std::uint16_t instance_id = 0;
  std::uint32_t visible_pixels = 0;
  std::uint32_t total_pixels = 0;
  float occlusion = 0.0f;
};

// One annotation: the metadata, the mask's extent and its COCO RLE runs.
struct InstanceAnnotation {
  BoxMeta meta;
  MaskExtent extent;
  std::vector<std::uint32_t> counts;
  // COCO bbox [x, y, w, h] in pixels, w = x_max - x_min + 1.
  int bboxX() const { return extent.x_min; }
  int bboxY() const { return extent.y_min; }
  int bboxW() const { return extent.x_max - extent.x_min + 1; }
  int bboxH() const { return extent.y_max - extent.y_min + 1; }
};

// The extents of every instance id in a width x height instance image (one pass).
std::map<std::uint16_t, MaskExtent> instanceExtents(const std::uint16_t* instances, int width,
                                                    int height);

// Annotations of a frame, in the order of `boxes`: one per box whose instance id has at least
// one pixel in the image. Boxes whose id is 0 or absent from the image are counted in
// `*skipped` (may be null).
std::vector<InstanceAnnotation> annotateFrame(const std::uint16_t* instances, int width, int height,
                                              const std::vector<BoxMeta>& boxes, int* skipped);

// YOLO label lines "class cx cy w h" (normalised to the image, 6 decimals) of annotations;
// `class_index` maps an entity class to its YOLO class index (classes absent are left out).
std::string yoloLabels(const std::vector<InstanceAnnotation>& annotations, int width, int height,
                       const std::map<std::string, int>& class_index);

// Depth in metres (32-bit float) to millimetres (16-bit): round to nearest; NaN, infinite,
// <= 0 -> 0 (no return); >= 65.535 m -> 65535 (saturated).
std::uint16_t depthToMillimetres(float metres);

// A named split and its fraction, as in --split train=0.8,val=0.2.
struct SplitSpec {
  std::string name;
  double fraction = 1.0;
};

// Parses "name=fraction,..." (names [A-Za-z0-9_-]+, unique; fractions > 0 summing to 1 within
// 1e-6); throws std::invalid_argument with a message naming the bad part.
std::vector<SplitSpec> parseSplits(const std::string& text);

// The split of a key under a seed: a 64-bit hash of (seed, key) mapped to [0, 1) and looked up
// in the cumulative fractions. Same seed and key -> same split, on every machine.
const std::string& assignSplit(const std::vector<SplitSpec>& splits, std::uint64_t seed,
                               const std::string& key);

}  // namespace hameritt::dataset
