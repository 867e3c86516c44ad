#!/usr/bin/env bash
# Runs a command and checks both its exit code and its output (stdout + stderr):
#   expect_exit.sh CODE REGEX COMMAND [ARGS...]
set -u
want="$1"; regex="$2"; shift 2
out="$("$@" 2>&1)"; rc=$?
echo "$out"
[ "$rc" -eq "$want" ] || { echo "FAIL: exit code $rc, expected $want: $*"; exit 1; }
tr "\n" " " <<<"$out" | grep -Eq -- "$regex" || { echo "FAIL: output does not match /$regex/: $*"; exit 1; }
