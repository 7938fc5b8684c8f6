// Private declarations shared by the renderer's sources: GPU-side records, frame slots and
// Renderer::Impl.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "camera_effects.h"
#include "egl_context.h"
#include "environment_model.h"
#include "gl.h"
#include "hameritt/render/renderer.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/share_dir.h"
#include "mesh.h"
#include "scene.h"
#include "shaders.h"

namespace hameritt::render {

namespace renderer_internal {

using Clock = std::chrono::steady_clock;

inline double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Instances whose bounding sphere projects to a radius below this many pixels are not drawn:
// they could cover at most about one pixel centre (see README "Rendering").
constexpr double kMinProjectedRadiusPx = 0.5;
// Culling grid cell (metres).
constexpr double kCellSize = 40.0;
// A geometry pass drawing more triangles than this is flushed half-way (see geometryPass()).
constexpr std::size_t kSplitTriangles = 40000;

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

inline std::string num(double v) { return scenario::formatNumber(v); }

// One instance as the vertex shader reads it (instanced attributes, divisor 1).
struct GpuInstance {
  float row[3][4];     // model matrix rows
  float normal[3][4];  // normal matrix rows (cofactors); w: canopy scale, length, width
  std::uint32_t color;
  std::uint32_t label;
};
static_assert(sizeof(GpuInstance) == 104, "tightly packed");

inline GpuInstance gpuInstance(const InstanceRecord& r) {
  GpuInstance g;
  std::memcpy(g.row, r.row, sizeof(g.row));
  Eigen::Matrix3f m;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m(i, j) = r.row[i][j];
  }
  // Cofactor matrix = det(M) M^-T: transforms normals, defined even for a degenerate M.
  Eigen::Matrix3f cof;
  cof.col(0) = m.col(1).cross(m.col(2));
  cof.col(1) = m.col(2).cross(m.col(0));
  cof.col(2) = m.col(0).cross(m.col(1));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) g.normal[i][j] = cof(i, j);
  }
  g.normal[0][3] = r.canopy;
  g.normal[1][3] = m.col(0).norm();
  g.normal[2][3] = m.col(1).norm();
  g.color = r.color;
  g.label = r.label;
  return g;
}

// A frustum plane n.x + d >= 0 inside, n normalized.
struct Plane {
  Eigen::Vector3d n;
  double d;
};

// The render targets of one image size.
struct Targets {
  int width = 0, height = 0;
  GLuint fbo = 0, color = 0, depth_labels = 0, zbuffer = 0;
  GLuint particle_fbo = 0;  // the colour target alone, for blending particles onto it
};

// A layer of weather particles (sizes in pixels at 640 px image width).
struct ParticleLayer {
  float cell, length, radius, alpha, density;
};
constexpr ParticleLayer kRainLayers[] = {
    {46, 38, 1.3f, 0.30f, 0.30f}, {26, 20, 0.9f, 0.24f, 0.45f}, {14, 10, 0.7f, 0.18f, 0.55f}};
constexpr ParticleLayer kSnowLayers[] = {
    {40, 0, 3.2f, 0.95f, 0.45f}, {22, 0, 2.0f, 0.85f, 0.55f}, {12, 0, 1.2f, 0.70f, 0.60f}};

struct Uniforms {
  GLint view_proj, camera, canopy_center, near_clip, far_clip, sun_dir, sun_color, sky_ambient,
      ground_ambient, snow, wet, world_R_optical, intrinsics, extinction_color, extinction_k;
};

struct GeometryProgram {
  GLuint id = 0;
  Uniforms u{};
};

// Pixel bounds and count of one instance in the mask.
struct BoxAcc {
  int x_min = 0, y_min = 0, x_max = 0, y_max = 0, count = 0;
};

// One request of a batch between its phases, in a slot that keeps its buffers and targets from
// call to call (no allocation per frame once warm).
struct Frame {
  const RenderRequest* request = nullptr;
  FrameSet* out = nullptr;
  Targets* targets = nullptr;
  std::vector<Targets> target_cache;  // by image size
  GLuint instance_buffer = 0;         // the culled instances of this frame
  Lighting lighting;
  CameraEffects effects;
  float view_proj[16] = {};
  Eigen::Vector3d camera{0, 0, 0};
  std::vector<GLuint> base_instance;  // per model: first instance in the upload
  std::vector<GLsizei> count;         // per model: instances drawn
  std::vector<int> slot;              // per record: its index in the upload, or -1
  std::vector<int> model;             // per uploaded record: the model it is drawn with
  std::vector<std::uint32_t> uploaded;
  std::vector<GpuInstance> upload;
  std::vector<std::uint8_t> color;              // read-back colour before the camera effects
  std::vector<std::pair<int, BoxAcc>> touched;  // instances of interest in the mask
  RenderStats stats;
};

}  // namespace renderer_internal

using namespace renderer_internal;

struct Renderer::Impl {
  Impl(const scenario::World& world, const scenario::SimConfig& cfg, const RendererOptions& opt);

  ~Impl();

  // ------------------------------------------------------------------------------ set-up
  void initGl();

  void checkGl(const char* where);

  // Static instances (world and parked scenario entities) sorted by grid cell, per model, so
  // that a frame tests cells against the frustum first and instances only in cut cells.
  void buildCulling();

  Frame& frameSlot(std::size_t i);

  Targets& targetsFor(Frame& f, int w, int h);

  static void deleteTargets(Targets* t);

  // ------------------------------------------------------------------------------ per frame
  void validate(const RenderRequest& r);

  // Column-major float 4x4 of projection * [R^T | 0] (camera-relative world to clip), and the
  // same with the translation for the frustum planes (double).
  static void projection(const RenderRequest& r, float view_proj[16], Eigen::Matrix4d* full);

  void frustumPlanes(const Eigen::Matrix4d& m);

  // -1 outside, 0 cut, 1 inside.
  int classifyBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) const;

  bool sphereVisible(const Eigen::Vector3f& c, float radius, bool test_planes) const;

  void setHidden(const std::vector<std::string>& ids);

  // Frustum culling (cells, then spheres) and the upload of the visible instances, grouped by
  // model in draw order.
  void cullAndUpload(const RenderRequest& r, Frame& f);

  void setFrameUniforms(const Frame& f);

  // The geometry program variant of model m.
  const GeometryProgram& programFor(int m) const;

  // Draws model m's instances [base, base + count) of the bound instance buffer: one call per
  // model, the materials are in the vertices.
  void drawModel(int m, GLuint base, GLsizei count, RenderStats* stats);

  // `triangles`: what the frame will draw; a heavy frame is handed to the rasterizer in two
  // halves, so that the GL rasterizes the first while the CPU processes the second's vertices.
  void geometryPass(Frame& f, std::size_t triangles);

  // True when every pixel's ray meets the lawn between the clip planes: the ray through a pixel
  // has a world z component linear in (u, v), so the extreme rays pass through image corners;
  // the rays' ground points form the image of the rectangle, inside the lawn when its corners
  // are.
  bool groundFillsView(const RenderRequest& r) const;

  // Counter-based key of (scenario seed, camera index, frame index): particles use x, y; the
  // noise z, w.
  void frameKey(const RenderRequest& r, GLuint key[4]) const;

  // Rain streaks and snow flakes blended onto the colour target (weather on, intensity > 0).
  void particlePass(const Frame& f);

  // Motion blur and sensor noise of this request (applied on the CPU after the read-back).
  void cameraEffects(Frame& f) const;

  // Colour (into the frame's buffer when the camera effects follow), depth and labels.
  void readBack(Frame& f);

  // Splits depth and labels and grows the boxes of the instances of interest in the same pass.
  void splitLabels(Frame& f);

  // Pixel rectangle that surely contains the projection of the instance uploaded at `slot`.
  std::array<int, 4> projectedRect(const Frame& f, int model, int slot) const;

  // total_pixels: the entities with a visible pixel are drawn again without the rest of the
  // scene, in groups whose projected rectangles do not overlap (so that no member can cover
  // another), and their labels are counted inside their rectangles. Same program, instance data
  // and rasterization as the geometry pass, so the visible pixels are a subset of these.
  void boxes(Frame& f);

  // Renders the requests in phases so that the CPU and the GL overlap: every geometry pass is
  // submitted first (the GL rasterizes one while the next is culled and its vertices
  // processed), then each frame is read back, then the camera effects of each run on the CPU
  // (while the GL still works on later frames), then the boxes.
  void render(const std::vector<const RenderRequest*>& requests,
              const std::vector<FrameSet*>& outs);

  const scenario::SimConfig config;  // a copy: the scene poses movers from it
  RendererOptions options;
  Scene scene;
  EglContext egl;
  std::string gl_renderer;
  RenderStats stats;
  std::unordered_multimap<std::string, int> by_id;

  GeometryProgram geometry[3];  // objects, ground layers, building facades
  GLuint bound_program = 0;
  GLuint sky_program = 0, particle_program = 0;
  GLuint coverage_program = 0;  // boxes: the objects' positions, no shading
  struct {
    GLint view_proj, camera;
  } coverage_loc{};
  struct {
    GLint world_R_optical, intrinsics, zenith, horizon, sun_dir, glow, far_clip, haze_color, haze_k;
  } sky_loc{};
  struct {
    GLint key, size, cells_x, cell, length, radius, density, layer, fall, intrinsics, alpha,
        brightness;
  } particle_loc{};
  GLuint vao = 0, empty_vao = 0, vertex_buffer = 0, element_buffer = 0;
  std::vector<GLint> model_base_vertex;
  std::vector<std::size_t> model_first_element;
  std::vector<int> draw_order;
  std::vector<InstanceRecord> records;
  std::uint32_t uav_record = 0;
  std::vector<std::unique_ptr<Frame>> frames;      // one slot per request of a batch
  std::vector<const RenderRequest*> request_list;  // the requests of the current call
  std::vector<FrameSet*> out_list;
  std::vector<std::pair<std::size_t, std::size_t>> order;  // (triangles, frame) of a batch

  // Culling.
  int grid_nx = 1, grid_ny = 1;
  std::vector<Eigen::Vector3f> cell_lo, cell_hi;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> cell_range;  // [cell * models + model]
  std::vector<std::uint32_t> cell_items;
  std::vector<std::uint32_t> movers, always;
  // Traffic-light masts (record) and the signalised intersection they stand at.
  std::vector<std::pair<std::uint32_t, int>> signal_masts;
  std::vector<std::pair<Eigen::Vector3f, float>> mover_sphere;  // per record
  std::array<Plane, 6> planes{};
  Eigen::Vector3d camera{0, 0, 0};
  double focal = 1.0;
  LodView lod;
  std::vector<std::pair<double, int>> cell_order;
  std::vector<std::vector<std::uint32_t>> visible;  // per model
  std::vector<std::uint8_t> hidden;                 // per record
  std::vector<std::uint32_t> hidden_list;

  // Labels, boxes, camera effects.
  std::vector<std::uint8_t> interest;  // per instance id
  std::vector<int> instance_record;    // instance id -> record
  std::vector<std::vector<int>> part_records;  // instance id -> the records of its parts
  std::vector<BoxAcc> box_acc;         // per instance id
  std::vector<int> touched;
  std::vector<std::uint32_t> label_scratch;
  CameraEffectsScratch effects_scratch;
  CameraEffectsWorker effects_worker;
  std::vector<std::array<int, 4>> box_rect;
  std::vector<int> box_group, box_total;
  std::vector<std::uint8_t> box_query;  // per touched instance: counted by an occlusion query
  std::vector<GLuint> query_pool;       // GL_SAMPLES_PASSED queries, grown on demand
  std::vector<GpuInstance> box_upload;
  std::vector<GLuint> group_base;
  std::vector<GLsizei> group_count;
  std::vector<std::uint32_t> box_labels;
};

}  // namespace hameritt::render
