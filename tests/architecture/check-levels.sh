#!/usr/bin/env bash
# Fails if a library source includes a module from a higher level
# (docs/architecture.md: a module uses only its own level or below).
set -u
root=${1:-${TB_SOURCE_DIR:?}}
cd "$root" || exit 2
bad=0
check() { # check FOLDER FORBIDDEN-REGEX
  local hits
  hits=$(grep -rnE "^[[:space:]]*#[[:space:]]*include[[:space:]]*[\"<]($2)" "$1" --include='*.c' --include='*.h' 2>/dev/null)
  if [[ -n "$hits" ]]; then
    echo "level violation: files in $1 may not include $2:"
    echo "$hits"
    bad=1
  fi
}
check util 'host/|tools/'
for d in host/mid host/object; do
  [[ -d $d ]] && check "$d" 'host/render|host/radiosity|host/gpu|host/dist|tools/'
done
for d in host/render host/radiosity host/gpu host/dist; do
  [[ -d $d ]] && check "$d" 'tools/'
done
# The check itself must be able to fail: a planted violation must be found.
tmp=$(mktemp -d)
mkdir -p "$tmp/util/x"
echo '#include "host/mid/mid.h"' > "$tmp/util/x/a.c"
if ! (cd "$tmp" && grep -rqE '^[[:space:]]*#[[:space:]]*include[[:space:]]*["<](host/|tools/)' util); then
  echo "self-test failed: planted violation not detected"; bad=1
fi
rm -rf "$tmp"
[[ $bad == 0 ]] && echo "levels ok"
exit $bad
