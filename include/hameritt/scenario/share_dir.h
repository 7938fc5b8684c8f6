#pragma once

#include <string>

namespace hameritt::scenario {

// The package's data directory, which holds config/ (and config/schema/), models/, scenarios/
// and launch/: $HAMERITT_SHARE_DIR when set; else <prefix>/share/hameritt when this library
// runs from an install space (<prefix>/lib); else the source tree the build came from (a devel
// space). Installed programs thus never read the checkout they were built from.
std::string shareDir();

}  // namespace hameritt::scenario
