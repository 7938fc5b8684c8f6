// Renderer throughput on the shipped default scenario: both payload cameras (front and down,
// 640 x 480) rendered at UAV poses along the scenario's perception path, everything read back
// (RGB, depth, labels split into semantic and instance, boxes with occlusion). Prints frame
// sets per second (one frame set = every payload camera once) rendered as one batch
// (Renderer::render(vector)) and as one render() call per camera, the CPU time per frame set,
// then the time per stage from a run that waits for the GL at the end of each stage, the GL
// renderer, and the triangles and instances drawn per frame.
//
// Usage: bench_render [frame_sets] [--backend auto|surfaceless|device] [--sim-config FILE]
// (--sim-config: another scenario, e.g. one generated with hameritt_generate --world city)

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hameritt/render/renderer.h"
#include "hameritt/scenario/share_dir.h"
#include "hameritt/scenario/sim_config_io.h"

namespace render = hameritt::render;
namespace scenario = hameritt::scenario;

namespace {

using Clock = std::chrono::steady_clock;

// CPU time of the process (all threads), seconds.
double cpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Stages {
  double cull = 0, draw = 0, post = 0, readback = 0, boxes = 0;
  double triangles = 0, instances = 0, lod_instances = 0, boxes_count = 0, box_groups = 0;
};

// The requests of frame set i of n: the UAV on the perception path, from the end of the climb to
// the end of the path.
std::vector<render::RenderRequest> frameSet(const scenario::SimConfig& cfg, int i, int n) {
  const auto& path = cfg.uav.perception_path->trajectory;
  const double t0 = std::min(path.back().t, 20.0), t1 = path.back().t;
  const double t = t0 + (t1 - t0) * (n > 1 ? static_cast<double>(i % n) / (n - 1) : 0.0);
  const auto p = scenario::sampleTrajectory(path, t);
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = Eigen::Vector3d(p.x, p.y, p.z);
  base.linear() = Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<render::RenderRequest> out;
  for (std::size_t c = 0; c < cfg.uav.cameras.size(); ++c) {
    const auto& cam = cfg.uav.cameras[c];
    render::RenderRequest r;
    r.intrinsics = render::intrinsicsFromHfov(cam.width, cam.height, cam.hfov_deg);
    r.world_T_optical = render::opticalPose(base, cam.mount_xyz, cam.mount_rpy * (M_PI / 180.0));
    r.time = t;
    r.camera_index = static_cast<int>(c);
    r.frame_index = static_cast<std::uint64_t>(i);
    out.push_back(r);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 100;
  std::string backend = "auto";
  double lod_px = render::RendererOptions().lod_max_error_px;
  std::string file = scenario::shareDir() + "/scenarios/default/sim_config.json";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--backend" && i + 1 < argc) {
      backend = argv[++i];
    } else if (a == "--sim-config" && i + 1 < argc) {
      file = argv[++i];
    } else if (a == "--lod" && i + 1 < argc) {
      lod_px = std::atof(argv[++i]);
    } else if (!a.empty() && a[0] != '-') {
      frames = std::max(1, std::atoi(a.c_str()));
    } else {
      std::fprintf(stderr,
                   "usage: bench_render [frame_sets] [--backend auto|surfaceless|device] "
                   "[--lod MAX_ERROR_PX (0: full detail)] [--sim-config FILE]\n");
      return 2;
    }
  }
  const scenario::SimConfig cfg = scenario::loadSimConfig(file);
  const scenario::World world = scenario::generateCheckedWorld(cfg, file);
  if (!cfg.uav.perception_path || cfg.uav.perception_path->trajectory.empty()) {
    std::fprintf(stderr, "bench_render: %s has no perception path\n", file.c_str());
    return 1;
  }
  std::printf("scenario %s: %zu world entities, %zu scenario entities, %zu cameras\n",
              cfg.scenario_id.c_str(), world.entities().size(), cfg.entities.size(),
              cfg.uav.cameras.size());
  for (const auto& c : cfg.uav.cameras) {
    std::printf("  camera %s: %d x %d, hfov %.3f deg, pitch %.2f deg\n", c.name.c_str(), c.width,
                c.height, c.hfov_deg, c.mount_rpy.y());
  }
  std::printf(
      "environment: time %.2f h, rain %.2f, snow %.2f, fog %.2f, dust %.2f, foliage %.2f; "
      "noise std %.4f, salt %.5f, blur %.2f px\n",
      cfg.environment.time_of_day, cfg.environment.rain, cfg.environment.snow, cfg.environment.fog,
      cfg.environment.dust, cfg.environment.foliage, cfg.perturbations.gaussian_noise_std,
      cfg.perturbations.salt_pepper_probability, cfg.perturbations.motion_blur_px);

  std::vector<render::FrameSet> out(cfg.uav.cameras.size());
  const int warmup = 5;
  const char* kModes[] = {"batched: render(vector) per frame set", "one render() per camera",
                          "stage timing"};
  for (int mode = 0; mode < 3; ++mode) {
    render::RendererOptions opt;
    opt.backend = backend;
    opt.stage_timing = mode == 2;
    opt.lod_max_error_px = lod_px;
    const auto c0 = Clock::now();
    render::Renderer r(world, cfg, opt);
    const double setup_ms = std::chrono::duration<double, std::milli>(Clock::now() - c0).count();
    if (mode == 0) {
      std::printf("GL_RENDERER: %s (EGL %s), renderer set-up %.0f ms\n", r.glRenderer().c_str(),
                  r.eglBackend().c_str(), setup_ms);
      std::printf("level of detail: coarse meshes where their deviation is <= %.2f px%s\n", lod_px,
                  lod_px > 0 ? "" : " (off: full detail)");
    }
    auto run = [&](const std::vector<render::RenderRequest>& reqs, std::vector<Stages>* st) {
      if (mode == 0) {
        r.render(reqs, &out);
        return;
      }
      for (std::size_t c = 0; c < reqs.size(); ++c) {
        r.render(reqs[c], &out[c]);
        if (st == nullptr) continue;
        const auto& s = r.lastStats();
        Stages& x = (*st)[c];
        x.cull += s.cull_upload_ms;
        x.draw += s.draw_ms;
        x.post += s.post_ms;
        x.readback += s.readback_ms;
        x.boxes += s.boxes_ms;
        x.triangles += static_cast<double>(s.triangles);
        x.instances += static_cast<double>(s.instances);
        x.lod_instances += static_cast<double>(s.lod_instances);
        x.box_groups += static_cast<double>(s.box_groups);
        x.boxes_count += static_cast<double>(out[c].boxes.size());
      }
    };
    for (int i = 0; i < warmup; ++i) run(frameSet(cfg, i * 7, frames), nullptr);
    std::vector<Stages> per_camera(cfg.uav.cameras.size());
    const double cpu0 = cpuSeconds();
    const auto t0 = Clock::now();
    for (int i = 0; i < frames; ++i) run(frameSet(cfg, i, frames), &per_camera);
    const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
    const double cpu = cpuSeconds() - cpu0;
    std::printf(
        "\n%s: %d frame sets in %.2f s: %.1f frame sets/s (%.1f ms wall, %.1f ms CPU "
        "per frame set)\n",
        kModes[mode], frames, wall, frames / wall, 1e3 * wall / frames, 1e3 * cpu / frames);
    if (mode == 2) {
      std::printf("  per frame (ms):  %12s %8s %8s %10s %8s %8s | %9s %9s %7s %6s %6s\n", "cull/upload",
                  "draw", "post", "readback", "boxes", "total", "triangles", "instances", "coarse",
                  "boxes", "groups");
      for (std::size_t c = 0; c < per_camera.size(); ++c) {
        const Stages& st = per_camera[c];
        const double total = st.cull + st.draw + st.post + st.readback + st.boxes;
        std::printf("  %-16s %12.2f %8.2f %8.2f %10.2f %8.2f %8.2f | %9.0f %9.0f %7.0f %6.1f %6.1f\n",
                    cfg.uav.cameras[c].name.c_str(), st.cull / frames, st.draw / frames,
                    st.post / frames, st.readback / frames, st.boxes / frames, total / frames,
                    st.triangles / frames, st.instances / frames, st.lod_instances / frames,
                    st.boxes_count / frames, st.box_groups / frames);
      }
    }
  }
  return 0;
}
