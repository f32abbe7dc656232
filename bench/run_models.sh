#!/usr/bin/env bash
# Volume-meshes every shared model at the default size, a coarse hmax
# (bounding-box diagonal / 8) and a fine one (diagonal / 35), and prints one
# line per run: tets, time (total, and of the quality optimization),
# validity, Steiner points and volume flips of recovery, quality. The issue's
# "every model, default + coarse + fine" check, comparable run to run.
#
# usage: bench/run_models.sh [BUILD_DIR] [MODELS_DIR] [extra curvemesh mesh options...]
set -uo pipefail
build=${1:-build}
models=${2:-../shared/models}
shift 2 2>/dev/null || shift $#
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-40s %-8s %10s %9s %8s %8s %6s %8s %6s %8s %8s %8s\n' model size hmax tets seconds opt_s valid steiner vflips minq meanq mindih
fail=0
for f in "$models"/*.st[ep]* "$models"/*.ig[es]* "$models"/*.brep; do
  [ -f "$f" ] || continue
  name=$(basename "$f")
  "$build/curvemesh" info "$f" --json "$tmp/info.json" >/dev/null 2>&1 || { echo "$name: info failed"; fail=1; continue; }
  diag=$(python3 -c "import json,math;b=json.load(open('$tmp/info.json'))['bounding_box'];print(math.dist(b['min'],b['max']))")
  for size in default coarse fine; do
    case $size in
      default) opt=() ;;
      coarse) opt=(--hmax "$(python3 -c "print($diag/8)")") ;;
      fine) opt=(--hmax "$(python3 -c "print($diag/35)")") ;;
    esac
    rm -f "$tmp/m.json"
    if "$build/curvemesh" mesh "$f" "${opt[@]}" "$@" --json "$tmp/m.json" -o "$tmp/out.msh" >"$tmp/log" 2>&1; then
      python3 - "$tmp/m.json" "$name" "$size" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
r, q = d["recovery"], d["quality"]
print(f'{sys.argv[2]:40s} {sys.argv[3]:8s} {d["hmax"]:10.4g} {d["counts"]["tets"]:9d} {d["seconds"]["total"]:8.2f} '
      f'{d["seconds"]["optimize"]:8.2f} '
      f'{str(d["check"]["valid"]):>6s} {r["steiner_on_model_edges"] + r["steiner_on_model_faces"]:8d} '
      f'{r["volume_flips"]:6d} '
      f'{q["mean_ratio_min"]:8.3f} {q["mean_ratio_mean"]:8.3f} {q["min_dihedral_deg"]:8.2f}')
EOF
    else
      printf '%-40s %-8s FAILED: %s\n' "$name" "$size" "$(tail -1 "$tmp/log" | cut -c1-160)"
      fail=1
    fi
  done
done
exit $fail
