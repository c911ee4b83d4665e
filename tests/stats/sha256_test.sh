#!/usr/bin/env bash
# tb_sha256_file (OpenSSL EVP) must print what coreutils' sha256sum prints.
set -eu
tool=$1
dir=${TB_TEST_TMPDIR:-/tmp}/stats_sha256.$$
mkdir -p "$dir"
trap 'rm -rf "$dir"' EXIT
: > "$dir/empty"
printf 'abc' > "$dir/abc"
head -c 1048576 /dev/urandom > "$dir/one MiB"          # 1 MiB, a name with a space
head -c 200003 /dev/urandom > "$dir/odd-size"           # not a multiple of any block size
fail=0
for f in "$dir/empty" "$dir/abc" "$dir/one MiB" "$dir/odd-size"; do
  want=$(sha256sum "$f" | cut -d' ' -f1)
  got=$("$tool" sha256 "$f" | cut -d' ' -f1)
  if [[ "$got" != "$want" ]]; then
    echo "FAIL: $f: got $got, sha256sum says $want"; fail=1
  else
    echo "ok: $(basename "$f"): $got"
  fi
done
# A missing file is an error, not a digest.
if "$tool" sha256 "$dir/missing" 2>/dev/null; then
  echo "FAIL: missing file accepted"; fail=1
fi
exit $fail
