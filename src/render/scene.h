#pragma once
// What the renderer draws, on the CPU: the class meshes, and one instance per drawn object with
// its model matrix, colour and label. The world's instances never change; the scenario's movers
// are posed per frame from their trajectories.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "hameritt/render/renderer.h"
#include "lod_manifest.h"
#include "mesh.h"

namespace hameritt::render {

// Per-instance data (the renderer turns it into the vertex shader's instance attributes).
struct InstanceRecord {
  float row[3][4];          // rows of the 3x4 model matrix (mesh -> world)
  std::uint32_t color = 0;  // kPaint: display colour (RGB8, gamma 2); kFoliage: linear tint / 2
  std::uint32_t label = 0;  // semantic << 16 | instance
  float canopy = 1.0f;      // canopy scale about the mesh's canopy centre; buildings: storey (m)
};


// One drawn object.
struct SceneInstance {
  int model = 0;        // index into Scene::models()
  int instance_id = 0;  // label instance (0 for ground layers and for parts, below)
  // A part of another instance (a building's rooftop equipment): that instance's label id. Its
  // pixels carry that instance's label, so its box, mask and visible pixels include the part,
  // and hiding the entity hides the part; 0 for an instance of its own.
  int part_of = 0;
  int semantic = 0;
  int scenario_entity = -1;   // index into SimConfig::entities when it comes from the scenario
  bool mover = false;         // posed from its trajectory at the frame time
  bool interest = false;      // car, pedestrian or a city class: gets a bounding box
  // A closed convex mesh (the city classes' procedural boxes, an alley's quad): drawn alone
  // without a depth test it covers each of its pixels once, so an occlusion query counts its
  // unoccluded pixels.
  bool convex = false;
  scenario::EntityClass cls = scenario::EntityClass::kCar;
  geometry::OrientedBox box;  // pose and size (scale of a normalized mesh)
  InstanceRecord record;      // at t = 0 for movers
  Eigen::Vector3f center{0, 0, 0};  // bounding sphere
  float radius = 0;
  // Levels of detail of `model` (Scene::lodModel): how many, and the metres by which each may
  // depart from the full mesh at this instance's size (the level's stated deviation scaled by
  // the box), increasing with the level.
  int lod_levels = 0;
  std::array<float, kMaxLodLevels> lod_deviation{};
};

// The level-of-detail rule of one view: an instance is drawn with the coarsest level of its
// model whose deviation at the instance's size, projected anywhere on its bounding sphere that
// the image shows, is at most max_error_px pixels. The bound is first order and
// conservative: a displacement d at optical depth Z on a ray at angle t from the optical axis
// moves the point's image by at most f |d| / (Z cos t) pixels (the norm of the projection's
// Jacobian); Z is taken at the sphere's nearest depth and t at the sphere's widest ray, capped
// by the image's widest ray.
struct LodView {
  Eigen::Vector3d eye{0, 0, 0};
  Eigen::Vector3d axis{0, 0, 1};  // optical z in the world
  double focal = 0;               // max(fx, fy)
  double max_angle = 0;           // the image's widest ray from the optical axis (radians)
  double max_error_px = 0;        // 0: never coarse
  LodView() = default;
  LodView(const RenderRequest& r, double max_error_px);
  // The coarsest level of detail allowed for the instance (0: its full mesh).
  int level(const SceneInstance& si, const Eigen::Vector3f& center, float radius) const;
};

// Rooftop equipment of a city building, solid boxes standing on its roof (the scene draws them as
// parts of the building: its label): an air-handling unit (2.4 x 1.6 x 1.3 m) on every roof of
// at least 8 x 6.4 m, a water tank (2.6 x 2.6 x 3.2 m) on about half the buildings of 6 storeys
// or more, a stair bulkhead (3.6 x 2.6 x 3 m) on every roof of a building 60 m or taller (at
// least 14 x 10 m). Each stands in its own quarter of the roof, at least 0.5 m clear of the
// roof's centre lines and 0.8 m inside the parapet, placed by a hash of the building's id (the
// same in every scene; no seed stream is drawn from). The generator's occluders and the
// planner's obstacles do not include them (docs/explanation/city.md).
struct RooftopPart {
  enum class Kind { kUnit, kTank, kBulkhead } kind;
  geometry::OrientedBox box;
};
std::vector<RooftopPart> rooftopEquipment(const scenario::Entity& building);

// Model indices of the procedural parts.
struct SceneModels {
  int ground = -1, sidewalks = -1, street = -1, driveway = -1, uav = -1;
  int building = -1;  // city buildings (facade program); -1 in a scene without buildings
  int signal = -1;    // traffic-light masts (facade program, lamps); -1 without any
};

class Scene {
 public:
  // Loads every class mesh from models_dir/meshes (RenderError naming a missing or malformed
  // file) and builds the instances. Throws RenderError for unknown colour names and for more
  // instances than a 16-bit label holds. `config` must outlive the scene (movers are posed
  // from it).
  Scene(const scenario::World& world, const scenario::SimConfig& config,
        const std::string& models_dir);

  const std::vector<Mesh>& models() const { return models_; }
  const SceneModels& procedural() const { return procedural_; }
  // World instances (static) first, then the scenario's (movers among them).
  const std::vector<SceneInstance>& instances() const { return instances_; }
  // Instance id -> entity id ("" for 0 and the UAV is "uav").
  const std::vector<std::string>& entityIds() const { return entity_ids_; }
  int uavInstanceId() const { return uav_instance_; }
  // The scenario entity an instance stands for (SceneInstance::scenario_entity): the
  // configuration's entities, then its aircraft (scenario::aircraftEntities).
  const scenario::ScenarioEntity& scenarioEntity(int j) const;
  double foliage() const { return foliage_; }
  // Record and bounding sphere of instance i at `time` (movers follow their trajectories).
  void pose(std::size_t i, double time, InstanceRecord* record, Eigen::Vector3f* center,
            float* radius) const;
  // The UAV's record at world_T_uav.
  InstanceRecord uavRecord(const Eigen::Isometry3d& world_T_uav) const;
  // World-space triangles of every instance at `time` (what the geometry pass rasterizes), each
  // with its full mesh, or with the mesh `lod` picks for it.
  SceneTriangles triangles(double time, const LodView* lod = nullptr) const;
  // Level `level` (1, 2, ...) of model m (models_dir/meshes/lod.json); m itself for level 0.
  int lodModel(int m, int level) const {
    if (level == 0) return m;
    return lods_[static_cast<std::size_t>(m)][static_cast<std::size_t>(level - 1)].model;
  }
  // The model instance i is drawn with under `lod`.
  int modelFor(std::size_t i, const Eigen::Vector3f& center, float radius, const LodView& lod) const {
    const SceneInstance& si = instances_[i];
    return lodModel(si.model, lod.level(si, center, radius));
  }
  // Indices of model m that are drawn: all, or without the canopy at foliage density 0.
  std::uint32_t drawnIndexCount(int m) const {
    const Mesh& mesh = models_[static_cast<std::size_t>(m)];
    return foliage_ > 0 ? static_cast<std::uint32_t>(mesh.indices.size()) : mesh.foliage_first;
  }

 private:
  int addModel(Mesh mesh);
  // Reads dir/lod.json (when present) and loads the coarse meshes it names.
  void loadLods(const std::string& dir, const std::unordered_map<std::string, int>& file_model);

  const scenario::SimConfig& config_;
  std::vector<scenario::ScenarioEntity> aircraft_;
  std::vector<Mesh> models_;
  // Per model: its coarser levels, from fine to coarse.
  struct LodLevel {
    int model = 0;               // index into models_
    Eigen::Vector3f axis_error;  // stated deviation / design size, per axis
  };
  std::vector<std::vector<LodLevel>> lods_;
  SceneModels procedural_;
  std::vector<SceneInstance> instances_;
  std::vector<std::string> entity_ids_;
  int uav_instance_ = 0;
  double foliage_ = 1.0;
};

// The display colour (RGB8, gamma 2, packed R | G << 8 | B << 16 | 255 << 24) of a named paint:
// red, blue, white, black, silver, grey, green, yellow, beige, brick, brown, orange, and the
// driveway materials concrete and asphalt; false for an unknown name.
bool paintColor(const std::string& name, std::uint32_t* srgb8);

// InstanceRecord::color of a traffic-light mast: bits 0-1 the lamp lit towards axis 0's
// traffic, 2-3 towards axis 1's (0 red, 1 yellow, 2 green, 3 none), bit 4 (5) set while axis 0
// (1) shows its protected left arrow (a green arrow in the green lamp's place, beside the red
// lamp; the other axis' faces show a right arrow then, as its right turns go), 8-15 axis 0's
// heading in 256ths of a turn.
constexpr std::uint32_t kSignalDark = 3u | (3u << 2);
std::uint32_t signalLamps(scenario::SignalState axis0, scenario::SignalState axis1,
                          double heading0);

// Model matrix rows of a normalized mesh placed at an entity box (bottom centre, yaw, size).
void boxRecordRows(const geometry::OrientedBox& box, double lift, float rows[3][4]);

}  // namespace hameritt::render
