// The JSON Schema engine itself: the input is a schema (seeded with config/schema/*.json).
// Compiling it accepts or throws ConfigError/SchemaError; a compiled schema validates the
// shipped documents (and the schema itself as a document) without throwing.
#include <fstream>
#include <sstream>
#include <vector>

#include "fuzz_util.h"
#include "hameritt/scenario/validation.h"

namespace {

std::vector<nlohmann::json> shippedDocuments() {
  std::vector<nlohmann::json> docs;
  const std::string root = HAMERITT_FUZZ_ROOT;
  for (const char* f : {"/scenarios/default/mission.json", "/config/world.json"}) {
    std::ifstream in(root + f);
    std::stringstream s;
    s << in.rdbuf();
    docs.push_back(nlohmann::json::parse(s.str()));
  }
  return docs;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  static const std::vector<nlohmann::json> docs = shippedDocuments();
  nlohmann::json schema;
  scenario::ValidationIssue issue;
  if (!scenario::parseJsonText(fuzz::text(data, size), "fuzz.schema.json", &schema, &issue)) {
    return 0;
  }
  try {
    const scenario::JsonSchema compiled(schema, "fuzz.schema.json");
    for (const auto& d : docs) (void)compiled.validate(d);
    (void)compiled.validate(schema);
  } catch (const scenario::ConfigError&) {
  }
  return 0;
}
