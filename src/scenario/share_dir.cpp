#include "hameritt/scenario/share_dir.h"

#include <dlfcn.h>
#include <sys/stat.h>

#include <cstdlib>

#include "hameritt/build_paths.h"

namespace hameritt::scenario {

namespace {

bool isFile(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// "/a/b/c" -> "/a/b"; "" when there is no parent.
std::string parentOf(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos || slash == 0 ? "" : path.substr(0, slash);
}

// The directory of the shared object (or executable) this function was linked into.
std::string ownDirectory() {
  Dl_info info{};
  if (::dladdr(reinterpret_cast<void*>(&ownDirectory), &info) == 0 || info.dli_fname == nullptr) {
    return "";
  }
  return parentOf(info.dli_fname);
}

}  // namespace

std::string shareDir() {
  if (const char* env = std::getenv("HAMERITT_SHARE_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  // An install space: the library in <prefix>/lib (or linked statically into a program in
  // <prefix>/lib/hameritt), the data in <prefix>/share/hameritt. A devel space has no config/
  // there and falls through to the source tree.
  const std::string lib = ownDirectory();
  for (const std::string& prefix : {parentOf(lib), parentOf(parentOf(lib))}) {
    if (prefix.empty()) continue;
    const std::string candidate = prefix + "/share/hameritt";
    if (isFile(candidate + "/config/world.json")) return candidate;
  }
  return HAMERITT_SOURCE_DIR;
}

}  // namespace hameritt::scenario
