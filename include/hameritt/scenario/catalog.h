#pragma once
// Vocabularies of the neighborhood: car models with their dimensions, colours, materials,
// tree species and street names.

#include <string>
#include <vector>

#include "hameritt/scenario/rng.h"

namespace hameritt::scenario::catalog {

// A car model and its bounding-box dimensions in metres.
struct CarModel {
  std::string vehicle_class;  // sedan, suv, pickup, hatchback, van
  std::string make;
  std::string model;
  double length;
  double width;
  double height;
};

const std::vector<CarModel>& carModels();
// The model with this make and model name, or nullptr.
const CarModel* findCarModel(const std::string& make, const std::string& model);
const std::vector<std::string>& carColors();
const std::vector<std::string>& houseColors();
const std::vector<std::string>& garageColors();
const std::vector<std::string>& fenceColors();
const std::vector<std::string>& fenceMaterials();
const std::vector<std::string>& treeSpecies();
const std::vector<std::string>& clothingColors();
// Name of the i-th north-south (ns = true) or east-west street.
std::string streetName(bool ns, int i);

template <typename T>
const T& pick(Rng& rng, const std::vector<T>& v) {
  return rng.pick(v);
}
inline const CarModel& pickModel(Rng& rng) { return rng.pick(carModels()); }

}  // namespace hameritt::scenario::catalog
