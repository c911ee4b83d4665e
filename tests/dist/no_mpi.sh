#!/bin/sh
# A build without MPI asked to run as one of several ranks (the environment
# mpirun gives its processes) refuses with a clear message and exit 1, and
# writes nothing; as one rank it renders.
#   no_mpi.sh  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
fail() { echo "FAIL: $*"; exit 1; }
T="${TB_TEST_TMPDIR:-/tmp}/dist_no_mpi.$$"
rm -rf "$T" && mkdir -p "$T"
sed 's/resolution = \[512 512\]/resolution = [16 16]/' "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" > "$T/box.mid"
OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=0 "$TESTBED" render "$T/box.mid" -o "$T/a.pfm" > "$T/out" 2>&1
rc=$?
[ $rc = 1 ] || { cat "$T/out"; fail "exit $rc, expected 1"; }
grep -q "built without MPI" "$T/out" || { cat "$T/out"; fail "no message"; }
[ ! -e "$T/a.pfm" ] || fail "an image was written"
OMPI_COMM_WORLD_SIZE=1 "$TESTBED" render "$T/box.mid" -o "$T/a.pfm" > "$T/out" 2>&1 || { cat "$T/out"; fail "one rank"; }
rm -rf "$T"
echo "dist no mpi: ok"
