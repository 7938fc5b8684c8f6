// GL set-up of the renderer: shader programs, mesh buffers, the culling grid, render targets.
#include "renderer_internal.h"

namespace hameritt::render {

namespace {

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

}  // namespace

Renderer::Impl::Impl(const scenario::World& world, const scenario::SimConfig& cfg,
                     const RendererOptions& opt)
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

Renderer::Impl::~Impl() {
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
  glDeleteProgram(coverage_program);
  if (!query_pool.empty()) {
    glDeleteQueries(static_cast<GLsizei>(query_pool.size()), query_pool.data());
  }
  glDeleteProgram(sky_program);
  glDeleteProgram(particle_program);
  GLuint buffers[] = {vertex_buffer, element_buffer};
  glDeleteBuffers(2, buffers);
  glDeleteVertexArrays(1, &vao);
  glDeleteVertexArrays(1, &empty_vao);
}

void Renderer::Impl::initGl() {
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
  // Three variants of the geometry program: objects, the ground layers with their patterns,
  // and the buildings with their facades.
  static const char* const kDefines[] = {"", "#define GROUND_LAYERS 1\n", "#define FACADE 1\n"};
  static const char* const kNames[] = {"geometry (objects)", "geometry (ground layers)",
                                       "geometry (facades)"};
  for (int g = 0; g < 3; ++g) {
    const std::string define = kDefines[g];
    geometry[g].id =
        linkProgram(version + define + shaders::kGeometryVertex,
                    version + define + shaders::kCommon + shaders::kGeometryFragment, kNames[g]);
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
  // Coverage counting (boxes): the objects' vertex stage (same positions, gl_Position is
  // invariant) and a fragment stage that does nothing.
  coverage_program =
      linkProgram(version + shaders::kGeometryVertex, version + "void main() {}\n", "coverage");
  coverage_loc.view_proj = glGetUniformLocation(coverage_program, "u_view_proj");
  coverage_loc.camera = glGetUniformLocation(coverage_program, "u_camera");
  sky_program = linkProgram(shaders::kFullscreenVertex,
                            version + shaders::kCommon + shaders::kSkyFragment, "sky");
  particle_program = linkProgram(version + shaders::kHash + shaders::kParticleVertex,
                                 version + shaders::kParticleFragment, "particles");
  auto sky = [this](const char* n) { return glGetUniformLocation(sky_program, n); };
  sky_loc = {sky("u_world_R_optical"), sky("u_intrinsics"), sky("u_zenith"), sky("u_horizon"),
             sky("u_sun_dir"),         sky("u_glow"),       sky("u_far"),    sky("u_haze_color"),
             sky("u_haze_k")};
  auto part = [this](const char* n) { return glGetUniformLocation(particle_program, n); };
  particle_loc = {part("u_key"),    part("u_size"),       part("u_cells_x"), part("u_cell"),
                  part("u_length"), part("u_radius"),     part("u_density"), part("u_layer"),
                  part("u_fall"),   part("u_intrinsics"), part("u_alpha"),   part("u_brightness")};

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
  part_records.assign(scene.entityIds().size(), {});
  for (std::size_t i = 0; i < scene.instances().size(); ++i) {
    const SceneInstance& si = scene.instances()[i];
    if (si.part_of > 0) part_records[static_cast<std::size_t>(si.part_of)].push_back(static_cast<int>(i));
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

void Renderer::Impl::checkGl(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    char buf[16];
    std::snprintf(buf, sizeof(buf), "0x%04x", e);
    throw RenderError(std::string("GL: error ") + buf + " in " + where);
  }
}

void Renderer::Impl::buildCulling() {
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
    if (si.model == p.signal && config.signals && !si.mover) {
      // The nearest signalised intersection within 30 m (a mast stands at one of its corners).
      int best = -1;
      double best_d = 30.0;
      const auto& list = config.signals->intersections;
      for (std::size_t k = 0; k < list.size(); ++k) {
        const double d = (list[k].position - si.box.center2()).norm();
        if (d < best_d) {
          best_d = d;
          best = static_cast<int>(k);
        }
      }
      if (best >= 0) signal_masts.emplace_back(static_cast<std::uint32_t>(i), best);
    }
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

Frame& Renderer::Impl::frameSlot(std::size_t i) {
  while (frames.size() <= i) {
    auto f = std::make_unique<Frame>();
    glCreateBuffers(1, &f->instance_buffer);
    // The culled instances, then the groups of entities drawn alone for their boxes.
    glNamedBufferStorage(f->instance_buffer,
                         static_cast<GLsizeiptr>(2 * records.size() * sizeof(GpuInstance)), nullptr,
                         GL_DYNAMIC_STORAGE_BIT);
    f->slot.assign(records.size(), -1);
    f->model.assign(records.size(), -1);
    f->upload.reserve(records.size());
    f->uploaded.reserve(records.size());
    frames.push_back(std::move(f));
  }
  return *frames[i];
}

Targets& Renderer::Impl::targetsFor(Frame& f, int w, int h) {
  for (auto& t : f.target_cache) {
    if (t.width == w && t.height == h) return t;
  }
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
  if (w > max_size || h > max_size) {
    throw RenderError("RenderRequest.intrinsics: " + std::to_string(w) + " x " + std::to_string(h) +
                      " exceeds the GL limit of " + std::to_string(max_size));
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

void Renderer::Impl::deleteTargets(Targets* t) {
  GLuint tex[] = {t->color, t->depth_labels};
  glDeleteTextures(2, tex);
  glDeleteRenderbuffers(1, &t->zbuffer);
  GLuint fbos[] = {t->fbo, t->particle_fbo};
  glDeleteFramebuffers(2, fbos);
  *t = Targets{};
}

}  // namespace hameritt::render
