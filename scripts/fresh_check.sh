#!/usr/bin/env bash
# The two commands of README.md on a fresh machine: a minimal Debian bookworm root made with
# debootstrap (--variant=minbase, plus git and ca-certificates, nothing else), the committed HEAD
# of this checkout cloned into it (/root/knotflow), then, under chroot as root with /proc, /sys
# and /dev mounted:
#     bash scripts/run.sh        bash scripts/test.sh
# For each: its exit status, wall time and the last lines of its output; the full logs stay in
# <dir>/logs.  The mounts are undone and the root removed on any exit (a trap), unless --keep.
# Needs root, chroot, mount and debootstrap (Debian: apt-get install debootstrap) and the network
# (deb.debian.org, PyPI); without root or debootstrap it says so and exits 77.
#
#   scripts/fresh_check.sh [--keep] [--dir DIR] [--only run|test] [--slow] [--cache FILE]
#     --keep         keep the root (DIR/root) after the check
#     --dir DIR      work directory (default: a new /var/tmp/knotflow-fresh.XXXXXX); DIR/root is
#                    the Debian root (made again if it exists), DIR/logs the logs
#     --only run|test  run only one of the two commands
#     --slow         scripts/test.sh --slow (the tests labelled slow as well)
#     --cache FILE   the packages of the debootstrap stage in a tarball: made on first use
#                    (debootstrap --make-tarball), then unpacked (saves the download)
#     --tail N       lines of output shown per command (default 30)
# Exit status: 0 when every command run exited 0, 1 when one failed, 2 for a usage error,
# 77 when a prerequisite (root, debootstrap, chroot, mount) is missing.
# Environment: KNOTFLOW_FRESH_MIRROR (default http://deb.debian.org/debian); KNOTFLOW_JOBS and
# KNOTFLOW_NP are passed to the commands when set; nothing else of the caller's environment is.
set -uo pipefail

usage() { sed -n '2,/^set -uo/p' "${BASH_SOURCE[0]}" | sed '$d' | sed 's/^# \{0,1\}//'; }
die_usage() { printf 'fresh_check.sh: %s\n' "$*" >&2; exit 2; }
log() { printf '==> %s\n' "$*"; }

keep=0 dir="" only="" slow=0 cache="" tail_lines=30
while [ $# -gt 0 ]; do
  case "$1" in
    --keep) keep=1 ;;
    --dir) [ $# -ge 2 ] || die_usage "--dir needs a directory"; dir="$2"; shift ;;
    --only) [ $# -ge 2 ] || die_usage "--only needs run or test"; only="$2"; shift
            case "$only" in run|test) ;; *) die_usage "--only $only: allowed are run and test" ;; esac ;;
    --slow) slow=1 ;;
    --cache) [ $# -ge 2 ] || die_usage "--cache needs a file"; cache="$2"; shift ;;
    --tail) if [ $# -lt 2 ] || ! [[ "$2" =~ ^[1-9][0-9]*$ ]]; then die_usage "--tail needs a positive integer"; fi
            tail_lines="$2"; shift ;;
    -h|--help) usage; exit 0 ;;
    *) die_usage "unknown argument '$1' (see --help)" ;;
  esac
  shift
done

src="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mirror="${KNOTFLOW_FRESH_MIRROR:-http://deb.debian.org/debian}"
suite=bookworm

# Prerequisites: exit 77 (skipped) with the reason.
if [ "$(id -u)" -ne 0 ]; then
  echo "fresh_check.sh: needs root (debootstrap, mount and chroot): skipped"; exit 77
fi
for tool in debootstrap chroot mount umount git; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "fresh_check.sh: '$tool' not found (Debian: apt-get install debootstrap): skipped"; exit 77
  fi
done
commit="$(git -C "$src" rev-parse HEAD 2>/dev/null)" || { echo "fresh_check.sh: $src is not a git checkout" >&2; exit 2; }
if [ -n "$(git -C "$src" status --porcelain --untracked-files=no 2>/dev/null)" ]; then
  log "note: $src has uncommitted changes; the check uses the committed HEAD only"
fi

if [ -z "$dir" ]; then
  dir="$(mktemp -d /var/tmp/knotflow-fresh.XXXXXX)" || { echo "fresh_check.sh: cannot make a work directory" >&2; exit 1; }
fi
mkdir -p "$dir/logs" || { echo "fresh_check.sh: cannot make $dir/logs" >&2; exit 1; }
dir="$(cd "$dir" && pwd)"
root="$dir/root" logs="$dir/logs"
if [ -n "$cache" ]; then
  case "$cache" in /*) ;; *) cache="$(pwd)/$cache" ;; esac
fi

# The mounts under the root, deepest first.
mounts_under() { awk -v r="$root" '$2 == r || index($2, r "/") == 1 { print $2 }' /proc/self/mounts | sort -r; }

# shellcheck disable=SC2317  # called by the trap
cleanup() {
  local pid link m
  # processes still running inside the root (daemons a test started, orphans) hold its mounts
  for pid in /proc/[0-9]*; do
    link="$(readlink "$pid/root" 2>/dev/null)" || continue
    if [ "$link" = "$root" ]; then
      kill -KILL "${pid#/proc/}" 2>/dev/null || true
    fi
  done
  for m in $(mounts_under); do
    umount "$m" 2>/dev/null || umount -l "$m" 2>/dev/null || true
  done
  if [ "$keep" = 1 ]; then
    log "root kept: $root (chroot $root /bin/bash)"
  elif [ -d "$root" ]; then
    if [ -n "$(mounts_under)" ]; then
      log "WARNING: mounts left under $root (not removed): $(mounts_under | tr '\n' ' ')"
    else
      rm -rf --one-file-system "$root"
    fi
  fi
  log "logs: $logs"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# A root from an earlier check is made again (its mounts undone first).
if [ -e "$root" ]; then
  for m in $(mounts_under); do umount "$m" 2>/dev/null || umount -l "$m"; done
  [ -z "$(mounts_under)" ] || { echo "fresh_check.sh: cannot unmount under $root" >&2; exit 1; }
  rm -rf --one-file-system "$root"
fi

t0=$(date +%s)
boot=(--variant=minbase "--include=git,ca-certificates")
if [ -n "$cache" ] && [ ! -s "$cache" ]; then
  log "debootstrap --make-tarball $cache ($suite, $mirror)"
  rm -rf "$dir/tarball-root"
  debootstrap "${boot[@]}" --make-tarball="$cache" "$suite" "$dir/tarball-root" "$mirror" \
    >"$logs/debootstrap-tarball.log" 2>&1 \
    || { tail -n 20 "$logs/debootstrap-tarball.log"; rm -f "$cache"; echo "fresh_check.sh: debootstrap --make-tarball failed" >&2; exit 1; }
  rm -rf "$dir/tarball-root"
fi
if [ -n "$cache" ]; then
  log "debootstrap $suite into $root (packages from $cache)"
  boot+=(--unpack-tarball="$cache")
else
  log "debootstrap $suite into $root ($mirror)"
fi
debootstrap "${boot[@]}" "$suite" "$root" "$mirror" >"$logs/debootstrap.log" 2>&1 \
  || { tail -n 20 "$logs/debootstrap.log"; echo "fresh_check.sh: debootstrap failed" >&2; exit 1; }
log "debootstrap: $(( $(date +%s) - t0 )) s, $(chroot "$root" dpkg-query -W | wc -l) packages"

# The network of the host; no daemon started by a package's installation (usual in a chroot:
# the tests that need munge or SLURM start their own).
cp /etc/resolv.conf "$root/etc/resolv.conf"
cp /etc/hosts "$root/etc/hosts"
# The host's local CA certificates (a TLS-inspecting proxy of the site): without them pip cannot
# reach PyPI from the root where the host can.
if compgen -G "/usr/local/share/ca-certificates/*.crt" >/dev/null; then
  mkdir -p "$root/usr/local/share/ca-certificates"
  cp /usr/local/share/ca-certificates/*.crt "$root/usr/local/share/ca-certificates/"
  chroot "$root" update-ca-certificates >"$logs/ca.log" 2>&1 \
    || { cat "$logs/ca.log"; echo "fresh_check.sh: update-ca-certificates failed" >&2; exit 1; }
  log "the host's local CA certificates added: $(cd /usr/local/share/ca-certificates && echo ./*.crt)"
fi
printf '#!/bin/sh\nexit 101\n' >"$root/usr/sbin/policy-rc.d"
chmod 755 "$root/usr/sbin/policy-rc.d"

mount -t proc proc "$root/proc" || { echo "fresh_check.sh: cannot mount /proc in the root: skipped"; exit 77; }
mount -t sysfs sysfs "$root/sys" 2>/dev/null || mount --rbind /sys "$root/sys" \
  || { echo "fresh_check.sh: cannot mount /sys in the root: skipped"; exit 77; }
if ! { mount --rbind /dev "$root/dev" && mount --make-rslave "$root/dev"; }; then
  echo "fresh_check.sh: cannot mount /dev in the root: skipped"; exit 77
fi

log "git clone $src (HEAD $commit) into /root/knotflow"
if ! { git clone -q --no-checkout "$src" "$root/root/knotflow" \
       && git -C "$root/root/knotflow" checkout -q --detach "$commit"; } >"$logs/clone.log" 2>&1; then
  cat "$logs/clone.log"; echo "fresh_check.sh: git clone failed" >&2; exit 1
fi

# A clean environment, as a root login on a new machine has.
envs=(HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 TERM=dumb
      USER=root LOGNAME=root SHELL=/bin/bash)
for v in KNOTFLOW_JOBS KNOTFLOW_NP; do
  [ -n "${!v:-}" ] && envs+=("$v=${!v}")
done

status=0
summary=()
run_cmd() {   # run_cmd NAME COMMAND...
  local name="$1" t rc secs
  shift
  log "chroot: cd /root/knotflow && $* (log: $logs/$name.log)"
  t=$(date +%s)
  chroot "$root" /usr/bin/env -i "${envs[@]}" /bin/bash -c 'cd /root/knotflow && "$@"' bash "$@" \
    </dev/null >"$logs/$name.log" 2>&1
  rc=$?
  secs=$(( $(date +%s) - t ))
  echo "---- last $tail_lines lines of '$*' ----"
  tail -n "$tail_lines" "$logs/$name.log"
  echo "----"
  printf -v line '%-22s exit %3d   %4d min %02d s   (log %s)' "$*" "$rc" $(( secs / 60 )) $(( secs % 60 )) "$logs/$name.log"
  summary+=("$line")
  log "$line"
  [ "$rc" -eq 0 ] || status=1
}

if [ -z "$only" ] || [ "$only" = run ]; then
  run_cmd run bash scripts/run.sh
fi
if [ -z "$only" ] || [ "$only" = test ]; then
  if [ "$slow" = 1 ]; then
    run_cmd test bash scripts/test.sh --slow
  else
    run_cmd test bash scripts/test.sh
  fi
fi

echo
log "fresh check of $commit ($suite, $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)):"
for line in "${summary[@]}"; do echo "    $line"; done
log "total: $(( ($(date +%s) - t0) / 60 )) min"
exit "$status"
