#pragma once
// The UAV's payload cameras in the simulator node: renders each camera of the sim_config payload
// at its rate (in sim time) on a dedicated render thread that owns the EGL context, and
// publishes per camera /uav/camera/<name>/{image_raw, depth, segmentation, instances,
// camera_info, boxes}, stamped with the sim time of the physics state the images show. The
// physics loop hands over snapshots (time and UAV pose) and only waits when the render thread
// is more than `queue_depth` frames behind, so rendering overlaps physics and publishing.

#include <ros/ros.h>

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"
#include "hameritt/sim/simulator.h"

namespace hameritt::render {
class Renderer;
struct FrameSet;
}  // namespace hameritt::render

namespace hameritt::ros_wrappers {

class LockstepGate;

struct CameraRigOptions {
  std::string backend = "auto";  // EGL backend (render::RendererOptions::backend)
  std::string models_dir;        // "" = the package's models/
  bool weather = true;           // fog, dust, rain, snow effects on the colour image
  bool noise = true;             // sim_config camera noise
  // Level of detail (render::RendererOptions::lod_max_error_px; 0 = every mesh in full).
  double lod_max_error_px = 0.5;
  int queue_depth = 2;           // snapshots the physics loop may run ahead of the renderer
  // Render threads, each with its own renderer (EGL context): consecutive frame sets render
  // concurrently and are published in order. Two fill the gaps where one thread waits for the
  // rasterizer and the rasterizer for it.
  int render_threads = 2;
  double physics_rate_hz = 500;  // camera rates must divide it
  // Also publish every k-th frame's images on /uav/camera/<name>/decimated/<modality> at this
  // rate (Hz of sim time; 0 = off; must divide the camera rate): the compact training stream
  // that record.launch records by default.
  double decimated_rate_hz = 0.0;
  // The compact stream's depth: 16UC1 millimetres (render/depth_encoding.h: 0.5 mm, 0 = no
  // return, 65535 = 65.5345 m or farther) when true, else the full stream's 32FC1 metres.
  bool decimated_depth_mm = true;
  // The compact stream's colour image: without the sensor noise (render::FrameSet::
  // rgb_noise_free: blur and weather kept) when true, else the noisy full-rate image.
  bool decimated_rgb_noise_free = true;
  // Also publish the compact stream as sensor_msgs/CompressedImage PNG on <topic>/compressed
  // (ros_wrappers::toPngCompressed; depth only as 16UC1), at this zlib level (0-9; < 0: off).
  int decimated_png_level = -1;
  // Lock-step missions: every publisher is watched and every message counted (not owned).
  LockstepGate* gate = nullptr;
};

class CameraRig {
 public:
  // Throws scenario::ConfigError for a camera rate that does not divide the physics rate, and
  // render::RenderError when no EGL context can be made (the message says why).
  CameraRig(ros::NodeHandle& nh, const scenario::World& world, const scenario::SimConfig& config,
            const CameraRigOptions& options);
  ~CameraRig();
  CameraRig(const CameraRig&) = delete;
  CameraRig& operator=(const CameraRig&) = delete;

  // Called after every physics step with the step count since t = 0: queues a render of every
  // camera due at this step.
  void afterStep(std::int64_t step, const sim::UavState& uav);
  // Blocks until every queued frame has been rendered and published.
  void flush();
  // Frames rendered and published so far, all cameras.
  std::uint64_t framesPublished() const;
  std::string glRenderer() const;
  // Subscribers of one of the rig's topics (resolved name), or -1 when it is not the rig's.
  int subscribers(const std::string& topic) const;

  // Static transforms uav/base_link -> uav/camera_<name>_optical (optical: z forward, x right,
  // y down) for every camera.
  std::vector<std::pair<std::string, Eigen::Isometry3d>> opticalMounts() const;

 private:
  struct Camera;
  // The cameras due at one physics step, rendered as one batch.
  struct Job {
    std::uint64_t seq = 0;                              // order of publication
    std::vector<std::pair<int, std::uint64_t>> shots;  // (camera, frame index)
    double time = 0;
    Eigen::Isometry3d world_T_base = Eigen::Isometry3d::Identity();
    Eigen::Vector3d velocity{0, 0, 0};
  };
  void run(int worker);
  void publish(const Camera& cam, std::uint64_t frame, double time, const render::FrameSet& fs);

  const scenario::World& world_;
  const scenario::SimConfig& config_;
  CameraRigOptions options_;
  std::vector<std::unique_ptr<Camera>> cameras_;

  std::vector<std::thread> threads_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> queue_;
  std::uint64_t next_seq_ = 0;      // the next job's sequence number
  std::uint64_t next_publish_ = 0;  // the job whose frames are published next
  int busy_ = 0;                    // jobs taken by a render thread, not yet published
  bool stop_ = false;
  int ready_ = 0;                   // render threads that have built their renderer (or failed)
  std::string error_;
  std::string gl_renderer_;
  std::uint64_t published_ = 0;
};

}  // namespace hameritt::ros_wrappers
