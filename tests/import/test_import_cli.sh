#!/usr/bin/env bash
# `testbed import` end to end: help, usage errors (exit 2), a model that
# cannot be read (exit 1, the model named in the message, nothing written),
# and good imports that `testbed check` accepts.
set -u
tb=${TESTBED:?}
src=${TB_SOURCE_DIR:?}
models=${TB_ASSIMP_MODELS:-/usr/share/assimp/models}
w=${TB_TEST_TMPDIR:-/tmp}/import-cli
rm -rf "$w" && mkdir -p "$w" || exit 1
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# expect STATUS STDERR-SUBSTRING -- ARGS...: runs testbed with ARGS.
expect() {
  local want=$1 text=$2
  shift 3
  "$tb" "$@" >"$w/stdout" 2>"$w/stderr"
  local got=$?
  [[ $got == "$want" ]] || fail "testbed $*: exit $got, expected $want ($(head -c 300 "$w/stderr"))"
  if [[ -n $text ]] && ! grep -qF -- "$text" "$w/stderr" "$w/stdout"; then
    fail "testbed $*: output lacks '$text': $(head -c 300 "$w/stderr")"
  fi
}

expect 0 "usage: testbed import MODEL -o OUT.mid" -- import --help
expect 0 "usage: testbed import" -- help import
grep -q "import" <("$tb" help) || fail "testbed help does not list import"
expect 2 "no MODEL given" -- import
expect 2 "no output given" -- import "$models/OBJ/box.obj"
expect 2 "-o: missing value OUT.mid" -- import "$models/OBJ/box.obj" -o
expect 2 "unknown option '--bogus'" -- import --bogus "$models/OBJ/box.obj" -o "$w/x.mid"
expect 2 "unexpected argument 'b.obj'" -- import a.obj b.obj -o "$w/x.mid"
expect 2 "cannot go to standard output" -- import "$models/OBJ/box.obj" -o -

mkdir -p "$w/out"
expect 1 "testbed import: error: $w/none.obj: No such file or directory" -- import "$w/none.obj" -o "$w/out/x.mid"
printf 'not a model\n' >"$w/junk.xyz"
expect 1 "testbed import: error: $w/junk.xyz: Assimp cannot read it" -- import "$w/junk.xyz" -o "$w/out/x.mid"
[[ -z $(ls -A "$w/out") ]] || fail "failed imports left files: $(ls -A "$w/out")"

# Good imports, checked by `testbed check`; warnings go to stderr, the summary to stdout.
expect 0 "" -- import "$models/OBJ/spider.obj" -o "$w/out/spider.mid"
grep -q "19 objects" "$w/stdout" || fail "spider summary: $(cat "$w/stdout")"
grep -q "testbed import: warning: mesh 'Zahn'" "$w/stderr" || fail "spider: no warning about degenerate faces"
expect 0 "valid MID" -- check "$w/out/spider.mid"
expect 0 "" -- import -q --binary-fed --triangulate "$src/tests/import/data/scene.gltf" -o "$w/out/scene.mid"
[[ ! -s $w/stdout && ! -s $w/stderr ]] || fail "--quiet printed something"
[[ -f $w/out/scene.data/mesh-0.fedb ]] || fail "--binary-fed: no mesh-0.fedb"
expect 0 "lights: 3" -- check "$w/out/scene.mid"
expect 0 "" -- import -q "$models/STL/Spider_binary.stl" -o "$w/out/stl.mid"
expect 0 "valid MID" -- check "$w/out/stl.mid"

[[ $fails == 0 ]] && rm -rf "$w" && echo "import cli ok"
exit $((fails > 0))
