#!/usr/bin/env bash
# Installs the Debian package (default: the newest .deb/ros-stereo-fusion_*.deb of build_deb.sh)
# into a throw-away copy of the system and runs the installed demo there: in a private mount
# namespace, /usr, /etc and /var become overlays on a tmpfs (apt and dpkg write only to those),
# the source tree is hidden, and /usr/lib/stereo_fusion/demo.sh runs in an empty environment.
# Nothing of it outlives the run; the machine's own packages are untouched. Needs root (mount
# namespaces, overlayfs) and the package's dependencies installed or downloadable.
#   scripts/try_deb.sh [DEB] [demo.sh options, default --frames 20]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck disable=SC2012  # names without spaces (the package's own)
DEB="${1:-$(ls -t "$ROOT"/.deb/ros-stereo-fusion_*.deb 2>/dev/null | head -n 1)}"
[ $# -gt 0 ] && shift
if [ -z "$DEB" ] || [ ! -f "$DEB" ]; then
  echo "try_deb.sh: no package: run scripts/build_deb.sh first" >&2
  exit 1
fi
DEB="$(readlink -f "$DEB")"
[ "$(id -u)" -eq 0 ] || { echo "try_deb.sh: needs root (mount namespace, overlayfs)" >&2; exit 1; }
DEMO_ARGS=("$@")
[ ${#DEMO_ARGS[@]} -gt 0 ] || DEMO_ARGS=(--frames 20)
SCRATCH="$(mktemp -d /tmp/stereo_fusion_try_deb.XXXXXX)"
trap 'rmdir "$SCRATCH"' EXIT
# shellcheck disable=SC2016  # expanded by the inner bash
unshare --mount --propagation private /bin/bash -c '
set -euo pipefail
scratch="$1" deb="$2" root="$3"
shift 3
mount -t tmpfs stereo_fusion_try_deb "$scratch"
for d in usr etc var; do
  mkdir -p "$scratch/$d/up" "$scratch/$d/work"
  mount -t overlay overlay -o "lowerdir=/$d,upperdir=$scratch/$d/up,workdir=$scratch/$d/work" "/$d"
done
cp "$deb" "$scratch/"
mount -t tmpfs -o ro,size=1k stereo_fusion_hidden "$root"  # no source or build tree from here on
echo "[try_deb] apt-get install ./$(basename "$deb") (into the overlays)"
cd "$scratch"
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "./$(basename "$deb")" \
  >"$scratch/apt.log" 2>&1 || { tail -n 20 "$scratch/apt.log"; exit 1; }
dpkg-query -W -f="[try_deb] installed \${Package} \${Version}\n" ros-stereo-fusion
mkdir -p "$scratch/home"
cd "$scratch/home"
echo "[try_deb] env -i /usr/lib/stereo_fusion/demo.sh $*"
env -i PATH=/usr/bin:/bin HOME="$scratch/home" LANG=C.UTF-8 /usr/lib/stereo_fusion/demo.sh "$@"
' try_deb "$SCRATCH" "$DEB" "$ROOT" "${DEMO_ARGS[@]}"
