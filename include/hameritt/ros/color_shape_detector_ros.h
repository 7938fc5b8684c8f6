#pragma once
// The baseline perception client: the colour/shape detector (clients::ColorShapeDetector) on the
// UAV's cameras, with the symbolic context (clients::ContextFilter over the public map) rejecting
// look-alikes, publishing one hameritt/Detection per candidate location.

#include <message_filters/pass_through.h>
#include <message_filters/time_synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <topic_tools/shape_shifter.h>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/Mission.h"
#include "hameritt/PerceptionReport.h"
#include "hameritt/clients/claims.h"
#include "hameritt/clients/color_detector.h"
#include "hameritt/clients/context_filter.h"
#include "hameritt/ros/lockstep.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::ros_wrappers {

// Topics (relative names), per camera c of ~cameras: sub uav/camera/<c>/image_raw (rgb8),
// uav/camera/<c>/depth (32FC1, matched by exact stamp), uav/camera/<c>/camera_info; sub mission
// (latched), adk/state (any type); tf map -> the image's frame (else map -> uav/base_link and the
// sim_config's mount); pub perception/detections (hameritt/Detection); with ~publish_blobs,
// pub perception/blobs (hameritt/PerceptionReport: per processed frame, the accepted blobs of
// each target description's colour with their image box and measured position, stamped with
// the image's header; entity_id and role empty, attributes the description's).
//
// Parameters (private): ~sim_config (required; public part only), ~cameras (["down"]),
// ~max_rate_hz (2: frames processed per camera and second of sim time), ~colors/<name> (lists of
// [h_min, h_max, s_min, s_max, v_min, v_max], OpenCV HSV scale; defaults for the catalog colours),
// ~min_blob_pixels, ~open_kernel, ~close_kernel, ~height_min, ~height_max, ~merge_gap,
// ~size_tolerance, ~max_range, ~reject_border (clients::DetectorSettings), ~region_tolerance,
// ~distance_tolerance, ~bearing_tolerance_deg, ~check_relations (clients::ContextSettings),
// ~claim_radius (4 m), ~claim_hold (30 s), ~min_confidence (0), ~mission_start_time (0),
// ~claim (true: publish claims on perception/detections), ~publish_blobs (false).
// config/perception_client.yaml holds the defaults (launch/clients.launch loads it).
class ColorShapeDetectorRos {
 public:
  // Throws scenario::ConfigError for bad parameters or files (the node exits with ROS_FATAL).
  ColorShapeDetectorRos(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  // Serves callbacks until shutdown (in turns when ~lockstep).
  void spin() { gate_->spin(); }

 private:
  struct Camera {
    std::string name;
    scenario::CameraSpec spec;
    std::optional<clients::PinholeCamera> intrinsics;  // from camera_info
    double last_processed = -1e18;
    // The subscriptions feed the pass-throughs, the pass-throughs the synchronizer (the
    // subscriptions are declared last, so they go first).
    message_filters::PassThrough<sensor_msgs::Image> image_in, depth_in;
    std::unique_ptr<message_filters::TimeSynchronizer<sensor_msgs::Image, sensor_msgs::Image>> sync;
    ros::Subscriber image_sub, depth_sub, info_sub;
  };

  void onMission(const hameritt::Mission::ConstPtr& msg);
  void onState(const topic_tools::ShapeShifter::ConstPtr& msg);
  void onFrame(Camera* camera, const sensor_msgs::Image::ConstPtr& image,
               const sensor_msgs::Image::ConstPtr& depth);
  // map -> optical frame at the image's stamp; std::nullopt when tf has no answer.
  std::optional<Eigen::Isometry3d> cameraPose(const Camera& camera,
                                              const sensor_msgs::Image& image) const;

  // First, destroyed last: the subscriptions go through it.
  std::unique_ptr<LockstepGate> gate_;
  scenario::SimConfig sim_;  // public part only
  std::unique_ptr<scenario::World> world_;
  clients::ContextSettings context_settings_;
  std::unique_ptr<clients::ColorShapeDetector> detector_;
  std::optional<scenario::Mission> mission_;
  std::unique_ptr<clients::ContextFilter> filter_;
  clients::ClaimLedger claims_;
  double max_rate_ = 2.0, min_confidence_ = 0.0, mission_start_ = 0.0;
  bool ended_ = false, claim_ = true, publish_blobs_ = false;

  tf2_ros::Buffer tf_;
  // Fills tf_ on its own thread; in lock-step, gated /tf and /tf_static subscriptions do.
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  ros::Subscriber tf_sub_, tf_static_sub_;
  std::vector<std::unique_ptr<Camera>> cameras_;
  ros::Publisher detection_pub_, blobs_pub_;
  ros::Subscriber mission_sub_, state_sub_;
};

}  // namespace hameritt::ros_wrappers
