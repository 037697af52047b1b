#!/usr/bin/env bash
# The package run from an install space alone (ctest: stereo_fusion_install_space). Installs the
# built package (cmake --install) into a temporary prefix, moves that prefix elsewhere, fails if a
# text file or an ELF run path in it names the source or the build tree, then runs three rostests
# against it: launch/stereo_pipeline.launch, launch/replay.launch, launch/fusion.launch with
# launch/base_station.launch (the .test files beside this script). They run in an environment
# made from nothing but the prefix's setup.bash and, where a mount namespace can be made (root, or
# unprivileged user namespaces), with the source and build trees hidden under empty tmpfs mounts:
# whatever still reached into them fails. The test nodes themselves (the rostest binaries of the
# build, with the bags and test_config.yaml) are copied into a throw-away package,
# stereo_fusion_install_check. Each rostest starts its own master on a free port.
#   install_space_test.sh SOURCE_DIR BUILD_DIR TEST_BIN_DIR PAIR_BAG REPLAY_BAG
set -euo pipefail
if [ $# -ne 5 ]; then
  echo "usage: $0 SOURCE_DIR BUILD_DIR TEST_BIN_DIR PAIR_BAG REPLAY_BAG" >&2
  exit 2
fi
SRC="$(readlink -f "$1")"
BUILD="$(readlink -f "$2")"
TEST_BIN="$(readlink -f "$3")"
PAIR_BAG="$4"
REPLAY_BAG="$5"
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

TMP="$(mktemp -d /tmp/stereo_fusion_install_space.XXXXXX)"
cleanup() { [ -n "${KEEP_INSTALL_SPACE_TEST:-}" ] || rm -rf "$TMP"; }  # set it to keep the folder
trap cleanup EXIT
fail() {
  echo "[install_space] FAIL: $*" >&2
  exit 1
}

# 1. Install into a staging root (DESTDIR: catkin installs its setup files to the configured
# CMAKE_INSTALL_PREFIX itself, so cmake --install --prefix would put them there), then move the
# prefix out of it: nothing may depend on where it was installed to, and nothing may have been
# installed outside it.
CONFIGURED="$(sed -n 's/^CMAKE_INSTALL_PREFIX:PATH=//p' "$BUILD/CMakeCache.txt")"
echo "[install_space] DESTDIR=$TMP/staging cmake --install $BUILD (prefix $CONFIGURED)"
DESTDIR="$TMP/staging" cmake --install "$BUILD" >"$TMP/install.log" 2>&1 || {
  tail -n 20 "$TMP/install.log"
  fail "cmake --install failed"
}
PREFIX="$TMP/opt/stereo_fusion"
mkdir -p "$TMP/opt"
mv "$TMP/staging$CONFIGURED" "$PREFIX"
# Into /usr catkin installs as a binary package, without setup.bash: this test needs another prefix.
[ "$CONFIGURED" != /usr ] || fail "the build is configured with CMAKE_INSTALL_PREFIX=/usr (no setup.bash then)"
outside="$(find "$TMP/staging" ! -type d)"
[ -z "$outside" ] || fail "installed outside the prefix $CONFIGURED: $outside"
for f in share/stereo_fusion/package.xml share/stereo_fusion/nodelet_plugins.xml lib/libstereo_fusion_nodelet.so \
  lib/libstereo_fusion_image_transport.so lib/libstereo_fusion_decode_reports.so \
  lib/stereo_fusion/mesh_assembler_node lib/stereo_fusion/stereo_fusion_simulate lib/stereo_fusion/demo_monitor.py \
  lib/stereo_fusion/demo.sh share/stereo_fusion/launch/stereo_pipeline.launch share/stereo_fusion/config/default.yaml \
  share/stereo_fusion/rviz/stereo_fusion.rviz share/stereo_fusion/msg/MeshUpdate.msg include/stereo_fusion/MeshUpdate.h \
  setup.bash; do
  [ -e "$PREFIX/$f" ] || fail "the install has no $f"
done
# Paths back into the trees: text files (launch, config, cmake, pkg-config, setup scripts, Python
# relays) and the run paths of the ELF files. (Compiled-in __FILE__ strings of log macros name the
# sources too but locate nothing.)
leaks="$(grep -rIlF -e "$SRC" -e "$BUILD" "$PREFIX" || true)"
[ -z "$leaks" ] || fail "installed files name the source or build tree: $leaks"
while IFS= read -r -d '' elf; do
  if readelf -d "$elf" 2>/dev/null | grep -E 'R(UN)?PATH' | grep -qF -e "$SRC" -e "$BUILD"; then
    fail "$elf has a run path into the source or build tree: $(readelf -d "$elf" | grep -E 'R(UN)?PATH')"
  fi
done < <(find "$PREFIX" -type f -print0)

# 2. The test's own package: the rostest binaries, their config, the .test files and the bags.
CHECK="$TMP/check/stereo_fusion_install_check"
mkdir -p "$CHECK" "$TMP/data" "$TMP/home" "$TMP/results"
cat >"$CHECK/package.xml" <<'EOF'
<?xml version="1.0"?>
<package format="2">
  <name>stereo_fusion_install_check</name>
  <version>0.0.0</version>
  <description>stereo_fusion's install-space test nodes (made by install_space_test.sh)</description>
  <maintainer email="dev@stereo-fusion.local">stereo_fusion developers</maintainer>
  <license>BSD-3-Clause</license>
  <buildtool_depend>catkin</buildtool_depend>
</package>
EOF
for exe in stereo_fusion_pipeline_test stereo_fusion_replay_test stereo_fusion_assembler_test; do
  [ -x "$TEST_BIN/$exe" ] || fail "$TEST_BIN/$exe is not built (cmake --build BUILD --target tests)"
  cp "$TEST_BIN/$exe" "$CHECK/"
done
cp "$HERE"/*.test "$SRC/test/ros/test_config.yaml" "$CHECK/"
cp "$PAIR_BAG" "$TMP/data/pair.bag"
cp "$REPLAY_BAG" "$TMP/data/replay.bag"

# 3. Hide the trees where a mount namespace can be made; otherwise say so (the environment
# below still holds nothing of them).
HIDE=()
if [ "$(id -u)" -eq 0 ] && unshare --mount --propagation private true 2>/dev/null; then
  HIDE=(unshare --mount --propagation private)
elif unshare --user --map-root-user --mount true 2>/dev/null; then
  HIDE=(unshare --user --map-root-user --mount)
else
  echo "[install_space] NOTE: no mount namespace here: the source and build trees stay visible;" \
    "the run uses only the install's environment"
fi
HIDDEN=("$SRC")
case "$BUILD/" in "$SRC"/*) ;; *) HIDDEN+=("$BUILD") ;; esac
case "$TEST_BIN/" in "$SRC"/* | "$BUILD"/*) ;; *) HIDDEN+=("$TEST_BIN") ;; esac

# One rostest in a fresh environment: the install's setup.bash and the check package only.
# Runs as `bash -c` inside the namespace; $1 = prefix, $2 = check package folder, $3 = results,
# $4 = the .test file, $5.. = its arguments; HIDE_DIRS lists the trees to cover.
# shellcheck disable=SC2016  # expanded by the inner bash
RUN_ONE='
set -eu
if [ -n "$HIDE_DIRS" ]; then
  for d in $HIDE_DIRS; do mount -t tmpfs -o ro,size=1k stereo_fusion_hidden "$d"; done
  for d in $HIDE_DIRS; do [ -z "$(ls -A "$d")" ] || { echo "could not hide $d" >&2; exit 1; }; done
fi
prefix="$1" check="$2" results="$3" test_file="$4"
shift 4
set +u
source "$prefix/setup.bash"
set -u
export ROS_PACKAGE_PATH="$(dirname "$check"):$ROS_PACKAGE_PATH"
found="$(/usr/bin/python3 -c "import rospkg; print(rospkg.RosPack().get_path(\"stereo_fusion\"))")"
[ "$found" = "$prefix/share/stereo_fusion" ] || { echo "roslaunch would find stereo_fusion in $found" >&2; exit 1; }
cd "$HOME"
exec rostest --results-base-dir="$results" stereo_fusion_install_check "$test_file" "$@"
'
run_rostest() {
  local name="$1"
  shift
  local hide_dirs=""
  ((${#HIDE[@]} > 0)) && hide_dirs="${HIDDEN[*]}"
  echo "[install_space] rostest $name (from $PREFIX)"
  env -i PATH=/usr/local/bin:/usr/bin:/bin HOME="$TMP/home" ROS_HOME="$TMP/home/.ros" LANG=C.UTF-8 \
    ROS_HOSTNAME=localhost PYENV_VERSION=system HIDE_DIRS="$hide_dirs" \
    "${HIDE[@]}" /bin/bash -c "$RUN_ONE" run_one "$PREFIX" "$CHECK" "$TMP/results" "$@" \
    >"$TMP/$name.log" 2>&1 || {
    tail -n 40 "$TMP/$name.log"
    fail "rostest $name did not run"
  }
}
run_rostest stereo_pipeline stereo_pipeline.test bag:="$TMP/data/pair.bag"
run_rostest replay replay.test bag:="$TMP/data/replay.bag"
run_rostest base_station base_station.test

# 4. rostest exits 0 on failed tests (ros-on-debian.md #4): the result files decide. Each test node
# must have written its own (a node that never ran writes none).
for name in stereo_pipeline replay base_station; do
  [ -f "$TMP/results/stereo_fusion_install_check/rosunit-install_$name.xml" ] || {
    tail -n 30 "$TMP/$name.log"
    fail "the $name test node wrote no result"
  }
done
if ! catkin_test_results --verbose "$TMP/results"; then
  for name in stereo_pipeline replay base_station; do
    echo "---- $name" && tail -n 30 "$TMP/$name.log"
  done
  fail "a rostest failed"
fi
echo "[install_space] the stereo pipeline, the replay and the base station ran from the install alone"
