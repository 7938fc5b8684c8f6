#include "hameritt/ros/cop_ros.h"

#include <ros/callback_queue.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <stdexcept>

#include "hameritt/CopTrackArray.h"
#include "hameritt/ros/cop_conversions.h"

namespace hameritt::ros_wrappers {
namespace {

std::atomic<bool> g_stop{false};

cop::CopConfig loadConfig(ros::NodeHandle& pnh) {
  cop::CopConfig c;
  pnh.param("process_accel_sigma", c.process_accel_sigma, c.process_accel_sigma);
  pnh.param("height_walk_sigma", c.height_walk_sigma, c.height_walk_sigma);
  pnh.param("gate_chi2", c.gate_chi2, c.gate_chi2);
  pnh.param("merge_chi2", c.merge_chi2, c.merge_chi2);
  pnh.param("initial_speed_sigma", c.initial_speed_sigma, c.initial_speed_sigma);
  int hits = static_cast<int>(c.confirm_hits);
  pnh.param("confirm_hits", hits, hits);
  if (hits < 1)
    throw std::invalid_argument("~confirm_hits = " + std::to_string(hits) + " (expected >= 1)");
  c.confirm_hits = static_cast<std::uint32_t>(hits);
  pnh.param("tentative_timeout", c.tentative_timeout, c.tentative_timeout);
  pnh.param("confirmed_timeout", c.confirmed_timeout, c.confirmed_timeout);
  pnh.param("belief_threshold", c.belief_threshold, c.belief_threshold);
  c.validate();
  return c;
}

}  // namespace

void spinUntilSignal() {
  std::signal(SIGINT, [](int) { g_stop = true; });
  std::signal(SIGTERM, [](int) { g_stop = true; });
  while (!g_stop && ros::ok()) ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.1));
}

CopRos::CopRos(ros::NodeHandle& nh, ros::NodeHandle& pnh) : picture_(loadConfig(pnh)) {
  double rate = 2.0;
  pnh.param("publish_rate_hz", rate, rate);
  pnh.param("frame_id", frame_id_, frame_id_);
  pnh.param("claim_sigma", claim_sigma_, claim_sigma_);
  pnh.param("perfect_sigma", perfect_sigma_, perfect_sigma_);
  if (!std::isfinite(rate) || rate <= 0)
    throw std::invalid_argument("~publish_rate_hz = " + std::to_string(rate) + " (expected > 0)");
  if (!std::isfinite(claim_sigma_) || claim_sigma_ <= 0)
    throw std::invalid_argument("~claim_sigma = " + std::to_string(claim_sigma_) +
                                " (expected > 0 m)");
  if (!std::isfinite(perfect_sigma_) || perfect_sigma_ <= 0)
    throw std::invalid_argument("~perfect_sigma = " + std::to_string(perfect_sigma_) +
                                " (expected > 0 m)");

  tracks_pub_ = nh.advertise<hameritt::CopTrackArray>("cop/tracks", 10);
  markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("cop/markers", 2);
  detection_sub_ = nh.subscribe("perception/detections", 100, &CopRos::onDetection, this);
  perception_sub_ = nh.subscribe("adk/perfect_perception", 50, &CopRos::onPerception, this);
  mission_sub_ = nh.subscribe("mission", 1, &CopRos::onMission, this);
  timer_ = nh.createTimer(ros::Duration(1.0 / rate), &CopRos::onTimer, this);
  ROS_INFO(
      "cop: fusing perception/detections and adk/perfect_perception, publishing cop/tracks "
      "at %.1f Hz (gate chi2 %.2f, confirm after %u reports)",
      rate, picture_.config().gate_chi2, picture_.config().confirm_hits);
}

void CopRos::onDetection(const hameritt::Detection::ConstPtr& msg) {
  try {
    reports_++;
    picture_.update({fromMsg(*msg, claim_sigma_)});
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(5.0, "cop: detection from %s ignored: %s", msg->client.c_str(), e.what());
  }
}

void CopRos::onPerception(const hameritt::PerceptionReport::ConstPtr& msg) {
  try {
    reports_++;
    picture_.update(fromMsg(*msg, perfect_sigma_));
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(5.0, "cop: perception report ignored: %s", e.what());
  }
}

void CopRos::onMission(const hameritt::Mission::ConstPtr& msg) {
  picture_.setTargets(targetsOf(*msg));
  ROS_INFO("cop: mission %s, %zu target(s)", msg->scenario_id.c_str(),
           msg->objective.targets.size());
}

void CopRos::onTimer(const ros::TimerEvent&) {
  const ros::Time now = ros::Time::now();
  picture_.prune(now.toSec());
  publish(now);
}

void CopRos::publish(const ros::Time& now) {
  hameritt::CopTrackArray array;
  array.header.stamp = now;
  array.header.frame_id = frame_id_;
  visualization_msgs::MarkerArray markers;
  visualization_msgs::Marker clear;
  clear.action = visualization_msgs::Marker::DELETEALL;
  markers.markers.push_back(clear);
  int n = 0;
  for (const auto& [id, track] : picture_.tracks()) {
    array.tracks.push_back(toMsg(track));
    const hameritt::CopTrack& t = array.tracks.back();
    visualization_msgs::Marker m;
    m.header = array.header;
    m.ns = "cop_tracks";
    m.id = n++;
    m.type = visualization_msgs::Marker::CYLINDER;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.position = t.position;
    m.pose.position.z += 1.0;
    m.pose.orientation.w = 1.0;
    // Two sigma across, at least 1 m.
    const double sigma = std::sqrt(std::max(t.position_covariance[0], t.position_covariance[4]));
    m.scale.x = m.scale.y = std::max(1.0, 4.0 * sigma);
    m.scale.z = 2.0;
    const bool target = !t.target_id.empty();
    m.color.r = target ? 1.0f : (t.confirmed ? 1.0f : 0.6f);
    m.color.g = target ? 0.1f : (t.confirmed ? 0.8f : 0.6f);
    m.color.b = target ? 0.1f : (t.confirmed ? 0.1f : 0.6f);
    m.color.a = 0.7f;
    markers.markers.push_back(m);
    visualization_msgs::Marker text = m;
    text.ns = "cop_labels";
    text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    text.pose.position.z += 4.0;
    text.scale.x = text.scale.y = 0.0;
    text.scale.z = 3.0;
    text.color.r = text.color.g = text.color.b = text.color.a = 1.0f;
    char belief[32];
    std::snprintf(belief, sizeof belief, " %.2f", t.target_belief);
    text.text = t.id + " " + t.entity_class + (target ? " = " + t.target_id + belief : "");
    markers.markers.push_back(text);
  }
  tracks_pub_.publish(array);
  markers_pub_.publish(markers);
  publications_++;
}

void CopRos::logSummary() const {
  const cop::CopStats& s = picture_.stats();
  size_t confirmed = 0;
  for (const auto& [id, t] : picture_.tracks()) confirmed += t.confirmed ? 1 : 0;
  ROS_INFO(
      "cop: summary: %zu tracks (%zu confirmed), %llu reports, %llu observations, %llu "
      "associated, %llu tracks created, %llu merged, %llu deleted, %llu publications",
      picture_.tracks().size(), confirmed, static_cast<unsigned long long>(reports_),
      static_cast<unsigned long long>(s.observations),
      static_cast<unsigned long long>(s.associated), static_cast<unsigned long long>(s.created),
      static_cast<unsigned long long>(s.merged), static_cast<unsigned long long>(s.deleted),
      static_cast<unsigned long long>(publications_));
  for (const cop::TargetSpec& target : picture_.targets()) {
    // Look-alikes with the same description are equally likely: list every candidate, best
    // first (belief, then reports), with the ground-truth entity where perfect perception gave it.
    std::vector<const cop::Track*> candidates;
    for (const auto& [id, t] : picture_.tracks())
      if (t.target_id == target.id) candidates.push_back(&t);
    std::stable_sort(candidates.begin(), candidates.end(), [](const auto* a, const auto* b) {
      return std::make_pair(a->target_belief, a->hits) > std::make_pair(b->target_belief, b->hits);
    });
    if (candidates.empty()) {
      ROS_INFO("cop: summary: target %s not found by any track", target.id.c_str());
      continue;
    }
    std::string list;
    for (const cop::Track* t : candidates) {
      char line[256];
      std::snprintf(line, sizeof line, "%s%s (belief %.2f, %u reports, at %.1f %.1f%s%s)",
                    list.empty() ? "" : ", ", t->id.c_str(), t->target_belief, t->hits,
                    t->state.x(), t->state.y(), t->entity_id.empty() ? "" : ", entity ",
                    t->entity_id.c_str());
      list += line;
    }
    ROS_INFO("cop: summary: target %s believed to be %s", target.id.c_str(), list.c_str());
  }
}

}  // namespace hameritt::ros_wrappers
