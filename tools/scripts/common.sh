# Shared by tools/run-main and tools/run-tests: install missing Debian packages, configure, build.
set -euo pipefail
UH_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
UH_JOBS="${UH_JOBS:-$(nproc)}"

# Debian packages the build and its figures need (the CHAI3D examples add GLFW/GL/Xvfb).
UH_PACKAGES=(cmake g++ make libeigen3-dev catch2 libusb-1.0-0-dev libbenchmark-dev libcli11-dev
             nlohmann-json3-dev python3-matplotlib)

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
uh_build() {
  local dir="$1"; shift
  cmake -S "$UH_ROOT" -B "$dir" -DCMAKE_BUILD_TYPE=Release "$@"
  cmake --build "$dir" -j "$UH_JOBS"
}
