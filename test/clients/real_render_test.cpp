// The colour/shape detector on REAL frames of the in-house renderer (llvmpipe on a CPU, the EGL
// device on a GPU): the shipped default scenario (dawn, rain, camera noise) rendered from the
// front camera along the sim_config's perception path, where car_706 (the white RAV4 target) is
// in view, and from poses over the confusers' streets. The detector plus the context filter must
// claim the target within 2 m and never a confuser. Ground truth (entity poses, instance masks)
// is used here for judging and for the colour measurements only, never by the client code.
//
// HAMERITT_MEASURE=1 prints per-frame HSV percentiles of the target's and confusers' pixels
// (from the instance mask) and of the background, and every blob the detector measured.
#include "hameritt/build_paths.h"
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "hameritt/clients/color_detector.h"
#include "hameritt/clients/context_filter.h"
#include "hameritt/clients/public_config.h"
#include "hameritt/render/renderer.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::clients {
namespace {

using geometry::Vec3;

const std::string kDir = std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/";

bool measuring() {
  const char* m = std::getenv("HAMERITT_MEASURE");
  return m && *m && std::string(m) != "0";
}

struct Frame {
  cv::Mat rgb, depth;
  std::vector<std::uint16_t> instance;
  PinholeCamera cam;
  Eigen::Isometry3d world_T_optical;
};

class RealRenderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    truth_ = new scenario::SimConfig(scenario::loadSimConfig(kDir + "sim_config.json"));
    mission_ = new scenario::Mission(scenario::loadMission(kDir + "mission.json"));
    // The renderer draws the scenario (ground truth); the client's filter gets the public map.
    world_ = new scenario::World(scenario::generateCheckedWorld(*truth_, kDir + "sim_config.json"));
    public_world_ = new scenario::World(scenario::generateCheckedWorld(
        loadPublicSimConfig(kDir + "sim_config.json"), kDir + "sim_config.json"));
    renderer_ = new render::Renderer(*world_, *truth_);
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete public_world_;
    delete world_;
    delete mission_;
    delete truth_;
  }

  static const scenario::CameraSpec& camera(const std::string& name) {
    for (const auto& c : truth_->uav.cameras) {
      if (c.name == name) return c;
    }
    throw std::runtime_error("no camera " + name);
  }

  // The payload camera `name` on the UAV level at (x, y, z, yaw), scenario time t.
  static Frame render(const std::string& name, double x, double y, double z, double yaw,
                      double t, std::uint64_t frame_index = 0) {
    const scenario::CameraSpec& c = camera(name);
    render::RenderRequest req;
    req.intrinsics = render::intrinsicsFromHfov(c.width, c.height, c.hfov_deg);
    Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
    base.translation() = Eigen::Vector3d(x, y, z);
    base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    req.world_T_optical = render::opticalPose(base, c.mount_xyz, c.mount_rpy * (M_PI / 180.0));
    req.time = t;
    req.frame_index = frame_index;
    for (std::size_t i = 0; i < truth_->uav.cameras.size(); ++i) {
      if (truth_->uav.cameras[i].name == name) req.camera_index = static_cast<int>(i);
    }
    const render::FrameSet f = renderer_->render(req);
    Frame out;
    out.rgb = cv::Mat(f.intrinsics.height, f.intrinsics.width, CV_8UC3,
                      const_cast<std::uint8_t*>(f.rgb.data()))
                  .clone();
    out.depth = cv::Mat(f.intrinsics.height, f.intrinsics.width, CV_32FC1,
                        const_cast<float*>(f.depth.data()))
                    .clone();
    out.instance = f.instance;
    // What the client computes from the sim_config's mount (the same convention).
    out.cam = pinholeFromHfov(c.width, c.height, c.hfov_deg);
    out.world_T_optical = opticalPose(base, c.mount_xyz, c.mount_rpy);
    return out;
  }

  static Vec3 truthPosition(const std::string& id) {
    for (const auto& e : truth_->entities) {
      if (e.entity.id == id) return e.entity.position();
    }
    throw std::runtime_error("no entity " + id);
  }

  // HSV percentiles (5, 50, 95) of the pixels of one entity, or of the background (id "").
  static void printHsv(const Frame& f, const std::string& id, const char* label) {
    cv::Mat hsv;
    cv::cvtColor(f.rgb, hsv, cv::COLOR_RGB2HSV);
    std::vector<int> h, s, v;
    for (int i = 0; i < f.rgb.rows * f.rgb.cols; ++i) {
      const std::string& e = renderer_->instanceEntityId(f.instance[static_cast<std::size_t>(i)]);
      if (e != id) continue;
      const cv::Vec3b p = hsv.at<cv::Vec3b>(i / f.rgb.cols, i % f.rgb.cols);
      h.push_back(p[0]);
      s.push_back(p[1]);
      v.push_back(p[2]);
    }
    if (h.empty()) return;
    auto pct = [](std::vector<int> x, double q) {
      std::sort(x.begin(), x.end());
      return x[static_cast<std::size_t>(q * (x.size() - 1))];
    };
    std::printf("  %-10s %6zu px  H %3d/%3d/%3d  S %3d/%3d/%3d  V %3d/%3d/%3d\n", label, h.size(),
                pct(h, 0.05), pct(h, 0.5), pct(h, 0.95), pct(s, 0.05), pct(s, 0.5), pct(s, 0.95),
                pct(v, 0.05), pct(v, 0.5), pct(v, 0.95));
  }

  // HSV percentiles of car pixels nearer than max_range, pooled by the cars' paint colour.
  static void printByColour(const Frame& f, double max_range) {
    cv::Mat hsv;
    cv::cvtColor(f.rgb, hsv, cv::COLOR_RGB2HSV);
    std::map<std::string, std::string> colour_of;
    for (const auto& e : world_->entities()) colour_of[e.id] = e.attributes.str("color");
    for (const auto& e : truth_->entities) colour_of[e.entity.id] = e.entity.attributes.str("color");
    std::map<std::string, std::array<std::vector<int>, 3>> px;
    for (int i = 0; i < f.rgb.rows * f.rgb.cols; ++i) {
      const auto inst = f.instance[static_cast<std::size_t>(i)];
      if (inst == 0 || f.depth.at<float>(i / f.rgb.cols, i % f.rgb.cols) > max_range) continue;
      const auto it = colour_of.find(renderer_->instanceEntityId(inst));
      if (it == colour_of.end() || it->second.empty()) continue;
      const cv::Vec3b p = hsv.at<cv::Vec3b>(i / f.rgb.cols, i % f.rgb.cols);
      for (int c = 0; c < 3; ++c) px[it->second][static_cast<std::size_t>(c)].push_back(p[c]);
    }
    for (auto& [name, ch] : px) {
      auto pct = [](std::vector<int> x, double q) {
        std::sort(x.begin(), x.end());
        return x[static_cast<std::size_t>(q * (x.size() - 1))];
      };
      std::printf("  colour %-8s %6zu px  S %3d/%3d/%3d  V %3d/%3d/%3d/%3d/%3d\n", name.c_str(),
                  ch[0].size(), pct(ch[1], 0.05), pct(ch[1], 0.5), pct(ch[1], 0.95),
                  pct(ch[2], 0.05), pct(ch[2], 0.25), pct(ch[2], 0.5), pct(ch[2], 0.75), pct(ch[2], 0.95));
    }
  }

  struct Claim {
    Vec3 position;
    std::string reason;
  };

  // The client's pipeline on one frame: detector, then context filter at mission time t.
  static std::vector<Claim> claims(const Frame& f, double t, const ColorShapeDetector& det) {
    const scenario::TargetDescription& target = mission_->objective.targets.front();
    const ContextFilter filter(*mission_, public_world_);
    std::vector<Claim> out;
    for (const auto& c : det.detect(f.rgb, f.depth, f.cam, f.world_T_optical, target.color,
                                    nominalSize(target))) {
      std::string verdict = c.reject;
      if (c.reject.empty()) {
        CandidatePose p;
        p.position = c.position;
        p.yaw = c.yaw;
        p.size = Vec3(c.length, c.width, nominalSize(target).z());
        const ContextVerdict v = filter.check(p, t, target);
        if (v.accepted) {
          out.push_back({c.position, v.reason});
          verdict = "CLAIM (" + v.reason + ")";
        } else {
          verdict = "context: " + v.reason;
        }
      }
      if (measuring()) {
        std::printf("  blob (%.1f, %.1f) %.2f x %.2f m, %d px, range %.0f m: %s\n",
                    c.position.x(), c.position.y(), c.length, c.width, c.pixels, c.range,
                    verdict.c_str());
      }
    }
    return out;
  }

  static scenario::SimConfig* truth_;
  static scenario::Mission* mission_;
  static scenario::World* world_;
  static scenario::World* public_world_;
  static render::Renderer* renderer_;
};
scenario::SimConfig* RealRenderTest::truth_ = nullptr;
scenario::Mission* RealRenderTest::mission_ = nullptr;
scenario::World* RealRenderTest::world_ = nullptr;
scenario::World* RealRenderTest::public_world_ = nullptr;
render::Renderer* RealRenderTest::renderer_ = nullptr;

// The shipped config/perception_client.yaml's HSV ranges of one colour (the node loads them over
// the defaults), read with a line parser: "  white:  [[h0, h1, s0, s1, v0, v1], ...]".
std::vector<HsvRange> shippedRanges(const std::string& colour) {
  std::FILE* f = std::fopen((std::string(HAMERITT_SOURCE_DIR) + "/config/perception_client.yaml").c_str(), "r");
  if (!f) throw std::runtime_error("config/perception_client.yaml");
  char line[512];
  std::vector<HsvRange> out;
  while (std::fgets(line, sizeof(line), f)) {
    const std::string l = line;
    const std::string key = "  " + colour + ":";
    if (l.rfind(key, 0) != 0) continue;
    std::size_t at = l.find("[[");
    while (at != std::string::npos && at < l.size()) {
      const std::size_t open = l.find('[', at + 1);
      if (open == std::string::npos || l.find('#') < open) break;
      HsvRange r;
      if (std::sscanf(l.c_str() + open, "[%d, %d, %d, %d, %d, %d]", &r.h_min, &r.h_max, &r.s_min,
                      &r.s_max, &r.v_min, &r.v_max) != 6) {
        break;
      }
      out.push_back(r);
      at = l.find(']', open);
    }
  }
  std::fclose(f);
  return out;
}

// Settings under test: the defaults, with HAMERITT_WHITE=h0,h1,s0,s1,v0,v1 overriding white.
DetectorSettings measureSettings() {
  DetectorSettings s = defaultDetectorSettings();
  if (const char* w = std::getenv("HAMERITT_WHITE")) {
    HsvRange r;
    std::sscanf(w, "%d,%d,%d,%d,%d,%d", &r.h_min, &r.h_max, &r.s_min, &r.s_max, &r.v_min, &r.v_max);
    s.colors["white"] = {r};
  }
  return s;
}

TEST_F(RealRenderTest, Measure) {
  if (!measuring()) GTEST_SKIP() << "set HAMERITT_MEASURE=1";
  const auto& path = truth_->uav.perception_path->trajectory;
  const char* ts = std::getenv("HAMERITT_MEASURE_TIMES");
  std::vector<double> times;
  if (ts) {
    std::string s = ts;
    std::size_t a = 0;
    while (a < s.size()) {
      const std::size_t b = s.find(',', a);
      times.push_back(std::stod(s.substr(a, b - a)));
      if (b == std::string::npos) break;
      a = b + 1;
    }
  } else {
    for (double t = 20; t < 80; t += 5) times.push_back(t);
  }
  const ColorShapeDetector det(measureSettings());
  // A ring around the target at the search altitude, facing it (outside its keep-out zone).
  const Vec3 tgt = truthPosition(std::getenv("HAMERITT_MEASURE_ID") ? std::getenv("HAMERITT_MEASURE_ID") : "car_706");
  for (double r : {45.0, 70.0}) {
    for (int k = 0; k < 8; ++k) {
      const double a = k * M_PI / 4;
      const double x = tgt.x() + r * std::cos(a), y = tgt.y() + r * std::sin(a);
      const double yaw = a + M_PI;
      const Frame f = render("front", x, y, 38.0, yaw, 60.0);
      std::printf("ring r %.0f a %.0f deg uav (%.1f, %.1f)\n", r, a * 180 / M_PI, x, y);
      for (const auto& e : truth_->entities) {
        if (e.role == "target" || e.role == "confuser") printHsv(f, e.entity.id, e.entity.id.c_str());
      }
      printHsv(f, "", "background");
      printByColour(f, 90.0);
      claims(f, 60.0, det);
    }
  }
  for (double t : times) {
    const auto p = scenario::sampleTrajectory(path, t);
    const Frame f = render("front", p.x, p.y, p.z, p.yaw, t);
    const Vec3 tgt = truthPosition("car_706");
    std::printf("t %.1f  uav (%.1f, %.1f, %.1f) yaw %.2f  target %.0f m\n", t, p.x, p.y, p.z,
                p.yaw, std::hypot(tgt.x() - p.x, tgt.y() - p.y));
    printHsv(f, "car_706", "car_706");
    printHsv(f, "", "background");
    claims(f, t, det);
  }
}

// The client as shipped: default settings with the config file's white ranges.
DetectorSettings shippedSettings() {
  DetectorSettings s = defaultDetectorSettings();
  s.colors["white"] = shippedRanges("white");
  return s;
}

TEST_F(RealRenderTest, ShippedConfigMatchesDefaults) {
  const auto shipped = shippedRanges("white");
  const auto defaults = defaultDetectorSettings().colors.at("white");
  ASSERT_EQ(shipped.size(), defaults.size());
  for (std::size_t i = 0; i < shipped.size(); ++i) {
    EXPECT_EQ(shipped[i].s_max, defaults[i].s_max);
    EXPECT_EQ(shipped[i].v_min, defaults[i].v_min);
    EXPECT_EQ(shipped[i].v_max, defaults[i].v_max);
  }
}

// The target seen by the front camera from the search altitude (38 m), 45 to 70 m away, from
// several sides (outside its 0-96 m keep-out zone), with the shipped dawn, rain and noise.
TEST_F(RealRenderTest, FrontCameraClaimsTheTarget) {
  const ColorShapeDetector det(shippedSettings());
  const Vec3 target = truthPosition("car_706");
  struct View {
    double range, bearing_deg;
  };
  std::uint64_t frame = 1;
  for (const View& v : {View{45, 45}, View{45, 180}, View{45, 270}, View{70, 135}, View{70, 0}}) {
    const double a = v.bearing_deg * M_PI / 180;
    const double x = target.x() + v.range * std::cos(a), y = target.y() + v.range * std::sin(a);
    const Frame f = render("front", x, y, 38.0, a + M_PI, 60.0, frame++);
    const auto found = claims(f, 60.0, det);
    SCOPED_TRACE("from (" + std::to_string(x) + ", " + std::to_string(y) + ")");
    int near = 0;
    for (const auto& c : found) {
      const double d = (c.position - target).head<2>().norm();
      EXPECT_LT(d, 2.0) << "a claim at (" << c.position.x() << ", " << c.position.y()
                        << "), not the target";
      near += d < 2.0;
    }
    EXPECT_EQ(near, 1);
  }
}

// The confusers (white RAV4s too) from the search altitude, in their areas' windows: the detector
// measures them as RAV4-sized white blobs, and the context rejects every one.
TEST_F(RealRenderTest, FrontCameraClaimsNoConfuser) {
  const ColorShapeDetector det(shippedSettings());
  struct View {
    const char* id;
    double range, bearing_deg, t;
  };
  std::uint64_t frame = 11;
  for (const View& v : {View{"car_722", 45, 135, 60}, View{"car_668", 70, 180, 100},
                        View{"car_658", 45, 45, 150}, View{"car_721", 45, 180, 60}}) {
    const Vec3 p = truthPosition(v.id);
    const double a = v.bearing_deg * M_PI / 180;
    const double x = p.x() + v.range * std::cos(a), y = p.y() + v.range * std::sin(a);
    const Frame f = render("front", x, y, 38.0, a + M_PI, v.t, frame++);
    SCOPED_TRACE(v.id);
    // The confuser is measured (so the rejection below is the context's) ...
    bool measured = false;
    const auto& target = mission_->objective.targets.front();
    for (const auto& c : det.detect(f.rgb, f.depth, f.cam, f.world_T_optical, target.color,
                                    nominalSize(target))) {
      measured |= c.reject.empty() && (c.position - p).head<2>().norm() < 2.0;
    }
    EXPECT_TRUE(measured);
    // ... and nothing is claimed.
    for (const auto& c : claims(f, v.t, det)) {
      ADD_FAILURE() << "a claim at (" << c.position.x() << ", " << c.position.y() << ")";
    }
  }
}

}  // namespace
}  // namespace hameritt::clients
