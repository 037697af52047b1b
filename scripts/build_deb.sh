#!/usr/bin/env bash
# Builds the Debian package of the working tree (debian/; tracked and untracked files that git does
# not ignore) with dpkg-buildpackage into .deb/ (or --out DIR): ros-stereo-fusion_<version>_<arch>.deb.
# Installs the packaging tools and the build dependencies (scripts/setup.sh --with deb). One
# compile job (parallel=1; --jobs N for more), niced; the tests are not run (scripts/test.sh).
#   scripts/build_deb.sh [--out DIR] [--jobs N]
# Then: apt install ./.deb/ros-stereo-fusion_*.deb; /usr/lib/stereo_fusion/demo.sh (doc/robot.md), or
# scripts/try_deb.sh to try both in a throw-away overlay of the system.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/.deb"
JOBS=1
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --jobs) JOBS="$2"; shift 2 ;;
    -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
    *) echo "build_deb.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
export PYENV_VERSION=system
# The build packages and the packaging tools (dpkg-dev, debhelper); debian/control's Build-Depends
# must then hold.
"$ROOT/scripts/setup.sh" --no-build --with deb
dpkg-checkbuilddeps "$ROOT/debian/control"

# dpkg-buildpackage writes its results next to the source folder: a copy of the tree under OUT.
SRC="$OUT/src"
rm -rf "$SRC"
mkdir -p "$SRC"
(cd "$ROOT" && git ls-files -z --cached --others --exclude-standard | tar --null -T - -cf -) | tar -xf - -C "$SRC"
rm -f "$OUT"/ros-stereo-fusion_*
# debhelper gives the build its own HOME: point ccache (debian/rules uses it when installed) at the
# caller's cache and configuration, so the objects of the developer's build are reused.
if command -v ccache >/dev/null; then
  CCACHE_DIR="$(ccache -k cache_dir)"
  export CCACHE_DIR
  config="${XDG_CONFIG_HOME:-$HOME/.config}/ccache/ccache.conf"
  if [ -f "$config" ]; then export CCACHE_CONFIGPATH="$config"; fi
fi
echo "[deb] dpkg-buildpackage -us -uc -b in $SRC (log: $OUT/build.log)"
start=$(date +%s)
if ! (cd "$SRC" && DEB_BUILD_OPTIONS="nocheck parallel=$JOBS" nice dpkg-buildpackage -us -uc -b) \
  >"$OUT/build.log" 2>&1; then
  tail -n 30 "$OUT/build.log"
  echo "[deb] dpkg-buildpackage failed, see $OUT/build.log" >&2
  exit 1
fi
rm -rf "$SRC"
for deb in "$OUT"/ros-stereo-fusion_*.deb; do
  echo "[deb] $deb ($(du -h "$deb" | cut -f1), built in $(($(date +%s) - start)) s)"
done
