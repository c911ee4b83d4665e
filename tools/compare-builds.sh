#!/usr/bin/env bash
# Renders the bundled scenes with two testbed binaries and compares the outputs
# byte for byte: the check that a refactor left behaviour unchanged.
#   tools/compare-builds.sh OLD_TESTBED NEW_TESTBED [--no-vulkan]
# Outputs carry no provenance that differs between builds (PFM images, patch
# CSVs, hit files), so any difference is a change of behaviour. Exit 1 on the
# first set that differs (it names it), 0 when all agree.
set -euo pipefail
if [[ $# -lt 2 || $1 == --help || $1 == -h ]]; then
  sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'
  [[ $# -ge 2 ]]; exit $?
fi
old=$(realpath "$1"); new=$(realpath "$2"); vulkan=1
[[ "${3:-}" == --no-vulkan ]] && vulkan=0
cd "$(dirname "$0")/.."
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
fail=0

# run NAME ARGS...: the same command with both binaries; every file named
# @OUT.ext in ARGS is written per binary and compared.
run() {
  local name=$1; shift
  local which bin files=()
  for which in old new; do
    bin=$old; [[ $which == new ]] && bin=$new
    local args=()
    for a in "$@"; do
      if [[ $a == @* ]]; then
        args+=("$out/$which-$name-${a#@}"); [[ $which == old ]] && files+=("${a#@}")
      else args+=("$a"); fi
    done
    if ! "$bin" "${args[@]}" >"$out/$which-$name.log" 2>&1; then
      echo "FAIL $name: $which binary exited non-zero:"; tail -5 "$out/$which-$name.log"; fail=1; return
    fi
  done
  local f
  for f in "${files[@]}"; do
    if cmp -s "$out/old-$name-$f" "$out/new-$name-$f"; then
      echo "same $name $f ($(md5sum <"$out/new-$name-$f" | cut -c1-12))"
    else
      echo "DIFF $name $f"; fail=1
    fi
  done
}

scenes=(scenes/cornell-box.mid scenes/cornell-box-rgb.mid scenes/materials.mid
        scenes/showcase.mid scenes/radiosity-room.mid scenes/tests/cornell-box-coplanar-light.mid
        scenes/cornell-box-spheres.mid)
for s in "${scenes[@]}"; do
  n=$(basename "$s" .mid)
  run "rt-$n" render "$s" -o @img.pfm --spp 2 --backend cpu --threads 2
done
run rt-adaptive render scenes/showcase.mid -o @img.pfm --adaptive --max-spp 8 --backend cpu --filter mitchell
run rt-grid render scenes/materials.mid -o @img.pfm --accel grid --backend cpu
for s in scenes/cornell-box.mid scenes/cornell-box-rgb.mid scenes/radiosity-room.mid; do
  n=$(basename "$s" .mid)
  run "rad-$n" render "$s" --method radiosity --patches @patches.csv -o @img.pfm --threads 2
done
run rad-hemicube render scenes/cornell-box.mid --method radiosity --formfactor hemicube \
  --patches @patches.csv --max-shots 40
run rad-adapt render scenes/cornell-box-rgb.mid --method radiosity --adapt 0.05 --adapt-levels 2 \
  --patches @patches.csv --max-shots 60
run rad-two-level render scenes/radiosity-room.mid --method radiosity --patch-edge 1.0 \
  --patches @patches.csv --max-shots 40
if ((vulkan)); then
  for s in scenes/cornell-box.mid scenes/materials.mid scenes/showcase.mid; do
    n=$(basename "$s" .mid)
    run "vk-$n" render "$s" -o @img.pfm --spp 1 --backend vulkan
  done
  run vk-rad render scenes/cornell-box.mid --method radiosity --backend vulkan \
    --patches @patches.csv --max-shots 30
fi
if ((fail)); then echo "compare-builds: outputs differ"; exit 1; fi
echo "compare-builds: every output identical"
