// Per-request checks, projection, frustum culling and the upload of the visible instances.
#include "renderer_internal.h"

namespace hameritt::render {

void Renderer::Impl::validate(const RenderRequest& r) {
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

void Renderer::Impl::projection(const RenderRequest& r, float view_proj[16],
                                Eigen::Matrix4d* full) {
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

void Renderer::Impl::frustumPlanes(const Eigen::Matrix4d& m) {
  const Eigen::RowVector4d r0 = m.row(0), r1 = m.row(1), r2 = m.row(2), r3 = m.row(3);
  const Eigen::RowVector4d raw[6] = {r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 - r2, r2};
  for (int i = 0; i < 6; ++i) {
    const double len = raw[i].head<3>().norm();
    planes[static_cast<std::size_t>(i)] = {raw[i].head<3>().transpose() / len, raw[i](3) / len};
  }
}

int Renderer::Impl::classifyBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) const {
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

bool Renderer::Impl::sphereVisible(const Eigen::Vector3f& c, float radius, bool test_planes) const {
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

void Renderer::Impl::setHidden(const std::vector<std::string>& ids) {
  for (std::uint32_t i : hidden_list) hidden[i] = 0;
  hidden_list.clear();
  for (const std::string& id : ids) {
    auto [b, e] = by_id.equal_range(id);
    for (auto it = b; it != e; ++it) {
      const auto rec =
          static_cast<std::uint32_t>(instance_record[static_cast<std::size_t>(it->second)]);
      hidden[rec] = 1;
      hidden_list.push_back(rec);
      for (const int part : part_records[static_cast<std::size_t>(it->second)]) {
        hidden[static_cast<std::size_t>(part)] = 1;
        hidden_list.push_back(static_cast<std::uint32_t>(part));
      }
    }
  }
}

void Renderer::Impl::cullAndUpload(const RenderRequest& r, Frame& f) {
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
  // Traffic-light masts: their lamps at the frame time.
  for (const auto& [rec, k] : signal_masts) {
    const auto& plan = *config.signals;
    const auto& is = plan.intersections[static_cast<std::size_t>(k)];
    records[rec].color =
        signalLamps(plan.state(is, 0, r.time), plan.state(is, 1, r.time), is.heading[0]);
  }
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

}  // namespace hameritt::render
