#!/usr/bin/env bash
# tools/check-fresh.sh --dry-run finds the README's two commands (main job,
# then tests) and a mirror; .ci/run executes exactly the test command.
set -euo pipefail
: "${TB_SOURCE_DIR:?}"
out=$(bash "$TB_SOURCE_DIR/tools/check-fresh.sh" --dry-run)
printf '%s\n' "$out"
main=$(sed -n 's/^check-fresh: command 1: //p' <<<"$out")
tests=$(sed -n 's/^check-fresh: command 2: //p' <<<"$out")
[[ $main == tools/run-main.sh ]] || { echo "FAIL: README's first command is '$main'"; exit 1; }
[[ $tests == tools/run-tests.sh ]] || { echo "FAIL: README's second command is '$tests'"; exit 1; }
grep -qE '^check-fresh: mirror [a-z]+://' <<<"$out" || { echo "FAIL: no mirror found"; exit 1; }
# .ci/run: its one command is the README's test command
ci=$(grep -vE '^[[:space:]]*(#|$|set |cd )' "$TB_SOURCE_DIR/.ci/run")
[[ $ci == "exec $tests" ]] || { echo "FAIL: .ci/run runs '$ci', not the README's '$tests'"; exit 1; }
# both scripts answer --help, and an unknown option is a usage error
bash "$TB_SOURCE_DIR/tools/check-fresh.sh" --help | grep -q debootstrap || { echo "FAIL: --help"; exit 1; }
set +e; bash "$TB_SOURCE_DIR/tools/check-fresh.sh" --bogus 2>/dev/null; rc=$?; set -e
[[ $rc == 2 ]] || { echo "FAIL: unknown option exit $rc, expected 2"; exit 1; }
echo "ok"
