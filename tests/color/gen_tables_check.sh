#!/usr/bin/env bash
# The build-time table generator (util/color/gen_color_tables.cmake) copies a
# good CSV number for number and refuses malformed ones with file:line.
#   gen_tables_check.sh CMAKE SOURCE_DIR
set -u
cmake=$1
gen=$2/util/color/gen_color_tables.cmake
tmp=$(mktemp -d "${TB_TEST_TMPDIR:-/tmp}/gen_tables.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
bad=0

run() { # run NAME CSV-TEXT -> exit status, output in $tmp/NAME.log
  printf '%s' "$2" > "$tmp/$1.csv"
  "$cmake" -DOUT_C="$tmp/$1.c" -DOUT_H="$tmp/$1.h" "-DTABLES=t=$tmp/$1.csv" -P "$gen" \
    > "$tmp/$1.log" 2>&1
}
expect_fail() { # expect_fail NAME CSV-TEXT MESSAGE
  if run "$1" "$2"; then
    echo "FAIL $1: accepted"; bad=1
  elif ! tr -s ' \n' '  ' < "$tmp/$1.log" | grep -qF -- "$3"; then # CMake wraps messages
    echo "FAIL $1: message lacks '$3':"; cat "$tmp/$1.log"; bad=1
  else
    echo "ok   $1"
  fi
}

if run good $'# comment, with commas\nlambda_nm,a\n380,0.5\n385,1e-3\n390,-2.25\n'; then
  if grep -qF 'const double tb__t_a[TB__T_COUNT] = {0.5, 1e-3, -2.25, };' "$tmp/good.c" &&
     grep -qF '#define TB__T_COUNT 3' "$tmp/good.h"; then
    echo "ok   good"
  else
    echo "FAIL good: unexpected output"; cat "$tmp/good.c" "$tmp/good.h"; bad=1
  fi
else
  echo "FAIL good: rejected"; cat "$tmp/good.log"; bad=1
fi
expect_fail equal $'lambda_nm,a\n380,1\n385,1\n385,2\n' 'equal.csv:4: 385 does not increase'
expect_fail decreasing_msg $'lambda_nm,a\n380,1\n385,1\n384.5,2\n' 'does not increase'
expect_fail number $'lambda_nm,a\n380,1\n385,1.0.0\n' "'1.0.0' is not a number"
expect_fail nan $'lambda_nm,a\n380,1\n385,nan\n' "'nan' is not a number"
expect_fail fields $'lambda_nm,a\n380,1\n385\n' '1 fields, the header has 2'
expect_fail header $'lambda nm,a\n380,1\n385,2\n' 'is not a C identifier'
expect_fail short $'lambda_nm,a\n380,1\n' 'fewer than two rows'
exit $bad
