# Shared by tools/run-main and tools/run-tests: install missing Debian packages, configure, build.
set -euo pipefail
UH_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
UH_JOBS="${UH_JOBS:-$(nproc)}"

# Debian packages the build and its figures need. The second line is the CHAI3D layer's: what
# CHAI3D 3.3 builds against (GL/GLU, X11, ALSA, libusb), GLFW for the scenes and CHAI3D's examples,
# Xvfb (and xauth, which xvfb-run needs) to run them headless.
UH_PACKAGES=(cmake ninja-build g++ make git libeigen3-dev catch2 libusb-1.0-0-dev libbenchmark-dev
             libcli11-dev nlohmann-json3-dev python3-matplotlib
             libgl1-mesa-dev libglu1-mesa-dev xorg-dev libasound2-dev libglfw3-dev xvfb xauth)

# CHAI3D: the user's build (CHAI3D_DIR) or a source archive/folder (CHAI3D_SOURCE) pass through the
# environment to CMake. Without either, a CHAI3D archive laid beside the repository
# (../shared/third_party, as on CI) is used before falling back to fetching CHAI3D's repository.
# Every build tree of these scripts shares one CHAI3D build, made once in build/chai3d-3.3.0.
if [ -z "${CHAI3D_DIR:-}" ] && [ -z "${CHAI3D_SOURCE:-}" ] &&
   [ -f "$UH_ROOT/../shared/third_party/chai3d-3.3.0-src.tar.xz" ]; then
  export CHAI3D_SOURCE="$(cd "$UH_ROOT/../shared/third_party" && pwd)/chai3d-3.3.0-src.tar.xz"
fi
UH_CHAI3D_ARGS=(-DUHAPTICS_CHAI3D_CACHE="${UH_CHAI3D_CACHE:-$UH_ROOT/build/chai3d-3.3.0}")

uh_ensure_packages() {
  local missing=()
  for p in "${UH_PACKAGES[@]}" "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "uhaptics: installing missing Debian packages: ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
      echo "uhaptics: cannot install packages (not root, no sudo). Run as root:" >&2
      echo "  apt-get update && apt-get install -y ${missing[*]}" >&2
      exit 1
    fi
  fi
  if ! { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"; }; then
    echo "uhaptics: package installation failed. Install by hand:" >&2
    echo "  apt-get update && apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
}

# uh_build <build-dir> [cmake args...]
# Ninja for new build trees (an existing tree keeps the generator it was made with).
uh_build() {
  local dir="$1"; shift
  uh_configure "$dir" "$@"
  cmake --build "$dir" -j "$UH_JOBS"
}
# ccache, when installed, caches compiles across build trees and branches (not installed by these
# scripts: a fresh clone gains nothing from an empty cache).
uh_configure() {
  local dir="$1"; shift
  local generator=() launcher=()
  [ -f "$dir/CMakeCache.txt" ] || generator=(-G Ninja)
  command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  cmake -S "$UH_ROOT" -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "${UH_CHAI3D_ARGS[@]}" "$@"
}
