#pragma once
// The dataset's documents: COCO instances_<split>.json and YOLO data.yaml, written
// deterministically (fixed member order, shortest round-trip numbers) from frame records.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hameritt/dataset/frame.h"

namespace hameritt::dataset {

// A COCO category: one per entity class of the world (id = the class's semantic id).
struct Category {
  int id = 0;
  std::string name;
};

// The world's entity classes as categories, in semantic id order.
std::vector<Category> entityCategories();

// YOLO class index of each category name (its position in `categories`).
std::map<std::string, int> yoloClassIndex(const std::vector<Category>& categories);

// A scene relation of the mission (hameritt/SceneRelation, ROS-free).
struct RelationRef {
  std::string target_id;
  std::string op;
  bool eventually = false;
  std::string related_id;
  std::string related_class;
  std::string text;
};

// The symbolic context of one mission bag: scenario id, the ids the simulator marked as
// targets (role "target"), and the mission's scene relations.
struct SceneContext {
  std::string scenario_id;
  std::vector<std::string> target_ids;
  std::vector<RelationRef> relations;
};

// One exported camera frame and the files written for it (paths relative to the dataset root).
struct FrameRecord {
  std::int64_t image_id = 0;
  std::string split;
  std::string camera;
  int width = 0, height = 0;
  std::int64_t stamp_ns = 0;  // header stamp (sim time) in nanoseconds
  std::string image_file, depth_file, segmentation_file, instances_file, label_file;
  int context = 0;  // index into the contexts
  std::vector<InstanceAnnotation> annotations;
};

// The COCO document of the frames of one split (frames in image id order; annotation ids
// continue from `*next_annotation_id`, which is advanced).
std::string cocoJson(const std::vector<const FrameRecord*>& frames,
                     const std::vector<Category>& categories,
                     const std::vector<SceneContext>& contexts, const std::string& split,
                     std::int64_t* next_annotation_id);

// YOLO's data.yaml: the split image folders and the class names.
std::string yoloDataYaml(const std::vector<std::string>& splits,
                         const std::vector<Category>& categories);

}  // namespace hameritt::dataset
