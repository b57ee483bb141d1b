#!/usr/bin/env bash
# Runs every livod test: installs dependencies, builds the release preset and runs all tests, then
# builds the ThreadSanitizer preset for the ring/thread/shutdown tests (label "threads") and runs
# them, then the AddressSanitizer + UndefinedBehaviorSanitizer preset for the bad-input suite
# (label "badinput": the livod binary on corrupt, truncated and hostile inputs). Exit status is
# non-zero if anything fails.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

./scripts/install-deps.sh

echo "== release build"
cmake --preset release >/dev/null
cmake --build --preset release -j "$jobs"
echo "== release tests"
ctest --preset release -j "$jobs"

echo "== tsan build (tests labelled 'threads')"
cmake --preset tsan >/dev/null
cmake --build --preset tsan -j "$jobs" --target livod_threads_tests
echo "== tsan tests"
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
  ctest --preset tsan -j "$jobs" -L threads

echo "== asan + ubsan build (the bad-input suite, label 'badinput': livod and its test only)"
cmake --preset asan >/dev/null
cmake --build --preset asan -j "$jobs" --target livod_badinput_tests
echo "== asan + ubsan tests"
ASAN_OPTIONS="detect_leaks=1 abort_on_error=0" UBSAN_OPTIONS="halt_on_error=1 print_stacktrace=1" \
  ctest --preset asan -j "$jobs" -L badinput
