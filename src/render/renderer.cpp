#include "hameritt/render/renderer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "camera_effects.h"
#include "egl_context.h"
#include "environment_model.h"
#include "gl.h"
#include "hameritt/scenario/error.h"
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
  GLuint fbo = 0, color = 0, depth = 0, labels = 0, zbuffer = 0;
  GLuint particle_fbo = 0;  // the colour target alone, for blending particles onto it
  GLuint occlusion_fbo = 0;
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
      ground_ambient, snow, wet, haze_color, haze_k, world_R_optical, intrinsics;
};

}  // namespace

struct Renderer::Impl {
  Impl(const scenario::World& world, const scenario::SimConfig& cfg, const RendererOptions& opt)
      : config(cfg),
        options(opt),
        scene(world, config, opt.models_dir.empty() ? defaultModelsDir() : opt.models_dir),
        egl(opt.backend) {
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
    for (auto& t : targets) deleteTargets(&t);
    glDeleteProgram(geometry_program);
    glDeleteProgram(sky_program);
    glDeleteProgram(particle_program);
    GLuint buffers[] = {vertex_buffer, element_buffer, instance_buffer};
    glDeleteBuffers(3, buffers);
    glDeleteVertexArrays(1, &vao);
    glDeleteVertexArrays(1, &empty_vao);
    if (!queries.empty()) glDeleteQueries(static_cast<GLsizei>(queries.size()), queries.data());
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
    const std::string common = std::string("#version 450 core\n") + shaders::kCommon;
    geometry_program = linkProgram(shaders::kGeometryVertex, common + shaders::kGeometryFragment,
                                   "geometry");
    sky_program = linkProgram(shaders::kFullscreenVertex, common + shaders::kSkyFragment, "sky");
    const std::string version = "#version 450 core\n";
    particle_program = linkProgram(version + shaders::kHash + shaders::kParticleVertex,
                                   version + shaders::kParticleFragment, "particles");
    auto loc = [this](const char* n) { return glGetUniformLocation(geometry_program, n); };
    u = {loc("u_view_proj"),   loc("u_camera"),         loc("u_canopy_center"),
         loc("u_near"),        loc("u_far"),            loc("u_sun_dir"),
         loc("u_sun_color"),   loc("u_sky_ambient"),    loc("u_ground_ambient"),
         loc("u_snow"),        loc("u_wet"),            loc("u_haze_color"),
         loc("u_haze_k"),      loc("u_world_R_optical"), loc("u_intrinsics")};

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
    glCreateBuffers(1, &instance_buffer);
    glNamedBufferStorage(instance_buffer,
                         static_cast<GLsizeiptr>(records.size() * sizeof(GpuInstance)), nullptr,
                         GL_DYNAMIC_STORAGE_BIT);
    slot.assign(records.size(), -1);

    glCreateVertexArrays(1, &vao);
    glVertexArrayVertexBuffer(vao, 0, vertex_buffer, 0, sizeof(Vertex));
    glVertexArrayVertexBuffer(vao, 1, instance_buffer, 0, sizeof(GpuInstance));
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
    grid_origin = lo;
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
      const int cx = std::clamp(static_cast<int>((si.center.x() - lo.x()) / kCellSize), 0, grid_nx - 1);
      const int cy = std::clamp(static_cast<int>((si.center.y() - lo.y()) / kCellSize), 0, grid_ny - 1);
      const int c = cy * grid_nx + cx;
      per[static_cast<std::size_t>(c * models + si.model)].push_back(static_cast<std::uint32_t>(i));
      cell_lo[static_cast<std::size_t>(c)] =
          cell_lo[static_cast<std::size_t>(c)].cwiseMin(si.center - Eigen::Vector3f::Constant(si.radius));
      cell_hi[static_cast<std::size_t>(c)] =
          cell_hi[static_cast<std::size_t>(c)].cwiseMax(si.center + Eigen::Vector3f::Constant(si.radius));
    }
    cell_range.assign(static_cast<std::size_t>(cells * models), {0, 0});
    for (int c = 0; c < cells; ++c) {
      for (int m = 0; m < models; ++m) {
        auto& v = per[static_cast<std::size_t>(c * models + m)];
        const auto begin = static_cast<std::uint32_t>(cell_items.size());
        cell_items.insert(cell_items.end(), v.begin(), v.end());
        cell_range[static_cast<std::size_t>(c * models + m)] = {
            begin, static_cast<std::uint32_t>(cell_items.size())};
      }
    }
    visible.resize(static_cast<std::size_t>(models));
    cell_order.reserve(static_cast<std::size_t>(cells));
    upload.reserve(records.size());
    uploaded.reserve(records.size());
  }

  Targets& targetsFor(int w, int h) {
    for (auto& t : targets) {
      if (t.width == w && t.height == h) return t;
    }
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    if (w > max_size || h > max_size) {
      throw RenderError("RenderRequest.intrinsics: " + std::to_string(w) + " x " +
                        std::to_string(h) + " exceeds the GL limit of " + std::to_string(max_size));
    }
    // Keep a few sizes; drop the oldest beyond that.
    if (targets.size() >= 4) {
      deleteTargets(&targets.front());
      targets.erase(targets.begin());
    }
    Targets t;
    t.width = w;
    t.height = h;
    glCreateTextures(GL_TEXTURE_2D, 1, &t.color);
    glTextureStorage2D(t.color, 1, GL_RGBA8, w, h);
    glCreateTextures(GL_TEXTURE_2D, 1, &t.depth);
    glTextureStorage2D(t.depth, 1, GL_R32F, w, h);
    glCreateTextures(GL_TEXTURE_2D, 1, &t.labels);
    glTextureStorage2D(t.labels, 1, GL_R32UI, w, h);
    glCreateRenderbuffers(1, &t.zbuffer);
    glNamedRenderbufferStorage(t.zbuffer, GL_DEPTH_COMPONENT32F, w, h);
    glCreateFramebuffers(1, &t.fbo);
    glNamedFramebufferTexture(t.fbo, GL_COLOR_ATTACHMENT0, t.color, 0);
    glNamedFramebufferTexture(t.fbo, GL_COLOR_ATTACHMENT1, t.depth, 0);
    glNamedFramebufferTexture(t.fbo, GL_COLOR_ATTACHMENT2, t.labels, 0);
    glNamedFramebufferRenderbuffer(t.fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.zbuffer);
    const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glNamedFramebufferDrawBuffers(t.fbo, 3, bufs);
    glCreateFramebuffers(1, &t.particle_fbo);
    glNamedFramebufferTexture(t.particle_fbo, GL_COLOR_ATTACHMENT0, t.color, 0);
    glNamedFramebufferDrawBuffer(t.particle_fbo, GL_COLOR_ATTACHMENT0);
    // Occlusion counting reuses the depth buffer once the geometry pass has been read back.
    glCreateFramebuffers(1, &t.occlusion_fbo);
    glNamedFramebufferRenderbuffer(t.occlusion_fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                                   t.zbuffer);
    glNamedFramebufferDrawBuffer(t.occlusion_fbo, GL_NONE);
    glNamedFramebufferReadBuffer(t.occlusion_fbo, GL_NONE);
    for (GLuint f : {t.fbo, t.particle_fbo, t.occlusion_fbo}) {
      if (glCheckNamedFramebufferStatus(f, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        deleteTargets(&t);
        throw RenderError("GL: incomplete framebuffer for " + std::to_string(w) + " x " +
                          std::to_string(h));
      }
    }
    checkGl("render targets");
    targets.push_back(t);
    return targets.back();
  }

  static void deleteTargets(Targets* t) {
    GLuint tex[] = {t->color, t->depth, t->labels};
    glDeleteTextures(3, tex);
    glDeleteRenderbuffers(1, &t->zbuffer);
    GLuint fbos[] = {t->fbo, t->particle_fbo, t->occlusion_fbo};
    glDeleteFramebuffers(3, fbos);
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
        throw RenderError(std::string("RenderRequest.") + field + ": expected a finite value > 0, got " +
                          num(v));
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
  }

  // Column-major float 4x4 of projection * [R^T | 0] (camera-relative world to clip), and the
  // same with the translation for the frustum planes (double).
  void projection(const RenderRequest& r, float view_proj[16], Eigen::Matrix4d* full) {
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

  void cullAndUpload(const RenderRequest& r) {
    const int models = static_cast<int>(scene.models().size());
    for (auto& v : visible) v.clear();
    // Movers: posed at the frame time; their records are rewritten in place.
    if (!movers.empty()) {
      for (std::uint32_t i : movers) {
        Eigen::Vector3f c;
        float radius;
        scene.pose(i, r.time, &records[i], &c, &radius);
        mover_sphere[i] = {c, radius};
      }
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
          visible[static_cast<std::size_t>(m)].push_back(i);
        }
      }
    }
    for (std::uint32_t i : movers) {
      if (hidden[i]) continue;
      const auto& [c, radius] = mover_sphere[i];
      if (sphereVisible(c, radius, true)) visible[static_cast<std::size_t>(inst[i].model)].push_back(i);
    }
    for (std::uint32_t i : always) {
      if (sphereVisible(inst[i].center, inst[i].radius, true)) {
        visible[static_cast<std::size_t>(inst[i].model)].push_back(i);
      }
    }
    if (r.draw_uav) visible[static_cast<std::size_t>(scene.procedural().uav)].push_back(uav_record);
    // One upload of the visible instances, in draw order.
    for (std::uint32_t i : uploaded) slot[i] = -1;
    uploaded.clear();
    upload.clear();
    model_base_instance.assign(static_cast<std::size_t>(models), 0);
    for (int m : draw_order) {
      model_base_instance[static_cast<std::size_t>(m)] = static_cast<GLuint>(upload.size());
      for (std::uint32_t i : visible[static_cast<std::size_t>(m)]) {
        slot[i] = static_cast<int>(upload.size());
        uploaded.push_back(i);
        upload.push_back(gpuInstance(records[i]));
      }
    }
    if (!upload.empty()) {
      glNamedBufferSubData(instance_buffer, 0,
                           static_cast<GLsizeiptr>(upload.size() * sizeof(GpuInstance)),
                           upload.data());
    }
    stats.instances = upload.size();
  }

  void setFrameUniforms(const RenderRequest& r, const Lighting& l, const float view_proj[16]) {
    const GLuint p = geometry_program;
    glProgramUniformMatrix4fv(p, u.view_proj, 1, GL_FALSE, view_proj);
    const Eigen::Vector3f cam = camera.cast<float>();
    glProgramUniform3fv(p, u.camera, 1, cam.data());
    glProgramUniform1f(p, u.near_clip, static_cast<float>(r.near_clip));
    glProgramUniform1f(p, u.far_clip, static_cast<float>(r.far_clip));
    glProgramUniform3fv(p, u.sun_dir, 1, l.sun_dir.data());
    glProgramUniform3fv(p, u.sun_color, 1, l.sun_color.data());
    glProgramUniform3fv(p, u.sky_ambient, 1, l.sky_ambient.data());
    glProgramUniform3fv(p, u.ground_ambient, 1, l.ground_ambient.data());
    glProgramUniform1f(p, u.snow, l.snow_cover);
    glProgramUniform1f(p, u.wet, l.wetness);
    glProgramUniform3fv(p, u.haze_color, 1, l.haze_color.data());
    glProgramUniform1f(p, u.haze_k, l.haze_k);
    const Eigen::Matrix3f rot = r.world_T_optical.linear().cast<float>();
    glProgramUniformMatrix3fv(p, u.world_R_optical, 1, GL_FALSE, rot.data());
    const float intr[4] = {static_cast<float>(r.intrinsics.fx), static_cast<float>(r.intrinsics.fy),
                           static_cast<float>(r.intrinsics.cx), static_cast<float>(r.intrinsics.cy)};
    glProgramUniform4fv(p, u.intrinsics, 1, intr);
  }

  // Draws model m's instances [base, base + count) of the bound instance-index buffer: one
  // call per model, the materials are in the vertices.
  void drawModel(int m, GLuint base, GLsizei count) {
    const Mesh& mesh = scene.models()[static_cast<std::size_t>(m)];
    const std::uint32_t n = scene.drawnIndexCount(m);
    if (n == 0) return;
    if (mesh.foliage_first < n) {
      glProgramUniform3fv(geometry_program, u.canopy_center, 1, mesh.canopy_center.data());
    }
    glDrawElementsInstancedBaseVertexBaseInstance(
        GL_TRIANGLES, static_cast<GLsizei>(n), GL_UNSIGNED_INT,
        reinterpret_cast<const void*>(model_first_element[static_cast<std::size_t>(m)] *
                                      sizeof(std::uint32_t)),
        count, model_base_vertex[static_cast<std::size_t>(m)], base);
    stats.triangles += static_cast<std::size_t>(n / 3) * static_cast<std::size_t>(count);
    ++stats.draw_calls;
  }

  void geometryPass(const RenderRequest& r, const Lighting& l, const Targets& t) {
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glViewport(0, 0, t.width, t.height);
    glDisable(GL_SCISSOR_TEST);
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_GREATER);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    const float black[4] = {0, 0, 0, 1};
    const float inf[4] = {std::numeric_limits<float>::infinity(), 0, 0, 0};
    const GLuint none[4] = {0, 0, 0, 0};
    glClearNamedFramebufferfv(t.fbo, GL_COLOR, 0, black);
    glClearNamedFramebufferfv(t.fbo, GL_COLOR, 1, inf);
    glClearNamedFramebufferuiv(t.fbo, GL_COLOR, 2, none);
    const float zero = 0.0f;
    glClearNamedFramebufferfv(t.fbo, GL_DEPTH, 0, &zero);

    glUseProgram(geometry_program);
    glBindVertexArray(vao);
    for (int m : draw_order) {
      const auto count = static_cast<GLsizei>(visible[static_cast<std::size_t>(m)].size());
      if (count > 0) drawModel(m, model_base_instance[static_cast<std::size_t>(m)], count);
    }

    // Sky where nothing was drawn (window depth still 0).
    glUseProgram(sky_program);
    glBindVertexArray(empty_vao);
    glDisable(GL_CULL_FACE);  // the full-screen triangle's winding is mirrored too
    glDepthFunc(GL_EQUAL);
    glDepthMask(GL_FALSE);
    const Eigen::Matrix3f rot = r.world_T_optical.linear().cast<float>();
    glProgramUniformMatrix3fv(sky_program, sky_loc.world_R_optical, 1, GL_FALSE, rot.data());
    const float intr[4] = {static_cast<float>(r.intrinsics.fx), static_cast<float>(r.intrinsics.fy),
                           static_cast<float>(r.intrinsics.cx), static_cast<float>(r.intrinsics.cy)};
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

  // Counter-based key of (scenario seed, camera index, frame index): particles use x, y; the
  // noise z, w.
  void frameKey(const RenderRequest& r, GLuint key[4]) const {
    const std::uint64_t k1 = splitmix64(
        config.seed ^ splitmix64(static_cast<std::uint64_t>(static_cast<std::int64_t>(r.camera_index)) ^
                                 splitmix64(r.frame_index)));
    const std::uint64_t k2 = splitmix64(k1);
    key[0] = static_cast<GLuint>(k1);
    key[1] = static_cast<GLuint>(k1 >> 32);
    key[2] = static_cast<GLuint>(k2);
    key[3] = static_cast<GLuint>(k2 >> 32);
  }

  // Rain streaks and snow flakes blended onto the colour target (weather on, intensity > 0).
  void particlePass(const RenderRequest& r, const Lighting& l, const Targets& t) {
    const float rain = r.weather ? static_cast<float>(std::clamp(config.environment.rain, 0.0, 1.0)) : 0.0f;
    const float snow = r.weather ? static_cast<float>(std::clamp(config.environment.snow, 0.0, 1.0)) : 0.0f;
    if (rain <= 0.0f && snow <= 0.0f) return;
    const GLuint p = particle_program;
    GLuint key[4];
    frameKey(r, key);
    glProgramUniform4uiv(p, particle_loc.key, 1, key);
    glProgramUniform2f(p, particle_loc.size, static_cast<float>(t.width), static_cast<float>(t.height));
    const Eigen::Vector3f fall =
        (r.world_T_optical.linear().transpose() * Eigen::Vector3d(0, 0, -1)).cast<float>();
    glProgramUniform3fv(p, particle_loc.fall, 1, fall.data());
    const float intr[4] = {static_cast<float>(r.intrinsics.fx), static_cast<float>(r.intrinsics.fy),
                           static_cast<float>(r.intrinsics.cx), static_cast<float>(r.intrinsics.cy)};
    glProgramUniform4fv(p, particle_loc.intrinsics, 1, intr);
    // Particles are lit by the diffuse light.
    const Eigen::Vector3f light = l.sky_ambient + 0.3f * l.sun_color;
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
        glDrawArraysInstanced(GL_TRIANGLES, 0, 6, nx * ny);
      }
    };
    layers(kRainLayers, rain, 1);
    layers(kSnowLayers, snow, 4);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE);
  }

  // Motion blur and sensor noise of this request (applied on the CPU after the read-back).
  void cameraEffects(const RenderRequest& r) {
    const auto& pert = config.perturbations;
    effects.blur = r.noise ? motionBlurKernel(r.blur_direction.x(), r.blur_direction.y(),
                                              pert.motion_blur_px)
                           : std::vector<BlurTap>{};
    effects.noise_std = r.noise ? static_cast<float>(pert.gaussian_noise_std) : 0.0f;
    effects.salt = r.noise ? static_cast<float>(pert.salt_pepper_probability) : 0.0f;
    GLuint key[4];
    frameKey(r, key);
    effects.key[0] = key[2];
    effects.key[1] = key[3];
  }

  void readBack(const Targets& t, FrameSet* out) {
    const std::size_t n = static_cast<std::size_t>(t.width) * static_cast<std::size_t>(t.height);
    out->rgb.resize(3 * n);
    out->depth.resize(n);
    out->semantic.resize(n);
    out->instance.resize(n);
    label_scratch.resize(n);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t.fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    std::uint8_t* color = out->rgb.data();
    if (effects.any()) {
      color_scratch.resize(3 * n);
      color = color_scratch.data();
    }
    glReadPixels(0, 0, t.width, t.height, GL_RGB, GL_UNSIGNED_BYTE, color);
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, t.width, t.height, GL_RED, GL_FLOAT, out->depth.data());
    glReadBuffer(GL_COLOR_ATTACHMENT2);
    glReadPixels(0, 0, t.width, t.height, GL_RED_INTEGER, GL_UNSIGNED_INT, label_scratch.data());
    checkGl("read back");
  }

  struct BoxAcc {
    int x_min = 0, y_min = 0, x_max = 0, y_max = 0, count = 0;
  };

  // Splits the labels and grows the boxes of the instances of interest in the same pass.
  void splitLabels(int width, FrameSet* out) {
    touched.clear();
    const std::size_t n = label_scratch.size();
    const std::uint32_t* src = label_scratch.data();
    std::uint8_t* sem = out->semantic.data();
    std::uint16_t* ins = out->instance.data();
    const std::size_t n_ids = interest.size();
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t v = src[i];
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
  }

  // Pixel rectangle that surely contains instance i's projection, or the whole image.
  std::array<int, 4> projectedRect(const RenderRequest& r, std::uint32_t rec) const {
    const Intrinsics& k = r.intrinsics;
    const SceneInstance& si = scene.instances()[rec];
    const Mesh& mesh = scene.models()[static_cast<std::size_t>(si.model)];
    const InstanceRecord& ir = records[rec];
    const Eigen::Isometry3d optical_T_world = r.world_T_optical.inverse();
    double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d p((c & 1) ? mesh.max.x() : mesh.min.x(), (c & 2) ? mesh.max.y() : mesh.min.y(),
                              (c & 4) ? mesh.max.z() : mesh.min.z());
      Eigen::Vector3d w;
      for (int a = 0; a < 3; ++a) {
        w[a] = ir.row[a][0] * p.x() + ir.row[a][1] * p.y() + ir.row[a][2] * p.z() + ir.row[a][3];
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

  // total_pixels: each entity with a visible pixel is drawn alone (scissored to its projected
  // rectangle): a depth pass, then a GL_EQUAL pass counted by an occlusion query. Same program,
  // same vertices, same rasterization as the geometry pass, so visible <= total exactly.
  void boxes(const RenderRequest& r, const Targets& t, FrameSet* out) {
    out->boxes.clear();
    if (touched.empty()) return;
    if (queries.size() < touched.size()) {
      const std::size_t old = queries.size();
      queries.resize(touched.size());
      glCreateQueries(GL_SAMPLES_PASSED, static_cast<GLsizei>(touched.size() - old), queries.data() + old);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, t.occlusion_fbo);
    glViewport(0, 0, t.width, t.height);
    glUseProgram(geometry_program);
    glBindVertexArray(vao);
    glEnable(GL_SCISSOR_TEST);
    glEnable(GL_DEPTH_TEST);
    const float zero = 0.0f;
    for (std::size_t q = 0; q < touched.size(); ++q) {
      const int id = touched[q];
      const auto rec = static_cast<std::uint32_t>(instance_record[static_cast<std::size_t>(id)]);
      const auto rect = projectedRect(r, rec);
      glScissor(rect[0], rect[1], rect[2], rect[3]);
      glDepthMask(GL_TRUE);
      glClearNamedFramebufferfv(t.occlusion_fbo, GL_DEPTH, 0, &zero);
      glDepthFunc(GL_GREATER);
      const int model = scene.instances()[rec].model;
      const auto base = static_cast<GLuint>(slot[rec]);  // drawn, so uploaded this frame
      drawModel(model, base, 1);
      glDepthMask(GL_FALSE);
      glDepthFunc(GL_EQUAL);
      glBeginQuery(GL_SAMPLES_PASSED, queries[q]);
      drawModel(model, base, 1);
      glEndQuery(GL_SAMPLES_PASSED);
    }
    glDisable(GL_SCISSOR_TEST);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_GREATER);
    out->boxes.reserve(touched.size());
    for (std::size_t q = 0; q < touched.size(); ++q) {
      const int id = touched[q];
      BoxAcc& acc = box_acc[static_cast<std::size_t>(id)];
      GLuint total = 0;
      glGetQueryObjectuiv(queries[q], GL_QUERY_RESULT, &total);
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
      // The counted coverage holds the visible pixels; max() only guards a driver that breaks
      // the invariance the GL promises.
      b.total_pixels = std::max(static_cast<int>(total), acc.count);
      b.occlusion = 1.0 - static_cast<double>(b.visible_pixels) / b.total_pixels;
      out->boxes.push_back(std::move(b));
      acc = BoxAcc{};
    }
    checkGl("boxes");
  }

  void setHidden(const std::vector<std::string>& ids) {
    for (std::uint32_t i : hidden_list) hidden[i] = 0;
    hidden_list.clear();
    for (const std::string& id : ids) {
      auto [b, e] = by_id.equal_range(id);
      if (b == e) throw RenderError("RenderRequest.hidden_entities: unknown entity '" + id + "'");
      for (auto it = b; it != e; ++it) {
        const auto rec = static_cast<std::uint32_t>(instance_record[static_cast<std::size_t>(it->second)]);
        hidden[rec] = 1;
        hidden_list.push_back(rec);
      }
    }
  }

  void render(const RenderRequest& r, FrameSet* out) {
    egl.makeCurrent();
    validate(r);
    setHidden(r.hidden_entities);
    stats = RenderStats{};
    auto stage_end = [this](Clock::time_point* t0, double* ms) {
      if (options.stage_timing) glFinish();
      *ms += msSince(*t0);
      *t0 = Clock::now();
    };
    auto t0 = Clock::now();
    Targets& t = targetsFor(r.intrinsics.width, r.intrinsics.height);
    camera = r.world_T_optical.translation();
    focal = std::max(r.intrinsics.fx, r.intrinsics.fy);
    float view_proj[16];
    Eigen::Matrix4d full;
    projection(r, view_proj, &full);
    frustumPlanes(full);
    cullAndUpload(r);
    const Lighting l = lightingFor(config.environment, r.weather);
    setFrameUniforms(r, l, view_proj);
    cameraEffects(r);
    stage_end(&t0, &stats.cull_upload_ms);

    geometryPass(r, l, t);
    stage_end(&t0, &stats.draw_ms);
    particlePass(r, l, t);
    stage_end(&t0, &stats.post_ms);
    readBack(t, out);
    splitLabels(t.width, out);
    stage_end(&t0, &stats.readback_ms);
    if (effects.any()) {
      applyCameraEffects(color_scratch.data(), t.width, t.height, effects, out->rgb.data(),
                         &effects_scratch);
      stage_end(&t0, &stats.post_ms);
    }
    boxes(r, t, out);
    stage_end(&t0, &stats.boxes_ms);

    out->time = r.time;
    out->intrinsics = r.intrinsics;
    out->world_T_optical = r.world_T_optical;
  }
  const scenario::SimConfig config;  // a copy: the scene poses movers from it
  RendererOptions options;
  Scene scene;
  EglContext egl;
  std::string gl_renderer;
  RenderStats stats;
  std::unordered_multimap<std::string, int> by_id;

  GLuint geometry_program = 0, sky_program = 0, particle_program = 0;
  Uniforms u{};
  struct {
    GLint world_R_optical, intrinsics, zenith, horizon, sun_dir, glow, far_clip, haze_color, haze_k;
  } sky_loc{};

  struct {
    GLint key, size, cells_x, cell, length, radius, density, layer, fall, intrinsics, alpha,
        brightness;
  } particle_loc{};
  CameraEffects effects;
  std::vector<std::uint8_t> color_scratch;
  CameraEffectsScratch effects_scratch;
  GLuint vao = 0, empty_vao = 0, vertex_buffer = 0, element_buffer = 0, instance_buffer = 0;
  std::vector<GLint> model_base_vertex;
  std::vector<std::size_t> model_first_element;
  std::vector<GLuint> model_base_instance;
  std::vector<int> draw_order;
  std::vector<InstanceRecord> records;
  std::uint32_t uav_record = 0;
  std::vector<Targets> targets;

  // Culling.
  Eigen::Vector2d grid_origin{0, 0};
  int grid_nx = 1, grid_ny = 1;
  std::vector<Eigen::Vector3f> cell_lo, cell_hi;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> cell_range;  // [cell * models + model]
  std::vector<std::uint32_t> cell_items;
  std::vector<std::uint32_t> movers, always;
  std::vector<std::pair<Eigen::Vector3f, float>> mover_sphere;  // per record
  std::array<Plane, 6> planes{};
  Eigen::Vector3d camera{0, 0, 0};
  double focal = 1.0;
  std::vector<std::pair<double, int>> cell_order;
  std::vector<std::vector<std::uint32_t>> visible;  // per model
  std::vector<GpuInstance> upload;
  std::vector<int> slot;  // per record: its index in this frame's upload, or -1
  std::vector<std::uint32_t> uploaded;  // records in this frame's upload
  std::vector<std::uint8_t> hidden;  // per record
  std::vector<std::uint32_t> hidden_list;

  // Labels and boxes.
  std::vector<std::uint8_t> interest;   // per instance id
  std::vector<int> instance_record;     // instance id -> record
  std::vector<BoxAcc> box_acc;          // per instance id
  std::vector<int> touched;
  std::vector<std::uint32_t> label_scratch;
  std::vector<GLuint> queries;
};

Renderer::Renderer(const scenario::World& world, const scenario::SimConfig& config,
                   const RendererOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {
  auto& i = *impl_;
  auto sky = [&i](const char* n) { return glGetUniformLocation(i.sky_program, n); };
  i.sky_loc = {sky("u_world_R_optical"), sky("u_intrinsics"), sky("u_zenith"),  sky("u_horizon"),    sky("u_sun_dir"),
               sky("u_glow"),       sky("u_far"),     sky("u_haze_color"), sky("u_haze_k")};
  auto part = [&i](const char* n) { return glGetUniformLocation(i.particle_program, n); };
  i.particle_loc = {part("u_key"),    part("u_size"),      part("u_cells_x"), part("u_cell"),
                    part("u_length"), part("u_radius"),    part("u_density"), part("u_layer"),
                    part("u_fall"),   part("u_intrinsics"), part("u_alpha"),  part("u_brightness")};
}

Renderer::~Renderer() = default;

void Renderer::render(const RenderRequest& request, FrameSet* out) { impl_->render(request, out); }

FrameSet Renderer::render(const RenderRequest& request) {
  FrameSet f;
  impl_->render(request, &f);
  return f;
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

std::string defaultModelsDir() { return std::string(HAMERITT_SOURCE_DIR) + "/models"; }

}  // namespace hameritt::render
