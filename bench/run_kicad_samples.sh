#!/usr/bin/env bash
# More models nothing was tuned on: one STEP file from each of 45 library
# folders of Debian's kicad-packages3d (electronic parts: connectors,
# packages, relays, heatsinks), picked at random with a fixed seed so runs
# compare, each volume-meshed at the default, a coarse and a fine size by
# bench/run_models.sh. The package is 379 MB and is not installed: its .deb
# is downloaded once into CACHE_DIR and the picked files extracted from it.
# At stop 29 they showed an invalid mesh (a 5 um wire), a 16 GB runaway (a
# face crossing itself) and a healing that dropped 50 of a part's 53 faces.
#
# usage: bench/run_kicad_samples.sh [BUILD_DIR] [CACHE_DIR] [extra curvemesh mesh options...]
# Each run is limited to 16 GB of address space, so a runaway fails alone.
set -uo pipefail
build=$(cd "${1:-build}" && pwd)
cache=${2:-${XDG_CACHE_HOME:-$HOME/.cache}/curvemesh-kicad}
shift 2 2>/dev/null || shift $#
mkdir -p "$cache"
deb=$(ls "$cache"/kicad-packages3d_*_all.deb 2>/dev/null | head -1)
if [ -z "$deb" ]; then
  (cd "$cache" && apt-get download kicad-packages3d) || { echo "cannot download kicad-packages3d" >&2; exit 2; }
  deb=$(ls "$cache"/kicad-packages3d_*_all.deb | head -1)
fi
if [ ! -f "$cache/picked.txt" ]; then
  dpkg -c "$deb" | awk '{print $3, $6}' | grep -iE "\.(step|stp)$" > "$cache/listing.txt"
  python3 - "$cache/listing.txt" "$cache/picked.txt" <<'PY'
import collections, random, sys
random.seed(29)
by = collections.defaultdict(list)
for line in open(sys.argv[1]):
    size, path = line.split()
    if int(size) < 2_500_000:
        by[path.split('/')[-2]].append(path)
folders = sorted(by)
random.shuffle(folders)
open(sys.argv[2], 'w').write(''.join(random.choice(by[f]) + '\n' for f in folders[:45]))
PY
  mkdir -p "$cache/files"
  dpkg --fsys-tarfile "$deb" | tar -x -C "$cache/files" -T "$cache/picked.txt"
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
find "$cache/files" -iname "*.st*p" -exec ln -sf {} "$dir/" \;
ulimit -v 16000000
exec bash "$(dirname "$0")/run_models.sh" "$build" "$dir" "$@"
