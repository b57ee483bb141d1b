#!/usr/bin/env bash
# Builds the libFuzzer targets (the `fuzz` preset: clang, ASan + UBSan) and runs each of them.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]
#
# SECONDS per target (default 60); TARGETs are fuzz/<name>_fuzz.cpp stems (default: all). Each
# target keeps its corpus in <build>/corpus/<target>, seeded from fuzz/seeds/<target>/ and, where
# fuzz/seeds/<target>.shared lists them, from files of the shared test data (copied at run time,
# never into the repository). A fuzz/<target>.dict is passed as the dictionary. Crash inputs land
# in <build>/artifacts/<target>/. Exits non-zero if any target finds a crash, leak or timeout
# (a unit running longer than FUZZ_TIMEOUT s), or a slow unit (longer than FUZZ_SLOW_UNIT_S s:
# a hostile input that stalls a parser is a defect even when it ends).
#
# Environment: FUZZ_BUILD_DIR (default build/fuzz), FUZZ_JOBS (build jobs, default nproc),
# LIVOD_DATA_DIR (default ../shared/data), FUZZ_TIMEOUT (default 10), FUZZ_SLOW_UNIT_S (default 1).
set -euo pipefail
cd "$(dirname "$0")/.."

usage() {
  sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
}

seconds=60
if (($# > 0)); then
  [[ $1 == -h || $1 == --help ]] && usage
  if [[ $1 =~ ^[0-9]+$ ]]; then
    seconds=$1
    shift
  fi
fi
build_dir=${FUZZ_BUILD_DIR:-build/fuzz}
jobs=${FUZZ_JOBS:-$(nproc)}
data_dir=${LIVOD_DATA_DIR:-../shared/data}
timeout_s=${FUZZ_TIMEOUT:-10}
slow_unit_s=${FUZZ_SLOW_UNIT_S:-1}

targets=("$@")
if ((${#targets[@]} == 0)); then
  for f in fuzz/*_fuzz.cpp; do
    targets+=("$(basename "$f" .cpp)")
  done
fi
for t in "${targets[@]}"; do
  if [[ ! -f fuzz/$t.cpp ]]; then
    echo "fuzz.sh: no fuzz target '$t' (expected fuzz/$t.cpp)" >&2
    exit 2
  fi
done

echo "== configure + build ${targets[*]} in $build_dir"
cmake --preset fuzz -B "$build_dir" >/dev/null
cmake --build "$build_dir" -j "$jobs" --target "${targets[@]}"

failed=()
summary=()
for t in "${targets[@]}"; do
  corpus="$build_dir/corpus/$t"
  artifacts="$build_dir/artifacts/$t"
  mkdir -p "$corpus" "$artifacts"
  if [[ -d fuzz/seeds/$t ]]; then
    cp -n fuzz/seeds/"$t"/* "$corpus"/ 2>/dev/null || true
  fi
  if [[ -f fuzz/seeds/$t.shared ]]; then
    while read -r rel; do
      [[ -z $rel || $rel == \#* ]] && continue
      if [[ -f $data_dir/$rel ]]; then
        cp -n "$data_dir/$rel" "$corpus/shared-$(basename "$rel")" 2>/dev/null || true
      else
        echo "fuzz.sh: note: seed $data_dir/$rel not found, skipped" >&2
      fi
    done <"fuzz/seeds/$t.shared"
  fi
  args=(-max_total_time="$seconds" -timeout="$timeout_s" -report_slow_units="$slow_unit_s"
    -print_final_stats=1 -artifact_prefix="$artifacts/")
  if [[ -f fuzz/$t.dict ]]; then
    args+=(-dict="fuzz/$t.dict")
  fi
  log="$build_dir/$t.log"
  echo "== $t: ${seconds} s, corpus $corpus ($(find "$corpus" -type f | wc -l) files)"
  status=0
  slow_before=$(find "$artifacts" -name 'slow-unit-*' | wc -l)
  "$build_dir/fuzz/$t" "${args[@]}" "$corpus" >"$log" 2>&1 || status=$?
  # libFuzzer only reports slow units (it writes them as slow-unit-* artifacts): fail on them.
  slow_after=$(find "$artifacts" -name 'slow-unit-*' | wc -l)
  if ((status == 0 && slow_after > slow_before)); then
    status=3
    echo "fuzz.sh: $t: a unit ran longer than ${slow_unit_s} s (see $artifacts/slow-unit-*)" >&2
  fi
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -1 | cut -d' ' -f2)
  files=$(find "$corpus" -type f | wc -l)
  line=$(printf '%-24s %-6s execs %-10s (%s/s)  cov %-6s corpus %s' "$t" \
    "$([[ $status -eq 0 ]] && echo ok || echo FAIL)" "${execs:-?}" "${rate:-?}" "${cov:-?}" "$files")
  summary+=("$line")
  if ((status != 0)); then
    failed+=("$t")
    echo "fuzz.sh: $t failed (exit $status); log: $log; artifacts: $artifacts" >&2
    grep -E 'ERROR|SUMMARY|Test unit written|Slowest unit|slow-unit' "$log" >&2 || tail -20 "$log" >&2
  fi
done

echo "== summary (${seconds} s per target)"
printf '%s\n' "${summary[@]}"
if ((${#failed[@]} > 0)); then
  echo "fuzz.sh: FAILED: ${failed[*]}" >&2
  exit 1
fi
