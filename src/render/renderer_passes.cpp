// The draw passes of a frame: uniforms, the geometry pass, the sky test, weather particles.
#include "renderer_internal.h"

namespace hameritt::render {

void Renderer::Impl::setFrameUniforms(const Frame& f) {
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
                         static_cast<float>(r.intrinsics.cx), static_cast<float>(r.intrinsics.cy)};
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

const GeometryProgram& Renderer::Impl::programFor(int m) const {
  const auto& p = scene.procedural();
  if (m == p.building || m == p.signal) return geometry[2];
  const bool ground = m == p.ground || m == p.sidewalks || m == p.street;
  return geometry[ground ? 1 : 0];
}

void Renderer::Impl::drawModel(int m, GLuint base, GLsizei count, RenderStats* stats) {
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

void Renderer::Impl::geometryPass(Frame& f, std::size_t triangles) {
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

bool Renderer::Impl::groundFillsView(const RenderRequest& r) const {
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

void Renderer::Impl::frameKey(const RenderRequest& r, GLuint key[4]) const {
  const std::uint64_t k1 =
      splitmix64(config.seed ^
                 splitmix64(static_cast<std::uint64_t>(static_cast<std::int64_t>(r.camera_index)) ^
                            splitmix64(r.frame_index)));
  const std::uint64_t k2 = splitmix64(k1);
  key[0] = static_cast<GLuint>(k1);
  key[1] = static_cast<GLuint>(k1 >> 32);
  key[2] = static_cast<GLuint>(k2);
  key[3] = static_cast<GLuint>(k2 >> 32);
}

void Renderer::Impl::particlePass(const Frame& f) {
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
                         static_cast<float>(r.intrinsics.cx), static_cast<float>(r.intrinsics.cy)};
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

}  // namespace hameritt::render
