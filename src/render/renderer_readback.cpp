// Read-back of a frame: camera effects, depth and label split, bounding boxes and visibility.
#include "renderer_internal.h"

namespace hameritt::render {

void Renderer::Impl::cameraEffects(Frame& f) const {
  const RenderRequest& r = *f.request;
  const auto& pert = config.perturbations;
  motionBlurKernel(r.blur_direction.x(), r.blur_direction.y(), r.noise ? pert.motion_blur_px : 0.0,
                   &f.effects.blur);
  f.effects.noise_std = r.noise ? static_cast<float>(pert.gaussian_noise_std) : 0.0f;
  f.effects.salt = r.noise ? static_cast<float>(pert.salt_pepper_probability) : 0.0f;
  GLuint key[4];
  frameKey(r, key);
  f.effects.key[0] = key[2];
  f.effects.key[1] = key[3];
}

void Renderer::Impl::readBack(Frame& f) {
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

void Renderer::Impl::splitLabels(Frame& f) {
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

std::array<int, 4> Renderer::Impl::projectedRect(const Frame& f, int model, int slot) const {
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

void Renderer::Impl::boxes(Frame& f) {
  FrameSet* out = f.out;
  out->boxes.clear();
  if (f.touched.empty()) return;
  const Targets& t = *f.targets;
  // Greedy grouping by rectangle overlap (convex instances are counted by queries instead).
  const std::size_t n = f.touched.size();
  box_rect.resize(n);
  box_group.assign(n, -1);
  box_total.assign(n, 0);
  box_query.assign(n, 0);
  int groups = 0;
  std::size_t queries = 0;
  for (std::size_t a = 0; a < n; ++a) {
    const auto rec =
        static_cast<std::size_t>(instance_record[static_cast<std::size_t>(f.touched[a].first)]);
    if (scene.instances()[rec].convex) {
      box_query[a] = 1;
      ++queries;
      continue;
    }
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
  if (queries > 0) {
    // A convex instance drawn alone, back faces culled, no depth test: every fragment is one
    // pixel it covers unoccluded; the query counts them without a read-back. Same program,
    // instance data and rasterization as the geometry pass. Nothing is written.
    if (query_pool.size() < queries) {
      const std::size_t have = query_pool.size();
      query_pool.resize(queries);
      glCreateQueries(GL_SAMPLES_PASSED, static_cast<GLsizei>(queries - have),
                      query_pool.data() + have);
    }
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_FALSE);
    glColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glUseProgram(coverage_program);
    bound_program = coverage_program;
    glProgramUniformMatrix4fv(coverage_program, coverage_loc.view_proj, 1, GL_FALSE, f.view_proj);
    const Eigen::Vector3f cam = f.camera.cast<float>();
    glProgramUniform3fv(coverage_program, coverage_loc.camera, 1, cam.data());
    std::size_t q = 0;
    for (std::size_t a = 0; a < n; ++a) {
      if (!box_query[a]) continue;
      const auto rec =
          static_cast<std::size_t>(instance_record[static_cast<std::size_t>(f.touched[a].first)]);
      const auto m = static_cast<std::size_t>(f.model[rec]);
      glBeginQuery(GL_SAMPLES_PASSED, query_pool[q++]);
      glDrawElementsInstancedBaseVertexBaseInstance(
          GL_TRIANGLES, static_cast<GLsizei>(scene.drawnIndexCount(f.model[rec])), GL_UNSIGNED_INT,
          reinterpret_cast<const void*>(model_first_element[m] * sizeof(std::uint32_t)), 1,
          model_base_vertex[m], static_cast<GLuint>(f.slot[rec]));
      glEndQuery(GL_SAMPLES_PASSED);
      ++f.stats.draw_calls;
    }
    q = 0;
    for (std::size_t a = 0; a < n; ++a) {
      if (!box_query[a]) continue;
      GLuint samples = 0;
      glGetQueryObjectuiv(query_pool[q++], GL_QUERY_RESULT, &samples);
      box_total[a] = static_cast<int>(samples);
    }
    glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  }
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
        const auto rec =
            static_cast<std::size_t>(instance_record[static_cast<std::size_t>(f.touched[a].first)]);
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
    b.cls = si.cls;
    b.role = si.scenario_entity >= 0 ? scene.scenarioEntity(si.scenario_entity).role : "world";
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

}  // namespace hameritt::render
