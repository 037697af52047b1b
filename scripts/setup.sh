#!/usr/bin/env bash
# Installs the Debian packages stereo_fusion needs (only the missing ones) and builds the
# package into .build/. Idempotent; safe to run on a fresh Debian bookworm machine.
#   scripts/setup.sh [--no-build] [--targets "T1 T2 ..."] [--screenshots] [--with sanitizers|fuzz|deb]...
# --targets builds only those CMake targets (and what they need), not the tests: what the demo and
# the offline tools pass, so a first run does not wait for the test suite. --screenshots adds
# ImageMagick (scripts/screenshots.sh); --with adds an opt-in package group
# (scripts/check.sh, scripts/fuzz.sh use them).
# Environment: BUILD_TYPE (default Release), BUILD_DIR (default <repo>/.build).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"

PACKAGES=(
  # toolchain
  g++ make cmake pkg-config
  # core library
  libeigen3-dev libopencv-dev libyaml-cpp-dev nlohmann-json3-dev zlib1g-dev libsqlite3-dev libzstd-dev
  # the offline fuser's octomap.bt
  liboctomap-dev
  # the tools' OBJ reader (tools/readers/ObjReader.cpp)
  libtinyobjloader-dev
  # the tools' command lines (tools/cli/)
  libcli11-dev
  # ROS 1 from Debian (catkin, messages, nodelet, tf2, synchronisation, images, bags)
  catkin ros-message-generation ros-message-runtime libroscpp-dev libnodeletlib-dev
  libmessage-filters-dev libtf2-dev libtf2-msgs-dev libtf2-ros-dev libtf2-eigen-dev libstd-msgs-dev
  libgeometry-msgs-dev libstd-srvs-dev ros-std-srvs
  # images through image_transport (raw only in Debian: the compressed and compressedDepth
  # subscribers are the package's own, image_transport_plugins.xml)
  libimage-transport-dev
  libnav-msgs-dev ros-nav-msgs
  # the planning topics: map_msgs/OccupancyGridUpdate, point clouds through pcl_conversions
  libmap-msgs-dev ros-map-msgs libpcl-conversions-dev
  libsensor-msgs-dev libstereo-msgs-dev libvisualization-msgs-dev ros-std-msgs
  ros-geometry-msgs ros-sensor-msgs ros-stereo-msgs ros-visualization-msgs libcv-bridge-dev
  libpcl-dev librosbag-dev libdiagnostic-updater-dev
  # the rviz display stereo_fusion/Mesh (stereo_fusion_rviz, rviz_plugin.xml) and rviz.launch
  librviz-dev rviz
  # tests (iproute2: test/ros/two_hosts.sh's network namespaces and veth pair; xvfb, xauth,
  # Mesa: rviz loads the display on a virtual screen in RvizPlugin.*)
  libgtest-dev librostest-dev python3-rostest libnodeletlib-tools iproute2 xvfb xauth libgl1-mesa-dri
  # the style check (scripts/check_format.sh)
  clang-format
  # running: demo, replay, command-line tools
  python3-rosbag python3-rosnode python3-rosservice python3-rostopic python3-rospy
  python3-sensor-msgs python3-stereo-msgs python3-visualization-msgs python3-tf2-msgs
  python3-diagnostic-msgs python3-std-srvs tf2-tools
  # launch/stereo_pipeline.launch and its rostest: image_proc + stereo_image_proc nodelets (the
  # -dev packages hold their package.xml and plugin XML: without them roslaunch cannot load them)
  ros-image-proc libimage-proc-dev ros-stereo-image-proc libstereo-image-proc-dev
)
# The screen capture for scripts/screenshots.sh: opt-in (`--screenshots`, which that script
# passes); rviz, Xvfb and Mesa are in the list above.
SCREENSHOT_PACKAGES=(imagemagick x11-apps)
NO_BUILD=0
TARGETS=()
while (($# > 0)); do
  case "$1" in
    --no-build) NO_BUILD=1 ;;
    --targets) read -r -a TARGETS <<<"${2:-}"; shift ;;
    --screenshots) PACKAGES+=("${SCREENSHOT_PACKAGES[@]}") ;;
    --with)
      case "${2:-}" in
        # g++'s ASan/UBSan/TSan runtimes (g++ pulls them in today; named so that stays true)
        sanitizers) PACKAGES+=(libasan8 libubsan1 libtsan2) ;;
        # libFuzzer lives in compiler-rt, which Debian ships apart from the compiler
        fuzz) PACKAGES+=(clang-14 libclang-rt-14-dev) ;;
        # the Debian package (scripts/build_deb.sh): dpkg-buildpackage and dh
        deb) PACKAGES+=(dpkg-dev debhelper) ;;
        *) echo "[setup] unknown package group '${2:-}' (sanitizers, fuzz, deb)" >&2; exit 2 ;;
      esac
      shift ;;
    *) echo "usage: scripts/setup.sh [--no-build] [--targets \"T1 T2 ...\"] [--screenshots] [--with sanitizers|fuzz|deb]..." >&2; exit 2 ;;
  esac
  shift
done

missing=()
for pkg in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done
if ((${#missing[@]} > 0)); then
  # No duration here: the measured fresh-machine times live in doc/getting_started.md alone.
  echo "[setup] installing ${#missing[@]} missing Debian packages (with what they pull in, about 1 000 on a"
  echo "[setup] fresh machine; times: doc/getting_started.md; log /tmp/stereo_fusion_apt.log): ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "[setup] apt-get update"
  $SUDO apt-get update -qq
  # A line per 100 packages downloaded and per 25 set up, so a long install is visibly moving.
  set +o pipefail
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}" 2>&1 \
    | tee /tmp/stereo_fusion_apt.log \
    | awk '/ newly installed, / {total = $3}
           /^Need to get/ {print "[setup] " $0; fflush()}
           /^Get:/ {g++; if (g % 100 == 0) {print "[setup] " g " of " total " packages downloaded"; fflush()}}
           /^Setting up / {n++; if (n % 25 == 0) {print "[setup] " n " of " total " packages set up (" $3 ")"; fflush()}}'
  apt_status=${PIPESTATUS[0]}
  set -o pipefail
  if ((apt_status != 0)); then tail -n 30 /tmp/stereo_fusion_apt.log; exit 1; fi
  echo "[setup] packages installed"
else
  echo "[setup] all ${#PACKAGES[@]} Debian packages present"
fi

if ((NO_BUILD)); then exit 0; fi

# ROS tooling must run on Debian's Python, not the python3 first on PATH (ros-on-debian.md #1).
export PYENV_VERSION=system
echo "[setup] configuring and building in ${BUILD_DIR} (${BUILD_TYPE:-Release})"
# ccache only speeds up rebuilds on a developer's machine; it is optional and not installed here.
LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" "${LAUNCHER[@]}" \
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
  -DCATKIN_ENABLE_TESTING=ON >"$BUILD_DIR.configure.log" 2>&1 \
  || { cat "$BUILD_DIR.configure.log"; exit 1; }
if ((${#TARGETS[@]} > 0)); then
  echo "[setup] building ${TARGETS[*]} (a first build takes minutes: doc/getting_started.md)"
  cmake --build "$BUILD_DIR" -j"$(nproc)" --target "${TARGETS[@]}"
else
  cmake --build "$BUILD_DIR" -j"$(nproc)"
  # catkin builds the rostest executables only in its `tests` target.
  cmake --build "$BUILD_DIR" -j"$(nproc)" --target tests
fi
echo "[setup] build done"
