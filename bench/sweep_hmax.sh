#!/usr/bin/env bash
# Meshes one model at each of a list of hmax values and prints, per run,
# tets, worst mean ratio and worst dihedral angle: how steady the worst
# element is under small changes of the size (a single hmax can hide a
# fragile feature; 917_fusee's cusp tips moved between 3 and 14 deg over
# hmax 0.011 .. 0.054 before the optimizer's relocation guard).
#
# usage: bench/sweep_hmax.sh BUILD_DIR MODEL HMAX... [-- extra curvemesh mesh options]
set -uo pipefail
build=$1 model=$2
shift 2
sizes=()
while (($#)) && [[ $1 != -- ]]; do sizes+=("$1"); shift; done
[[ ${1:-} == -- ]] && shift
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-10s %9s %8s %8s\n' hmax tets minq mindih
worst=180
for h in "${sizes[@]}"; do
  if "$build/curvemesh" mesh "$model" --hmax "$h" "$@" --json "$tmp/m.json" -o "$tmp/out.msh" >"$tmp/log" 2>&1; then
    line=$(python3 - "$tmp/m.json" "$h" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
q = d["quality"]
print(f'{sys.argv[2]:10s} {d["counts"]["tets"]:9d} {q["mean_ratio_min"]:8.3f} {q["min_dihedral_deg"]:8.2f}')
PY
)
    echo "$line"
    worst=$(python3 -c "print(min($worst, ${line##* }))")
  else
    printf '%-10s FAILED: %s\n' "$h" "$(tail -1 "$tmp/log" | cut -c1-160)"
  fi
done
echo "worst dihedral over the sweep: $worst deg"
