#!/usr/bin/env bash
# Fails if an OpenCASCADE header is included anywhere in the library or CLI
# outside src/curvemesh/geom_occ/ (the one target allowed to see OCC).
set -euo pipefail
root=${1:-$(dirname "$0")/..}
pattern='#include *[<"](TopoDS|TopExp|TopAbs|TopLoc|TopTools|BRep|Geom|GeomAPI|GeomAbs|GeomLProp|gp_|Standard_|STEPControl|IGESControl|XSControl|ShapeFix|ShapeAnalysis|ShapeUpgrade|BOPAlgo|Bnd_|BRepAdaptor|Extrema|TColgp|TColStd|Precision|Interface_|IFSelect)'
offenders=$(grep -rlE "$pattern" "$root/src" "$root/cli" 2>/dev/null | grep -v '/src/curvemesh/geom_occ/' || true)
if [[ -n "$offenders" ]]; then
  echo "OpenCASCADE headers included outside src/curvemesh/geom_occ/:" >&2
  echo "$offenders" >&2
  exit 1
fi
echo "OCC headers confined to geom_occ"
