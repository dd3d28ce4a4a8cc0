#!/usr/bin/env bash
# Writes the farm's two bearer tokens (random, 192 bits each) into DIR: client_token (clients: submit,
# compare, ...) and worker_token (workers). The master refuses to start if they are equal.
#   deploy/make-tokens.sh deploy/secrets
# The files are readable by everyone (the image runs as uid 10001, which must read them through a bind
# mount or a compose secret); DIR itself is private to its owner.
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 DIR" >&2; exit 2; }
mkdir -p "$1"
chmod 0700 "$1"
for name in client_token worker_token; do
    [ -e "$1/$name" ] && { echo "$1/$name exists; not overwriting it" >&2; continue; }
    head -c 24 /dev/urandom | od -An -tx1 | tr -d ' \n' >"$1/$name"
    chmod 0444 "$1/$name"
done
