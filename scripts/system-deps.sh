#!/usr/bin/env bash
# Installs the system components some tests run for real (gpsd and its clients, socat, headless
# Chromium for the offline HTML reports), where it can:
# as root on Debian/Ubuntu, with one `apt-get update` first. Elsewhere it says what is missing; the tests
# that need a missing component skip with a message naming it.
set -u
need=()
command -v gpsd >/dev/null 2>&1 || need+=(gpsd)
command -v gpsfake >/dev/null 2>&1 || need+=(gpsd-clients)
command -v socat >/dev/null 2>&1 || need+=(socat)
command -v chromium >/dev/null 2>&1 || need+=(chromium)
[ ${#need[@]} -eq 0 ] && exit 0
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "installing system packages: ${need[*]}"
  export DEBIAN_FRONTEND=noninteractive
  if apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null 2>&1; then
    exit 0
  fi
  echo "warning: apt-get could not install ${need[*]}; the tests that need them will skip" >&2
else
  echo "note: not root on Debian: ${need[*]} not installed; the tests that need them will skip" >&2
fi
exit 0
