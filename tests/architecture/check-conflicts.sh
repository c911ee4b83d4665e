#!/bin/sh
# No merge-conflict markers left in tracked files (a merge committed with its
# markers once broke tools/bench/run-all.sh without failing a build: shell
# scripts and docs are not compiled). Lines of exactly "=======" are allowed
# (Markdown/reST underlines); the "<<<<<<< " and ">>>>>>> " openers are not.
#   check-conflicts.sh SOURCE_DIR
set -u
cd "$1" || exit 1
git rev-parse --is-inside-work-tree > /dev/null 2>&1 || { echo "not a git checkout: skipped"; exit 77; }
hits=$(git grep -n -I -E '^(<<<<<<<|>>>>>>>) ' -- . ':!tests/architecture/check-conflicts.sh')
if [ -n "$hits" ]; then
    echo "merge-conflict markers:"
    echo "$hits"
    exit 1
fi
# self-check: the pattern finds a marker in a file of its own
t=$(mktemp)
printf 'a\n<<<<<<< HEAD\nb\n' > "$t"
grep -q -E '^(<<<<<<<|>>>>>>>) ' "$t" || { rm -f "$t"; echo "FAIL: the pattern missed a marker"; exit 1; }
rm -f "$t"
echo "no merge-conflict markers"
