#!/bin/sh
# `testbed bench rays` on an imported mesh: the height field of
# rays-heightfield.py (2 N^2 triangles, N = 250 by default: 125 000) written
# as OBJ, imported through Assimp by `testbed import` (a FED file), with the
# benchmark's camera, area light and sphere appended to the imported MID.
# Arguments go to `bench rays` (e.g. --embree --repeat 7 --no-stats).
#
#   TESTBED=build/release/testbed tools/bench/rays-imported.sh --embree --no-stats
#   HF_N=20 tools/bench/rays-imported.sh --rays 2000      (a small mesh)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
TESTBED=${TESTBED:-$here/../../build/release/testbed}
n=${HF_N:-250}
dir=$(mktemp -d "${TMPDIR:-/tmp}/rays-imported.XXXXXX")
trap 'rm -rf "$dir"' EXIT INT TERM
python3 "$here/rays-heightfield.py" --obj "$n" > "$dir/heightfield.obj"
"$TESTBED" import "$dir/heightfield.obj" -o "$dir/heightfield.mid"
python3 "$here/rays-heightfield.py" --rest >> "$dir/heightfield.mid"
"$TESTBED" bench rays "$dir/heightfield.mid" "$@"
