#!/bin/sh
# Install the Debian programs the end-to-end tests drive, when missing: chromium (Playwright drives
# this system browser; it never downloads its own) and nginx (tests/e2e/test_proxy_routing.py runs
# docker-compose's proxy configuration with it; only the program is used, no service is started).
set -eu
missing=""
[ -x /usr/bin/chromium ] || missing="$missing chromium"
[ -x /usr/sbin/nginx ] || missing="$missing nginx-light"
if [ -z "$missing" ]; then
    exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
# shellcheck disable=SC2086  # one word per package
$SUDO apt-get install -y -qq $missing
/usr/bin/chromium --version
/usr/sbin/nginx -v
