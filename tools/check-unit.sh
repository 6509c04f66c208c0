#!/usr/bin/env bash
# Verifies a systemd unit (floorposed.service, floorpose-dashboard.service) and checks
# its systemd exposure score (<= 2.0).
#
#   tools/check-unit.sh [UNIT]     (default: systemd/floorposed.service)
#
# `systemd-analyze verify` insists that the ExecStart binary exists, and floorposed is
# usually not installed where this runs, so the check uses a temporary copy of the unit
# whose ExecStart binary is replaced by /bin/true (arguments kept). Exits non-zero when
# verification prints anything or fails, or when `systemd-analyze security --offline=yes`
# scores the unit above MAX_EXPOSURE (default 2.0). Needs systemd-analyze (apt-get install
# systemd).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
unit="${1:-$root/systemd/floorposed.service}"
stand_in=/bin/true

if ! command -v systemd-analyze >/dev/null 2>&1; then
  echo "check-unit: systemd-analyze not found (apt-get install systemd)" >&2
  exit 2
fi
[[ -f "$unit" ]] || { echo "check-unit: $unit: no such file" >&2; exit 2; }

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
copy="$tmp/$(basename "$unit")"
sed -E "s|^(ExecStart=[-@:+!]*)[^ ]+|\1$stand_in|" "$unit" >"$copy"
grep -q "^ExecStart=.*$stand_in" "$copy" || { echo "check-unit: no ExecStart= in $unit" >&2; exit 1; }

echo "== systemd-analyze verify $(basename "$unit") (ExecStart binary -> $stand_in)"
status=0
out="$(SYSTEMD_LOG_COLOR=0 systemd-analyze verify --man=no "$copy" 2>&1)" || status=$?
if [[ -n "$out" ]]; then
  printf '%s\n' "$out"
fi
if ((status != 0)) || [[ -n "$out" ]]; then
  echo "check-unit: verify FAILED (exit $status)" >&2
  exit 1
fi
echo "verify: OK (no messages)"

echo
echo "== systemd-analyze security --offline=yes"
# The exposure score must stay at or below MAX_EXPOSURE (lower is safer; 2.0 by default).
max_exposure="${MAX_EXPOSURE:-2.0}"
SYSTEMD_LOG_COLOR=0 systemd-analyze security --offline=yes --no-pager "$copy" >"$tmp/security.txt" 2>&1 || true
score="$(sed -nE 's/^(→|->) Overall exposure level for [^:]+: ([0-9.]+).*/\2/p' "$tmp/security.txt")"
if [[ -z "$score" ]]; then
  cat "$tmp/security.txt"
  echo "check-unit: no exposure score printed" >&2
  exit 1
fi
echo "exposure: $score (at most $max_exposure)"
if ! awk -v s="$score" -v m="$max_exposure" 'BEGIN { exit !(s <= m) }'; then
  cat "$tmp/security.txt"
  echo "check-unit: exposure $score is above $max_exposure" >&2
  exit 1
fi
if [[ "${VERBOSE:-0}" != 0 ]]; then
  cat "$tmp/security.txt"
fi
