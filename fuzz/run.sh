#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan) in build-fuzz/ and runs each for SECONDS
# (default 60), one after another, or the targets named after it:
#   fuzz/run.sh 1800                 every target, 30 minutes each
#   fuzz/run.sh 300 hdf5 vdb_file    two targets
# Corpora grow in build-fuzz/corpus/TARGET (seeded by make_corpus.sh); failing inputs land in
# build-fuzz/findings/TARGET/. Each run's figures are appended to build-fuzz/fuzz-runs.tsv, and a
# table of the totals per target is printed at the end. Exit status 1 when anything was found.
# Environment: JOBS (parallel fuzzing processes per target, default 1), ORTHOFRONT (a built
# orthofront for the seed corpus; default build/apps/orthofront, else built here).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
seconds="${1:-60}"
shift || true
all=(grid_vec grid_am grid_nrrd grid_nhdr grid_vti grid_vtk grid_vdb vdb_file hdf5 netcdf pvd
     mesh_vtp mesh_ply mesh_obj parse_seed parse_field parse_bytes job_file checkpoint)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")
build="$root/build-fuzz"
jobs="${JOBS:-1}"

if [ ! -f "$build/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S "$root" -B "$build" -DORTHOFRONT_FUZZ=ON \
    -DORTHOFRONT_BUILD_TESTS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
fi
cmake --build "$build" -j"$(nproc)" --target "${targets[@]/#/fuzz_}" >/dev/null

if [ ! -d "$build/corpus" ]; then
  bin="${ORTHOFRONT:-$root/build/apps/orthofront}"
  if [ ! -x "$bin" ]; then
    cmake --build "$build" -j"$(nproc)" --target orthofront >/dev/null
    bin="$build/apps/orthofront"
  fi
  ORTHOFRONT="$bin" "$root/fuzz/make_corpus.sh" "$build/corpus" >/dev/null
fi

log="$build/fuzz-runs.tsv"
[ -f "$log" ] || printf 'date\ttarget\tseconds\texecutions\tfindings\n' >"$log"
found=0
# A single allocation over 1000 MiB fails (std::bad_alloc) instead of ending the run, so that a
# reader that turns it into a message passes and one that lets it escape is a finding.
export ASAN_OPTIONS="allocator_may_return_null=1:max_allocation_size_mb=1000${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
for t in "${targets[@]}"; do
  mkdir -p "$build/corpus/$t" "$build/findings/$t"
  # slow-unit-* files are inputs that took over -report_slow_units seconds, not failures.
  before=$(find "$build/findings/$t" -type f ! -name 'slow-unit-*' | wc -l)
  out="$build/findings/$t.log"
  # Limits: 2 GiB resident, 1 GiB in one allocation (a reader must check sizes before allocating
  # them), 60 s per input (a hang: the child reads of OpenVDB and HDF5 files stop at 10 s). Findings do not stop the run (-fork keeps going).
  seeds=("$build/corpus/$t")
  [ -d "$root/fuzz/regressions/$t" ] && seeds+=("$root/fuzz/regressions/$t")
  "$build/fuzz/fuzz_$t" "${seeds[@]}" -fork="$jobs" \
    -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 -max_total_time="$seconds" \
    -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=60 -max_len=65536 \
    -artifact_prefix="$build/findings/$t/" >"$out" 2>&1 || true
  execs=$(grep -o 'exec/s: [0-9]*\|#[0-9]*' "$out" | grep -o '^#[0-9]*' | tail -1 | tr -d '#')
  after=$(find "$build/findings/$t" -type f ! -name 'slow-unit-*' | wc -l)
  new=$((after - before))
  [ "$new" -eq 0 ] || found=1
  printf '%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$t" "$seconds" "${execs:-0}" "$new" >>"$log"
done

echo "fuzz totals (all runs in $log):"
awk -F'\t' 'NR > 1 { s[$2] += $3; e[$2] += $4; f[$2] += $5 }
  END { printf "%-12s %10s %14s %9s\n", "target", "seconds", "executions", "findings";
        for (t in s) printf "%-12s %10d %14d %9d\n", t, s[t], e[t], f[t] }' "$log" | sort
[ "$found" -eq 0 ] || echo "new findings in $build/findings/ (see the .log beside each folder)"
exit "$found"
