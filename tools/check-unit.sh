#!/usr/bin/env bash
# Verifies systemd/floorposed.service and prints its systemd exposure score.
#
#   tools/check-unit.sh [UNIT]     (default: systemd/floorposed.service)
#
# `systemd-analyze verify` insists that the ExecStart binary exists, and floorposed is
# usually not installed where this runs, so the check uses a temporary copy of the unit
# whose ExecStart binary is replaced by /bin/true (arguments kept). Exits non-zero when
# verification prints anything or fails. Needs systemd-analyze (Debian: apt-get install
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
# The score is informational: --threshold is not used so that a systemd upgrade that
# rescores settings does not fail the check.
SYSTEMD_LOG_COLOR=0 systemd-analyze security --offline=yes --no-pager "$copy" 2>&1 |
  tee "$tmp/security.txt" | grep -E '^(→|->) Overall exposure level' ||
  { cat "$tmp/security.txt"; echo "check-unit: no exposure score printed" >&2; exit 1; }
if [[ "${VERBOSE:-0}" != 0 ]]; then
  cat "$tmp/security.txt"
fi
