#pragma once
// The in-house off-screen renderer: OpenGL 4.5 core over EGL, headless (Mesa's surfaceless
// platform with llvmpipe on a CPU-only machine, the EGL device platform on an NVIDIA GPU). One
// geometry pass writes lit colour, metric depth along the optical axis and packed semantic +
// instance labels into a multi-target framebuffer; a particle pass adds rain and snow, and after
// the read-back the CPU adds motion blur and the seeded camera noise, to the colour only. Labels
// and depth are exact ground truth of the drawn geometry; bounding boxes come from the instance
// mask. ROS-free.
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "hameritt/scenario/entity.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::render {

// Semantic ids besides scenario::semanticId(class): sky (nothing hit), ground (lawn and
// sidewalks), and the UAV model (drawn only with RenderRequest::draw_uav).
constexpr int kSkySemantic = 0;
constexpr int kGroundSemantic = 1;
constexpr int kUavSemantic = 10;

// EGL/GL unavailable, a model file missing or malformed, a bad request. The message names the
// file or the field.
class RenderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Pinhole intrinsics in the ROS / OpenCV convention: pixel centres at integer (u, v), u right,
// v down, no distortion. The renderer's projection matches them exactly, so
// sensor_msgs/CameraInfo K = [fx 0 cx; 0 fy cy; 0 0 1], P = [K | 0].
struct Intrinsics {
  int width = 640;
  int height = 480;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};
// Square pixels, principal point at the image centre: fx = fy = (width / 2) / tan(hfov / 2),
// cx = (width - 1) / 2, cy = (height - 1) / 2. Throws RenderError for sizes < 1 or a field of
// view outside (0, 180) degrees.
Intrinsics intrinsicsFromHfov(int width, int height, double hfov_deg);

// The optical frame (z forward, x right, y down) of a camera mounted on base_link (FLU) at
// mount_xyz (m) with mount_rpy (radians, roll-pitch-yaw, positive pitch looks down), in the
// world (ENU), given world_T_base.
Eigen::Isometry3d opticalPose(const Eigen::Isometry3d& world_T_base, const Eigen::Vector3d& mount_xyz,
                              const Eigen::Vector3d& mount_rpy);

// Pixel (u, v) where a world point appears in a camera at world_T_optical with intrinsics k
// (u = fx X / Z + cx, v = fy Y / Z + cy in the optical frame); false when Z <= 0.
bool projectPoint(const Intrinsics& k, const Eigen::Isometry3d& world_T_optical,
                  const Eigen::Vector3d& p_world, Eigen::Vector2d* uv);

struct RenderRequest {
  Intrinsics intrinsics;
  Eigen::Isometry3d world_T_optical = Eigen::Isometry3d::Identity();
  // Scenario time (s): moving entities are drawn at their sim_config trajectory pose at this time.
  double time = 0.0;
  // Seeds the camera noise and the weather particles together with the scenario seed and the
  // camera index: the same (seed, camera_index, frame_index) gives the same image, byte for byte.
  int camera_index = 0;
  std::uint64_t frame_index = 0;
  // Colour effects; false gives the clean image (labels and depth are never affected).
  bool weather = true;  // fog/dust attenuation, rain/snow particles, snow cover (from sim_config)
  bool noise = true;    // sim_config perturbations.camera_noise
  // Also return FrameSet::rgb_noise_free: the colour image with its blur and weather but
  // without the sensor noise (Gaussian, salt-and-pepper), from the same pass.
  bool noise_free_rgb = false;
  // Image-plane direction of the motion blur (perturbations.camera_noise.motion_blur_px long).
  Eigen::Vector2d blur_direction{1.0, 0.0};
  // Draw the UAV model at world_T_uav (for external views; a payload camera leaves it out).
  bool draw_uav = false;
  Eigen::Isometry3d world_T_uav = Eigen::Isometry3d::Identity();
  double near_clip = 0.1;   // m
  double far_clip = 2000.0; // m
  // Entity ids (world or scenario) left out of this frame: not drawn, not labelled, no box.
  std::vector<std::string> hidden_entities;
};

// Whether the instances of a class get a BoundingBox: cars and pedestrians, and the city's
// classes (building, parking_garage, parking_lot, alley, lamp_post, traffic_light, bus_stop,
// bench, street_tree). The suburb's scenery (street, driveway, house, garage, fence, tree) gets
// none.
bool hasBoundingBox(scenario::EntityClass c);

// A 2D box of one entity of interest (hasBoundingBox(): parked world cars, the scenario's
// entities, the city's buildings and street furniture) with at least one visible pixel,
// computed from the instance mask.
struct BoundingBox {
  int instance = 0;                   // value in FrameSet::instance
  std::string entity_id;              // "car_706", "building_12"
  scenario::EntityClass cls = scenario::EntityClass::kCar;
  std::string role;                   // scenario role (target, confuser, ...) or "world"
  int x_min = 0, y_min = 0, x_max = 0, y_max = 0;  // inclusive pixel bounds of the visible pixels
  int visible_pixels = 0;             // pixels of the instance in the mask
  int total_pixels = 0;               // pixels the entity covers with nothing in front of it
  double occlusion = 0.0;             // 1 - visible / total
};

struct FrameSet {
  double time = 0.0;
  Intrinsics intrinsics;
  Eigen::Isometry3d world_T_optical = Eigen::Isometry3d::Identity();
  std::vector<std::uint8_t> rgb;        // width*height*3, row-major, top row first (rgb8)
  std::vector<std::uint8_t> rgb_noise_free;  // RenderRequest::noise_free_rgb, else empty
  std::vector<float> depth;             // metres along the optical axis; +inf where nothing is hit
  std::vector<std::uint8_t> semantic;   // 0 sky, 1 ground, else scenario::semanticId(class)
  std::vector<std::uint16_t> instance;  // 0 none, else Renderer::instanceEntityId(value)
  std::vector<BoundingBox> boxes;       // sorted by instance
};

struct RendererOptions {
  std::string models_dir;          // meshes (models/meshes/*.obj); empty: <package>/models
  std::string backend = "auto";    // auto (device if an EGL device with a GPU exists, else
                                   // surfaceless) | surfaceless | device; the environment
                                   // variable HAMERITT_EGL_BACKEND overrides it
  // Wait for the GL at the end of each stage so that Renderer::lastStats() splits the frame
  // time by stage (benchmarks); off, the stage times only count the calling thread's work.
  bool stage_timing = false;
  // Level of detail: an instance whose class mesh has a coarse version (models/meshes/lod.json)
  // is drawn with it when the coarse mesh's stated deviation from the full mesh, scaled to the
  // instance and projected at the instance's nearest depth, is at most this many pixels
  // anywhere in the image (first-order bound). Labels, depth and boxes are those of what is
  // drawn. 0 draws every instance with its full mesh.
  double lod_max_error_px = 0.5;
};

// What the last render() call did and where its time went (milliseconds of wall time; summed
// over the requests of a batch).
struct RenderStats {
  double cull_upload_ms = 0;   // frustum culling, instance upload
  double draw_ms = 0;          // geometry pass (with stage_timing: until the GL has finished it)
  double post_ms = 0;          // weather particles, motion blur, noise
  double readback_ms = 0;      // colour, depth and labels read back and split
  double boxes_ms = 0;         // boxes: entities drawn alone and their pixels counted
  std::size_t instances = 0;   // instances drawn in the geometry pass
  std::size_t lod_instances = 0;  // of which drawn with a coarser level of detail
  std::size_t box_groups = 0;     // boxes: groups of entities drawn alone
  std::size_t triangles = 0;   // triangles submitted to the geometry pass
  std::size_t draw_calls = 0;  // all passes
};

// World triangles for ray-cast checks (what the renderer draws, in world coordinates).
struct SceneTriangles {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::uint32_t> indices;  // 3 per triangle
  std::vector<int> triangle_instance;  // instance id per triangle (0 for the ground)
};

class Renderer {
 public:
  // Builds the scene (meshes loaded with assimp, instanced per class) for the world and the
  // scenario's entities, and creates the EGL context (current on the calling thread).
  Renderer(const scenario::World& world, const scenario::SimConfig& config,
           const RendererOptions& options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders one frame set and reads it back; `out`'s buffers are reused.
  void render(const RenderRequest& request, FrameSet* out);
  FrameSet render(const RenderRequest& request);
  // Renders several requests (e.g. every camera of one instant) into out[i], the same as one
  // render() each, faster: the GL rasterizes one request while the CPU prepares the next and
  // applies the camera effects of another. `out`'s buffers are reused.
  void render(const std::vector<RenderRequest>& requests, std::vector<FrameSet>* out);

  // Makes the EGL context current on the calling thread (render() from another thread; render()
  // also does it when needed). The thread that had it must call releaseCurrent() first.
  void makeCurrent();
  // Releases the context from the calling thread.
  void releaseCurrent();

  int instanceCount() const;                      // highest instance id + 1
  const std::string& instanceEntityId(int instance) const;  // "" for 0 / out of range
  std::string glRenderer() const;                  // GL_RENDERER, e.g. "llvmpipe (LLVM 15...)"
  std::string eglBackend() const;                  // the EGL platform used: surfaceless | device
  const RenderStats& lastStats() const;
  // Instance id of an entity id (world or scenario), or 0.
  int instanceOf(const std::string& entity_id) const;
  // Everything drawn at `time` except the UAV model, in world coordinates, every instance with
  // its full mesh: the triangles a geometry pass with lod_max_error_px = 0 rasterizes (same
  // canopy scaling, same z offsets of the ground layers).
  SceneTriangles sceneTriangles(double time) const;
  // The triangles `request`'s geometry pass rasterizes: each instance with the mesh the level of
  // detail picks for that view (RendererOptions::lod_max_error_px); culling is not applied.
  SceneTriangles sceneTriangles(const RenderRequest& request) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Default models directory: the package's models/ (scenario::shareDir()).
std::string defaultModelsDir();

}  // namespace hameritt::render
