#!/usr/bin/env bash
# The module dependency graph of docs/architecture.md, declared here and
# checked on the sources: every `#include "A/B/..."` in a module's .c/.h/.inc
# must name the module itself or one it may use. A module folder that is not
# declared fails too, so a new module is placed in the graph on purpose.
#   check-levels.sh [SOURCE_DIR]
set -u
root=${1:-${TB_SOURCE_DIR:?}}

# module -> the modules it may include (besides itself). `util/*` means every
# utility module. The levels: utility < object < rendering < applications.
declare -A may_use=(
  # utility level: numbers, colours, images, meshes, containers
  [util/base]=""
  [util/math]="util/base"
  [util/container]="util/base"
  [util/roots]="util/base util/math"
  [util/color]="util/base util/math util/container"
  [util/image]="util/base util/math util/color"
  [util/itembuf]="util/base util/math"
  [util/mesh]="util/base util/math util/container"
  [util/stats]="util/base util/image"
  # shared C/GLSL buffer layouts: plain types only
  [shaders/shared]="util/math"
  # object level: one object at a time
  [host/mid]="util/*"
  [host/object]="util/* host/mid"
  # rendering level: whole scenes. render knows neither the radiosity renderer
  # nor the Vulkan backend; radiosity builds on render's scene and accel; the
  # Vulkan backend accelerates both.
  [host/render]="util/* host/mid host/object"
  [host/radiosity]="util/* host/mid host/object host/render"
  [host/gpu]="util/* host/mid host/object host/render host/radiosity shaders/shared"
  # the hybrid radiosity + ray-tracing renderer: a user of both renderers
  [host/hybrid]="util/* host/mid host/object host/render host/radiosity"
  # the distributed layer (MPI): above the renderers, which it drives through
  # callbacks (tile exchange, radiosity exchange, checkpoints); none of them
  # may include it
  [host/dist]="util/* host/mid host/object host/render host/radiosity host/hybrid"
)

# check MODULE INCLUDE-PATH: 0 when MODULE may include INCLUDE-PATH.
check() {
  local module=$1 inc=$2 target dep
  target=$(sed -E 's#^((util|host|shaders|tools)/[^/]+)/.*#\1#' <<<"$inc")
  [[ $target == "$inc" ]] && return 0 # not a module path ("foo.h", <stdio.h>)
  [[ $target == "$module" ]] && return 0
  for dep in ${may_use[$module]-}; do
    [[ $dep == "$target" ]] && return 0
    [[ $dep == util/* && $dep == *'*' && $target == util/* ]] && return 0
  done
  return 1
}

# The check must be able to fail: a violating include is refused, a
# permitted one accepted, before the tree is looked at.
selftest_bad=0
check host/render host/gpu/gpu.h && { echo "self-test: host/render -> host/gpu accepted"; selftest_bad=1; }
check host/render host/radiosity/radiosity.h && { echo "self-test: host/render -> host/radiosity accepted"; selftest_bad=1; }
check host/object host/render/scene.h && { echo "self-test: host/object -> host/render accepted"; selftest_bad=1; }
check util/math host/mid/mid.h && { echo "self-test: util/math -> host/mid accepted"; selftest_bad=1; }
check util/base util/math/vec.h && { echo "self-test: util/base -> util/math accepted"; selftest_bad=1; }
check host/render tools/testbed/commands.h && { echo "self-test: host/render -> tools accepted"; selftest_bad=1; }
check host/gpu host/render/scene.h || { echo "self-test: host/gpu -> host/render refused"; selftest_bad=1; }
check host/object util/roots/roots.h || { echo "self-test: host/object -> util/roots refused"; selftest_bad=1; }
check host/radiosity host/hybrid/hybrid.h && { echo "self-test: host/radiosity -> host/hybrid accepted"; selftest_bad=1; }
check util/roots util/math/vec.h || { echo "self-test: util/roots -> util/math refused"; selftest_bad=1; }
check host/render host/dist/tiles.h && { echo "self-test: host/render -> host/dist accepted"; selftest_bad=1; }
check host/radiosity host/dist/dist.h && { echo "self-test: host/radiosity -> host/dist accepted"; selftest_bad=1; }
check host/dist host/render/film.h || { echo "self-test: host/dist -> host/render refused"; selftest_bad=1; }
if ((selftest_bad)); then echo "check-levels: self-test failed"; exit 1; fi

cd "$root" || exit 2
bad=0
for dir in util/* host/* shaders/shared; do
  [[ -d $dir ]] || continue
  if [[ -z ${may_use[$dir]+set} ]]; then
    echo "undeclared module $dir: add it to the graph in tests/architecture/check-levels.sh"
    bad=1
    continue
  fi
  while IFS= read -r line; do
    file=${line%%:*}; rest=${line#*:}; lineno=${rest%%:*}
    inc=$(sed -nE 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"([^"]+)".*/\1/p' <<<"${rest#*:}")
    [[ -n $inc ]] || continue
    if ! check "$dir" "$inc"; then
      echo "$file:$lineno: $dir may not include $inc (it may use: ${may_use[$dir]:-nothing})"
      bad=1
    fi
  done < <(grep -rnE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$dir" \
             --include='*.c' --include='*.h' --include='*.inc' 2>/dev/null)
done
[[ $bad == 0 ]] && echo "module graph ok"
exit $bad
