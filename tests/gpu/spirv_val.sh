#!/usr/bin/env bash
# spirv_val.sh SPIRV-VAL TARGET-ENV LIST SHADERS-DIR
# Validates every SPIR-V module the build generated (LIST: one path a line)
# with spirv-val, checks that every shaders/<name>.comp has a module, and
# that spirv-val does reject a damaged module (so this test can fail).
set -u
val=$1 env=$2 list=$3 shaders=$4
bad=0 n=0
while IFS= read -r spv; do
  [[ -z $spv ]] && continue
  n=$((n + 1))
  if [[ ! -s $spv ]]; then
    echo "missing module: $spv"; bad=1; continue
  fi
  if ! "$val" --target-env "$env" "$spv"; then
    echo "spirv-val rejects $spv"; bad=1
  fi
done < "$list"
for comp in "$shaders"/*.comp; do
  name=$(basename "$comp" .comp)
  if ! grep -q "/$name\.spv\$" "$list"; then
    echo "shaders/$name.comp has no generated module"; bad=1
  fi
done
(( n > 0 )) || { echo "no modules listed"; bad=1; }
# Self-check: a module cut short must be rejected.
first=$(grep -m1 . "$list")
tmp=$(mktemp)
head -c 64 "$first" > "$tmp"
if "$val" --target-env "$env" "$tmp" 2>/dev/null; then
  echo "self-check failed: spirv-val accepted a truncated module"; bad=1
fi
rm -f "$tmp"
[[ $bad == 0 ]] && echo "spirv-val: $n modules valid for $env"
exit $bad
