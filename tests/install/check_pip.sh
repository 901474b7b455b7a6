#!/usr/bin/env bash
# `pip install` of the source tree into a fresh virtual environment, offline (Debian's pip and
# setuptools, numpy from the system), then the package used from there as a user would.
#   usage: check_pip.sh SOURCE_DIR PYTHON
set -euo pipefail
source=$1 python=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$python" -m venv --system-site-packages "$work/venv"
# A copy of the tracked files: the install's build folders stay out of the checkout under test.
mkdir -p "$work/src"
(cd "$source" && git ls-files -z | xargs -0 cp --parents -t "$work/src")
ORTHOFRONT_CMAKE_ARGS="${ORTHOFRONT_CMAKE_ARGS:--DORTHOFRONT_CUDA=OFF -DORTHOFRONT_MPI=OFF}" \
  "$work/venv/bin/pip" install --no-build-isolation --no-index --no-deps "$work/src" \
  >"$work/pip.log" 2>&1 || { tail -50 "$work/pip.log" >&2; exit 1; }
cd "$work"
"$work/venv/bin/python" - "$work/venv" <<'PY'
import sys
import orthofront
assert orthofront.__file__.startswith(sys.argv[1]), orthofront.__file__
surface = orthofront.stream_surface("sinus", "line:-1,0,0:1,0,0", steps=5, edge=0.1)
assert len(surface.faces) > 0
streak = orthofront.streak_surface("double-gyre", "line:0.3,0.3,0:0.3,0.45,0", release="0:1",
                                   frames="1", edge=0.03)
assert len(streak) == 1 and len(streak[0].faces) > 0
print("pip:", orthofront.__file__, len(surface.vertices), "vertices")
PY
echo "check_pip: installed by pip into $work/venv and used from there"
