// Frame annotations (boxes = mask extents, area = pixel count, skipped boxes), YOLO labels,
// depth conversion, split parsing and the seeded split assignment, COCO document structure.
#include "hameritt/dataset/frame.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "hameritt/dataset/coco.h"

namespace hameritt::dataset {
namespace {

struct Image {
  int w = 10, h = 8;
  std::vector<std::uint16_t> px = std::vector<std::uint16_t>(80, 0);
  void fill(int x0, int y0, int x1, int y1, std::uint16_t id) {
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) px[y * w + x] = id;
    }
  }
};

BoxMeta box(const std::string& id, std::uint16_t inst, const std::string& cls = "car",
            const std::string& role = "traffic") {
  BoxMeta b;
  b.entity_id = id;
  b.entity_class = cls;
  b.role = role;
  b.instance_id = inst;
  b.occlusion = 0.25f;
  return b;
}

TEST(Frame, BoxesAreMaskExtentsAndAreasPixelCounts) {
  Image img;
  img.fill(2, 1, 5, 3, 4);  // 4 x 3 = 12 pixels
  img.fill(0, 6, 9, 7, 9);  // touches left, right and bottom borders: 20 pixels
  img.px[5 * 10 + 8] = 4;   // a stray pixel of 4 widens its extent
  int skipped = 0;
  const auto anns = annotateFrame(
      img.px.data(), img.w, img.h,
      {box("car_1", 4), box("ped_2", 9, "pedestrian", "target"), box("gone", 13), box("zero", 0)},
      &skipped);
  ASSERT_EQ(anns.size(), 2u);
  EXPECT_EQ(skipped, 2);
  EXPECT_EQ(anns[0].meta.entity_id, "car_1");
  EXPECT_EQ(anns[0].bboxX(), 2);
  EXPECT_EQ(anns[0].bboxY(), 1);
  EXPECT_EQ(anns[0].bboxW(), 7);  // x 2..8
  EXPECT_EQ(anns[0].bboxH(), 5);  // y 1..5
  EXPECT_EQ(anns[0].extent.pixels, 13u);
  EXPECT_EQ(anns[1].bboxX(), 0);
  EXPECT_EQ(anns[1].bboxW(), 10);
  EXPECT_EQ(anns[1].bboxY(), 6);
  EXPECT_EQ(anns[1].bboxH(), 2);
  EXPECT_EQ(anns[1].extent.pixels, 20u);
  const auto mask = decodeRuns(anns[1].counts, img.w, img.h);
  for (int i = 0; i < 80; ++i) EXPECT_EQ(mask[i], img.px[i] == 9 ? 1 : 0);

  const auto labels = yoloLabels(anns, img.w, img.h, {{"car", 6}, {"pedestrian", 7}});
  EXPECT_EQ(labels,
            "6 0.550000 0.437500 0.700000 0.625000\n"
            "7 0.500000 0.875000 1.000000 0.250000\n");
}

TEST(Frame, DepthMillimetres) {
  EXPECT_EQ(depthToMillimetres(1.2345f), 1235);  // 1234.5 -> nearest
  EXPECT_EQ(depthToMillimetres(0.0f), 0);
  EXPECT_EQ(depthToMillimetres(-1.0f), 0);
  EXPECT_EQ(depthToMillimetres(std::numeric_limits<float>::quiet_NaN()), 0);
  EXPECT_EQ(depthToMillimetres(std::numeric_limits<float>::infinity()), 0);
  EXPECT_EQ(depthToMillimetres(65.534f), 65534);
  EXPECT_EQ(depthToMillimetres(100.0f), 65535);
}

TEST(Frame, SplitParsing) {
  const auto s = parseSplits("train=0.8,val=0.2");
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[1].name, "val");
  EXPECT_DOUBLE_EQ(s[0].fraction, 0.8);
  for (const char* bad : {"", "train", "train=0.5", "train=0.8,val=0.3", "=1", "a=1,a=0", "train=x",
                          "tr ain=1", "train=0.8,", "a=-0.5,b=1.5"}) {
    EXPECT_THROW(parseSplits(bad), std::invalid_argument) << bad;
  }
}

TEST(Frame, SplitAssignmentSeededAndProportional) {
  const auto s = parseSplits("train=0.7,val=0.2,test=0.1");
  std::map<std::string, int> n;
  int changed = 0;
  for (int i = 0; i < 10000; ++i) {
    const std::string key = "bag@" + std::to_string(i * 100000000ll);
    const std::string& a = assignSplit(s, 5, key);
    EXPECT_EQ(a, assignSplit(s, 5, key));
    ++n[a];
    changed += a != assignSplit(s, 6, key);
  }
  // Binomial: 3 sigma of 10000 draws is < 150 for every split.
  EXPECT_NEAR(n["train"], 7000, 150);
  EXPECT_NEAR(n["val"], 2000, 150);
  EXPECT_NEAR(n["test"], 1000, 150);
  EXPECT_GT(changed, 3000);  // another seed, another assignment
  EXPECT_EQ(assignSplit(parseSplits("all=1"), 1, "x"), "all");
}

TEST(Coco, DocumentStructure) {
  Image img;
  img.fill(2, 1, 5, 3, 4);
  FrameRecord f;
  f.image_id = 3;
  f.camera = "down";
  f.width = img.w;
  f.height = img.h;
  f.stamp_ns = 12500000000;
  f.image_file = "images/train/000003_down.png";
  f.annotations =
      annotateFrame(img.px.data(), img.w, img.h, {box("car_706", 4, "car", "target")}, nullptr);
  SceneContext ctx;
  ctx.scenario_id = "sc1";
  ctx.target_ids = {"car_706"};
  ctx.relations = {{"car_706", "NEXT_TO", false, "tree_1", "tree", "[tree] [NEXT_TO] [car_706]"},
                   {"car_9", "NEXT_TO", false, "tree_2", "tree", "other"}};
  std::int64_t next = 10;
  const std::string text = cocoJson({&f}, entityCategories(), {ctx}, "train", &next);
  EXPECT_EQ(next, 11);
  EXPECT_EQ(text, cocoJson({&f}, entityCategories(), {ctx}, "train", &(next = 10)));
  const auto doc = nlohmann::json::parse(text);
  // The suburb's 8 classes, the city's 9 and the avoid missions' aircraft, each with its
  // semantic id.
  ASSERT_EQ(doc["categories"].size(), 18u);
  EXPECT_EQ(doc["categories"][8]["name"], "building");
  EXPECT_EQ(doc["categories"][8]["id"], 11);
  EXPECT_EQ(doc["categories"][16]["name"], "street_tree");
  EXPECT_EQ(doc["categories"][16]["id"], 19);
  EXPECT_EQ(doc["categories"][17]["name"], "aircraft");
  EXPECT_EQ(doc["categories"][17]["id"], 20);
  EXPECT_EQ(doc["images"][0]["extra"]["scenario_id"], "sc1");
  EXPECT_DOUBLE_EQ(doc["images"][0]["extra"]["sim_time"].get<double>(), 12.5);
  const auto& a = doc["annotations"][0];
  EXPECT_EQ(a["id"], 10);
  EXPECT_EQ(a["category_id"], 8);  // car's semantic id
  EXPECT_EQ(a["bbox"], nlohmann::json::parse("[2, 1, 4, 3]"));
  EXPECT_EQ(a["area"], 12);
  EXPECT_EQ(a["occlusion"].get<double>(), 0.25);
  EXPECT_EQ(a["segmentation"]["size"], nlohmann::json::parse("[8, 10]"));
  EXPECT_TRUE(a["extra"]["is_target"].get<bool>());
  ASSERT_EQ(a["extra"]["relations"].size(), 1u);
  EXPECT_EQ(a["extra"]["relations"][0]["related_id"], "tree_1");
  const auto runs = countsFromString(a["segmentation"]["counts"].get<std::string>());
  const auto mask = decodeRuns(runs, img.w, img.h);
  for (int i = 0; i < 80; ++i) EXPECT_EQ(mask[i], img.px[i] == 4 ? 1 : 0);

  const std::string yaml = yoloDataYaml({"train", "val"}, entityCategories());
  EXPECT_NE(yaml.find("val: images/val\n"), std::string::npos);
  EXPECT_NE(yaml.find("  6: car\n"), std::string::npos);
  EXPECT_NE(yaml.find("  8: building\n"), std::string::npos);
  EXPECT_NE(yaml.find("  16: street_tree\n"), std::string::npos);
  EXPECT_NE(yaml.find("  17: aircraft\n"), std::string::npos);
  EXPECT_NE(yaml.find("nc: 18\n"), std::string::npos);
}

}  // namespace
}  // namespace hameritt::dataset
