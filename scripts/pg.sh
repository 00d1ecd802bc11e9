#!/usr/bin/env bash
# A private PostgreSQL cluster for tests and the demo: no TCP port, only a Unix socket in a
# directory of its own, so it never meets a system PostgreSQL or another checkout's cluster.
#
#   scripts/pg.sh start DIR      create the cluster under DIR if needed, start it, print its URL
#   scripts/pg.sh stop DIR       stop it (the data stays)
#   scripts/pg.sh url DIR [DB]   the connection URL (database DB, default postgres)
#   scripts/pg.sh status DIR     exit 0 if it is running
#   scripts/pg.sh destroy DIR    stop it and delete DIR
#
# PostgreSQL refuses to run as root, so as root the cluster runs as the `postgres` user. When
# `postgres` cannot reach DIR (a checkout under /root, say) or the socket path would be too long
# for a Unix socket, the cluster lives under /tmp and DIR becomes a symlink to it. Authentication
# is `trust`: only root and the cluster's owner can open the socket directory.
set -euo pipefail

usage() { sed -n '5,9s/^# \{0,1\}//p' "$0" >&2; exit 2; }
[ $# -ge 2 ] || usage
command=$1
dir=$(realpath -ms "$2")  # -s: DIR may be our symlink; keep it
case "$dir" in *[[:space:]]*) echo "pg.sh: no spaces in DIR, please: '$dir'" >&2; exit 2 ;; esac

bindir=${PG_BINDIR:-$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)}
[ -x "$bindir/pg_ctl" ] || { echo "pg.sh: no PostgreSQL server found (install postgresql or set PG_BINDIR)" >&2; exit 1; }

as_owner() {
  if [ "$(id -u)" -eq 0 ]; then runuser -u postgres -- "$@"; else "$@"; fi
}

# Where the cluster really lives (DIR itself, or the /tmp directory it links to).
home() {
  if [ -L "$dir" ]; then readlink -f "$dir"; else echo "$dir"; fi
}

prepare() {
  [ -e "$dir" ] && return 0
  mkdir -p "$dir"
  local fallback=""
  [ ${#dir} -le 80 ] || fallback=yes  # Unix socket paths are limited to 107 bytes
  if [ "$(id -u)" -eq 0 ]; then
    chown postgres:postgres "$dir"
    chmod 0700 "$dir"
    runuser -u postgres -- test -w "$dir" || fallback=yes
  fi
  if [ -n "$fallback" ]; then
    local real
    real=$(mktemp -d "${TMPDIR:-/tmp}/bathyslam-pg.XXXXXX")
    [ "$(id -u)" -ne 0 ] || chown postgres:postgres "$real"
    rmdir "$dir"
    ln -s "$real" "$dir"
  fi
}

running() { [ -f "$(home)/data/PG_VERSION" ] && as_owner "$bindir/pg_ctl" -D "$(home)/data" status > /dev/null 2>&1; }

url() { echo "postgresql:///${1:-postgres}?host=$(home)/run&user=postgres"; }

case "$command" in
  start)
    prepare
    root=$(home)
    if [ ! -f "$root/data/PG_VERSION" ]; then
      as_owner "$bindir/initdb" -D "$root/data" -U postgres --auth=trust --encoding=UTF8 --no-locale > "$root/initdb.log" \
        || { cat "$root/initdb.log" >&2; exit 1; }
    fi
    as_owner mkdir -p "$root/run"
    if ! running; then
      as_owner "$bindir/pg_ctl" -D "$root/data" -l "$root/server.log" -w -t 60 \
        -o "-k $root/run -c listen_addresses=''" start > /dev/null \
        || { tail -n 20 "$root/server.log" >&2; exit 1; }
    fi
    url
    ;;
  stop)
    if running; then as_owner "$bindir/pg_ctl" -D "$(home)/data" -w -t 60 -m fast stop > /dev/null; fi
    ;;
  url) url "${3:-}" ;;
  status) running ;;
  destroy)
    if running; then as_owner "$bindir/pg_ctl" -D "$(home)/data" -w -t 60 -m immediate stop > /dev/null; fi
    [ -L "$dir" ] && rm -rf "$(home)"
    rm -rf "$dir"
    ;;
  *) usage ;;
esac
