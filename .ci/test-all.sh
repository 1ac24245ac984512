#!/usr/bin/env bash
# The project's one test command (README "Tests"): installs the Debian packages
# the tests need (skipped when already installed), runs every cargo test, builds
# the CMake project in build/ and runs ctest (including the Valgrind memcheck set),
# builds the C++ tests again with ASan + UBSan in build-asan/ and runs them, then
# builds the library and command as README does and checks where they are, and
# installs the Python package with pip from a fresh clone into a new virtual
# environment and meshes a part with it (.ci/pip-install-test.sh). Exits nonzero if anything fails.
# Idempotent: run it as often as you like.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(cmake g++ libgtest-dev libcgal-dev libeigen3-dev libgmp-dev libmpfr-dev libtet1.5-dev tetgen libvtk9-dev python3 python3-numpy python3-pytest python3-distributed python3-venv git chromium pkg-config valgrind)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "== installing Debian packages: ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo=sudo
  $sudo apt-get update
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
fi

jobs=$(nproc 2>/dev/null || echo 2)

echo "== cargo test --release"
# report.html is checked in headless Chromium (installed above): do not skip it here
export SDDPM_REQUIRE_CHROMIUM=1
# with the test-only C exports, as the CMake build of the C++ tests below builds the
# library (cargo feature test-hooks), so that it reuses this build
cargo test --release --features test-hooks

echo "== cmake configure + build (build/)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$jobs"

echo "== ctest"
ctest --test-dir build --output-on-failure -j"$jobs"

echo "== cpp_tests under AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/)"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSDDPM_SANITIZE=ON
cmake --build build-asan -j"$jobs"
ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:check_initialization_order=1 \
UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure -j"$jobs"

# Last: the library without test-hooks, as README builds it. Cargo keeps one build
# of the crate's own library at a time (its file names carry no hash), so this
# rebuilds the crate once; the pip build below then reuses it and compiles nothing.
echo "== cargo build --release (README: the library and the command where it says)"
cargo build --release
target=${CARGO_TARGET_DIR:-target}
for f in "$target/release/libsddpm.so" "$target/release/libsddpm.a" "$target/release/sddpm"; do
  [ -f "$f" ] || { echo "missing after cargo build --release: $f"; exit 1; }
done
"$target/release/sddpm" --version

echo "== pip install of the Python package from a fresh clone (.ci/pip-install-test.sh)"
bash .ci/pip-install-test.sh

