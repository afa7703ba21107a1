#!/usr/bin/env bash
# Builds the Debian package dist/calstand_VERSION_ARCH.deb from the source tree: configures a
# build of its own (build-deb/, Debian's hardening flags from dpkg-buildflags, no tests),
# builds the two programs with their man pages and completion, and wraps the install rules
# with CPack's DEB generator (docs/packaging.md). Then checks it with scripts/check-deb.sh
# (contents, the programs run, lintian without error; lintian installed by apt when missing).
#   bash scripts/package-deb.sh [--clean] [--no-check]   --clean: start build-deb/ afresh
# Environment: CALSTAND_DEB_BUILD_DIR (build-deb), CALSTAND_JOBS (all cores).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${CALSTAND_DEB_BUILD_DIR:-$root/build-deb}"
jobs="${CALSTAND_JOBS:-$(nproc)}"
check=1
for arg in "$@"; do
  case "$arg" in
    --clean) rm -rf "$build" ;;
    --no-check) check=0 ;;
    *) echo "package-deb: unknown option $arg" >&2; exit 2 ;;
  esac
done

for tool in dpkg-buildflags dpkg-shlibdeps dpkg-deb fakeroot; do
  command -v "$tool" >/dev/null || { echo "package-deb: $tool is missing (apt-get install dpkg-dev fakeroot)" >&2; exit 1; }
done

# Debian's build flags (hardening: stack protector, fortify, relro, bind-now), as
# dpkg-buildpackage would give them; NDEBUG as in the tested build. From the tree's root:
# -ffile-prefix-map names the current directory, and another would rebuild everything. Given
# to CMake each time (its cache takes CXXFLAGS and LDFLAGS from the environment only once).
cd "$root"
export DEB_BUILD_MAINT_OPTIONS="hardening=+all"
CXXFLAGS="$(dpkg-buildflags --get CXXFLAGS) $(dpkg-buildflags --get CPPFLAGS)"
LDFLAGS="$(dpkg-buildflags --get LDFLAGS)"
export CXXFLAGS LDFLAGS
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi

start=$(date +%s)
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-DNDEBUG" -DCMAKE_INSTALL_PREFIX=/usr \
  -DCMAKE_CXX_FLAGS="$CXXFLAGS" -DCMAKE_EXE_LINKER_FLAGS="$LDFLAGS" \
  -DCALSTAND_BUILD_TESTS=OFF -DCALSTAND_BUILD_BENCHMARKS=OFF "${launcher[@]}" >/dev/null
cmake --build "$build" -j "$jobs" --target calstand calstandd calstand_cli_docs
rm -rf "$build/cpack"
(cd "$build" && fakeroot cpack -G DEB --config CPackConfig.cmake >/dev/null)
mkdir -p "$root/dist"
deb="$(ls "$build"/cpack/calstand_*.deb)"
cp "$deb" "$root/dist/"
echo "package-deb: dist/$(basename "$deb") in $(( $(date +%s) - start )) s"
if [ "$check" -eq 1 ]; then bash "$root/scripts/check-deb.sh" "$root/dist/$(basename "$deb")"; fi
