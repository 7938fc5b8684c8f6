# Shared by scripts/run_main.sh and scripts/run_tests.sh: install what is missing, then build.
# Idempotent: with everything present it costs one dpkg query and an incremental build.
set -euo pipefail

# A pyenv python3 may shadow the system one and lacks catkin_pkg: pin /usr/bin first.
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:${PATH}"
export PYTHONNOUSERSITE=1

HAMERITT_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${HAMERITT_BUILD_DIR:-$HAMERITT_ROOT/build}"
JOBS="${HAMERITT_JOBS:-$(nproc)}"

# Debian 12 packages the project needs to build, run and test.
HAMERITT_PACKAGES=(
  build-essential cmake pkg-config
  catkin python3-catkin-pkg ros-base-dev ros-message-generation ros-message-runtime
  libroscpp-dev libstd-msgs-dev libgeometry-msgs-dev librostest-dev
  rosbash python3-roslaunch python3-rostest python3-rosbag ros-environment
  libgtest-dev googletest
  libnav-msgs-dev libsensor-msgs-dev libros-rosgraph-msgs-dev libtf2-dev libtf2-ros-dev
  libvisualization-msgs-dev libmessage-filters-dev libtopic-tools-dev
  libeigen3-dev nlohmann-json3-dev libopencv-dev
  libbullet-dev liburdfdom-dev liburdfdom-headers-dev libtinyxml2-dev libompl-dev
  python3-jsonschema python3-crcmod python3-rospy python3-nav-msgs python3-rosgraph-msgs
  python3-geometry-msgs python3-std-msgs python3-actionlib-msgs
  # rostopic and friends on the cameras' messages, and the MarkerArray for RViz users.
  python3-rostopic python3-sensor-msgs python3-visualization-msgs
  # Recording tests: an independent PNG decoder (OpenCV's Python binding, with numpy); YAML for
  # `rosbag info --yaml`.
  python3-opencv python3-numpy python3-yaml
  # Renderer: GL and EGL through glvnd, Mesa's EGL and llvmpipe for machines without a GPU,
  # assimp for the meshes.
  libegl-dev libopengl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libassimp-dev
  # hameritt_campaign: its YAML config (python3-yaml, above), and the single-node Slurm cluster
  # of its test.
  slurm-wlm munge
  # Dataset export (hameritt_export): the rosbag C++ API (its test reads PNGs with OpenCV, above).
  librosbag-storage-dev
  # Reliability: libFuzzer targets with clang (ASan/UBSan), the Shapely geometry oracle.
  clang-14 libclang-rt-14-dev libfuzzer-14-dev python3-shapely
  # Repeated builds (the sanitizer and workspace builds, a second clone) reuse objects.
  ccache
  # Package checks: catkin_lint; the workspace build (Ninja); strace judges that the install
  # space runs alone.
  catkin-lint ninja-build strace
  # The TAK bridge's TLS (OpenSSL); its test makes certificates with the openssl tool.
  libssl-dev openssl
  # The tracking scores' independent reference (TrackEval's formulas): scipy's assignment.
  python3-scipy
)

install_deps() {
  local missing=()
  local status
  for p in "${HAMERITT_PACKAGES[@]}"; do
    status="$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)"
    [[ "$status" == "install ok installed" ]] || missing+=("$p")
  done
  if ((${#missing[@]} == 0)); then
    echo "hameritt: all ${#HAMERITT_PACKAGES[@]} Debian packages present"
    return 0
  fi
  echo "hameritt: installing ${missing[*]}"
  local sudo=""
  [[ "$(id -u)" == 0 ]] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# ccache, keyed on paths relative to the checkout, so that two clones (or worktrees) share
# their objects; -g builds (the sanitizers) do not hash the working directory either.
export CCACHE_BASEDIR="$HAMERITT_ROOT" CCACHE_NOHASHDIR=1
CCACHE_ARGS=()
if command -v ccache >/dev/null 2>&1; then
  CCACHE_ARGS=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi

# Configures (always with testing on, so that switching between the two commands never
# reconfigures; test programs are only built by the "tests" target) and builds.
build() {
  cmake -S "$HAMERITT_ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON "${CCACHE_ARGS[@]}" >/dev/null
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

source_devel() {
  # setup.bash reads unset variables; relax -u while sourcing it.
  set +u
  # shellcheck disable=SC1091
  source "$BUILD_DIR/devel/setup.bash"
  set -u
}
