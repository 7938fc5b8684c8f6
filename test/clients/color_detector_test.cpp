// Colour/shape detector on synthetic frames (flat-topped coloured car bodies on a grey or green
// ground, exact depth, known intrinsics and pose), alone and with the context filter over the
// shipped scenario's neighborhood.
#include "hameritt/clients/color_detector.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "hameritt/clients/context_filter.h"
#include "hameritt/clients/public_config.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "synthetic_scene.h"

namespace hameritt::clients {
namespace {

using geometry::Vec2;
using geometry::Vec3;
using testing::car;
using testing::nadirCamera;
using testing::renderFrame;

const cv::Vec3b kWhite(235, 236, 238), kBlue(30, 60, 200), kRed(200, 25, 30);
const cv::Vec3b kAsphalt(110, 110, 112), kLawn(70, 130, 60);
const Vec3 kRav4(4.6, 1.855, 1.685);

const PinholeCamera& downCamera() {
  // The shipped scenario's down camera: 640 x 480, 62.044 deg.
  static const PinholeCamera cam = pinholeFromHfov(640, 480, 62.044);
  return cam;
}

TEST(ColorDetector, IntrinsicsAndOpticalFrameFollowTheConventions) {
  const PinholeCamera c = pinholeFromHfov(640, 480, 90.0);
  EXPECT_NEAR(c.fx, 320.0, 1e-9);
  EXPECT_DOUBLE_EQ(c.cx, 319.5);
  EXPECT_DOUBLE_EQ(c.cy, 239.5);
  EXPECT_THROW(pinholeFromHfov(640, 480, 180.0), scenario::ConfigError);
  // Down camera: optical z points down, x to the UAV's right, y backwards.
  const Eigen::Isometry3d down = nadirCamera(Vec3(0, 0, 40), 0.0);
  EXPECT_TRUE((down.linear() * Vec3::UnitZ()).isApprox(Vec3(0, 0, -1), 1e-12));
  EXPECT_TRUE((down.linear() * Vec3::UnitX()).isApprox(Vec3(0, -1, 0), 1e-12));
  EXPECT_TRUE((down.linear() * Vec3::UnitY()).isApprox(Vec3(-1, 0, 0), 1e-12));
  // A front camera pitched 10 deg down, UAV facing north: looks north and a little down.
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.linear() = Eigen::AngleAxisd(geometry::kPi / 2, Vec3::UnitZ()).toRotationMatrix();
  const Eigen::Isometry3d front = opticalPose(base, Vec3(0.1, 0, 0), Vec3(0, 10, 0));
  const Vec3 fwd = front.linear() * Vec3::UnitZ();
  EXPECT_NEAR(fwd.x(), 0.0, 1e-12);
  EXPECT_GT(fwd.y(), 0.9);
  EXPECT_NEAR(fwd.z(), -std::sin(geometry::degToRad(10)), 1e-12);
  EXPECT_TRUE(front.translation().isApprox(Vec3(0, 0.1, 0), 1e-12));
}

TEST(ColorDetector, ColourMasksSeparateTheCatalogColours) {
  const ColorShapeDetector det;
  cv::Mat img(1, 5, CV_8UC3);
  img.at<cv::Vec3b>(0, 0) = kWhite;
  img.at<cv::Vec3b>(0, 1) = kBlue;
  img.at<cv::Vec3b>(0, 2) = kRed;
  img.at<cv::Vec3b>(0, 3) = kAsphalt;
  img.at<cv::Vec3b>(0, 4) = cv::Vec3b(12, 12, 14);
  auto at = [](const cv::Mat& m, int i) { return m.at<std::uint8_t>(0, i) != 0; };
  const cv::Mat white = det.colorMask(img, "white"), blue = det.colorMask(img, "blue");
  const cv::Mat red = det.colorMask(img, "red"), black = det.colorMask(img, "black");
  const cv::Mat grey = det.colorMask(img, "grey");
  // White is tuned on real dawn-and-rain renders, where a white car is as dark as lit asphalt
  // (V ~ 100): the white box takes in the asphalt's grey too (the height gate drops the street).
  EXPECT_TRUE(at(white, 0) && !at(white, 1) && !at(white, 2));
  EXPECT_TRUE(at(blue, 1) && !at(blue, 0) && !at(blue, 2));
  EXPECT_TRUE(at(red, 2) && !at(red, 1) && !at(red, 0));
  EXPECT_TRUE(at(black, 4) && !at(black, 0));
  EXPECT_TRUE(at(grey, 3) && !at(grey, 0));
  EXPECT_THROW(det.colorMask(img, "mauve"), scenario::ConfigError);
  DetectorSettings bad = defaultDetectorSettings();
  bad.colors["white"][0].s_min = 300;
  EXPECT_THROW(ColorShapeDetector{bad}, scenario::ConfigError);
}

TEST(ColorDetector, FindsTheCarOfTheRightColourAndSizeWithItsPosition) {
  const Vec3 uav(10.0, -5.0, 38.0);
  const std::vector<testing::ColoredBox> scene = {
      car(12.3, -3.1, 0.6, 4.6, 1.855, 1.685, kWhite),  // the target's kind
      car(0.0, -12.0, 1.2, 4.6, 1.855, 1.685, kBlue),   // wrong colour
      car(16.0, -12.0, 0.0, 10.0, 4.0, 2.0, kWhite),    // white, but a shed
      car(-2.0, 5.0, 0.3, 2.0, 1.0, 1.2, kWhite),       // white, too small
  };
  const Eigen::Isometry3d pose = nadirCamera(uav, 0.4);
  const testing::Frame f = renderFrame(downCamera(), pose, scene, kAsphalt);
  const ColorShapeDetector det;
  const auto found = det.detect(f.rgb, f.depth, downCamera(), pose, "white", kRav4);
  std::vector<CarCandidate> accepted;
  for (const auto& c : found) {
    if (c.reject.empty()) accepted.push_back(c);
  }
  ASSERT_EQ(accepted.size(), 1u) << (found.empty() ? "" : found.front().reject);
  const CarCandidate& c = accepted.front();
  EXPECT_LT((c.position - Vec3(12.3, -3.1, 0.0)).norm(), 0.5);
  EXPECT_NEAR(c.length, 4.6, 0.3);
  EXPECT_NEAR(c.width, 1.855, 0.3);
  EXPECT_NEAR(std::abs(geometry::wrapPi(2 * (c.yaw - 0.6))) / 2, 0.0, 0.05);  // axis, mod pi
  EXPECT_NEAR(c.top, 1.685, 0.05);
  EXPECT_NEAR(c.range, 38.0 - 1.685 - 0.06, 0.5);
  EXPECT_GT(c.size_score, 0.7);
  // The shed and the small box are found but rejected by their size; the blue car is not white.
  int rejected_for_size = 0;
  for (const auto& x : found) rejected_for_size += x.reject.find("expected") != std::string::npos;
  EXPECT_EQ(rejected_for_size, 2);
  // Looking for a blue car finds the blue one.
  const auto blue = det.detect(f.rgb, f.depth, downCamera(), pose, "blue", kRav4);
  ASSERT_FALSE(blue.empty());
  EXPECT_TRUE(blue.front().reject.empty());
  EXPECT_LT((blue.front().position - Vec3(0.0, -12.0, 0.0)).norm(), 0.5);
  // And a red one finds nothing.
  EXPECT_TRUE(det.detect(f.rgb, f.depth, downCamera(), pose, "red", kRav4).empty());
}

TEST(ColorDetector, CarSplitByItsWindowsIsMergedAndGroundPaintIsIgnored) {
  const Vec3 uav(0.0, 0.0, 30.0);
  // A white car whose dark windscreen and rear window cut the top into hood, roof and trunk,
  // next to white road paint (on the ground: not at car height).
  std::vector<testing::ColoredBox> scene = {car(1.0, 2.0, 0.0, 4.6, 1.855, 1.5, kWhite)};
  scene.push_back(car(1.0 - 0.9, 2.0, 0.0, 0.5, 1.7, 1.52, cv::Vec3b(20, 25, 30)));
  scene.push_back(car(1.0 + 1.2, 2.0, 0.0, 0.5, 1.7, 1.52, cv::Vec3b(20, 25, 30)));
  const Eigen::Isometry3d pose = nadirCamera(uav, 0.0);
  testing::Frame f = renderFrame(downCamera(), pose, scene, kLawn);
  cv::rectangle(f.rgb, cv::Rect(40, 300, 200, 8), cv::Scalar(kWhite[0], kWhite[1], kWhite[2]),
                cv::FILLED);
  const ColorShapeDetector det;
  const auto found = det.detect(f.rgb, f.depth, downCamera(), pose, "white", kRav4);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_TRUE(found.front().reject.empty()) << found.front().reject;
  EXPECT_NEAR(found.front().length, 4.6, 0.3);
  EXPECT_LT((found.front().position - Vec3(1.0, 2.0, 0.0)).norm(), 0.5);
}

TEST(ColorDetector, CarsCutByTheImageBorderAreNotMeasured) {
  const Vec3 uav(0.0, 0.0, 38.0);
  const std::vector<testing::ColoredBox> scene = {car(17.0, 0.0, 0.0, 4.6, 1.855, 1.6, kWhite)};
  const Eigen::Isometry3d pose = nadirCamera(uav, 0.0);
  const testing::Frame f = renderFrame(downCamera(), pose, scene, kAsphalt);
  const auto found =
      ColorShapeDetector().detect(f.rgb, f.depth, downCamera(), pose, "white", kRav4);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found.front().reject, "touches the image border");
}

// The detector and the context filter together over the shipped scenario's neighborhood (the
// public map), with the scene built at the target's and the confusers' places.
class DetectorInContext : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    mission_ = new scenario::Mission(scenario::loadMission("scenarios/default/mission.json"));
    const scenario::SimConfig pub = loadPublicSimConfig("scenarios/default/sim_config.json");
    world_ = new scenario::World(scenario::generateCheckedWorld(pub, "sim_config.json"));
  }
  static void TearDownTestSuite() {
    delete world_;
    delete mission_;
  }

  // Detections of white RAV4s accepted by the detector and by the context at time t.
  std::vector<std::pair<CarCandidate, ContextVerdict>> look(
      const Vec3& uav, const std::vector<testing::ColoredBox>& scene, double t) const {
    const Eigen::Isometry3d pose = nadirCamera(uav, 0.0);
    const testing::Frame f = renderFrame(downCamera(), pose, scene, kAsphalt);
    const auto& target = mission_->objective.targets.front();
    const ContextFilter filter(*mission_, world_);
    std::vector<std::pair<CarCandidate, ContextVerdict>> out;
    for (const auto& c : ColorShapeDetector().detect(f.rgb, f.depth, downCamera(), pose,
                                                     target.color, nominalSize(target))) {
      if (!c.reject.empty()) continue;
      CandidatePose p;
      p.position = c.position;
      p.yaw = c.yaw;
      p.size = Vec3(c.length, c.width, nominalSize(target).z());
      out.emplace_back(c, filter.check(p, t, target));
    }
    return out;
  }

  static scenario::Mission* mission_;
  static scenario::World* world_;
};
scenario::Mission* DetectorInContext::mission_ = nullptr;
scenario::World* DetectorInContext::world_ = nullptr;

TEST_F(DetectorInContext, KeepsTheTargetAndRejectsALookAlikeThatIsNotNextToTheTree) {
  // The white RAV4 at the target's parking place (NEXT_TO tree_638, ON_TOP_OF street_32, ...),
  // and the same car 11 m down the street: in aoi_1, on the same street, but not next to the tree.
  const Vec2 target(-271.039, 248.982);
  const std::vector<testing::ColoredBox> scene = {
      car(target.x(), target.y(), 3.137, 4.6, 1.855, 1.685, kWhite),
      car(target.x() + 11.0, target.y() + 0.1, 3.137, 4.6, 1.855, 1.685, kWhite)};
  const auto seen = look(Vec3(target.x() + 5, target.y(), 38.0), scene, 100.0);
  ASSERT_EQ(seen.size(), 2u);
  int accepted = 0;
  for (const auto& [c, v] : seen) {
    if ((c.position.head<2>() - target).norm() < 0.5) {
      EXPECT_TRUE(v.accepted) << v.reason;
      EXPECT_EQ(v.region_id, "aoi_1");
      EXPECT_EQ(v.target_id, "car_706");
      EXPECT_GE(v.relations_checked, 5);
      EXPECT_GT(claimConfidence(c.size_score, v.relations_checked, v.relations_skipped), 0.8);
    } else {
      EXPECT_FALSE(v.accepted);
      EXPECT_NE(v.reason.find("tree_638"), std::string::npos) << v.reason;
    }
    accepted += v.accepted;
  }
  EXPECT_EQ(accepted, 1);
}

TEST_F(DetectorInContext, RejectsTheTargetsLookAlikeOutsideTheAreaOrOutsideItsWindow) {
  // Outside every area of interest (a confuser's place in the scenario).
  const Vec2 outside(294.322, 170.56);
  auto seen = look(Vec3(outside.x(), outside.y(), 38.0),
                   {car(outside.x(), outside.y(), 1.567, 4.6, 1.855, 1.685, kWhite)}, 100.0);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_FALSE(seen.front().second.accepted);
  EXPECT_NE(seen.front().second.reason.find("outside every active area"), std::string::npos);
  // The true target's place, but after aoi_1's window has closed (192 s).
  const Vec2 target(-271.039, 248.982);
  seen = look(Vec3(target.x(), target.y(), 38.0),
              {car(target.x(), target.y(), 3.137, 4.6, 1.855, 1.685, kWhite)}, 250.0);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_FALSE(seen.front().second.accepted);
}

TEST(ClaimConfidence, GrowsWithSizeAndVerifiedContext) {
  EXPECT_LT(claimConfidence(0.5, 0, 3), claimConfidence(0.5, 3, 0));
  EXPECT_LT(claimConfidence(0.2, 2, 1), claimConfidence(0.9, 2, 1));
  EXPECT_LE(claimConfidence(1.0, 6, 0), 1.0);
  EXPECT_GE(claimConfidence(0.0, 0, 0), 0.0);
}

}  // namespace
}  // namespace hameritt::clients
