#!/usr/bin/env bash
# Runs the README's two commands on a fresh Debian 12 system: builds a clean
# bookworm root with debootstrap (minbase + git, as a new user's machine),
# clones this repository's HEAD into it, and runs each command there as root,
# printing its result and time. Run it before resolving anything that touches
# set-up; a green CI on a long-lived machine can hide a missing install step.
#   tools/check-fresh.sh [--root DIR] [--keep] [--mirror URL] [--only main|tests] [--dry-run]
#     --root DIR     where to build the root (default: a new folder under /var/tmp); an
#                    existing root made by this script is reused, minus the old clone
#     --keep         keep the root afterwards (default: removed on success, kept on failure)
#     --mirror URL   Debian mirror for debootstrap (default: the machine's configured apt
#                    source for bookworm, from /etc/apt/sources.list{,.d})
#     --only WHICH   run only the README's main (first) or tests (second) command
#     --dry-run      print the mirror and the two commands, change nothing
# Needs root (debootstrap, chroot, mounts). Exit 0 when both commands pass.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
root="" keep=0 mirror="" only="" dry=0
usage() { sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; }
while (($#)); do
  case $1 in
    --root) root=${2:?--root needs a folder}; shift 2 ;;
    --keep) keep=1; shift ;;
    --mirror) mirror=${2:?--mirror needs a URL}; shift 2 ;;
    --only) only=${2:?--only needs main or tests}; shift 2
            [[ $only == main || $only == tests ]] || { echo "check-fresh: --only takes main or tests" >&2; exit 2; } ;;
    --dry-run) dry=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "check-fresh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

# The README's two commands: the command lines of its first sh block.
mapfile -t commands < <(awk '/^```sh/ { inb = 1; next } inb && /^```/ { exit } inb && NF { sub(/[[:space:]]+#.*/, ""); print }' "$repo/README.md")
if ((${#commands[@]} != 2)); then
  echo "check-fresh: expected two commands in the README's first sh block, found ${#commands[@]}" >&2
  exit 1
fi

# The machine's own apt source for bookworm (deb822 .sources or one-line .list).
find_mirror() {
  local f
  for f in /etc/apt/sources.list.d/*.sources; do
    [[ -f $f ]] || continue
    awk 'BEGIN { RS = ""; FS = "\n" }
         /(^|\n)Suites:[^\n]*bookworm([ \n]|$)/ && !/(^|\n)Enabled: *no/ {
           for (i = 1; i <= NF; i++) if ($i ~ /^URIs:/) { split($i, u, /[ \t]+/); print u[2]; exit } }' "$f"
  done
  { cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null || true; } |
    awk '$1 == "deb" && $0 ~ / bookworm / { for (i = 2; i <= NF; i++) if ($i ~ /^[a-z]+:\/\//) { print $i; exit } }'
}
[[ -n $mirror ]] || mirror=$(find_mirror | head -n 1 || true)
if [[ -z $mirror ]]; then
  echo "check-fresh: no bookworm apt source configured on this machine; give --mirror URL" >&2
  exit 1
fi

echo "check-fresh: repository $repo at $(git -C "$repo" rev-parse --short HEAD)"
echo "check-fresh: mirror $mirror"
for i in "${!commands[@]}"; do echo "check-fresh: command $((i + 1)): ${commands[$i]}"; done
if ((dry)); then exit 0; fi

[[ $(id -u) == 0 ]] || { echo "check-fresh: needs root (debootstrap, chroot, mounts)" >&2; exit 1; }
if [[ -n $(git -C "$repo" status --porcelain --untracked-files=no) ]]; then
  echo "check-fresh: warning: uncommitted changes are not tested (the clone is of HEAD)"
fi
if ! command -v debootstrap >/dev/null; then
  echo "check-fresh: installing debootstrap"
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >/dev/null
fi

[[ -n $root ]] || root=$(mktemp -d /var/tmp/testbed-fresh.XXXXXX)
mkdir -p "$root"; root=$(cd "$root" && pwd)
logs="$root.logs"; mkdir -p "$logs"
mounted=()
cleanup() {
  local status=$? m
  for ((m = ${#mounted[@]} - 1; m >= 0; m--)); do umount -R "${mounted[$m]}" 2>/dev/null || umount -lR "${mounted[$m]}" 2>/dev/null || true; done
  if ((status == 0 && !keep)); then rm -rf "$root" "$logs"; else echo "check-fresh: root kept at $root, logs at $logs"; fi
}
trap cleanup EXIT

start=$(date +%s)
if [[ ! -x $root/usr/bin/git ]]; then
  echo "check-fresh: debootstrap bookworm (minbase + git) into $root"
  debootstrap --variant=minbase --include=git bookworm "$root" "$mirror" >"$logs/debootstrap.log" 2>&1 ||
    { tail -20 "$logs/debootstrap.log"; echo "check-fresh: debootstrap failed"; exit 1; }
  echo "check-fresh: root ready in $(($(date +%s) - start)) s"
fi
# The machine's apt configuration, as a new machine here would have it:
# its sources (and the keyrings they name) and name resolution.
cp /etc/resolv.conf "$root/etc/resolv.conf"
[[ -f /etc/apt/sources.list ]] && cp /etc/apt/sources.list "$root/etc/apt/sources.list"
for f in /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources; do
  [[ -f $f ]] || continue
  cp "$f" "$root/etc/apt/sources.list.d/"
  for k in $(sed -nE 's/^Signed-By: *(\/[^ ]+)$/\1/p; s/.*signed-by=(\/[^] ]+).*/\1/p' "$f"); do
    [[ -f $k && ! -f $root$k ]] && mkdir -p "$root$(dirname "$k")" && cp "$k" "$root$k"
  done
done
for m in proc sys dev; do
  mkdir -p "$root/$m"
  case $m in
    proc) mount -t proc proc "$root/proc" ;;
    sys) mount --rbind /sys "$root/sys"; mount --make-rslave "$root/sys" ;;
    dev) mount --rbind /dev "$root/dev"; mount --make-rslave "$root/dev" ;;
  esac
  mounted+=("$root/$m")
done

rm -rf "$root/root/testbed"
git clone -q "$repo" "$root/root/testbed"
git -C "$root/root/testbed" checkout -q "$(git -C "$repo" rev-parse HEAD)"

fail=0
for i in "${!commands[@]}"; do
  which=main; ((i == 1)) && which=tests
  [[ -z $only || $only == "$which" ]] || continue
  cmd=${commands[$i]}
  echo "check-fresh: running '$cmd' (log: $logs/$which.log)"
  t0=$(date +%s)
  set +e
  chroot "$root" /usr/bin/env -i HOME=/root TERM=dumb PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    /bin/bash -c "cd /root/testbed && $cmd" </dev/null >"$logs/$which.log" 2>&1
  rc=$?
  set -e
  secs=$(($(date +%s) - t0))
  if ((rc == 0)); then
    echo "check-fresh: PASS '$cmd' in ${secs} s"
    grep -E "tests passed|tests failed" "$logs/$which.log" | sed 's/^/check-fresh:   /' || true
  else
    echo "check-fresh: FAIL '$cmd' (exit $rc) after ${secs} s; last lines:"
    tail -30 "$logs/$which.log" | sed 's/^/  | /'
    fail=1
  fi
done
echo "check-fresh: total $(($(date +%s) - start)) s"
exit $fail
