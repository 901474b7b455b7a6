#!/usr/bin/env bash
# Packs what a CUDA build of orthofront needs on a machine that has CUDA, CMake and a compiler but
# none of the project's Debian libraries (the GPU machine): the headers the build includes (found
# by the compiler itself, -M over compile_commands.json), the shared libraries the binaries load,
# and the CMake package files. Run here, after a configured build; then on the GPU machine
# `bash tools/gpu-build.sh` unpacks it and builds with CUDA.
#   usage: tools/gpu-carry.sh [BUILD_DIR=build] [OUT=.gpu-carry]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=${2:-.gpu-carry}
[[ -f $build/compile_commands.json ]] || { echo "gpu-carry: $build/compile_commands.json missing: configure and build first" >&2; exit 1; }
# The libraries are found by ldd on these binaries: OpenVDB's only through the tests that read it.
for bin in apps/orthofront tests/io_test_vdb tests/io_test_exr_front_image; do
  [[ -x $build/$bin ]] || { echo "gpu-carry: $build/$bin missing: build everything first (ninja -C $build)" >&2; exit 1; }
done
mkdir -p "$out"
list=$(mktemp)
trap 'rm -f "$list"' EXIT

# Headers: what every C++ compile of the project includes, outside the compiler's and libc's own
# (kept in $out/headers.txt: the scan preprocesses every source once).
headers=$out/headers.txt
if [[ ! -s $headers || $build/compile_commands.json -nt $headers ]]; then
python3 - "$build/compile_commands.json" >"$headers.tmp" <<'PY'
import json, shlex, subprocess, sys, os
skip = ("/usr/include/c++/", "/usr/include/x86_64-linux-gnu/", "/usr/lib/gcc/", "/work/")
libc = set(subprocess.run(["dpkg", "-L", "libc6-dev", "linux-libc-dev"], capture_output=True,
                          text=True).stdout.split())
from concurrent.futures import ThreadPoolExecutor
def scan(entry):
    args = shlex.split(entry["command"])
    if "-o" in args:
        i = args.index("-o")
        del args[i:i + 2]
    return subprocess.run(args + ["-M", "-MF", "/dev/stdout", "-o", "/dev/null"],
                          cwd=entry["directory"], capture_output=True, text=True).stdout
entries = [e for e in json.load(open(sys.argv[1])) if e["file"].endswith(".cpp")]
seen = set()
with ThreadPoolExecutor(os.cpu_count()) as pool:
    for deps in pool.map(scan, entries):
        for token in deps.replace("\\\n", " ").split():
            if token.endswith(":") or not token.startswith("/usr/"):
                continue
            path = os.path.realpath(token)
            if path.startswith(skip) or token in libc or path in libc:
                continue
            seen.add(token)
            seen.add(path)
print("\n".join(sorted(seen)))
PY
mv "$headers.tmp" "$headers"
fi
cat "$headers" >>"$list"

# Shared libraries the binaries load (not glibc's or the compiler's), with their .so links.
for bin in "$build"/apps/orthofront "$build"/tests/io_test_vdb "$build"/tests/io_test_exr_front_image; do
  ldd "$bin" | awk '/=> \//{print $3}'
done | sort -u | grep -v -E '/(libc|libm|libdl|librt|libpthread|libgcc_s|libstdc\+\+|ld-linux[^/]*)\.so' \
  | grep -v "/work/" | while read -r lib; do
    echo "$lib"
    real=$(readlink -f "$lib"); echo "$real"
    stem=$(basename "$lib" | sed -E 's/\.so(\..*)?$//')
    for link in /usr/lib/x86_64-linux-gnu/"$stem".so /lib/x86_64-linux-gnu/"$stem".so; do
      if [[ -e $link ]]; then echo "$link"; fi
    done
  done >>"$list"

# CMake package files and the HDF5 compiler wrapper FindHDF5 asks for its flags.
for d in /usr/lib/x86_64-linux-gnu/cmake/{TBB,Imath,OpenEXR,OpenVDB,tomlplusplus} \
         /usr/lib/x86_64-linux-gnu/cmake/Boost-1.74.0 /usr/lib/x86_64-linux-gnu/cmake/boost_*-1.74.0 \
         /usr/lib/x86_64-linux-gnu/cmake/BoostDetectToolset-1.74.0.cmake \
         /usr/lib/cmake/Catch2 /usr/share/cmake/CLI11 /usr/share/cmake/nlohmann_json \
         /usr/share/eigen3/cmake /usr/lib/x86_64-linux-gnu/hdf5/serial /usr/lib/x86_64-linux-gnu/pkgconfig/hdf5*.pc \
         /usr/lib/x86_64-linux-gnu/pkgconfig/blosc.pc; do
  if [[ -e $d ]]; then find "$d" \( -type f -o -type l \); fi
done >>"$list"
# Libraries the package files name (TBB's targets name tbbmalloc too), with their .so links.
grep -h -o -E '(\$\{_IMPORT_PREFIX\}|/usr)/lib/(x86_64-linux-gnu/)?lib[A-Za-z0-9_.+-]*\.(so[0-9.]*|a)' \
    $(grep -E '\.cmake$' "$list" | sort -u) 2>/dev/null | sed 's|${_IMPORT_PREFIX}|/usr|' | sort -u |
  while read -r lib; do
    if [[ -e $lib ]]; then echo "$lib"; readlink -f "$lib"; fi
  done >>"$list.libs"
cat "$list.libs" >>"$list"; rm -f "$list.libs"
for w in /usr/bin/h5cc; do if [[ -e $w ]]; then echo "$w"; readlink -f "$w"; fi; done >>"$list"
# The library links the HDF5 folder points to.
find /usr/lib/x86_64-linux-gnu/hdf5/serial -type l -exec readlink -f {} \; >>"$list"

sort -u "$list" | grep -v '^$' >"$out/files.txt"
tar -cJf "$out/orthofront-deps.tar.xz" -P -T "$out/files.txt"
echo "gpu-carry: $(wc -l <"$out/files.txt") files, $(du -h "$out/orthofront-deps.tar.xz" | cut -f1) in $out/orthofront-deps.tar.xz"
