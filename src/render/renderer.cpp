#include "hameritt/render/renderer.h"

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
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/share_dir.h"
#include "mesh.h"
#include "scene.h"
#include "shaders.h"

namespace hameritt::render {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Instances whose bounding sphere projects to a radius below this many pixels are not drawn:
// they could cover at most about one pixel centre (see README "Rendering").
constexpr double kMinProjectedRadiusPx = 0.5;
// Culling grid cell (metres).
constexpr double kCellSize = 40.0;
// A geometry pass drawing more triangles than this is flushed half-way (see geometryPass()).
constexpr std::size_t kSplitTriangles = 40000;

GLuint compileShader(GLenum type, const std::string& source, const char* name) {
  GLuint s = glCreateShader(type);
  const char* src = source.c_str();
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw RenderError(std::string("GL: shader ") + name + " does not compile: " + log);
  }
  return s;
}

GLuint linkProgram(const std::string& vs, const std::string& fs, const char* name) {
  const GLuint v = compileShader(GL_VERTEX_SHADER, vs, name);
  GLuint f = 0;
  try {
    f = compileShader(GL_FRAGMENT_SHADER, fs, name);
  } catch (...) {
    glDeleteShader(v);
    throw;
  }
  GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
    std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
    glGetProgramInfoLog(p, len, nullptr, log.data());
    glDeleteProgram(p);
    throw RenderError(std::string("GL: program ") + name + " does not link: " + log);
  }
  return p;
}

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

std::string num(double v) { return scenario::formatNumber(v); }

// One instance as the vertex shader reads it (instanced attributes, divisor 1).
struct GpuInstance {
  float row[3][4];     // model matrix rows
  float normal[3][4];  // normal matrix rows (cofactors); w: canopy scale, length, width
  std::uint32_t color;
  std::uint32_t label;
};
static_assert(sizeof(GpuInstance) == 104, "tightly packed");

GpuInstance gpuInstance(const InstanceRecord& r) {
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

}  // namespace

struct Renderer::Impl {
  Impl(const scenario::World& world, const scenario::SimConfig& cfg, const RendererOptions& opt)
      : config(cfg),
        options(opt),
        scene(world, config, opt.models_dir.empty() ? defaultModelsDir() : opt.models_dir),
        egl(opt.backend) {
    if (!std::isfinite(opt.lod_max_error_px) || opt.lod_max_error_px < 0) {
      throw RenderError("RendererOptions.lod_max_error_px: expected a finite value >= 0, got " +
                        num(opt.lod_max_error_px));
    }
    for (std::size_t i = 0; i < scene.entityIds().size(); ++i) {
      if (!scene.entityIds()[i].empty() && static_cast<int>(i) != scene.uavInstanceId()) {
        by_id.emplace(scene.entityIds()[i], static_cast<int>(i));
      }
    }
    initGl();
    buildCulling();
  }

  ~Impl() {
    try {
      egl.makeCurrent();
    } catch (const RenderError&) {
      return;  // another thread holds the context: the GL objects go with it
    }
    for (auto& f : frames) {
      for (auto& t : f->target_cache) deleteTargets(&t);
      glDeleteBuffers(1, &f->instance_buffer);
    }
    for (const auto& g : geometry) glDeleteProgram(g.id);
    glDeleteProgram(sky_program);
    glDeleteProgram(particle_program);
    GLuint buffers[] = {vertex_buffer, element_buffer};
    glDeleteBuffers(2, buffers);
    glDeleteVertexArrays(1, &vao);
    glDeleteVertexArrays(1, &empty_vao);
  }

  // ------------------------------------------------------------------------------ set-up
  void initGl() {
    gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const std::string gl_version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 45) {
      throw RenderError("GL: OpenGL 4.5 core is required, got " + gl_version + " (" + gl_renderer +
                        ")");
    }
    const std::string version = "#version 450 core\n";
    // Two variants of the geometry program: objects, and the ground layers with their patterns.
    for (int g = 0; g < 2; ++g) {
      const std::string define = g == 1 ? "#define GROUND_LAYERS 1\n" : "";
      geometry[g].id = linkProgram(version + define + shaders::kGeometryVertex,
                                   version + define + shaders::kCommon + shaders::kGeometryFragment,
                                   g == 1 ? "geometry (ground layers)" : "geometry (objects)");
      auto loc = [this, g](const char* n) { return glGetUniformLocation(geometry[g].id, n); };
      geometry[g].u = {loc("u_view_proj"),
                       loc("u_camera"),
                       loc("u_canopy_center"),
                       loc("u_near"),
                       loc("u_far"),
                       loc("u_sun_dir"),
                       loc("u_sun_color"),
                       loc("u_sky_ambient"),
                       loc("u_ground_ambient"),
                       loc("u_snow"),
                       loc("u_wet"),
                       loc("u_world_R_optical"),
                       loc("u_intrinsics"),
                       loc("u_extinction_color"),
                       loc("u_extinction_k")};
    }
    sky_program = linkProgram(shaders::kFullscreenVertex,
                              version + shaders::kCommon + shaders::kSkyFragment, "sky");
    particle_program = linkProgram(version + shaders::kHash + shaders::kParticleVertex,
                                   version + shaders::kParticleFragment, "particles");
    auto sky = [this](const char* n) { return glGetUniformLocation(sky_program, n); };
    sky_loc = {sky("u_world_R_optical"), sky("u_intrinsics"), sky("u_zenith"), sky("u_horizon"),
               sky("u_sun_dir"),         sky("u_glow"),       sky("u_far"),    sky("u_haze_color"),
               sky("u_haze_k")};
    auto part = [this](const char* n) { return glGetUniformLocation(particle_program, n); };
    particle_loc = {part("u_key"),        part("u_size"),   part("u_cells_x"),
                    part("u_cell"),       part("u_length"), part("u_radius"),
                    part("u_density"),    part("u_layer"),  part("u_fall"),
                    part("u_intrinsics"), part("u_alpha"),  part("u_brightness")};

    // All meshes in one vertex and one element buffer.
    std::vector<Vertex> vertices;
    std::vector<std::uint32_t> elements;
    for (const Mesh& m : scene.models()) {
      model_base_vertex.push_back(static_cast<GLint>(vertices.size()));
      model_first_element.push_back(elements.size());
      vertices.insert(vertices.end(), m.vertices.begin(), m.vertices.end());
      elements.insert(elements.end(), m.indices.begin(), m.indices.end());
    }
    glCreateBuffers(1, &vertex_buffer);
    glNamedBufferStorage(vertex_buffer, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)),
                         vertices.data(), 0);
    glCreateBuffers(1, &element_buffer);
    glNamedBufferStorage(element_buffer,
                         static_cast<GLsizeiptr>(elements.size() * sizeof(std::uint32_t)),
                         elements.data(), 0);

    // Instance records: the scene's, then the UAV's. Each frame uploads the culled ones.
    const std::size_t n = scene.instances().size();
    records.resize(n + 1);
    for (std::size_t i = 0; i < n; ++i) records[i] = scene.instances()[i].record;
    uav_record = static_cast<std::uint32_t>(n);

    glCreateVertexArrays(1, &vao);
    glVertexArrayVertexBuffer(vao, 0, vertex_buffer, 0, sizeof(Vertex));
    glVertexArrayBindingDivisor(vao, 1, 1);
    glVertexArrayElementBuffer(vao, element_buffer);
    for (GLuint a = 0; a < 10; ++a) glEnableVertexArrayAttrib(vao, a);
    glVertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, position));
    glVertexArrayAttribFormat(vao, 1, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, normal));
    glVertexArrayAttribIFormat(vao, 2, 1, GL_UNSIGNED_INT, offsetof(Vertex, material));
    for (GLuint a = 0; a < 3; ++a) {
      glVertexArrayAttribFormat(vao, 3 + a, 4, GL_FLOAT, GL_FALSE,
                                static_cast<GLuint>(offsetof(GpuInstance, row) + 16 * a));
      glVertexArrayAttribFormat(vao, 6 + a, 4, GL_FLOAT, GL_FALSE,
                                static_cast<GLuint>(offsetof(GpuInstance, normal) + 16 * a));
    }
    glVertexArrayAttribIFormat(vao, 9, 2, GL_UNSIGNED_INT, offsetof(GpuInstance, color));
    for (GLuint a = 0; a < 10; ++a) glVertexArrayAttribBinding(vao, a, a < 3 ? 0 : 1);
    glCreateVertexArrays(1, &empty_vao);

    // Draw order: large occluders first so that early depth rejection saves shading; the ground
    // layers last.
    const auto& p = scene.procedural();
    for (int m = 0; m < static_cast<int>(scene.models().size()); ++m) {
      if (m != p.street && m != p.driveway && m != p.sidewalks && m != p.ground && m != p.uav) {
        draw_order.push_back(m);
      }
    }
    for (int m : {p.uav, p.driveway, p.street, p.sidewalks, p.ground}) draw_order.push_back(m);

    interest.assign(scene.entityIds().size(), 0);
    instance_record.assign(scene.entityIds().size(), -1);
    for (std::size_t i = 0; i < scene.instances().size(); ++i) {
      const SceneInstance& si = scene.instances()[i];
      if (si.instance_id > 0) {
        instance_record[static_cast<std::size_t>(si.instance_id)] = static_cast<int>(i);
        interest[static_cast<std::size_t>(si.instance_id)] = si.interest ? 1 : 0;
      }
    }
    box_acc.assign(scene.entityIds().size(), BoxAcc{});
    hidden.assign(records.size(), 0);
    mover_sphere.assign(records.size(), {Eigen::Vector3f::Zero(), 0.0f});

    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    // Rows are rendered top first (see projection()), which mirrors the winding.
    glFrontFace(GL_CW);
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    checkGl("initialisation");
  }

  void checkGl(const char* where) {
    const GLenum e = glGetError();
    if (e != GL_NO_ERROR) {
      char buf[16];
      std::snprintf(buf, sizeof(buf), "0x%04x", e);
      throw RenderError(std::string("GL: error ") + buf + " in " + where);
    }
  }

  // Static instances (world and parked scenario entities) sorted by grid cell, per model, so
  // that a frame tests cells against the frustum first and instances only in cut cells.
  void buildCulling() {
    const auto& inst = scene.instances();
    const auto& p = scene.procedural();
    Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
    for (const auto& si : inst) {
      if (si.mover || si.model == p.ground || si.model == p.sidewalks) continue;
      lo = lo.cwiseMin(si.center.head<2>().cast<double>());
      hi = hi.cwiseMax(si.center.head<2>().cast<double>());
    }
    if (lo.x() > hi.x()) lo = hi = Eigen::Vector2d::Zero();
    grid_nx = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / kCellSize)) + 1);
    grid_ny = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / kCellSize)) + 1);
    const int cells = grid_nx * grid_ny;
    const int models = static_cast<int>(scene.models().size());
    std::vector<std::vector<std::uint32_t>> per(static_cast<std::size_t>(cells * models));
    cell_lo.assign(static_cast<std::size_t>(cells), Eigen::Vector3f::Constant(1e30f));
    cell_hi.assign(static_cast<std::size_t>(cells), Eigen::Vector3f::Constant(-1e30f));
    for (std::size_t i = 0; i < inst.size(); ++i) {
      const auto& si = inst[i];
      if (si.mover) {
        movers.push_back(static_cast<std::uint32_t>(i));
        continue;
      }
      if (si.model == p.ground || si.model == p.sidewalks) {
        always.push_back(static_cast<std::uint32_t>(i));
        continue;
      }
      const int cx =
          std::clamp(static_cast<int>((si.center.x() - lo.x()) / kCellSize), 0, grid_nx - 1);
      const int cy =
          std::clamp(static_cast<int>((si.center.y() - lo.y()) / kCellSize), 0, grid_ny - 1);
      const auto c = static_cast<std::size_t>(cy * grid_nx + cx);
      per[c * static_cast<std::size_t>(models) + static_cast<std::size_t>(si.model)].push_back(
          static_cast<std::uint32_t>(i));
      cell_lo[c] = cell_lo[c].cwiseMin(si.center - Eigen::Vector3f::Constant(si.radius));
      cell_hi[c] = cell_hi[c].cwiseMax(si.center + Eigen::Vector3f::Constant(si.radius));
    }
    cell_range.assign(static_cast<std::size_t>(cells * models), {0, 0});
    for (std::size_t k = 0; k < per.size(); ++k) {
      const auto begin = static_cast<std::uint32_t>(cell_items.size());
      cell_items.insert(cell_items.end(), per[k].begin(), per[k].end());
      cell_range[k] = {begin, static_cast<std::uint32_t>(cell_items.size())};
    }
    visible.resize(static_cast<std::size_t>(models));
    cell_order.reserve(static_cast<std::size_t>(cells));
  }

  Frame& frameSlot(std::size_t i) {
    while (frames.size() <= i) {
      auto f = std::make_unique<Frame>();
      glCreateBuffers(1, &f->instance_buffer);
      // The culled instances, then the groups of entities drawn alone for their boxes.
      glNamedBufferStorage(f->instance_buffer,
                           static_cast<GLsizeiptr>(2 * records.size() * sizeof(GpuInstance)),
                           nullptr, GL_DYNAMIC_STORAGE_BIT);
      f->slot.assign(records.size(), -1);
      f->model.assign(records.size(), -1);
      f->upload.reserve(records.size());
      f->uploaded.reserve(records.size());
      frames.push_back(std::move(f));
    }
    return *frames[i];
  }

  Targets& targetsFor(Frame& f, int w, int h) {
    for (auto& t : f.target_cache) {
      if (t.width == w && t.height == h) return t;
    }
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    if (w > max_size || h > max_size) {
      throw RenderError("RenderRequest.intrinsics: " + std::to_string(w) + " x " +
                        std::to_string(h) + " exceeds the GL limit of " + std::to_string(max_size));
    }
    // Keep a few sizes; drop the oldest beyond that.
    if (f.target_cache.size() >= 4) {
      deleteTargets(&f.target_cache.front());
      f.target_cache.erase(f.target_cache.begin());
    }
    Targets t;
    t.width = w;
    t.height = h;
    glCreateTextures(GL_TEXTURE_2D, 1, &t.color);
    glTextureStorage2D(t.color, 1, GL_RGBA8, w, h);
    // Depth (float bits) and label in one target: one store per pixel less than two targets.
    glCreateTextures(GL_TEXTURE_2D, 1, &t.depth_labels);
    glTextureStorage2D(t.depth_labels, 1, GL_RG32UI, w, h);
    glCreateRenderbuffers(1, &t.zbuffer);
    glNamedRenderbufferStorage(t.zbuffer, GL_DEPTH_COMPONENT32F, w, h);
    glCreateFramebuffers(1, &t.fbo);
    glNamedFramebufferTexture(t.fbo, GL_COLOR_ATTACHMENT0, t.color, 0);
    glNamedFramebufferTexture(t.fbo, GL_COLOR_ATTACHMENT1, t.depth_labels, 0);
    glNamedFramebufferRenderbuffer(t.fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.zbuffer);
    const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(t.fbo, 2, bufs);
    glCreateFramebuffers(1, &t.particle_fbo);
    glNamedFramebufferTexture(t.particle_fbo, GL_COLOR_ATTACHMENT0, t.color, 0);
    glNamedFramebufferDrawBuffer(t.particle_fbo, GL_COLOR_ATTACHMENT0);
    for (GLuint fb : {t.fbo, t.particle_fbo}) {
      if (glCheckNamedFramebufferStatus(fb, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        deleteTargets(&t);
        throw RenderError("GL: incomplete framebuffer for " + std::to_string(w) + " x " +
                          std::to_string(h));
      }
    }
    checkGl("render targets");
    f.target_cache.push_back(t);
    return f.target_cache.back();
  }

  static void deleteTargets(Targets* t) {
    GLuint tex[] = {t->color, t->depth_labels};
    glDeleteTextures(2, tex);
    glDeleteRenderbuffers(1, &t->zbuffer);
    GLuint fbos[] = {t->fbo, t->particle_fbo};
    glDeleteFramebuffers(2, fbos);
    *t = Targets{};
  }

  // ------------------------------------------------------------------------------ per frame
  void validate(const RenderRequest& r) {
    const Intrinsics& k = r.intrinsics;
    if (k.width < 1 || k.height < 1) {
      throw RenderError("RenderRequest.intrinsics: width and height must be >= 1, got " +
                        std::to_string(k.width) + " x " + std::to_string(k.height));
    }
    auto positive = [](const char* field, double v) {
      if (!std::isfinite(v) || v <= 0.0) {
        throw RenderError(std::string("RenderRequest.") + field +
                          ": expected a finite value > 0, got " + num(v));
      }
    };
    positive("intrinsics.fx", k.fx);
    positive("intrinsics.fy", k.fy);
    if (!std::isfinite(k.cx) || !std::isfinite(k.cy)) {
      throw RenderError("RenderRequest.intrinsics: cx, cy must be finite");
    }
    positive("near_clip", r.near_clip);
    if (!std::isfinite(r.far_clip) || r.far_clip <= r.near_clip) {
      throw RenderError("RenderRequest.far_clip: expected a finite value > near_clip (" +
                        num(r.near_clip) + "), got " + num(r.far_clip));
    }
    if (!std::isfinite(r.time)) throw RenderError("RenderRequest.time: expected a finite value");
    if (!r.world_T_optical.matrix().allFinite()) {
      throw RenderError("RenderRequest.world_T_optical: not finite");
    }
    if (r.draw_uav && !r.world_T_uav.matrix().allFinite()) {
      throw RenderError("RenderRequest.world_T_uav: not finite");
    }
    if (!r.blur_direction.allFinite()) {
      throw RenderError("RenderRequest.blur_direction: not finite");
    }
    for (const std::string& id : r.hidden_entities) {
      if (by_id.find(id) == by_id.end()) {
        throw RenderError("RenderRequest.hidden_entities: unknown entity '" + id + "'");
      }
    }
  }

  // Column-major float 4x4 of projection * [R^T | 0] (camera-relative world to clip), and the
  // same with the translation for the frustum planes (double).
  static void projection(const RenderRequest& r, float view_proj[16], Eigen::Matrix4d* full) {
    const Intrinsics& k = r.intrinsics;
    const double n = r.near_clip, f = r.far_clip, w = k.width, h = k.height;
    // Pixel centre (u, v) -> window (u + 0.5, v + 0.5): row 0 of the image is window row 0,
    // so glReadPixels returns the rows top first without a flip.
    Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
    p(0, 0) = 2.0 * k.fx / w;
    p(0, 2) = (2.0 * k.cx + 1.0) / w - 1.0;
    p(1, 1) = 2.0 * k.fy / h;
    p(1, 2) = (2.0 * k.cy + 1.0) / h - 1.0;
    // Reversed Z: window depth n (f - Z) / (Z (f - n)), 1 at the near plane, 0 at the far one.
    p(2, 2) = -n / (f - n);
    p(2, 3) = n * f / (f - n);
    p(3, 2) = 1.0;
    Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
    view.topLeftCorner<3, 3>() = r.world_T_optical.linear().transpose();
    const Eigen::Matrix4d vp = p * view;
    for (int c = 0; c < 4; ++c) {
      for (int row = 0; row < 4; ++row) view_proj[c * 4 + row] = static_cast<float>(vp(row, c));
    }
    Eigen::Matrix4d full_view = view;
    full_view.topRightCorner<3, 1>() =
        -r.world_T_optical.linear().transpose() * r.world_T_optical.translation();
    *full = p * full_view;
  }

  void frustumPlanes(const Eigen::Matrix4d& m) {
    const Eigen::RowVector4d r0 = m.row(0), r1 = m.row(1), r2 = m.row(2), r3 = m.row(3);
    const Eigen::RowVector4d raw[6] = {r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 - r2, r2};
    for (int i = 0; i < 6; ++i) {
      const double len = raw[i].head<3>().norm();
      planes[static_cast<std::size_t>(i)] = {raw[i].head<3>().transpose() / len, raw[i](3) / len};
    }
  }

  // -1 outside, 0 cut, 1 inside.
  int classifyBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) const {
    int result = 1;
    for (const Plane& pl : planes) {
      Eigen::Vector3d pos, neg;
      for (int a = 0; a < 3; ++a) {
        pos[a] = pl.n[a] >= 0 ? hi[a] : lo[a];
        neg[a] = pl.n[a] >= 0 ? lo[a] : hi[a];
      }
      if (pl.n.dot(pos) + pl.d < 0) return -1;
      if (pl.n.dot(neg) + pl.d < 0) result = 0;
    }
    return result;
  }

  bool sphereVisible(const Eigen::Vector3f& c, float radius, bool test_planes) const {
    const Eigen::Vector3d cd = c.cast<double>();
    if (test_planes) {
      for (const Plane& pl : planes) {
        if (pl.n.dot(cd) + pl.d < -radius) return false;
      }
    }
    // Far and tiny: the sphere's projected radius is below kMinProjectedRadiusPx.
    const double dist = (cd - camera).norm() - radius;
    return dist <= 0 || focal * radius >= kMinProjectedRadiusPx * dist;
  }

  void setHidden(const std::vector<std::string>& ids) {
    for (std::uint32_t i : hidden_list) hidden[i] = 0;
    hidden_list.clear();
    for (const std::string& id : ids) {
      auto [b, e] = by_id.equal_range(id);
      for (auto it = b; it != e; ++it) {
        const auto rec =
            static_cast<std::uint32_t>(instance_record[static_cast<std::size_t>(it->second)]);
        hidden[rec] = 1;
        hidden_list.push_back(rec);
      }
    }
  }

  // Frustum culling (cells, then spheres) and the upload of the visible instances, grouped by
  // model in draw order.
  void cullAndUpload(const RenderRequest& r, Frame& f) {
    const int models = static_cast<int>(scene.models().size());
    for (auto& v : visible) v.clear();
    // Movers: posed at the frame time.
    for (std::uint32_t i : movers) {
      Eigen::Vector3f c;
      float radius;
      scene.pose(i, r.time, &records[i], &c, &radius);
      mover_sphere[i] = {c, radius};
    }
    if (r.draw_uav) records[uav_record] = scene.uavRecord(r.world_T_uav);
    // Cells: inside, cut or outside; visited near to far.
    cell_order.clear();
    const int cells = grid_nx * grid_ny;
    for (int c = 0; c < cells; ++c) {
      const auto& lo = cell_lo[static_cast<std::size_t>(c)];
      const auto& hi = cell_hi[static_cast<std::size_t>(c)];
      if (lo.x() > hi.x()) continue;
      const int cls = classifyBox(lo, hi);
      if (cls < 0) continue;
      const Eigen::Vector3d mid = 0.5 * (lo + hi).cast<double>();
      cell_order.push_back({(mid - camera).squaredNorm(), c * 2 + cls});
    }
    std::sort(cell_order.begin(), cell_order.end());
    const auto& inst = scene.instances();
    for (const auto& [d2, code] : cell_order) {
      const int c = code / 2;
      const bool inside = (code & 1) != 0;
      for (int m = 0; m < models; ++m) {
        const auto [b, e] = cell_range[static_cast<std::size_t>(c * models + m)];
        for (std::uint32_t k = b; k < e; ++k) {
          const std::uint32_t i = cell_items[k];
          if (hidden[i]) continue;
          if (!sphereVisible(inst[i].center, inst[i].radius, !inside)) continue;
          visible[static_cast<std::size_t>(scene.modelFor(i, inst[i].center, inst[i].radius, lod))]
              .push_back(i);
        }
      }
    }
    for (std::uint32_t i : movers) {
      if (hidden[i]) continue;
      const auto& [c, radius] = mover_sphere[i];
      if (sphereVisible(c, radius, true))
        visible[static_cast<std::size_t>(scene.modelFor(i, c, radius, lod))].push_back(i);
    }
    for (std::uint32_t i : always) {
      if (sphereVisible(inst[i].center, inst[i].radius, true)) {
        visible[static_cast<std::size_t>(inst[i].model)].push_back(i);
      }
    }
    if (r.draw_uav) visible[static_cast<std::size_t>(scene.procedural().uav)].push_back(uav_record);
    // One upload of the visible instances, in draw order.
    for (std::uint32_t i : f.uploaded) f.slot[i] = -1;
    f.uploaded.clear();
    f.upload.clear();
    f.base_instance.assign(static_cast<std::size_t>(models), 0);
    f.count.assign(static_cast<std::size_t>(models), 0);
    for (int m : draw_order) {
      f.base_instance[static_cast<std::size_t>(m)] = static_cast<GLuint>(f.upload.size());
      f.count[static_cast<std::size_t>(m)] =
          static_cast<GLsizei>(visible[static_cast<std::size_t>(m)].size());
      for (std::uint32_t i : visible[static_cast<std::size_t>(m)]) {
        f.slot[i] = static_cast<int>(f.upload.size());
        f.model[i] = m;
        if (i != uav_record && m != inst[i].model) ++f.stats.lod_instances;
        f.uploaded.push_back(i);
        f.upload.push_back(gpuInstance(records[i]));
      }
    }
    if (!f.upload.empty()) {
      glNamedBufferSubData(f.instance_buffer, 0,
                           static_cast<GLsizeiptr>(f.upload.size() * sizeof(GpuInstance)),
                           f.upload.data());
    }
    f.stats.instances = f.upload.size();
  }

  void setFrameUniforms(const Frame& f) {
    const RenderRequest& r = *f.request;
    const Lighting& l = f.lighting;
    // Clear air and weather haze as one medium: summed extinction, in-scattered colours
    // weighted by their extinction.
    const float k = l.air_k + l.haze_k;
    const Eigen::Vector3f ext =
        k > 0 ? Eigen::Vector3f((l.air_k * l.air_color + l.haze_k * l.haze_color) / k)
              : Eigen::Vector3f::Zero();
    const Eigen::Vector3f cam = f.camera.cast<float>();
    const Eigen::Matrix3f rot = r.world_T_optical.linear().cast<float>();
    const float intr[4] = {static_cast<float>(r.intrinsics.fx), static_cast<float>(r.intrinsics.fy),
                           static_cast<float>(r.intrinsics.cx),
                           static_cast<float>(r.intrinsics.cy)};
    for (const auto& g : geometry) {
      const GLuint p = g.id;
      const Uniforms& u = g.u;
      glProgramUniformMatrix4fv(p, u.view_proj, 1, GL_FALSE, f.view_proj);
      glProgramUniform3fv(p, u.camera, 1, cam.data());
      glProgramUniform1f(p, u.near_clip, static_cast<float>(r.near_clip));
      glProgramUniform1f(p, u.far_clip, static_cast<float>(r.far_clip));
      glProgramUniform3fv(p, u.sun_dir, 1, l.sun_dir.data());
      glProgramUniform3fv(p, u.sun_color, 1, l.sun_color.data());
      glProgramUniform3fv(p, u.sky_ambient, 1, l.sky_ambient.data());
      glProgramUniform3fv(p, u.ground_ambient, 1, l.ground_ambient.data());
      glProgramUniform1f(p, u.snow, l.snow_cover);
      glProgramUniform1f(p, u.wet, l.wetness);
      glProgramUniform3fv(p, u.extinction_color, 1, ext.data());
      glProgramUniform1f(p, u.extinction_k, k);
      glProgramUniformMatrix3fv(p, u.world_R_optical, 1, GL_FALSE, rot.data());
      glProgramUniform4fv(p, u.intrinsics, 1, intr);
    }
  }

  // The geometry program variant of model m.
  const GeometryProgram& programFor(int m) const {
    const auto& p = scene.procedural();
    const bool ground = m == p.ground || m == p.sidewalks || m == p.street;
    return geometry[ground ? 1 : 0];
  }

  // Draws model m's instances [base, base + count) of the bound instance buffer: one call per
  // model, the materials are in the vertices.
  void drawModel(int m, GLuint base, GLsizei count, RenderStats* stats) {
    const Mesh& mesh = scene.models()[static_cast<std::size_t>(m)];
    const std::uint32_t n = scene.drawnIndexCount(m);
    if (n == 0) return;
    const GeometryProgram& program = programFor(m);
    if (program.id != bound_program) {
      glUseProgram(program.id);
      bound_program = program.id;
    }
    if (mesh.foliage_first < n) {
      glProgramUniform3fv(program.id, program.u.canopy_center, 1, mesh.canopy_center.data());
    }
    glDrawElementsInstancedBaseVertexBaseInstance(
        GL_TRIANGLES, static_cast<GLsizei>(n), GL_UNSIGNED_INT,
        reinterpret_cast<const void*>(model_first_element[static_cast<std::size_t>(m)] *
                                      sizeof(std::uint32_t)),
        count, model_base_vertex[static_cast<std::size_t>(m)], base);
    stats->triangles += static_cast<std::size_t>(n / 3) * static_cast<std::size_t>(count);
    ++stats->draw_calls;
  }

  // `triangles`: what the frame will draw; a heavy frame is handed to the rasterizer in two
  // halves, so that the GL rasterizes the first while the CPU processes the second's vertices.
  void geometryPass(Frame& f, std::size_t triangles) {
    const RenderRequest& r = *f.request;
    const Lighting& l = f.lighting;
    const Targets& t = *f.targets;
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glViewport(0, 0, t.width, t.height);
    glDisable(GL_SCISSOR_TEST);
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_GREATER);
    // Only the depth buffer is cleared: the sky pass writes every pixel that no geometry covers.
    const float zero = 0.0f;
    glClearNamedFramebufferfv(t.fbo, GL_DEPTH, 0, &zero);

    setFrameUniforms(f);
    bound_program = 0;
    glBindVertexArray(vao);
    glVertexArrayVertexBuffer(vao, 1, f.instance_buffer, 0, sizeof(GpuInstance));
    const std::size_t split = triangles > kSplitTriangles ? triangles / 2 : triangles + 1;
    bool flushed = false;
    for (int m : draw_order) {
      const GLsizei count = f.count[static_cast<std::size_t>(m)];
      if (count > 0) drawModel(m, f.base_instance[static_cast<std::size_t>(m)], count, &f.stats);
      if (!flushed && f.stats.triangles >= split) {
        glFlush();
        flushed = true;
      }
    }

    // Sky where nothing was drawn (window depth still 0), unless the lawn fills the view.
    if (groundFillsView(r)) return;
    glUseProgram(sky_program);
    glBindVertexArray(empty_vao);
    glDisable(GL_CULL_FACE);  // the full-screen triangle's winding is mirrored too
    glDepthFunc(GL_EQUAL);
    glDepthMask(GL_FALSE);
    const Eigen::Matrix3f rot = r.world_T_optical.linear().cast<float>();
    glProgramUniformMatrix3fv(sky_program, sky_loc.world_R_optical, 1, GL_FALSE, rot.data());
    const float intr[4] = {static_cast<float>(r.intrinsics.fx), static_cast<float>(r.intrinsics.fy),
                           static_cast<float>(r.intrinsics.cx),
                           static_cast<float>(r.intrinsics.cy)};
    glProgramUniform4fv(sky_program, sky_loc.intrinsics, 1, intr);
    glProgramUniform3fv(sky_program, sky_loc.zenith, 1, l.sky_zenith.data());
    glProgramUniform3fv(sky_program, sky_loc.horizon, 1, l.sky_horizon.data());
    glProgramUniform3fv(sky_program, sky_loc.sun_dir, 1, l.sun_dir.data());
    glProgramUniform3fv(sky_program, sky_loc.glow, 1, l.sun_glow.data());
    glProgramUniform1f(sky_program, sky_loc.far_clip, static_cast<float>(r.far_clip));
    glProgramUniform3fv(sky_program, sky_loc.haze_color, 1, l.haze_color.data());
    glProgramUniform1f(sky_program, sky_loc.haze_k, l.haze_k);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glEnable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_GREATER);
  }

  // True when every pixel's ray meets the lawn between the clip planes: the ray through a pixel
  // has a world z component linear in (u, v), so the extreme rays pass through image corners;
  // the rays' ground points form the image of the rectangle, inside the lawn when its corners
  // are.
  bool groundFillsView(const RenderRequest& r) const {
    const Eigen::Vector3d eye = r.world_T_optical.translation();
    if (eye.z() <= 0.0) return false;
    const Mesh& ground = scene.models()[static_cast<std::size_t>(scene.procedural().ground)];
    const Intrinsics& k = r.intrinsics;
    for (int c = 0; c < 4; ++c) {
      // Pixel edges, not centres: the rasterized area ends there.
      const double u = (c & 1) ? k.width - 0.5 : -0.5, v = (c & 2) ? k.height - 0.5 : -0.5;
      const Eigen::Vector3d d =
          r.world_T_optical.linear() * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      if (d.z() >= 0.0) return false;
      const double z_hit = eye.z() / -d.z();  // optical z of the ground point
      if (z_hit >= 0.99 * r.far_clip || z_hit <= 1.01 * r.near_clip) return false;
      const Eigen::Vector3d g = eye + z_hit * d;
      if (g.x() <= ground.min.x() || g.x() >= ground.max.x() || g.y() <= ground.min.y() ||
          g.y() >= ground.max.y()) {
        return false;
      }
    }
    return true;
  }

  // Counter-based key of (scenario seed, camera index, frame index): particles use x, y; the
  // noise z, w.
  void frameKey(const RenderRequest& r, GLuint key[4]) const {
    const std::uint64_t k1 = splitmix64(
        config.seed ^
        splitmix64(static_cast<std::uint64_t>(static_cast<std::int64_t>(r.camera_index)) ^
                   splitmix64(r.frame_index)));
    const std::uint64_t k2 = splitmix64(k1);
    key[0] = static_cast<GLuint>(k1);
    key[1] = static_cast<GLuint>(k1 >> 32);
    key[2] = static_cast<GLuint>(k2);
    key[3] = static_cast<GLuint>(k2 >> 32);
  }

  // Rain streaks and snow flakes blended onto the colour target (weather on, intensity > 0).
  void particlePass(const Frame& f) {
    const RenderRequest& r = *f.request;
    const Targets& t = *f.targets;
    const float rain =
        r.weather ? static_cast<float>(std::clamp(config.environment.rain, 0.0, 1.0)) : 0.0f;
    const float snow =
        r.weather ? static_cast<float>(std::clamp(config.environment.snow, 0.0, 1.0)) : 0.0f;
    if (rain <= 0.0f && snow <= 0.0f) return;
    const GLuint p = particle_program;
    GLuint key[4];
    frameKey(r, key);
    glProgramUniform4uiv(p, particle_loc.key, 1, key);
    glProgramUniform2f(p, particle_loc.size, static_cast<float>(t.width),
                       static_cast<float>(t.height));
    const Eigen::Vector3f fall =
        (r.world_T_optical.linear().transpose() * Eigen::Vector3d(0, 0, -1)).cast<float>();
    glProgramUniform3fv(p, particle_loc.fall, 1, fall.data());
    const float intr[4] = {static_cast<float>(r.intrinsics.fx), static_cast<float>(r.intrinsics.fy),
                           static_cast<float>(r.intrinsics.cx),
                           static_cast<float>(r.intrinsics.cy)};
    glProgramUniform4fv(p, particle_loc.intrinsics, 1, intr);
    // Particles are lit by the diffuse light.
    const Eigen::Vector3f light = f.lighting.sky_ambient + 0.3f * f.lighting.sun_color;
    const float lum = 0.2126f * light.x() + 0.7152f * light.y() + 0.0722f * light.z();
    glProgramUniform1f(p, particle_loc.brightness, std::clamp(0.25f + 0.9f * lum, 0.2f, 0.95f));

    glBindFramebuffer(GL_FRAMEBUFFER, t.particle_fbo);
    glViewport(0, 0, t.width, t.height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(p);
    glBindVertexArray(empty_vao);
    const float scale = static_cast<float>(t.width) / 640.0f;
    auto layers = [&](const ParticleLayer* ls, float intensity, GLuint first_layer) {
      if (intensity <= 0.0f) return;
      for (int k = 0; k < 3; ++k) {
        const ParticleLayer& pl = ls[k];
        const float cell = std::max(4.0f, pl.cell * scale);
        const int nx = static_cast<int>(std::ceil(t.width / cell));
        const int ny = static_cast<int>(std::ceil(t.height / cell));
        glProgramUniform1i(p, particle_loc.cells_x, nx);
        glProgramUniform1f(p, particle_loc.cell, cell);
        glProgramUniform1f(p, particle_loc.length, pl.length * scale);
        glProgramUniform1f(p, particle_loc.radius, std::max(0.6f, pl.radius * scale));
        glProgramUniform1f(p, particle_loc.alpha, pl.alpha);
        glProgramUniform1f(p, particle_loc.density, pl.density * intensity);
        glProgramUniform1ui(p, particle_loc.layer, first_layer + static_cast<GLuint>(k));
        glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, nx * ny);
      }
    };
    layers(kRainLayers, rain, 1);
    layers(kSnowLayers, snow, 4);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE);
  }

  // Motion blur and sensor noise of this request (applied on the CPU after the read-back).
  void cameraEffects(Frame& f) const {
    const RenderRequest& r = *f.request;
    const auto& pert = config.perturbations;
    motionBlurKernel(r.blur_direction.x(), r.blur_direction.y(),
                     r.noise ? pert.motion_blur_px : 0.0, &f.effects.blur);
    f.effects.noise_std = r.noise ? static_cast<float>(pert.gaussian_noise_std) : 0.0f;
    f.effects.salt = r.noise ? static_cast<float>(pert.salt_pepper_probability) : 0.0f;
    GLuint key[4];
    frameKey(r, key);
    f.effects.key[0] = key[2];
    f.effects.key[1] = key[3];
  }

  // Colour (into the frame's buffer when the camera effects follow), depth and labels.
  void readBack(Frame& f) {
    const Targets& t = *f.targets;
    FrameSet* out = f.out;
    const std::size_t n = static_cast<std::size_t>(t.width) * static_cast<std::size_t>(t.height);
    out->rgb.resize(3 * n);
    out->depth.resize(n);
    out->semantic.resize(n);
    out->instance.resize(n);
    label_scratch.resize(2 * n);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t.fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    std::uint8_t* color = out->rgb.data();
    if (f.effects.any()) {
      f.color.resize(3 * n);
      color = f.color.data();
    }
    glReadPixels(0, 0, t.width, t.height, GL_RGB, GL_UNSIGNED_BYTE, color);
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, t.width, t.height, GL_RG_INTEGER, GL_UNSIGNED_INT, label_scratch.data());
    checkGl("read back");
  }

  // Splits depth and labels and grows the boxes of the instances of interest in the same pass.
  void splitLabels(Frame& f) {
    FrameSet* out = f.out;
    const int width = f.targets->width;
    touched.clear();
    const std::size_t n = label_scratch.size() / 2;
    const std::uint32_t* src = label_scratch.data();
    float* depth = out->depth.data();
    std::uint8_t* sem = out->semantic.data();
    std::uint16_t* ins = out->instance.data();
    const std::size_t n_ids = interest.size();
    for (std::size_t i = 0; i < n; ++i) {
      std::memcpy(&depth[i], &src[2 * i], sizeof(float));
      const std::uint32_t v = src[2 * i + 1];
      const std::uint32_t id = v & 0xFFFFu;
      sem[i] = static_cast<std::uint8_t>(v >> 16);
      ins[i] = static_cast<std::uint16_t>(id);
      if (id < n_ids && interest[id]) {
        const int x = static_cast<int>(i % static_cast<std::size_t>(width));
        const int y = static_cast<int>(i / static_cast<std::size_t>(width));
        BoxAcc& b = box_acc[id];
        if (b.count == 0) {
          b = {x, y, x, y, 0};
          touched.push_back(static_cast<int>(id));
        } else {
          b.x_min = std::min(b.x_min, x);
          b.x_max = std::max(b.x_max, x);
          b.y_max = y;  // rows come in order
        }
        ++b.count;
      }
    }
    std::sort(touched.begin(), touched.end());
    f.touched.clear();
    for (int id : touched) {
      f.touched.emplace_back(id, box_acc[static_cast<std::size_t>(id)]);
      box_acc[static_cast<std::size_t>(id)] = BoxAcc{};
    }
  }

  // Pixel rectangle that surely contains the projection of the instance uploaded at `slot`.
  std::array<int, 4> projectedRect(const Frame& f, int model, int slot) const {
    const RenderRequest& r = *f.request;
    const Intrinsics& k = r.intrinsics;
    const Mesh& mesh = scene.models()[static_cast<std::size_t>(model)];
    const GpuInstance& gi = f.upload[static_cast<std::size_t>(slot)];
    const Eigen::Isometry3d optical_T_world = r.world_T_optical.inverse();
    double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d p((c & 1) ? mesh.max.x() : mesh.min.x(),
                              (c & 2) ? mesh.max.y() : mesh.min.y(),
                              (c & 4) ? mesh.max.z() : mesh.min.z());
      Eigen::Vector3d w;
      for (int a = 0; a < 3; ++a) {
        w[a] = gi.row[a][0] * p.x() + gi.row[a][1] * p.y() + gi.row[a][2] * p.z() + gi.row[a][3];
      }
      const Eigen::Vector3d q = optical_T_world * w;
      if (q.z() < r.near_clip) return {0, 0, k.width, k.height};
      const double u = k.fx * q.x() / q.z() + k.cx, v = k.fy * q.y() / q.z() + k.cy;
      u0 = std::min(u0, u);
      u1 = std::max(u1, u);
      v0 = std::min(v0, v);
      v1 = std::max(v1, v);
    }
    const int x0 = std::clamp(static_cast<int>(std::floor(u0)) - 2, 0, k.width);
    const int y0 = std::clamp(static_cast<int>(std::floor(v0)) - 2, 0, k.height);
    const int x1 = std::clamp(static_cast<int>(std::ceil(u1)) + 3, 0, k.width);
    const int y1 = std::clamp(static_cast<int>(std::ceil(v1)) + 3, 0, k.height);
    return {x0, y0, x1 - x0, y1 - y0};
  }

  // total_pixels: the entities with a visible pixel are drawn again without the rest of the
  // scene, in groups whose projected rectangles do not overlap (so that no member can cover
  // another), and their labels are counted inside their rectangles. Same program, instance data
  // and rasterization as the geometry pass, so the visible pixels are a subset of these.
  void boxes(Frame& f) {
    FrameSet* out = f.out;
    out->boxes.clear();
    if (f.touched.empty()) return;
    const Targets& t = *f.targets;
    // Greedy grouping by rectangle overlap.
    const std::size_t n = f.touched.size();
    box_rect.resize(n);
    box_group.assign(n, -1);
    box_total.assign(n, 0);
    int groups = 0;
    for (std::size_t a = 0; a < n; ++a) {
      const auto rec =
          static_cast<std::size_t>(instance_record[static_cast<std::size_t>(f.touched[a].first)]);
      box_rect[a] = projectedRect(f, f.model[rec], f.slot[rec]);
      for (int g = 0; g <= groups && box_group[a] < 0; ++g) {
        bool free = true;
        for (std::size_t b = 0; b < a && free; ++b) {
          if (box_group[b] != g) continue;
          const auto& p = box_rect[a];
          const auto& q = box_rect[b];
          free = p[0] + p[2] <= q[0] || q[0] + q[2] <= p[0] || p[1] + p[3] <= q[1] ||
                 q[1] + q[3] <= p[1];
        }
        if (free) box_group[a] = g;
      }
      groups = std::max(groups, box_group[a] + 1);
    }
    f.stats.box_groups = static_cast<std::size_t>(groups);
    setFrameUniforms(f);
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glViewport(0, 0, t.width, t.height);
    bound_program = 0;
    glBindVertexArray(vao);
    glVertexArrayVertexBuffer(vao, 1, f.instance_buffer, 0, sizeof(GpuInstance));
    glDisable(GL_SCISSOR_TEST);
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_GREATER);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t.fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    const GLuint none[4] = {0, 0, 0, 0};
    const float zero = 0.0f;
    const int models = static_cast<int>(scene.models().size());
    for (int g = 0; g < groups; ++g) {
      // The group's instances, by model, after the frame's culled ones.
      box_upload.clear();
      group_base.assign(static_cast<std::size_t>(models), 0);
      group_count.assign(static_cast<std::size_t>(models), 0);
      int x0 = t.width, y0 = t.height, x1 = 0, y1 = 0;
      for (int m = 0; m < models; ++m) {
        group_base[static_cast<std::size_t>(m)] =
            static_cast<GLuint>(f.upload.size() + box_upload.size());
        for (std::size_t a = 0; a < n; ++a) {
          if (box_group[a] != g) continue;
          const auto rec = static_cast<std::size_t>(
              instance_record[static_cast<std::size_t>(f.touched[a].first)]);
          if (f.model[rec] != m) continue;
          box_upload.push_back(f.upload[static_cast<std::size_t>(f.slot[rec])]);
          ++group_count[static_cast<std::size_t>(m)];
          const auto& r = box_rect[a];
          x0 = std::min(x0, r[0]);
          y0 = std::min(y0, r[1]);
          x1 = std::max(x1, r[0] + r[2]);
          y1 = std::max(y1, r[1] + r[3]);
        }
      }
      glNamedBufferSubData(
          f.instance_buffer, static_cast<GLintptr>(f.upload.size() * sizeof(GpuInstance)),
          static_cast<GLsizeiptr>(box_upload.size() * sizeof(GpuInstance)), box_upload.data());
      // Only the group's rectangles matter: clear and draw inside their union (the colour is
      // not needed).
      if (x1 <= x0 || y1 <= y0) continue;
      glEnable(GL_SCISSOR_TEST);
      glScissor(x0, y0, x1 - x0, y1 - y0);
      glClearNamedFramebufferuiv(t.fbo, GL_COLOR, 1, none);
      glClearNamedFramebufferfv(t.fbo, GL_DEPTH, 0, &zero);
      RenderStats counted;  // RenderStats::triangles counts the geometry pass only
      for (int m = 0; m < models; ++m) {
        const GLsizei c = group_count[static_cast<std::size_t>(m)];
        if (c > 0) drawModel(m, group_base[static_cast<std::size_t>(m)], c, &counted);
      }
      f.stats.draw_calls += counted.draw_calls;
      glDisable(GL_SCISSOR_TEST);
      // Count each member's label inside its own rectangle.
      const int w = x1 - x0, h = y1 - y0;
      box_labels.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
      glReadPixels(x0, y0, w, h, GL_GREEN_INTEGER, GL_UNSIGNED_INT, box_labels.data());
      for (std::size_t a = 0; a < n; ++a) {
        if (box_group[a] != g) continue;
        const auto id = static_cast<std::uint32_t>(f.touched[a].first);
        const auto& r = box_rect[a];
        int count = 0;
        for (int y = r[1]; y < r[1] + r[3]; ++y) {
          const std::uint32_t* row =
              box_labels.data() + static_cast<std::size_t>(y - y0) * static_cast<std::size_t>(w);
          for (int x = r[0]; x < r[0] + r[2]; ++x) count += (row[x - x0] & 0xFFFFu) == id ? 1 : 0;
        }
        box_total[a] = count;
      }
    }
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    out->boxes.reserve(n);
    for (std::size_t a = 0; a < n; ++a) {
      const auto& [id, acc] = f.touched[a];
      const int rec = instance_record[static_cast<std::size_t>(id)];
      const SceneInstance& si = scene.instances()[static_cast<std::size_t>(rec)];
      BoundingBox b;
      b.instance = id;
      b.entity_id = scene.entityIds()[static_cast<std::size_t>(id)];
      b.cls = si.semantic == scenario::semanticId(scenario::EntityClass::kPedestrian)
                  ? scenario::EntityClass::kPedestrian
                  : scenario::EntityClass::kCar;
      b.role = si.scenario_entity >= 0
                   ? config.entities[static_cast<std::size_t>(si.scenario_entity)].role
                   : "world";
      b.x_min = acc.x_min;
      b.y_min = acc.y_min;
      b.x_max = acc.x_max;
      b.y_max = acc.y_max;
      b.visible_pixels = acc.count;
      // The coverage holds the visible pixels; max() only guards a driver that breaks the
      // invariance the GL promises.
      b.total_pixels = std::max(box_total[a], acc.count);
      b.occlusion = 1.0 - static_cast<double>(b.visible_pixels) / b.total_pixels;
      out->boxes.push_back(std::move(b));
    }
    checkGl("boxes");
  }

  // Renders the requests in phases so that the CPU and the GL overlap: every geometry pass is
  // submitted first (the GL rasterizes one while the next is culled and its vertices
  // processed), then each frame is read back, then the camera effects of each run on the CPU
  // (while the GL still works on later frames), then the boxes.
  void render(const std::vector<const RenderRequest*>& requests,
              const std::vector<FrameSet*>& outs) {
    egl.makeCurrent();
    for (const RenderRequest* r : requests) validate(*r);
    const bool timing = options.stage_timing;
    auto stage_end = [timing](Clock::time_point* t0, double* ms) {
      if (timing) glFinish();
      *ms += msSince(*t0);
      *t0 = Clock::now();
    };
    // Culling of every request first (cheap), so that the geometry is submitted lightest first:
    // the GL rasterizes a light frame while the CPU processes the vertices of a heavy one.
    order.clear();
    for (std::size_t i = 0; i < requests.size(); ++i) {
      Frame& f = frameSlot(i);
      const RenderRequest& r = *requests[i];
      f.request = &r;
      f.out = outs[i];
      f.stats = RenderStats{};
      auto t0 = Clock::now();
      f.targets = &targetsFor(f, r.intrinsics.width, r.intrinsics.height);
      setHidden(r.hidden_entities);
      camera = r.world_T_optical.translation();
      f.camera = camera;
      focal = std::max(r.intrinsics.fx, r.intrinsics.fy);
      lod = LodView(r, options.lod_max_error_px);
      Eigen::Matrix4d full;
      projection(r, f.view_proj, &full);
      frustumPlanes(full);
      cullAndUpload(r, f);
      f.lighting = lightingFor(config.environment, r.weather);
      cameraEffects(f);
      std::size_t triangles = 0;
      for (int m = 0; m < static_cast<int>(f.count.size()); ++m) {
        triangles += static_cast<std::size_t>(f.count[static_cast<std::size_t>(m)]) *
                     scene.drawnIndexCount(m) / 3;
      }
      order.emplace_back(triangles, i);
      stage_end(&t0, &f.stats.cull_upload_ms);
    }
    std::stable_sort(order.begin(), order.end());
    for (const auto& [triangles, i] : order) {
      Frame& f = *frames[i];
      auto t0 = Clock::now();
      geometryPass(f, triangles);
      stage_end(&t0, &f.stats.draw_ms);
      particlePass(f);
      glFlush();
      stage_end(&t0, &f.stats.post_ms);
    }
    for (std::size_t i = 0; i < requests.size(); ++i) {
      Frame& f = *frames[i];
      auto t0 = Clock::now();
      readBack(f);
      splitLabels(f);
      stage_end(&t0, &f.stats.readback_ms);
      std::uint8_t* noise_free = nullptr;
      if (f.request->noise_free_rgb) {
        f.out->rgb_noise_free.resize(f.out->rgb.size());
        noise_free = f.out->rgb_noise_free.data();
      } else {
        f.out->rgb_noise_free.clear();
      }
      if (f.effects.any()) {
        effects_worker.apply(f.color.data(), f.targets->width, f.targets->height, f.effects,
                             f.out->rgb.data(), &effects_scratch, noise_free);
      } else if (noise_free != nullptr) {
        std::copy(f.out->rgb.begin(), f.out->rgb.end(), noise_free);
      }
      stage_end(&t0, &f.stats.post_ms);
    }
    stats = RenderStats{};
    for (std::size_t i = 0; i < requests.size(); ++i) {
      Frame& f = *frames[i];
      auto t0 = Clock::now();
      boxes(f);
      stage_end(&t0, &f.stats.boxes_ms);
      FrameSet* out = f.out;
      out->time = f.request->time;
      out->intrinsics = f.request->intrinsics;
      out->world_T_optical = f.request->world_T_optical;
      stats.cull_upload_ms += f.stats.cull_upload_ms;
      stats.draw_ms += f.stats.draw_ms;
      stats.post_ms += f.stats.post_ms;
      stats.readback_ms += f.stats.readback_ms;
      stats.boxes_ms += f.stats.boxes_ms;
      stats.instances += f.stats.instances;
      stats.lod_instances += f.stats.lod_instances;
      stats.box_groups += f.stats.box_groups;
      stats.triangles += f.stats.triangles;
      stats.draw_calls += f.stats.draw_calls;
      f.request = nullptr;
      f.out = nullptr;
    }
  }

  const scenario::SimConfig config;  // a copy: the scene poses movers from it
  RendererOptions options;
  Scene scene;
  EglContext egl;
  std::string gl_renderer;
  RenderStats stats;
  std::unordered_multimap<std::string, int> by_id;

  GeometryProgram geometry[2];  // objects, ground layers
  GLuint bound_program = 0;
  GLuint sky_program = 0, particle_program = 0;
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
  std::vector<BoxAcc> box_acc;         // per instance id
  std::vector<int> touched;
  std::vector<std::uint32_t> label_scratch;
  CameraEffectsScratch effects_scratch;
  CameraEffectsWorker effects_worker;
  std::vector<std::array<int, 4>> box_rect;
  std::vector<int> box_group, box_total;
  std::vector<GpuInstance> box_upload;
  std::vector<GLuint> group_base;
  std::vector<GLsizei> group_count;
  std::vector<std::uint32_t> box_labels;
};

Renderer::Renderer(const scenario::World& world, const scenario::SimConfig& config,
                   const RendererOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {}

Renderer::~Renderer() = default;

void Renderer::render(const RenderRequest& request, FrameSet* out) {
  auto& i = *impl_;
  i.request_list.assign(1, &request);
  i.out_list.assign(1, out);
  i.render(i.request_list, i.out_list);
}

FrameSet Renderer::render(const RenderRequest& request) {
  FrameSet f;
  render(request, &f);
  return f;
}

void Renderer::render(const std::vector<RenderRequest>& requests, std::vector<FrameSet>* out) {
  auto& i = *impl_;
  out->resize(requests.size());
  i.request_list.clear();
  i.out_list.clear();
  for (std::size_t k = 0; k < requests.size(); ++k) {
    i.request_list.push_back(&requests[k]);
    i.out_list.push_back(&(*out)[k]);
  }
  i.render(i.request_list, i.out_list);
}

void Renderer::makeCurrent() { impl_->egl.makeCurrent(); }
void Renderer::releaseCurrent() { impl_->egl.releaseCurrent(); }

int Renderer::instanceCount() const { return static_cast<int>(impl_->scene.entityIds().size()); }

const std::string& Renderer::instanceEntityId(int instance) const {
  static const std::string kNone;
  const auto& ids = impl_->scene.entityIds();
  if (instance <= 0 || instance >= static_cast<int>(ids.size())) return kNone;
  return ids[static_cast<std::size_t>(instance)];
}

int Renderer::instanceOf(const std::string& entity_id) const {
  auto it = impl_->by_id.find(entity_id);
  return it == impl_->by_id.end() ? 0 : it->second;
}

std::string Renderer::glRenderer() const { return impl_->gl_renderer; }
std::string Renderer::eglBackend() const { return impl_->egl.platform(); }
const RenderStats& Renderer::lastStats() const { return impl_->stats; }

SceneTriangles Renderer::sceneTriangles(double time) const { return impl_->scene.triangles(time); }

SceneTriangles Renderer::sceneTriangles(const RenderRequest& request) const {
  impl_->validate(request);
  const LodView lod(request, impl_->options.lod_max_error_px);
  return impl_->scene.triangles(request.time, &lod);
}

std::string defaultModelsDir() { return scenario::shareDir() + "/models"; }

}  // namespace hameritt::render
