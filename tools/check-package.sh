#!/usr/bin/env bash
# Builds the Debian package from a build tree and checks it: the files a site admin needs
# are where Debian puts them, the units name the installed binaries, the configuration is
# a conffile, both binaries answer --version, the man pages render, and lintian reports no
# errors.
#
#   tools/check-package.sh [BUILD_DIR]     (default: build)
#
# Needs cpack (cmake), dpkg-deb, man and lintian (apt-get install lintian).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)"
for tool in cpack dpkg-deb lintian man; do
  command -v "$tool" >/dev/null || { echo "check-package: $tool not found (apt-get install lintian man-db)" >&2; exit 2; }
done
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$out" >"$out/cpack.log" 2>&1 ||
  { cat "$out/cpack.log" >&2; exit 1; }
deb=("$out"/floorpose_*_*.deb)
[[ -f "${deb[0]}" ]] || { echo "check-package: no floorpose_<version>_<arch>.deb" >&2; exit 1; }
echo "== $(basename "${deb[0]}")"

files="$(dpkg-deb -c "${deb[0]}" | awk '{print $6}')"
fail=0
for want in ./usr/bin/floorposed ./usr/bin/floorpose ./lib/systemd/system/floorposed.service \
  ./lib/systemd/system/floorpose-dashboard.service ./etc/floorpose/floorposed.conf \
  ./etc/floorpose/plans/ ./usr/lib/sysusers.d/floorpose.conf \
  ./usr/share/man/man8/floorposed.8.gz ./usr/share/man/man1/floorpose.1.gz \
  ./usr/share/doc/floorpose/copyright ./usr/share/doc/floorpose/changelog.gz; do
  grep -qxF "$want" <<<"$files" || { echo "missing: $want" >&2; fail=1; }
done
if grep -q '^\./usr/local' <<<"$files"; then echo "files under /usr/local" >&2; fail=1; fi

dpkg-deb -x "${deb[0]}" "$out/root"
dpkg-deb -e "${deb[0]}" "$out/control"
grep -qxF /etc/floorpose/floorposed.conf "$out/control/conffiles" || { echo "not a conffile: floorposed.conf" >&2; fail=1; }
grep -q '^Depends: .*libc6' "$out/control/control" || { echo "no Depends from dpkg-shlibdeps" >&2; fail=1; }
# floorposed opens PROJ at run time (platform/wgs84.cc): no soname of it for shlibdeps.
grep -q '^Depends: .*libproj[0-9]' "$out/control/control" || { echo "no Depends on PROJ" >&2; fail=1; }
for unit in floorposed floorpose-dashboard; do
  exec_start="$(grep '^ExecStart=' "$out/root/lib/systemd/system/$unit.service")"
  grep -q '^ExecStart=/usr/bin/floorpose' <<<"$exec_start" || { echo "$unit: $exec_start" >&2; fail=1; }
done
"$out/root/usr/bin/floorposed" --version
"$out/root/usr/bin/floorpose" --version
for page in man8/floorposed.8.gz man1/floorpose.1.gz; do
  MANWIDTH=80 man -l "$out/root/usr/share/man/$page" 2>&1 >/dev/null | grep . && { echo "man $page warns" >&2; fail=1; }
  MANWIDTH=80 man -l "$out/root/usr/share/man/$page" | head -3
done

echo "== lintian"
lintian_rc=0
lintian --fail-on error "${deb[0]}" >"$out/lintian.log" 2>&1 || lintian_rc=$?
grep -v 'running with root privileges' "$out/lintian.log" || true
((lintian_rc == 0)) || { echo "lintian reports errors" >&2; fail=1; }
exit "$fail"
