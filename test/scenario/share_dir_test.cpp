// Where the programs find the package's data: the source tree in a devel space (this test's
// build), $HAMERITT_SHARE_DIR and $HAMERITT_CONFIG_DIR when set. The install space's
// <prefix>/share/hameritt is checked from an installed workspace by
// test/scripts/test_install_space.sh.
#include "hameritt/scenario/share_dir.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "hameritt/build_paths.h"
#include "hameritt/generation/generator.h"

using namespace hameritt::scenario;

namespace {

// Sets (or unsets, for nullptr) an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) {
      old_ = old;
      had_ = true;
    }
    if (value != nullptr) {
      ::setenv(name, value, 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (had_) {
      ::setenv(name_.c_str(), old_.c_str(), 1);
    } else {
      ::unsetenv(name_.c_str());
    }
  }

 private:
  std::string name_, old_;
  bool had_ = false;
};

}  // namespace

TEST(ShareDir, DevelSpaceReadsTheSourceTree) {
  ScopedEnv share("HAMERITT_SHARE_DIR", nullptr);
  ScopedEnv config("HAMERITT_CONFIG_DIR", nullptr);
  EXPECT_EQ(shareDir(), HAMERITT_SOURCE_DIR);
  EXPECT_EQ(defaultConfigDir(), std::string(HAMERITT_SOURCE_DIR) + "/config");
}

TEST(ShareDir, EnvironmentOverrides) {
  ScopedEnv share("HAMERITT_SHARE_DIR", "/opt/elsewhere/share/hameritt");
  ScopedEnv config("HAMERITT_CONFIG_DIR", nullptr);
  EXPECT_EQ(shareDir(), "/opt/elsewhere/share/hameritt");
  EXPECT_EQ(defaultConfigDir(), "/opt/elsewhere/share/hameritt/config");
  ScopedEnv config_only("HAMERITT_CONFIG_DIR", "/etc/hameritt");
  EXPECT_EQ(defaultConfigDir(), "/etc/hameritt");
  EXPECT_EQ(shareDir(), "/opt/elsewhere/share/hameritt");
}

TEST(ShareDir, EmptyVariableIsUnset) {
  ScopedEnv share("HAMERITT_SHARE_DIR", "");
  EXPECT_EQ(shareDir(), HAMERITT_SOURCE_DIR);
}
