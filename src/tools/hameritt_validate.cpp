// hameritt_validate: checks scenario documents against config/schema/ and the semantic rules.
//   hameritt_validate [--schema-dir DIR] FILE...
// Prints "FILE: ok" on stdout for each valid file and one "FILE: PATH: RULE: MESSAGE" line on
// stderr per issue. Exit codes: 0 all files valid, 2 any issue or bad usage.

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "hameritt/scenario/generator.h"
#include "hameritt/scenario/validation.h"

using namespace hameritt::scenario;

namespace {

const char* kUsage =
    "usage: hameritt_validate [--schema-dir DIR] FILE...\n"
    "  Validates mission.json, sim_config.json, world.json and manifest.json files (the kind\n"
    "  comes from each file's \"schema\" field). DIR defaults to the package's config/schema.\n";

int usageError(const std::string& message) {
  std::fprintf(stderr, "hameritt_validate: error: %s\n%s", message.c_str(), kUsage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string schema_dir = defaultConfigDir() + "/schema";
  std::vector<std::string> files;
  bool options_done = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (options_done || a.empty() || a[0] != '-' || a == "-") {
      files.push_back(a);
    } else if (a == "--") {
      options_done = true;
    } else if (a == "--schema-dir") {
      if (i + 1 >= argc) return usageError("--schema-dir: missing value");
      schema_dir = argv[++i];
    } else if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    } else {
      return usageError("unknown argument '" + a + "'");
    }
  }
  if (files.empty()) return usageError("no FILE given");
  std::error_code ec;
  if (!std::filesystem::is_directory(schema_dir, ec)) {
    return usageError("--schema-dir: '" + schema_dir + "' is not a directory");
  }

  bool all_ok = true;
  for (const auto& f : files) {
    const std::vector<ValidationIssue> issues = validateFile(f, schema_dir);
    if (issues.empty()) {
      std::printf("%s: ok\n", f.c_str());
      continue;
    }
    all_ok = false;
    for (const auto& issue : issues) std::fprintf(stderr, "%s\n", formatIssue(issue).c_str());
  }
  std::fflush(stdout);
  return all_ok ? 0 : 2;
}
