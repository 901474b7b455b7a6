#!/usr/bin/env bash
# On the GPU machine (CUDA, CMake, ninja and a compiler, none of the project's Debian libraries):
# unpacks what tools/gpu-carry.sh packed (into /, never replacing a file that is there), builds
# with the CUDA backend, and runs the [gpu] tests. Extra arguments go to the test binaries.
#   usage: tools/gpu-build.sh [BUILD_DIR=build-gpu]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-gpu}
shift || true
carry=${ORTHOFRONT_CARRY:-.gpu-carry}
[[ -f $carry/orthofront-deps.tar.xz ]] || { echo "gpu-build: $carry/orthofront-deps.tar.xz missing (run tools/gpu-carry.sh where the Debian packages are)" >&2; exit 1; }
tar -xJf "$carry/orthofront-deps.tar.xz" -P --skip-old-files
ldconfig
# Packages the machine has in another major version (Catch2 3 where the tests use Catch2 2) are
# taken from a copy under /opt/orthofront-deps.
mkdir -p /opt/orthofront-deps
tar -xJf "$carry/orthofront-deps.tar.xz" -C /opt/orthofront-deps --wildcards '/usr/lib/cmake/Catch2/*' '/usr/include/catch2/*' '/usr/lib/libCatch2*' 2>/dev/null ||
  tar -xJf "$carry/orthofront-deps.tar.xz" -C /opt/orthofront-deps
catch2=(-DCatch2_DIR=/opt/orthofront-deps/usr/lib/cmake/Catch2)
generator=(); command -v ninja >/dev/null && generator=(-G Ninja)
# The Boost that OpenVDB was built with, where the machine has another one (its config first).
boost=(); [[ -d /usr/lib/x86_64-linux-gnu/cmake/Boost-1.74.0 ]] && boost=(-DBoost_DIR=/usr/lib/x86_64-linux-gnu/cmake/Boost-1.74.0)
cmake -S . -B "$build" "${generator[@]}" "${boost[@]}" "${catch2[@]}" -DCMAKE_BUILD_TYPE=Release -DORTHOFRONT_CUDA=ON -DORTHOFRONT_MPI=OFF -DORTHOFRONT_NETCDF=OFF \
  -DCMAKE_CUDA_ARCHITECTURES="${CUDA_ARCHITECTURES:-90}"
cmake --build "$build" -j"$(nproc)" --target orthofront orthofront-bench lib_test_cuda_advector lib_test_batch_advector \
  spacetime_test_cuda_path_surface spacetime_test_bulk_front_advance lib_test_cuda_stream_surface \
  lib_test_merging_advector
"$build"/tests/lib_test_batch_advector
"$build"/tests/lib_test_merging_advector
"$build"/tests/spacetime_test_bulk_front_advance
"$build"/tests/lib_test_cuda_advector "$@"
"$build"/tests/spacetime_test_cuda_path_surface "$@"
"$build"/tests/lib_test_cuda_stream_surface "$@"
