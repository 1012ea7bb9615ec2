#!/usr/bin/env bash
# Installs the Debian 12 packages esf builds against, when any is missing (libfreenect: esf
# live and its tests under fakenect; chromium: the browser test of the report pages, ctest
# browser_pages). With the argument `fuzz`, also
# Debian's clang 16 and its libFuzzer (for make fuzz).
set -euo pipefail
packages=(
    build-essential cmake pkg-config clang-format
    libeigen3-dev libpcl-dev libflann-dev libassimp-dev libembree-dev libtbb-dev
    libcli11-dev libsqlite3-dev libpng-dev libfmt-dev nlohmann-json3-dev
    libgtest-dev libgmock-dev libbenchmark-dev
    libfreenect-dev libfreenect-bin
    python3-dev pybind11-dev python3-numpy python3-pytest python3-venv
    chromium
)
if [ "${1:-}" = fuzz ]; then
    packages+=(clang-16 libclang-rt-16-dev)
fi
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "esf: installing ${missing[*]}" >&2
sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
