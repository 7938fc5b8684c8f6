// Bad input fails with a RenderError that names the file or the field: missing or malformed
// model files, bad requests, unknown entities, label overflow; and the context moves between
// threads.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "render_test_util.h"

namespace hameritt::render {
namespace {

namespace fs = std::filesystem;
using testing::defaultSimConfig;
using testing::defaultWorld;

template <typename F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const RenderError& e) {
    return e.what();
  }
  return "no RenderError";
}

// A copy of the shipped models in a fresh temporary directory.
class ModelsCopy {
 public:
  ModelsCopy() {
    dir_ = fs::temp_directory_path() / ("hameritt_models_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "meshes");
    for (const auto& e : fs::directory_iterator(defaultModelsDir() + "/meshes")) {
      fs::copy_file(e.path(), dir_ / "meshes" / e.path().filename());
    }
  }
  ~ModelsCopy() { fs::remove_all(dir_); }
  std::string dir() const { return dir_.string(); }
  std::string mesh(const std::string& name) const { return (dir_ / "meshes" / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(mesh(name)) << text;
  }

 private:
  fs::path dir_;
};

RendererOptions in(const std::string& dir) {
  RendererOptions o;
  o.models_dir = dir;
  return o;
}

TEST(RenderErrors, MissingModelsDirectoryNamesTheFile) {
  const std::string e =
      errorOf([] { Renderer r(defaultWorld(), defaultSimConfig(), in("/nonexistent/models")); });
  EXPECT_NE(e.find("/nonexistent/models/meshes/house_1.obj"), std::string::npos) << e;
  EXPECT_NE(e.find("missing"), std::string::npos) << e;
}

TEST(RenderErrors, MalformedOrMisfitModelsNameTheFile) {
  ModelsCopy m;
  m.write("car_suv.obj", "this is not a wavefront file\n\x01\x02\x03");
  std::string e = errorOf([&] { Renderer r(defaultWorld(), defaultSimConfig(), in(m.dir())); });
  EXPECT_NE(e.find(m.mesh("car_suv.obj")), std::string::npos) << e;
  // Faces that index vertices that do not exist.
  m.write("car_suv.obj",
          "mtllib car_suv.mtl\nv 0 0 0\nv 1 0 0\nvn 0 0 1\nusemtl paint\nf 1//1 2//1 9//1\n");
  e = errorOf([&] { Renderer r(defaultWorld(), defaultSimConfig(), in(m.dir())); });
  EXPECT_NE(e.find(m.mesh("car_suv.obj")), std::string::npos) << e;
  // A material that the .mtl does not define.
  m.write("car_suv.obj", "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0 0.5 1\nvn 0 0 1\nf 1//1 2//1 3//1\n");
  e = errorOf([&] { Renderer r(defaultWorld(), defaultSimConfig(), in(m.dir())); });
  EXPECT_NE(e.find(m.mesh("car_suv.obj")), std::string::npos) << e;
  EXPECT_NE(e.find("material"), std::string::npos) << e;
  // A class mesh outside the unit box.
  m.write("car_suv.obj",
          "mtllib car_suv.mtl\nv -0.5 -0.5 0\nv 3.5 -0.5 0\nv 0 0.5 1\nvn 0 0 1\n"
          "usemtl paint\nf 1//1 2//1 3//1\n");
  e = errorOf([&] { Renderer r(defaultWorld(), defaultSimConfig(), in(m.dir())); });
  EXPECT_NE(e.find(m.mesh("car_suv.obj") + ": model does not fit the unit box"), std::string::npos)
      << e;
  // An empty file.
  m.write("pedestrian.obj", "");
  fs::copy_file(defaultModelsDir() + "/meshes/car_suv.obj", m.mesh("car_suv.obj"),
                fs::copy_options::overwrite_existing);
  e = errorOf([&] { Renderer r(defaultWorld(), defaultSimConfig(), in(m.dir())); });
  EXPECT_NE(e.find(m.mesh("pedestrian.obj")), std::string::npos) << e;
}

TEST(RenderErrors, BadLevelOfDetailIndexNamesTheFileAndField) {
  ModelsCopy m;
  const std::string lod = m.mesh("lod.json");
  auto error = [&] {
    return errorOf([&] { Renderer r(defaultWorld(), defaultSimConfig(), in(m.dir())); });
  };
  // One house entry with the given design size and levels.
  auto index = [&](const std::string& size, const std::string& levels) {
    m.write("lod.json", R"({"schema": "hameritt_mesh_lod", "schema_version": 2, "meshes": [)"
                        R"({"mesh": "house_1", "design_size_m": )" + size +
                            R"(, "levels": )" + levels + "}]}");
  };
  const std::string level1 = R"({"file": "house_1_lod1.obj", "max_deviation_m": 0.1})";
  m.write("lod.json", "{ not json");
  std::string e = error();
  EXPECT_NE(e.find(lod + ": not valid JSON"), std::string::npos) << e;
  m.write("lod.json", R"({"schema": "hameritt_mesh_lod", "schema_version": 1, "meshes": []})");
  e = error();
  EXPECT_NE(e.find(lod + ": schema_version: expected 2"), std::string::npos) << e;
  index("[10, 11, 5.6]", R"([{"file": "house_1_lod1.obj", "max_deviation_m": -0.1}])");
  e = error();
  EXPECT_NE(e.find(lod + ": meshes[0].levels[0].max_deviation_m: expected a finite number >= 0"),
            std::string::npos)
      << e;
  index("[10, 11, 5.6]", "[" + level1 + R"(, {"file": "house_1_lod1.obj", "max_deviation_m": 0.05}])");
  e = error();
  EXPECT_NE(e.find(lod + ": meshes[0].levels[1].max_deviation_m: expected more than the previous"),
            std::string::npos)
      << e;
  index("[10, 11, 5.6]", "[]");
  e = error();
  EXPECT_NE(e.find(lod + ": meshes[0].levels: expected an array of 1 to"), std::string::npos) << e;
  m.write("lod.json", R"({"schema": "hameritt_mesh_lod", "schema_version": 2, "meshes": [)"
                      R"({"mesh": "castle", "design_size_m": [1, 1, 1], "levels": [)" +
                          level1 + "]}]}");
  e = error();
  EXPECT_NE(e.find(lod + ": meshes[0].mesh: expected a class mesh name"), std::string::npos) << e;
  EXPECT_NE(e.find("'castle'"), std::string::npos) << e;
  index("[10, 0, 5]", "[" + level1 + "]");
  e = error();
  EXPECT_NE(e.find(lod + ": meshes[0].design_size_m: expected three numbers > 0"),
            std::string::npos)
      << e;
  // The coarse mesh a level names is missing.
  fs::remove(m.mesh("house_1_lod1.obj"));
  index("[10, 11, 5.6]", "[" + level1 + "]");
  e = error();
  EXPECT_NE(e.find(m.mesh("house_1_lod1.obj")), std::string::npos) << e;
  // Without lod.json every instance is drawn in full.
  fs::remove(lod);
  e = error();
  EXPECT_EQ(e, "no RenderError");
  RendererOptions bad = in(m.dir());
  bad.lod_max_error_px = -1;
  e = errorOf([&] { Renderer r(defaultWorld(), defaultSimConfig(), bad); });
  EXPECT_NE(e.find("RendererOptions.lod_max_error_px"), std::string::npos) << e;
}

TEST(RenderErrors, BadEntityAttributesAndTooManyInstances) {
  scenario::SimConfig c = defaultSimConfig();
  c.entities[0].entity.attributes.set("color", std::string("mauve"));
  std::string e = errorOf([&] { Renderer r(defaultWorld(), c); });
  EXPECT_NE(e.find("entity car_706: attribute color"), std::string::npos) << e;
  EXPECT_NE(e.find("'mauve'"), std::string::npos) << e;

  scenario::SimConfig many = defaultSimConfig();
  const scenario::ScenarioEntity walker = many.entities.back();
  many.entities.assign(61100, walker);
  e = errorOf([&] { Renderer r(defaultWorld(), many); });
  EXPECT_NE(e.find("16-bit instance labels"), std::string::npos) << e;
}

TEST(RenderErrors, BadRequestsNameTheField) {
  Renderer& r = testing::defaultRenderer();
  RenderRequest ok;
  ok.intrinsics = intrinsicsFromHfov(64, 48, 60);
  auto fails = [&](const std::function<void(RenderRequest*)>& edit) {
    RenderRequest q = ok;
    edit(&q);
    return errorOf([&] { r.render(q); });
  };
  EXPECT_NE(
      fails([](RenderRequest* q) { q->intrinsics.width = 0; }).find("RenderRequest.intrinsics"),
      std::string::npos);
  EXPECT_NE(fails([](RenderRequest* q) { q->intrinsics.fx = 0; }).find("intrinsics.fx"),
            std::string::npos);
  EXPECT_NE(fails([](RenderRequest* q) { q->intrinsics.fy = NAN; }).find("intrinsics.fy"),
            std::string::npos);
  EXPECT_NE(fails([](RenderRequest* q) { q->near_clip = 0; }).find("near_clip"), std::string::npos);
  EXPECT_NE(fails([](RenderRequest* q) { q->far_clip = 0.05; }).find("far_clip"),
            std::string::npos);
  EXPECT_NE(fails([](RenderRequest* q) { q->time = INFINITY; }).find("RenderRequest.time"),
            std::string::npos);
  EXPECT_NE(fails([](RenderRequest* q) {
              q->world_T_optical.translation().x() = NAN;
            }).find("world_T_optical"),
            std::string::npos);
  EXPECT_NE(fails([](RenderRequest* q) {
              q->hidden_entities = {"car_706", "boat_1"};
            }).find("hidden_entities: unknown entity 'boat_1'"),
            std::string::npos);
  EXPECT_NE(
      fails([](RenderRequest* q) { q->intrinsics.width = 1 << 20; }).find("exceeds the GL limit"),
      std::string::npos);
  EXPECT_NO_THROW(r.render(ok));
}

TEST(RenderErrors, BackendIsValidated) {
  RendererOptions o;
  o.backend = "vulkan";
  EXPECT_NE(errorOf([&] {
              Renderer r(defaultWorld(), defaultSimConfig(), o);
            }).find("backend: expected auto, surfaceless or device"),
            std::string::npos);
  ::setenv("HAMERITT_EGL_BACKEND", "bogus", 1);
  const std::string e = errorOf([&] { Renderer r(defaultWorld(), defaultSimConfig()); });
  ::unsetenv("HAMERITT_EGL_BACKEND");
  EXPECT_NE(e.find("from HAMERITT_EGL_BACKEND"), std::string::npos) << e;
  // The device platform works on a machine with a GPU and is refused clearly without one.
  o.backend = "device";
  try {
    Renderer r(defaultWorld(), defaultSimConfig(), o);
    EXPECT_EQ(r.eglBackend(), "device");
  } catch (const RenderError& err) {
    EXPECT_NE(std::string(err.what()).find("device"), std::string::npos) << err.what();
  }
  o.backend = "surfaceless";
  Renderer s(defaultWorld(), defaultSimConfig(), o);
  EXPECT_EQ(s.eglBackend(), "surfaceless");
  EXPECT_FALSE(s.glRenderer().empty());
}

TEST(RenderErrors, ContextMovesBetweenThreads) {
  Renderer r(defaultWorld(), defaultSimConfig());
  RenderRequest q;
  q.intrinsics = intrinsicsFromHfov(64, 48, 60);
  const FrameSet here = r.render(q);
  // Held here, the other thread is told to release it first.
  std::string held;
  std::thread([&] { held = errorOf([&] { r.render(q); }); }).join();
  EXPECT_NE(held.find("releaseCurrent"), std::string::npos) << held;
  r.releaseCurrent();
  FrameSet there;
  std::thread([&] {
    r.makeCurrent();
    r.render(q, &there);
    r.releaseCurrent();
  }).join();
  EXPECT_EQ(here.rgb, there.rgb);
  EXPECT_EQ(r.render(q).rgb, here.rgb) << "render() takes the context back on this thread";
}

}  // namespace
}  // namespace hameritt::render
