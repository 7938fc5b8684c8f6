#include "hameritt/dataset/coco.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "hameritt/scenario/entity.h"
#include "hameritt/scenario/json_writer.h"

namespace hameritt::dataset {

using scenario::JsonWriter;

std::vector<Category> entityCategories() {
  using scenario::EntityClass;
  std::vector<Category> out;
  for (EntityClass c : {EntityClass::kStreet, EntityClass::kDriveway, EntityClass::kHouse,
                        EntityClass::kGarage, EntityClass::kFence, EntityClass::kTree,
                        EntityClass::kCar, EntityClass::kPedestrian, EntityClass::kBuilding,
                        EntityClass::kParkingGarage, EntityClass::kParkingLot, EntityClass::kAlley,
                        EntityClass::kLampPost, EntityClass::kTrafficLight, EntityClass::kBusStop,
                        EntityClass::kBench, EntityClass::kStreetTree, EntityClass::kAircraft}) {
    out.push_back({scenario::semanticId(c), scenario::toString(c)});
  }
  std::sort(out.begin(), out.end(),
            [](const Category& a, const Category& b) { return a.id < b.id; });
  return out;
}

std::map<std::string, int> yoloClassIndex(const std::vector<Category>& categories) {
  std::map<std::string, int> out;
  for (std::size_t i = 0; i < categories.size(); ++i) out[categories[i].name] = static_cast<int>(i);
  return out;
}

namespace {

void writeRelation(JsonWriter& w, const RelationRef& r) {
  w.beginObject();
  w.key("target_id").value(r.target_id);
  w.key("op").value(r.op);
  w.key("eventually").value(r.eventually);
  w.key("related_id").value(r.related_id);
  w.key("related_class").value(r.related_class);
  w.key("text").value(r.text);
  w.endObject();
}

// Float metadata (occlusion) as the shortest decimal of the float, not of its double widening.
double floatValue(float f) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9g", static_cast<double>(f));
  for (int prec = 1; prec <= 9; ++prec) {
    char b[32];
    std::snprintf(b, sizeof(b), "%.*g", prec, static_cast<double>(f));
    if (std::strtof(b, nullptr) == f) return std::strtod(b, nullptr);
  }
  return std::strtod(buf, nullptr);
}

}  // namespace

std::string cocoJson(const std::vector<const FrameRecord*>& frames,
                     const std::vector<Category>& categories,
                     const std::vector<SceneContext>& contexts, const std::string& split,
                     std::int64_t* next_annotation_id) {
  std::map<std::string, int> category_id;
  for (const auto& c : categories) category_id[c.name] = c.id;
  JsonWriter w(false);
  w.beginObject();
  w.key("info").beginObject();
  w.key("description").value("hameritt mission bags exported by hameritt_export");
  w.key("version").value("1");
  w.key("split").value(split);
  w.key("depth_png").value("16-bit, millimetres, 0 = no return, 65535 = 65.535 m or farther");
  w.endObject();
  w.key("licenses").beginArray().endArray();
  w.key("categories").beginArray();
  for (const auto& c : categories) {
    w.beginObject();
    w.key("id").value(c.id);
    w.key("name").value(c.name);
    w.key("supercategory").value("entity");
    w.endObject();
  }
  w.endArray();
  w.key("images").beginArray();
  for (const FrameRecord* f : frames) {
    const SceneContext& ctx = contexts.at(static_cast<std::size_t>(f->context));
    w.beginObject();
    w.key("id").value(static_cast<std::int64_t>(f->image_id));
    w.key("file_name").value(f->image_file);
    w.key("width").value(f->width);
    w.key("height").value(f->height);
    w.key("extra").beginObject();
    w.key("sim_time").value(static_cast<double>(f->stamp_ns) / 1e9);
    w.key("stamp_ns").value(static_cast<std::int64_t>(f->stamp_ns));
    w.key("camera").value(f->camera);
    w.key("scenario_id").value(ctx.scenario_id);
    w.key("depth_file").value(f->depth_file);
    w.key("segmentation_file").value(f->segmentation_file);
    w.key("instances_file").value(f->instances_file);
    w.endObject();
    w.endObject();
  }
  w.endArray();
  w.key("annotations").beginArray();
  for (const FrameRecord* f : frames) {
    const SceneContext& ctx = contexts.at(static_cast<std::size_t>(f->context));
    for (const auto& a : f->annotations) {
      const auto cat = category_id.find(a.meta.entity_class);
      w.beginObject();
      w.key("id").value(static_cast<std::int64_t>((*next_annotation_id)++));
      w.key("image_id").value(static_cast<std::int64_t>(f->image_id));
      w.key("category_id").value(cat == category_id.end() ? 0 : cat->second);
      w.key("bbox").beginArray();
      w.value(a.bboxX()).value(a.bboxY()).value(a.bboxW()).value(a.bboxH());
      w.endArray();
      w.key("area").value(static_cast<std::int64_t>(a.extent.pixels));
      w.key("iscrowd").value(0);
      w.key("segmentation").beginObject();
      w.key("size").beginArray().value(f->height).value(f->width).endArray();
      w.key("counts").value(countsToString(a.counts));
      w.endObject();
      w.key("occlusion").value(floatValue(a.meta.occlusion));
      w.key("extra").beginObject();
      w.key("entity_id").value(a.meta.entity_id);
      w.key("entity_class").value(a.meta.entity_class);
      w.key("role").value(a.meta.role);
      w.key("instance_id").value(static_cast<int>(a.meta.instance_id));
      w.key("visible_pixels").value(static_cast<std::int64_t>(a.meta.visible_pixels));
      w.key("total_pixels").value(static_cast<std::int64_t>(a.meta.total_pixels));
      w.key("is_target").value(a.meta.role == "target");
      w.key("target_ids").beginArray();
      for (const auto& t : ctx.target_ids) w.value(t);
      w.endArray();
      w.key("relations").beginArray();
      for (const auto& r : ctx.relations) {
        if (r.target_id == a.meta.entity_id || r.related_id == a.meta.entity_id) {
          writeRelation(w, r);
        }
      }
      w.endArray();
      w.endObject();
      w.endObject();
    }
  }
  w.endArray();
  w.endObject();
  return w.take();
}

std::string yoloDataYaml(const std::vector<std::string>& splits,
                         const std::vector<Category>& categories) {
  std::string out =
      "# YOLO dataset written by hameritt_export: labels/<split>/<image>.txt hold\n"
      "# 'class cx cy w h' normalised to the image size.\npath: .\n";
  for (const auto& s : splits) out += s + ": images/" + s + "\n";
  out += "nc: " + std::to_string(categories.size()) + "\nnames:\n";
  for (std::size_t i = 0; i < categories.size(); ++i) {
    out += "  " + std::to_string(i) + ": " + categories[i].name + "\n";
  }
  return out;
}

}  // namespace hameritt::dataset
