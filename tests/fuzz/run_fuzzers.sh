#!/usr/bin/env bash
# usage: run_fuzzers.sh SOURCE_DIR FUZZ_BUILD_DIR SECONDS
# Builds the libFuzzer targets with clang (ASan + UBSan) and runs each reader's
# fuzzer for SECONDS on a copy of its seed corpus. Fails on any finding.
set -euo pipefail
src=$1 out=$2 seconds=${3:-30}
cxx=$(command -v clang++ || command -v clang++-14 || true)
if [[ -z "$cxx" ]]; then
  echo "fuzz: clang++ is required (scripts/setup.sh installs it)" >&2
  exit 1
fi
cmake -S "$src" -B "$out" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCURVEMESH_BUILD_FUZZ=ON >"$out.configure.log" 2>&1 || { cat "$out.configure.log"; exit 1; }
cmake --build "$out" -j2 >"$out.build.log" 2>&1 || { tail -50 "$out.build.log"; exit 1; }
status=0
for reader in msh medit sol; do
  corpus="$out/corpus_$reader"
  rm -rf "$corpus" && mkdir -p "$corpus"
  cp "$src/tests/fuzz/seeds/$reader/"* "$corpus/"
  echo "fuzz: $reader for ${seconds}s"
  if ! (cd "$out" && "$out/tests/fuzz/fuzz_$reader" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
        -max_len=65536 -print_final_stats=1 "$corpus" >"$out/fuzz_$reader.log" 2>&1); then
    echo "fuzz: $reader FAILED" >&2
    tail -60 "$out/fuzz_$reader.log" >&2
    status=1
  else
    grep -E 'stat::number_of_executed_units|Done' "$out/fuzz_$reader.log" | tail -2
  fi
done
exit $status
