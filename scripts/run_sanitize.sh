#!/usr/bin/env bash
# `make test-sanitize`: builds the ROS-free core and every core gtest program
# with -fsanitize=address,undefined in a build directory of its own
# (test/sanitize/CMakeLists.txt, into $SEMEXP_SANITIZE_BUILD, default
# .colcon/sanitize) and runs them. Any sanitizer report fails the program
# (halt_on_error, -fno-sanitize-recover); leaks are reported too.
# Ends with "sanitize: N passed, N failed"; exits non-zero on any failure.
# Results (logs, gtest XML, exit_codes: one "name rc" line per program) go
# to $1 if given; scripts/run_tests.sh (make test) counts them with the rest.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${SEMEXP_SANITIZE_BUILD:-$ROOT/.colcon/sanitize}"
OUT="${1:-$BUILD/results}"
JOBS="${JOBS:-$(nproc)}"
START=$(date +%s)
mkdir -p "$BUILD" "$OUT"
: > "$OUT/exit_codes"
export PATH="/usr/bin:$PATH"
launcher=()
if command -v ccache > /dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
if ! { cmake -S "$ROOT/test/sanitize" -B "$BUILD" -DCMAKE_BUILD_TYPE=None "${launcher[@]}" \
         -DSEMEXP_WERROR="${SEMEXP_WERROR:-ON}" \
       && cmake --build "$BUILD" -j "$JOBS"; } > "$OUT/build.log" 2>&1; then
  tail -n 40 "$OUT/build.log"
  echo "sanitize: build failed (log: $OUT/build.log)"
  echo "build 1" >> "$OUT/exit_codes"
  echo "sanitize: 0 passed, 1 failed"
  exit 1
fi
echo "[sanitize] build done after $(( $(date +%s) - START )) s"
# detect_leaks needs ptrace-free LeakSanitizer; it is on by default where it works.
export ASAN_OPTIONS="halt_on_error=1:abort_on_error=0:detect_stack_use_after_return=1:strict_string_checks=1:check_initialization_order=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
# Every test case runs here; make test runs the core programs nowhere else.
# SEMEXP_SANITIZE_EXCLUDE leaves cases out (a gtest filter: A.b:C.*), for a
# quick local run. The slowest case, TsdfAccuracy.AMinimumWeightKeepsNoisy-
# ZeroCrossingsOutOfTheMesh (360 noisy frames), takes 45-60 s instrumented.
EXCLUDE="${SEMEXP_SANITIZE_EXCLUDE:-}"
filter=()
if [ -n "$EXCLUDE" ]; then filter=(--gtest_filter="-$EXCLUDE"); fi
run_one() {  # name: runs one program, appends "name rc" to exit_codes
  local name=$1 rc
  timeout 900 "$BUILD/$name" "${filter[@]}" --gtest_output="xml:$OUT/$name.xml" > "$OUT/$name.log" 2>&1
  rc=$?
  # A report always fails the program (halt_on_error); grep as well, in case one is printed at exit.
  if [ $rc -eq 0 ] && grep -q -e "ERROR: AddressSanitizer" -e "ERROR: LeakSanitizer" -e "runtime error:" \
       "$OUT/$name.log"; then rc=1; fi
  echo "$name $rc" >> "$OUT/exit_codes"
}
# JOBS programs at a time (most are single-threaded), the longest first
# (60-130 s each instrumented on the 2-core machine; most others take under
# 15 s), so that the last ones do not leave a lane idle at the end.
LONGEST="test_core_tsdf_accuracy test_core_object_map test_core_planning_lazy test_core_object_map_imperfect"
LONGEST+=" test_core_planning_closed_loop"
programs=()
for name in $LONGEST; do [ -f "$ROOT/test/core/${name#test_core_}_test.cpp" ] && programs+=("$name"); done
# One program per test/core/*_test.cpp (not a glob of the build directory,
# which keeps the programs of removed or renamed tests). A program the build
# did not produce counts as failed.
for src in "$ROOT"/test/core/*_test.cpp; do
  name=test_core_$(basename "$src" _test.cpp)
  [[ " $LONGEST " != *" $name "* ]] && programs+=("$name")
done
for name in "${programs[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n; done
  run_one "$name" &
done
wait
passed=0; failed=0
while read -r name rc; do
  if [ "$rc" -eq 0 ]; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    grep -m1 -A 30 -e "ERROR: AddressSanitizer" -e "ERROR: LeakSanitizer" -e "runtime error:" "$OUT/$name.log" \
      || tail -n 30 "$OUT/$name.log"
    echo "[sanitize] $name FAILED (log: $OUT/$name.log)"
  fi
done < "$OUT/exit_codes"
echo "[sanitize] total time $(( $(date +%s) - START )) s"
echo "sanitize: $passed passed, $failed failed"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
