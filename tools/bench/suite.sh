#!/bin/sh
# The benchmark suite of docs/performance.md ("Benchmark suite"): generated
# meshes (tools/bench/suite-gen.py), real models of the Debian package
# assimp-testmodels imported through `testbed import`, and bundled scenes.
# On each scene: `testbed bench rays --embree` (primary, shadow and diffuse
# rays, ours vs Embree's rtcIntersect1 / rtcOccluded1 in the same process)
# and `testbed bench accel --scene --embree` (BVH build time and SAH cost,
# ours vs Embree's high-quality builds), at 1 and 2 threads. Prints the whole
# table, then the minimum over the suite of every ratio (the maximum of the
# SAH ratio, where lower is better).
#
#   tools/bench/suite.sh [--quick] [--only NAME[,NAME...]] [--repeat R] [--keep DIR]
#
# Environment: TESTBED (default build/release/testbed), TMPDIR (scratch:
# the default suite writes about 400 MB of MID text).
# Exit status: 0 every scene ran and Embree agreed on all but <= 1 ray in
# 1000 (ties on shared edges; where its default test disagrees more, as on
# slivers, its robust mode must agree), 1 otherwise, 2 usage error.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
TESTBED=${TESTBED:-$root/build/release/testbed}
models=/usr/share/assimp/models

usage() {
    cat <<EOF
usage: tools/bench/suite.sh [--quick] [--only NAME[,NAME...]] [--repeat R] [--keep DIR]

Runs \`testbed bench rays --embree\` and \`testbed bench accel --scene --embree\`
on every scene of the suite (docs/performance.md, "Benchmark suite") at 1 and 2
threads and prints one table row per scene and the minimum of each ratio over
the suite.

  --quick        tiny sizes (a few thousand triangles, 2000 rays, one round):
                 checks that everything runs and that the hits agree with
                 Embree; the figures mean nothing
  --only NAMES   only these scenes (comma-separated names of the table)
  --repeat R     rounds per measurement, the best kept (default 3; --quick 1)
  --keep DIR     write the scenes and each command's output to DIR (kept)
  -h, --help     this help

Environment: TESTBED (default build/release/testbed), TMPDIR.
EOF
}

quick=0 only="" repeat="" keep=""
while [ $# -gt 0 ]; do
    case $1 in
    --quick) quick=1 ;;
    --only) [ $# -ge 2 ] || { usage >&2; exit 2; }; only=$2; shift ;;
    --repeat) [ $# -ge 2 ] || { usage >&2; exit 2; }; repeat=$2; shift ;;
    --keep) [ $# -ge 2 ] || { usage >&2; exit 2; }; keep=$2; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "suite.sh: error: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
    esac
    shift
done
case $repeat in '' | *[!0-9]* | 0) [ -z "$repeat" ] || { echo "suite.sh: error: --repeat wants a whole number >= 1" >&2; exit 2; } ;; esac
if [ ! -x "$TESTBED" ]; then
    echo "suite.sh: error: $TESTBED is not an executable (set TESTBED or build build/release)" >&2
    exit 1
fi

# name|source|argument: gen (suite-gen.py KIND --tris N --seed 1), model
# (an assimp-testmodels file), scene (a bundled MID file)
if [ $quick = 1 ]; then
    repeat=${repeat:-1} rays=2000
    suite="bumpy|gen|bumpy 3000
terrain|gen|terrain 3000
boxes|gen|boxes 3000
slivers|gen|slivers 3000
objects|gen|objects 3000
mixed|gen|mixed 3000
human|model|Collada/human.zae
cornell-box|scene|cornell-box.mid"
else
    repeat=${repeat:-3} rays=100000
    suite="bumpy|gen|bumpy 1000000
terrain|gen|terrain 3000000
boxes|gen|boxes 360000
slivers|gen|slivers 500000
objects|gen|objects 320000
mixed|gen|mixed 360000
engine|model|glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb
house|model|IFC/AC14-FZK-Haus.ifc
human|model|Collada/human.zae
at-at|model|Q3D/E-AT-AT.q3o
cornell-box|scene|cornell-box.mid
spheres-box|scene|cornell-box-spheres.mid
showcase|scene|showcase.mid"
fi

if [ -n "$keep" ]; then
    mkdir -p "$keep"
    dir=$(cd "$keep" && pwd)
else
    dir=$(mktemp -d "${TMPDIR:-/tmp}/suite.XXXXXX")
    trap 'rm -rf "$dir"' EXIT INT TERM
fi

# Counts of rays that differ are checked here; rates are only reported.
fail=0
rows="$dir/rows.txt"
: >"$rows"
echo "testbed bench suite: $TESTBED, $(date -u '+%Y-%m-%d %H:%M UTC'), load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "each scene: bench rays --embree --threads 1,2 --repeat $repeat --rays $rays --no-stats;"
echo "            bench accel --scene --embree --threads 1,2 --repeat $repeat --no-stats"
printf '%s\n' "$suite" | while IFS='|' read -r name src arg; do
    if [ -n "$only" ] && ! printf ',%s,' "$only" | grep -q ",$name,"; then
        continue
    fi
    mid="$dir/$name.mid"
    case $src in
    gen)
        # shellcheck disable=SC2086 # arg is "KIND N"
        set -- $arg
        python3 "$here/suite-gen.py" "$1" --tris "$2" --seed 1 >"$mid"
        ;;
    model)
        if [ ! -f "$models/$arg" ]; then
            echo "suite.sh: error: $models/$arg is missing (install assimp-testmodels: tools/setup.sh)" >&2
            echo "$name FAIL" >>"$rows"
            continue
        fi
        "$TESTBED" import "$models/$arg" -o "$mid" --triangulate --quiet
        # the model's box, for the camera and lamp that suite-gen.py --rest frames it with
        : >"$dir/none.rays"
        box=$("$TESTBED" trace "$mid" --rays "$dir/none.rays" --hits "$dir/none.hits" --verbose 2>&1 |
            sed -n 's/^bounds: \[\(.*\)\] - \[\(.*\)\]$/\1 \2/p')
        # a model with a camera of its own (glTF) keeps it: MID has one camera
        own=""
        if grep -q '^camera ' "$mid"; then own=--no-camera; fi
        # shellcheck disable=SC2086 # box is six numbers, own empty or one option
        python3 "$here/suite-gen.py" --rest $own $box >>"$mid"
        ;;
    scene) cp "$root/scenes/$arg" "$mid" ;;
    esac
    echo "== $name: $src $arg ($(date -u +%H:%M:%S), load $(cut -d' ' -f1 /proc/loadavg))" >&2
    if ! "$TESTBED" bench rays "$mid" --embree --threads 1,2 --repeat "$repeat" --rays "$rays" --no-stats \
        >"$dir/$name.rays.txt" 2>&1; then
        cat "$dir/$name.rays.txt" >&2
        echo "$name FAIL" >>"$rows"
        continue
    fi
    # Embree's default triangle test is not watertight: where it disagrees with
    # ours on more than 1 ray in 1000 (slivers: rays through their edges), the
    # agreement is taken from its robust mode (RTC_SCENE_FLAG_ROBUST) instead.
    agree="$dir/$name.rays.txt"
    if ! awk '/ agreement: / && $5 > 0 && $3 > $5 / 1000 { bad = 1 } END { exit bad }' "$agree"; then
        agree="$dir/$name.robust.txt"
        if ! "$TESTBED" bench rays "$mid" --embree-robust --threads 1 --repeat 1 --rays "$rays" --no-stats \
            >"$agree" 2>&1; then
            cat "$agree" >&2
            echo "$name FAIL" >>"$rows"
            continue
        fi
    fi
    if ! "$TESTBED" bench accel --scene "$mid" --embree --threads 1,2 --repeat "$repeat" --no-stats \
        >"$dir/$name.accel.txt" 2>&1; then
        cat "$dir/$name.accel.txt" >&2
        echo "$name FAIL" >>"$rows"
        continue
    fi
    # One row: name tris, per set (primary shadow diffuse): ratio 1T, ratio 2T, ratio per CPU s 1T,
    # rays that differ, rays; then build Mtri/s ours 1T, Embree-high 1T, speed 1T, speed 2T, SAH ratio.
    awk -v name="$name" '
    FNR == 1 { file++ }
    file == 3 && /^Embree .*RTC_SCENE_FLAG_ROBUST/ { robust = 1 }
    file == 1 && /^scene / { for (i = 1; i <= NF; i++) if ($(i + 1) == "triangles,") tris = $i }
    file == 1 && /^(primary|shadow|diffuse) +[0-9]+ +[0-9.]+ +[0-9]+ / {
        if ($4 == 1) { r1[$1] = $7; c1[$1] = $10 } else r2[$1] = $7
    }
    file == 3 && / agreement: / { d[$1] = $3 (robust ? "r" : ""); n[$1] = $5 }
    file == 2 && /^ours +1 / { o1 = $4 }
    file == 2 && /^embree-high +1 / { e1 = $4 }
    file == 2 && /^build 1 threads:/ { s1 = $10; m1 = $14; sah = $NF }
    file == 2 && /^build 2 threads:/ { s2 = $10; m2 = $14 }
    END {
        printf "%s %s", name, tris
        split("primary shadow diffuse", sets, " ")
        for (k = 1; k <= 3; k++) {
            s = sets[k]
            printf " %s %s %s %s %s", (s in r1) ? r1[s] : "-", (s in r2) ? r2[s] : "-", (s in c1) ? c1[s] : "-",
                (s in d) ? d[s] : 0, (s in n) ? n[s] : 0
        }
        sub(/x;?$/, "", s1); sub(/x;?$/, "", s2); sub(/x;?$/, "", m1); sub(/x;?$/, "", m2)
        printf " %s %s %s %s %s %s %s\n", o1, e1, s1, s2, m1, m2, sah
    }' "$dir/$name.rays.txt" "$dir/$name.accel.txt" "$agree" >>"$rows"
done

echo
awk -v load="$(cut -d' ' -f1-3 /proc/loadavg)" '
function upd(key, v) { if (v == "-" || v == "") return; v += 0; if (!(key in mn) || v < mn[key]) { mn[key] = v; at[key] = $1 } }
function updmax(key, v) { if (v == "-" || v == "") return; v += 0; if (!(key in mx) || v > mx[key]) { mx[key] = v; atx[key] = $1 } }
BEGIN {
    print "| scene | triangles | primary 1T / 2T / CPU | shadow 1T / 2T / CPU | diffuse 1T / 2T / CPU | rays that differ | build Mtri/s ours / Embree high 1T | build speed vs high 1T / 2T | vs medium 1T / 2T | SAH ours / Embree |"
    print "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
}
$2 == "FAIL" { print "| " $1 " | FAILED | | | | | | | | |"; bad = 1; next }
{
    differ = ""; total = 0
    for (k = 0; k < 3; k++) {
        b = 3 + 5 * k
        upd("r1_" k, $b); upd("r2_" k, $(b + 1)); upd("c1_" k, $(b + 2))
        differ = differ (k ? " / " : "") $(b + 3)
        if ($(b + 4) > 0 && $(b + 3) + 0 > $(b + 4) / 1000) agree_bad = agree_bad " " $1
    }
    upd("s1", $20); upd("s2", $21); upd("m1", $22); upd("m2", $23); updmax("sah", $24)
    printf "| %s | %s | %s / %s / %s | %s / %s / %s | %s / %s / %s | %s | %s / %s | %s / %s | %s / %s | %s |\n",
        $1, $2, $3, $4, $5, $8, $9, $10, $13, $14, $15, differ, $18, $19, $20, $21, $22, $23, $24
}
END {
    print ""
    print "Ratios are ours / Embree: rays per second (1T, 2T: wall clock; CPU: per CPU second, 1 thread); build"
    print "speed = Embree build time (high quality, medium = its default) / ours, per scene build (rtcCommitScene vs"
    print "tb_scene_rebuild_accel); SAH: our tree / Embree rtcBuildBVH high-quality tree (lower is better)."
    print "Rays that differ (primary / shadow / diffuse) in hit/miss, object or face; r: against Embree'"'"'s robust"
    print "mode, where its default triangle test disagreed on more than 1 ray in 1000."
    print "Load average at the end: " load
    print ""
    print "| minimum over the suite | value | scene |"
    print "| --- | --- | --- |"
    split("primary shadow diffuse", sets, " ")
    for (k = 0; k < 3; k++) {
        printf "| %s ratio 1T | %s | %s |\n", sets[k + 1], mn["r1_" k], at["r1_" k]
        printf "| %s ratio 2T | %s | %s |\n", sets[k + 1], mn["r2_" k], at["r2_" k]
        printf "| %s ratio per CPU s 1T | %s | %s |\n", sets[k + 1], mn["c1_" k], at["c1_" k]
    }
    printf "| build speed vs Embree high 1T | %s | %s |\n", mn["s1"], at["s1"]
    printf "| build speed vs Embree high 2T | %s | %s |\n", mn["s2"], at["s2"]
    printf "| build speed vs Embree medium 1T | %s | %s |\n", mn["m1"], at["m1"]
    printf "| build speed vs Embree medium 2T | %s | %s |\n", mn["m2"], at["m2"]
    printf "| SAH ours / Embree (maximum) | %s | %s |\n", mx["sah"], atx["sah"]
    if (agree_bad != "") { print "suite.sh: more than 1 ray in 1000 differs from Embree on:" agree_bad > "/dev/stderr"; bad = 1 }
    exit bad
}' "$rows" || fail=1
exit $fail
