#!/usr/bin/env bash
# Installs the dependencies, builds curvemesh and runs it on the bundled
# example: a second-order Gmsh mesh of a torus. `check` certifies every
# curved element; `convert` writes it for ParaView.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j2 --target curvemesh
mkdir -p out
set +e
build/curvemesh check examples/torus_p2.msh --json out/torus_p2_check.json
check_status=$?
set -e
build/curvemesh convert examples/torus_p2.msh out/torus_p2.vtu
build/curvemesh convert examples/torus_p2.msh out/torus_p2_binary.msh --binary
echo
echo "check exit code: $check_status (0 valid, 1 invalid: Gmsh's P2 elements that fold are listed above)"
echo "outputs: $(pwd)/out/torus_p2_check.json  $(pwd)/out/torus_p2.vtu  $(pwd)/out/torus_p2_binary.msh"
