// The simulator's payload cameras through ROS, in lock-step: one frame set per camera period
// (also when several are rendered concurrently by the render threads, published in order),
// stamped with the sim time of the physics state shown, images of the advertised size and
// encoding, CameraInfo equal to the renderer's intrinsics, boxes that agree pixel for pixel with
// the instances image, and the ADK's perfect perception reporting exactly the boxes with enough
// visible pixels.
#include "hameritt/build_paths.h"
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include "hameritt/BoundingBoxArray.h"
#include "hameritt/PerceptionReport.h"
#include "hameritt/render/renderer.h"
#include "hameritt/scenario/sim_config_io.h"
#include "sim_test_client.h"

namespace {

struct CameraTopics {
  std::vector<sensor_msgs::Image> rgb, depth, seg, inst;
  std::vector<sensor_msgs::CameraInfo> info;
  std::vector<hameritt::BoundingBoxArray> boxes;
};

class CameraCollector {
 public:
  explicit CameraCollector(const std::vector<std::string>& names) {
    for (const auto& n : names) {
      const std::string ns = "/uav/camera/" + n + "/";
      CameraTopics* t = &cams[n];
      subs_.push_back(nh_.subscribe<sensor_msgs::Image>(ns + "image_raw", 50, [t](const auto& m) { t->rgb.push_back(*m); }));
      subs_.push_back(nh_.subscribe<sensor_msgs::Image>(ns + "depth", 50, [t](const auto& m) { t->depth.push_back(*m); }));
      subs_.push_back(nh_.subscribe<sensor_msgs::Image>(ns + "segmentation", 50, [t](const auto& m) { t->seg.push_back(*m); }));
      subs_.push_back(nh_.subscribe<sensor_msgs::Image>(ns + "instances", 50, [t](const auto& m) { t->inst.push_back(*m); }));
      subs_.push_back(nh_.subscribe<sensor_msgs::CameraInfo>(ns + "camera_info", 50, [t](const auto& m) { t->info.push_back(*m); }));
      subs_.push_back(nh_.subscribe<hameritt::BoundingBoxArray>(ns + "boxes", 50, [t](const auto& m) { t->boxes.push_back(*m); }));
    }
    subs_.push_back(nh_.subscribe<hameritt::PerceptionReport>("/adk/perfect_perception", 200, [this](const auto& m) { reports.push_back(*m); }));
  }
  bool connected() const {
    for (const auto& s : subs_) {
      if (s.getNumPublishers() == 0) return false;
    }
    return true;
  }
  // Waits until every camera has `n` messages on every topic.
  bool waitFor(std::size_t n) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(30);
    while (ros::WallTime::now() < until) {
      ros::spinOnce();
      bool all = true;
      for (const auto& [name, t] : cams) {
        all = all && t.rgb.size() >= n && t.depth.size() >= n && t.seg.size() >= n && t.inst.size() >= n &&
              t.info.size() >= n && t.boxes.size() >= n;
      }
      if (all) return true;
      ros::WallDuration(0.002).sleep();
    }
    return false;
  }
  std::map<std::string, CameraTopics> cams;
  std::vector<hameritt::PerceptionReport> reports;

 private:
  ros::NodeHandle nh_;
  std::vector<ros::Subscriber> subs_;
};

TEST(SimulatorCameras, FramesStampsIntrinsicsBoxesAndPerfectPerception) {
  const auto config =
      hameritt::scenario::loadSimConfig(std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/sim_config.json");
  std::vector<std::string> names;
  for (const auto& c : config.uav.cameras) names.push_back(c.name);
  ASSERT_EQ(names.size(), 2u);
  hameritt::testing::SimClient sim;
  CameraCollector col(names);
  sim.connect();
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(30);
  while (!col.connected() && ros::WallTime::now() < until) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  ASSERT_TRUE(col.connected());
  ros::WallDuration(0.5).sleep();  // the ADK subscribes to the boxes too

  // Take off, then 1 s of frames: 10 per camera at 10 Hz, one per 50 physics steps.
  sim.setPose(config.uav.start.x, config.uav.start.y, 25.0, config.uav.start.yaw);
  const int frames = 10;
  for (int i = 1; i <= frames; ++i) {
    sim.step(50);
    ASSERT_TRUE(col.waitFor(static_cast<std::size_t>(i))) << "frame " << i;
  }
  // Then 8 frame sets from one step call: the render threads (render_threads, default 2)
  // render them concurrently and must publish them complete and in order.
  const int batch = 8;
  sim.step(50 * batch);
  ASSERT_TRUE(col.waitFor(static_cast<std::size_t>(frames + batch)));
  for (int i = 0; i < 50; ++i) ros::spinOnce(), ros::WallDuration(0.002).sleep();

  int boxes_seen = 0;
  for (const auto& spec : config.uav.cameras) {
    const auto& t = col.cams[spec.name];
    const auto k = hameritt::render::intrinsicsFromHfov(spec.width, spec.height, spec.hfov_deg);
    ASSERT_EQ(t.rgb.size(), static_cast<std::size_t>(frames + batch)) << spec.name;
    for (int i = 0; i < frames + batch; ++i) {
      const double stamp = 0.1 * (i + 1);
      for (const auto* img : {&t.rgb[i], &t.depth[i], &t.seg[i], &t.inst[i]}) {
        EXPECT_NEAR(img->header.stamp.toSec(), stamp, 1e-9) << spec.name;
        EXPECT_EQ(img->header.frame_id, "uav/camera_" + spec.name + "_optical");
        EXPECT_EQ(img->width, 640u);
        EXPECT_EQ(img->height, 480u);
        EXPECT_EQ(img->data.size(), static_cast<std::size_t>(img->step) * img->height);
      }
      EXPECT_EQ(t.rgb[i].encoding, "rgb8");
      EXPECT_EQ(t.depth[i].encoding, "32FC1");
      EXPECT_EQ(t.seg[i].encoding, "mono8");
      EXPECT_EQ(t.inst[i].encoding, "16UC1");
      EXPECT_NEAR(t.info[i].header.stamp.toSec(), stamp, 1e-9);
      EXPECT_NEAR(t.boxes[i].header.stamp.toSec(), stamp, 1e-9);
      EXPECT_DOUBLE_EQ(t.info[i].K[0], k.fx);
      EXPECT_DOUBLE_EQ(t.info[i].K[2], k.cx);
      EXPECT_DOUBLE_EQ(t.info[i].K[4], k.fy);
      EXPECT_DOUBLE_EQ(t.info[i].K[5], k.cy);
      EXPECT_DOUBLE_EQ(t.info[i].P[0], k.fx);
      // Depth: positive metres or +inf (sky); never NaN.
      std::vector<float> depth(640 * 480);
      std::memcpy(depth.data(), t.depth[i].data.data(), depth.size() * 4);
      for (float d : depth) ASSERT_TRUE(d > 0 && !std::isnan(d));
      // Boxes agree with the instances image pixel for pixel.
      std::vector<std::uint16_t> inst(640 * 480);
      std::memcpy(inst.data(), t.inst[i].data.data(), inst.size() * 2);
      std::map<int, std::array<int, 5>> counted;  // instance -> count, x0, y0, x1, y1
      for (int v = 0; v < 480; ++v) {
        for (int u = 0; u < 640; ++u) {
          const int id = inst[v * 640 + u];
          if (id == 0) continue;
          auto it = counted.find(id);
          if (it == counted.end()) it = counted.emplace(id, std::array<int, 5>{0, u, v, u, v}).first;
          auto& c = it->second;
          ++c[0];
          c[1] = std::min(c[1], u), c[2] = std::min(c[2], v), c[3] = std::max(c[3], u), c[4] = std::max(c[4], v);
        }
      }
      for (const auto& b : t.boxes[i].boxes) {
        ++boxes_seen;
        const auto& c = counted.at(b.instance_id);
        EXPECT_EQ(static_cast<int>(b.visible_pixels), c[0]) << b.entity_id;
        EXPECT_EQ(b.x_min, c[1]);
        EXPECT_EQ(b.y_min, c[2]);
        EXPECT_EQ(b.x_max, c[3]);
        EXPECT_EQ(b.y_max, c[4]);
        EXPECT_LE(b.visible_pixels, b.total_pixels);
        EXPECT_TRUE(b.entity_class == "car" || b.entity_class == "pedestrian");
      }
    }
  }
  EXPECT_GT(boxes_seen, 0) << "no car or pedestrian in 1 s of both cameras";

  // Perfect perception: for each camera frame, exactly the boxes with >= 20 visible pixels.
  std::size_t checked = 0;
  for (const auto& r : col.reports) {
    const auto& t = col.cams[r.camera];
    const hameritt::BoundingBoxArray* frame = nullptr;
    for (const auto& b : t.boxes) {
      if (std::abs(b.header.stamp.toSec() - r.header.stamp.toSec()) < 1e-9) frame = &b;
    }
    if (!frame) continue;
    std::set<std::string> want, got;
    for (const auto& b : frame->boxes) {
      if (b.visible_pixels >= 20) want.insert(b.entity_id);
    }
    for (const auto& e : r.entities) got.insert(e.entity_id);
    EXPECT_EQ(got, want) << r.camera << " at " << r.header.stamp.toSec();
    ++checked;
  }
  EXPECT_GE(checked, static_cast<std::size_t>(frames)) << "perfect perception reports matched to frames";
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "simulator_cameras_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
