#!/usr/bin/env bash
# Installs a build into a temporary prefix and uses it there as a user would: the two programs,
# a CMake project that finds the package and links its libraries, and the Python package.
#   usage: check_install.sh BUILD_DIR SOURCE_DIR [PYTHON PYTHON_INSTALL_DIR]
set -euo pipefail
build=$1 source=$2 python=${3:-} python_dir=${4:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" >"$work/install.log"

# The programs run from the prefix, their libraries found beside them (not in the build tree).
"$prefix/bin/orthofront" fields | grep -q double-gyre
"$prefix/bin/orthofront-bench" --help | grep -q gpu-streak
for f in "$prefix"/bin/orthofront "$prefix"/lib*/liborthofront_*.so; do
  if readelf -d "$f" | grep -E 'R(UN)?PATH' | grep -q "$build"; then
    echo "check_install: $f still looks for libraries in the build tree $build" >&2
    exit 1
  fi
done
ldd "$prefix/bin/orthofront" | grep liborthofront_lib | grep -q "$prefix" ||
  { echo "check_install: the installed orthofront does not load the installed libraries" >&2; exit 1; }

# A consumer project: find_package(orthofront) and the three imported targets.
cmake -S "$source/tests/install/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release >"$work/consumer.log"
cmake --build "$work/consumer" >>"$work/consumer.log" ||
  { cat "$work/consumer.log" >&2; exit 1; }
"$work/consumer/consumer" "$work"

# The Python package from the prefix's site folder, not the build tree.
if [[ -n $python ]]; then
  PYTHONPATH="$prefix/$python_dir" "$python" - "$prefix" <<'PY'
import sys
import orthofront
assert orthofront.__file__.startswith(sys.argv[1]), orthofront.__file__
surface = orthofront.stream_surface("sinus", "line:-1,0,0:1,0,0", steps=5, edge=0.1)
assert len(surface.faces) > 0
print("python", orthofront.__file__, len(surface.vertices), "vertices")
PY
fi
# The compiled ParaView plugin, where it was built: loaded from the prefix through
# PV_PLUGIN_PATH, its libraries found there, and its filter run.
plugin=$(ls "$prefix"/lib*/paraview-plugins/OrthofrontSurfaces/OrthofrontSurfaces.so 2>/dev/null || true)
if [[ -n $plugin ]]; then
  if ldd "$plugin" | grep -q "not found"; then
    ldd "$plugin" >&2
    echo "check_install: the installed ParaView plugin misses libraries" >&2
    exit 1
  fi
  ldd "$(dirname "$plugin")/libOrthofrontFilters.so" | grep liborthofront_lib | grep -q "$prefix" ||
    { echo "check_install: the installed plugin does not load the installed libraries" >&2; exit 1; }
  if command -v pvbatch >/dev/null; then
    cat >"$work/plugin.py" <<'PY'
from paraview.simple import OrthofrontStreamSurface, Wavelet, Gradient
from paraview import servermanager
gradient = Gradient(Input=Wavelet(WholeExtent=[0, 8, 0, 8, 0, 8]), ScalarArray=["POINTS", "RTData"])
gradient.UpdatePipeline()
surface = OrthofrontStreamSurface(Input=gradient, Vectors=["POINTS", "Gradient"],
                                  SeedPoint1=[-4, 0, 0], SeedPoint2=[4, 0, 0], Steps=3)
surface.UpdatePipeline()
print("plugin", servermanager.Fetch(surface).GetNumberOfPoints(), "points")
PY
    PV_PLUGIN_PATH=$(dirname "$plugin") pvbatch "$work/plugin.py" >"$work/plugin.log" 2>&1 ||
      { cat "$work/plugin.log" >&2; exit 1; }
    grep -qE "^plugin [1-9][0-9]* points" "$work/plugin.log" ||
      { cat "$work/plugin.log" >&2; echo "check_install: the installed plugin made no surface" >&2; exit 1; }
  fi
fi
echo "check_install: installed into $prefix and used from there"
