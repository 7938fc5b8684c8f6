#include "hameritt/scenario/catalog.h"

namespace hameritt::scenario::catalog {

const std::vector<CarModel>& carModels() {
  static const std::vector<CarModel> k = {
      {"sedan", "Toyota", "Camry", 4.885, 1.84, 1.445},
      {"sedan", "Honda", "Accord", 4.97, 1.862, 1.45},
      {"sedan", "Chevrolet", "Impala", 5.113, 1.854, 1.496},
      {"suv", "Ford", "Explorer", 5.05, 2.004, 1.778},
      {"suv", "Toyota", "RAV4", 4.6, 1.855, 1.685},
      {"pickup", "Ford", "F-150", 5.885, 2.029, 1.961},
      {"pickup", "Chevrolet", "Silverado", 5.885, 2.063, 1.917},
      {"hatchback", "Volkswagen", "Golf", 4.284, 1.789, 1.456},
      {"hatchback", "Honda", "Fit", 4.064, 1.694, 1.524},
      {"van", "Honda", "Odyssey", 5.159, 1.994, 1.763},
  };
  return k;
}

const CarModel* findCarModel(const std::string& make, const std::string& model) {
  for (const auto& m : carModels()) {
    if (m.make == make && m.model == model) return &m;
  }
  return nullptr;
}

const std::vector<std::string>& carColors() {
  static const std::vector<std::string> k = {"red",    "blue",  "white", "black",
                                             "silver", "grey",  "green", "yellow"};
  return k;
}
const std::vector<std::string>& houseColors() {
  static const std::vector<std::string> k = {"white", "beige", "grey", "blue", "yellow", "brick"};
  return k;
}
const std::vector<std::string>& garageColors() {
  static const std::vector<std::string> k = {"white", "beige", "grey", "brown", "red"};
  return k;
}
const std::vector<std::string>& fenceColors() {
  static const std::vector<std::string> k = {"white", "brown", "grey"};
  return k;
}
const std::vector<std::string>& fenceMaterials() {
  static const std::vector<std::string> k = {"wood", "vinyl", "chain_link"};
  return k;
}
const std::vector<std::string>& treeSpecies() {
  static const std::vector<std::string> k = {"oak", "maple", "pine", "birch"};
  return k;
}
const std::vector<std::string>& clothingColors() {
  static const std::vector<std::string> k = {"red", "blue", "black", "white", "green", "orange"};
  return k;
}

std::string streetName(bool ns, int i) {
  static const char* kNs[] = {"Elm Street",    "Oak Street",    "Maple Avenue", "Cedar Street",
                              "Pine Street",   "Walnut Street", "Birch Lane",   "Spruce Street",
                              "Chestnut Road", "Willow Way",    "Ash Street",   "Hickory Lane"};
  static const char* kEw[] = {"1st Avenue",  "2nd Avenue",  "3rd Avenue",  "4th Avenue",
                              "5th Avenue",  "6th Avenue",  "7th Avenue",  "8th Avenue",
                              "9th Avenue",  "10th Avenue", "11th Avenue", "12th Avenue"};
  const int n = 12;
  const std::string base = ns ? kNs[i % n] : kEw[i % n];
  return i < n ? base : base + " " + std::to_string(i / n + 1);
}

}  // namespace hameritt::scenario::catalog
