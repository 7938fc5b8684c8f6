// Renderer's public methods and the phased rendering of a batch of requests.
#include "hameritt/render/renderer.h"

#include "renderer_internal.h"

namespace hameritt::render {

void Renderer::Impl::render(const std::vector<const RenderRequest*>& requests,
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

bool hasBoundingBox(scenario::EntityClass c) {
  using scenario::EntityClass;
  switch (c) {
    case EntityClass::kCar:
    case EntityClass::kPedestrian:
    case EntityClass::kBuilding:
    case EntityClass::kParkingGarage:
    case EntityClass::kParkingLot:
    case EntityClass::kAlley:
    case EntityClass::kLampPost:
    case EntityClass::kTrafficLight:
    case EntityClass::kBusStop:
    case EntityClass::kBench:
    case EntityClass::kStreetTree:
    case EntityClass::kAircraft:
      return true;
    default:
      return false;
  }
}

std::string defaultModelsDir() { return scenario::shareDir() + "/models"; }

}  // namespace hameritt::render
