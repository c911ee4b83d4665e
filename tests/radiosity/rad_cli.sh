# Shell helpers shared by the radiosity script tests. Sourced after setting
# NAME (the scratch folder's name): NAME=radiosity_cli; . "$TB_SOURCE_DIR/tests/radiosity/rad_cli.sh"
# Gives $T (a fresh scratch folder, the caller removes it when it passes),
# $FURNACE (the white furnace scene), fail MESSAGE (prints it, exits 1) and
# rad ARGS... (`testbed render --method radiosity ARGS...`).
T="${TB_TEST_TMPDIR:-/tmp}/$NAME.$$"
rm -rf "$T" && mkdir -p "$T"
FURNACE="$TB_SOURCE_DIR/tests/radiosity/furnace.mid"
fail() { echo "FAIL: $*"; exit 1; }
rad() { "$TESTBED" render --method radiosity "$@"; }
