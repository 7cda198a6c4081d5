#!/usr/bin/env bash
# Fuzzes the readers of user files (case and law JSON, CSV curves, HDF5
# results) with libFuzzer, under AddressSanitizer and UndefinedBehaviorSanitizer,
# and runs the modules' tests under the same sanitizers (those that run in
# process: the ones that drive the gabion binary are left out, this build has none).
#   scripts/fuzz.sh [SECONDS] [--h5]   (per target; default 10: the bounded
#                                       CI run. A longer run: scripts/fuzz.sh 600 --h5)
# The HDF5 target mutates its inputs only with --h5: mutated HDF5 files reach
# bugs inside the HDF5 library itself (docs/hard-cases.md); without it, it
# reads its seed files once, a regression check of our readers.
# Builds into build-fuzz/ with clang (installed if missing); seeds each
# target with the project's own files; a crash, a hang (> 10 s on one input),
# a leak or a sanitizer report fails it, the input kept in build-fuzz/findings/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=10 mutate_h5=0
for a in "$@"; do
  case $a in
    --h5) mutate_h5=1 ;;
    *[!0-9]*) echo "usage: scripts/fuzz.sh [SECONDS] [--h5]" >&2; exit 2 ;;
    *) seconds=$a ;;
  esac
done
if ! command -v clang++ >/dev/null; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends clang >/dev/null
fi
dir=build-fuzz
# (-Wno-pass-failed: clang cannot vectorise some `omp simd` loops once instrumented; not a fault)
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -Wno-pass-failed"
# (line tables are all a sanitizer's report needs, and compile sooner than -g)
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
  -DCMAKE_CXX_FLAGS="$flags" -DGABION_FUZZ=ON -DGABION_BUILD_BENCH=OFF -DGABION_NATIVE=OFF >/dev/null
cmake --build "$dir" -j "$(nproc)" --target fuzz_case_json fuzz_law_file fuzz_curve_csv fuzz_curve_h5 test_bridge \
  test_macro test_micro test_fitting >/dev/null
# (allocator_may_return_null: as without ASan, a huge allocation that a corrupt
# HDF5 header asks for fails, and HDF5 reports an error the reader turns into
# an InputError)
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# (HDF5 keeps some allocations until exit by design: not ours)
export LSAN_OPTIONS=suppressions=$PWD/fuzz/lsan.supp

echo "bridge, macro, micro and fitting tests under ASan + UBSan"
"$dir"/tests/test_bridge --gtest_brief=1
# (left out: the tests that drive the gabion binary, which this build has
# not; MicroDeterminism's pinned hash, which is the GCC build's bits; and
# one netting equilibrium of a minute without sanitizers' slowdown)
"$dir"/tests/test_macro --gtest_brief=1 --gtest_filter=-MacroCli.*:MacroCases.*:MacroDefaultWall.*
micro_cli=MicroCell.*:CellFile.*:MicroCheckpoint.AKilled*:MicroLab.*:NettingScene.*:NettingTensile.*:MicroSceneCli.*
micro_cli=$micro_cli:NettingEngine.DrivenWire*:Porosity.SceneReports*:BlockFill.SceneReports*:Grading.BadTables*
"$dir"/tests/test_micro --gtest_brief=1 \
  --gtest_filter=-$micro_cli:MicroDeterminism.*:NettingEngine.ClosedBoxHangingFromItsTopFaceReachesEquilibrium
"$dir"/tests/test_fitting --gtest_brief=1 --gtest_filter=-FitCli.*:FitMacro.*

seeds() {  # target -> seed folder, filled with the project's own files of that type
  local d=$dir/seeds/$1
  rm -rf "$d" && mkdir -p "$d"
  case $1 in
    fuzz_case_json) cp cases/*.json cases/hard/*.json "$d"/ ;;
    fuzz_law_file) cp cases/laws/*.json cases/data/fit/illustrative_law.json "$d"/ ;;
    fuzz_curve_csv) cp cases/data/fit/*.csv "$d"/ ;;
    # (the result files the test suite's smoke runs left in the build folders)
    fuzz_curve_h5) find build* -maxdepth 6 -name 'result.h5' -size -4M 2>/dev/null | sort | head -20 |
                     while read -r f; do cp "$f" "$d/$(echo "$f" | tr / _)"; done ;;
  esac
  echo "$d"
}
mkdir -p "$dir/findings"
status=0
for t in fuzz_case_json fuzz_law_file fuzz_curve_csv fuzz_curve_h5; do
  echo "$t: $seconds s"
  corpus=$dir/corpus/$t
  mkdir -p "$corpus"
  budget=(-max_total_time="$seconds")
  [ "$t" = fuzz_curve_h5 ] && [ "$mutate_h5" = 0 ] && budget=(-runs=0) && echo "  (seeds only: --h5 mutates)"
  if ! "$dir/fuzz/$t" "$corpus" "$(seeds "$t")" "${budget[@]}" -timeout=10 -rss_limit_mb=2048 \
       -artifact_prefix="$dir/findings/$t-" -print_final_stats=1 2>"$dir/$t.log"; then
    echo "$t: FAILED (input and log: $dir/findings/, $dir/$t.log)"
    tail -40 "$dir/$t.log"
    status=1
  else
    grep -E 'stat::number_of_executed_runs|cov:' "$dir/$t.log" | tail -2 | tr '\n' ' '
    echo
  fi
done
exit $status
