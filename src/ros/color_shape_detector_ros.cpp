#include "hameritt/ros/color_shape_detector_ros.h"

#include <tf2_msgs/TFMessage.h>

#include <boost/bind/bind.hpp>
#include <set>

#include "hameritt/clients/public_config.h"
#include "hameritt/ros/client_conversions.h"
#include "hameritt/ros/mission_conversions.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::ros_wrappers {

namespace {

constexpr const char* kClientName = "color_shape_detector";

Eigen::Isometry3d toIsometry(const geometry_msgs::Transform& t) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  x.linear() = Eigen::Quaterniond(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  return x;
}

int toInt(XmlRpc::XmlRpcValue& v, const std::string& field) {
  if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) return static_cast<int>(v);
  if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
    const double d = static_cast<double>(v);
    if (d == static_cast<int>(d)) return static_cast<int>(d);
  }
  throw scenario::ConfigError(field + ": expected an integer");
}

// ~colors/<name>: [[h_min, h_max, s_min, s_max, v_min, v_max], ...] replaces that colour's ranges.
void loadColors(ros::NodeHandle& pnh, clients::DetectorSettings* s) {
  XmlRpc::XmlRpcValue colors;
  if (!pnh.getParam("colors", colors)) return;
  if (colors.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    throw scenario::ConfigError("~colors: expected a map from colour names to HSV range lists");
  }
  for (auto it = colors.begin(); it != colors.end(); ++it) {
    const std::string field = "~colors/" + it->first;
    XmlRpc::XmlRpcValue& list = it->second;
    if (list.getType() != XmlRpc::XmlRpcValue::TypeArray || list.size() == 0) {
      throw scenario::ConfigError(field +
                                  ": expected a list of [h_min, h_max, s_min, s_max, "
                                  "v_min, v_max] ranges");
    }
    std::vector<clients::HsvRange> ranges;
    for (int i = 0; i < list.size(); ++i) {
      XmlRpc::XmlRpcValue& r = list[i];
      const std::string f = field + "[" + std::to_string(i) + "]";
      if (r.getType() != XmlRpc::XmlRpcValue::TypeArray || r.size() != 6) {
        throw scenario::ConfigError(f +
                                    ": expected 6 integers [h_min, h_max, s_min, s_max, "
                                    "v_min, v_max]");
      }
      clients::HsvRange h;
      h.h_min = toInt(r[0], f);
      h.h_max = toInt(r[1], f);
      h.s_min = toInt(r[2], f);
      h.s_max = toInt(r[3], f);
      h.v_min = toInt(r[4], f);
      h.v_max = toInt(r[5], f);
      ranges.push_back(h);
    }
    s->colors[it->first] = ranges;
  }
}

}  // namespace

ColorShapeDetectorRos::ColorShapeDetectorRos(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  gate_ = std::make_unique<LockstepGate>(nh, pnh);
  std::string sim_path;
  if (!pnh.getParam("sim_config", sim_path)) {
    throw scenario::ConfigError("~sim_config: required parameter (path of a sim_config.json)");
  }
  clients::DetectorSettings ds = clients::defaultDetectorSettings();
  loadColors(pnh, &ds);
  pnh.param("min_blob_pixels", ds.min_blob_pixels, ds.min_blob_pixels);
  pnh.param("open_kernel", ds.open_kernel, ds.open_kernel);
  pnh.param("close_kernel", ds.close_kernel, ds.close_kernel);
  pnh.param("height_min", ds.height_min, ds.height_min);
  pnh.param("height_max", ds.height_max, ds.height_max);
  pnh.param("merge_gap", ds.merge_gap, ds.merge_gap);
  pnh.param("size_tolerance", ds.size_tolerance, ds.size_tolerance);
  pnh.param("max_range", ds.max_range, ds.max_range);
  pnh.param("reject_border", ds.reject_border, ds.reject_border);
  pnh.param("snow_whitening", ds.snow_whitening, ds.snow_whitening);
  ds.validate();
  pnh.param("region_tolerance", context_settings_.region_tolerance,
            context_settings_.region_tolerance);
  pnh.param("distance_tolerance", context_settings_.distance_tolerance,
            context_settings_.distance_tolerance);
  pnh.param("bearing_tolerance_deg", context_settings_.bearing_tolerance_deg,
            context_settings_.bearing_tolerance_deg);
  pnh.param("check_relations", context_settings_.check_relations,
            context_settings_.check_relations);
  context_settings_.validate();
  double claim_radius = 4.0, claim_hold = 30.0;
  pnh.param("claim_radius", claim_radius, claim_radius);
  pnh.param("claim_hold", claim_hold, claim_hold);
  claims_ = clients::ClaimLedger(claim_radius, claim_hold);
  pnh.param("max_rate_hz", max_rate_, max_rate_);
  pnh.param("min_confidence", min_confidence_, min_confidence_);
  pnh.param("mission_start_time", mission_start_, mission_start_);
  pnh.param("claim", claim_, claim_);
  pnh.param("publish_blobs", publish_blobs_, publish_blobs_);
  if (!(max_rate_ > 0)) throw scenario::ConfigError("~max_rate_hz: expected > 0");

  // The honesty rule: the public map and the UAV's own cameras, never the scenario's entities.
  sim_ = clients::loadPublicSimConfig(sim_path);
  world_ = std::make_unique<scenario::World>(scenario::generateCheckedWorld(sim_, sim_path));
  // The weather any pilot sees: snow whitens the roofs a down camera sees.
  ds.snow = sim_.environment.snow;
  detector_ = std::make_unique<clients::ColorShapeDetector>(ds);  // validates

  // Both payload cameras: the front camera (oblique) sees targets the down camera cannot reach
  // (under vantage-denial keep-out zones).
  if (gate_->enabled()) {
    // Subscribed before the images: a turn hands the transforms over before the frames.
    auto feed = [this](bool is_static) {
      return std::function<void(const tf2_msgs::TFMessage::ConstPtr&)>(
          [this, is_static](const tf2_msgs::TFMessage::ConstPtr& m) {
            for (const auto& t : m->transforms) {
              try {
                tf_.setTransform(t, "lockstep", is_static);
              } catch (const std::exception& e) {
                ROS_WARN_THROTTLE(10.0, "%s: tf: %s", kClientName, e.what());
              }
            }
          });
    };
    tf_sub_ = gate_->subscribe<tf2_msgs::TFMessage>(nh, "/tf", 1000, feed(false));
    tf_static_sub_ = gate_->subscribe<tf2_msgs::TFMessage>(nh, "/tf_static", 100, feed(true));
  } else {
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_);
  }
  std::vector<std::string> names{"down", "front"};
  pnh.param("cameras", names, names);
  if (names.empty()) throw scenario::ConfigError("~cameras: expected at least one camera name");
  for (const auto& name : names) {
    auto cam = std::make_unique<Camera>();
    cam->name = name;
    bool found = false;
    for (const auto& c : sim_.uav.cameras) {
      if (c.name == name) {
        cam->spec = c;
        found = true;
      }
    }
    if (!found) {
      throw scenario::ConfigError("~cameras: " + sim_path + " has no payload camera named '" +
                                  name + "'");
    }
    const std::string ns = "uav/camera/" + name + "/";
    Camera* raw = cam.get();
    using ImageFn = std::function<void(const sensor_msgs::Image::ConstPtr&)>;
    cam->image_sub = gate_->subscribe<sensor_msgs::Image>(
        nh, ns + "image_raw", 4,
        ImageFn([raw](const sensor_msgs::Image::ConstPtr& m) { raw->image_in.add(m); }));
    cam->depth_sub = gate_->subscribe<sensor_msgs::Image>(
        nh, ns + "depth", 4,
        ImageFn([raw](const sensor_msgs::Image::ConstPtr& m) { raw->depth_in.add(m); }));
    cam->sync =
        std::make_unique<message_filters::TimeSynchronizer<sensor_msgs::Image, sensor_msgs::Image>>(
            cam->image_in, cam->depth_in, 8);
    cam->sync->registerCallback(boost::bind(&ColorShapeDetectorRos::onFrame, this, raw,
                                            boost::placeholders::_1, boost::placeholders::_2));
    cam->info_sub = gate_->subscribe<sensor_msgs::CameraInfo>(
        nh, ns + "camera_info", 1,
        std::function<void(const sensor_msgs::CameraInfo::ConstPtr&)>(
            [raw](const sensor_msgs::CameraInfo::ConstPtr& m) {
              try {
                raw->intrinsics = fromMsg(*m);
              } catch (const std::exception& e) {
                ROS_WARN_THROTTLE(10.0, "%s: %s: %s", kClientName, raw->name.c_str(), e.what());
              }
            }));
    cameras_.push_back(std::move(cam));
  }
  if (claim_) {
    detection_pub_ = gate_->advertise<hameritt::Detection>(nh, "perception/detections", 50);
  }
  if (publish_blobs_) {
    blobs_pub_ = gate_->advertise<hameritt::PerceptionReport>(nh, "perception/blobs", 20);
  }
  mission_sub_ = gate_->subscribe(nh, "mission", 1, &ColorShapeDetectorRos::onMission, this);
  state_sub_ = gate_->subscribe(nh, "adk/state", 10, &ColorShapeDetectorRos::onState, this);
  ROS_INFO("%s: %zu camera(s), waiting for the mission", kClientName, cameras_.size());
}

void ColorShapeDetectorRos::onMission(const hameritt::Mission::ConstPtr& msg) {
  std::optional<scenario::Mission> m = acceptMission(*msg, sim_.scenario_id, kClientName);
  if (!m) return;
  if (mission_ && mission_->scenario_id == m->scenario_id) return;
  mission_ = std::move(*m);
  filter_ = std::make_unique<clients::ContextFilter>(*mission_, world_.get(), context_settings_);
  for (const auto& t : mission_->objective.targets) {
    if (!detector_->settings().colors.count(t.color)) {
      ROS_WARN("%s: no HSV ranges for colour '%s': %s cannot be detected", kClientName,
               t.color.c_str(), t.id.c_str());
    }
  }
  ROS_INFO("%s: looking for %s", kClientName, mission_->objective.text.c_str());
}

void ColorShapeDetectorRos::onState(const topic_tools::ShapeShifter::ConstPtr& msg) {
  const auto reading = readMissionState(*msg);
  if (reading && reading->ended && !ended_) {
    ended_ = true;
    ROS_INFO("%s: the ADK says the mission is over (%s): no more claims", kClientName,
             reading->state.c_str());
  }
}

std::optional<Eigen::Isometry3d> ColorShapeDetectorRos::cameraPose(
    const Camera& camera, const sensor_msgs::Image& image) const {
  // In lock-step every transform up to the image has been handed over already: no waiting
  // (tf2_ros refuses a timeout without a listener thread).
  const bool wait = !gate_->enabled();
  auto lookup = [&](const std::string& frame) {
    return wait ? tf_.lookupTransform("map", frame, image.header.stamp, ros::Duration(0.05))
                : tf_.lookupTransform("map", frame, image.header.stamp);
  };
  // An optical frame (z forward, x right, y down) from tf as it is; anything else (no frame, a
  // camera link frame) from the body pose and the sim_config's mount.
  if (image.header.frame_id.find("optical") != std::string::npos) {
    try {
      return toIsometry(lookup(image.header.frame_id).transform);
    } catch (const tf2::TransformException&) {
    }
  }
  try {
    const auto base = lookup("uav/base_link");
    return clients::opticalPose(toIsometry(base.transform), camera.spec.mount_xyz,
                                camera.spec.mount_rpy);
  } catch (const tf2::TransformException& e) {
    ROS_WARN_THROTTLE(5.0, "%s: %s: no camera pose at %.3f: %s", kClientName, camera.name.c_str(),
                      image.header.stamp.toSec(), e.what());
  }
  return std::nullopt;
}

void ColorShapeDetectorRos::onFrame(Camera* camera, const sensor_msgs::Image::ConstPtr& image,
                                    const sensor_msgs::Image::ConstPtr& depth) {
  if (!mission_ || ended_) return;
  const double stamp = image->header.stamp.toSec();
  if (stamp - camera->last_processed < 1.0 / max_rate_) return;
  try {
    const auto pose = cameraPose(*camera, *image);
    if (!pose) return;
    const cv::Mat rgb = rgbFromMsg(*image);
    const cv::Mat range = depthFromMsg(*depth);
    clients::PinholeCamera intrinsics =
        camera->intrinsics ? *camera->intrinsics
                           : clients::pinholeFromHfov(rgb.cols, rgb.rows, camera->spec.hfov_deg);
    if (intrinsics.width != rgb.cols || intrinsics.height != rgb.rows) {
      ROS_WARN_THROTTLE(10.0, "%s: %s: camera_info is %dx%d, the image %dx%d: skipped", kClientName,
                        camera->name.c_str(), intrinsics.width, intrinsics.height, rgb.cols,
                        rgb.rows);
      return;
    }
    camera->last_processed = stamp;
    const double t = stamp - mission_start_;
    hameritt::PerceptionReport blobs;
    blobs.header = image->header;
    blobs.camera = camera->name;
    std::set<std::string> looked;  // one pass per distinct description
    for (const auto& target : mission_->objective.targets) {
      const std::string key =
          target.color + "/" + target.make + "/" + target.model + "/" + target.vehicle_class;
      if (!looked.insert(key).second || !detector_->settings().colors.count(target.color)) {
        continue;
      }
      const geometry::Vec3 size = clients::nominalSize(target);
      for (const auto& c : detector_->detect(rgb, range, intrinsics, *pose, target.color, size)) {
        // A track's box may be a vehicle's part the image border cuts; a claim needs its size.
        if (publish_blobs_ && detector_->trackable(c, size)) {
          blobs.entities.push_back(toPerceivedBlob(target, c));
        }
        if (!c.reject.empty()) {
          ROS_DEBUG("%s: %s blob at (%.1f, %.1f): %s", kClientName, target.color.c_str(),
                    c.position.x(), c.position.y(), c.reject.c_str());
          continue;
        }
        if (!claim_) continue;
        clients::CandidatePose p;
        p.position = c.position;
        p.yaw = c.yaw;
        p.yaw_ambiguous = true;
        p.size = geometry::Vec3(c.length, c.width, size.z());
        const clients::ContextVerdict v = filter_->check(p, t, target);
        if (!v.accepted) {
          ROS_INFO_THROTTLE(5.0,
                            "%s: a %s-sized %s blob at (%.1f, %.1f) does not fit the "
                            "context: %s",
                            kClientName, target.vehicle_class.c_str(), target.color.c_str(),
                            c.position.x(), c.position.y(), v.reason.c_str());
          continue;
        }
        const double confidence =
            clients::claimConfidence(c.size_score, v.relations_checked, v.relations_skipped);
        if (confidence < min_confidence_ || !claims_.claim(c.position, t)) continue;
        gate_->publish(detection_pub_, makeDetection(kClientName, target, c.position, confidence,
                                                     image->header.stamp));
        ROS_INFO(
            "%s: claim: %s at (%.1f, %.1f) from the %s camera, %.1f x %.1f m, confidence "
            "%.2f (%s)",
            kClientName, clients::describe(target).c_str(), c.position.x(), c.position.y(),
            camera->name.c_str(), c.length, c.width, confidence, v.reason.c_str());
      }
    }
    if (publish_blobs_) gate_->publish(blobs_pub_, blobs);
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(5.0, "%s: %s frame at %.3f skipped: %s", kClientName, camera->name.c_str(),
                      stamp, e.what());
  }
}

}  // namespace hameritt::ros_wrappers
