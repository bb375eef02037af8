#!/usr/bin/env bash
# Installs what the experiment report's test needs and cachert's charts use, where it is missing: Debian's
# chromium (tests/report.rs loads the report in headless Chromium) and a TrueType font (chart labels).
# Part of the set-up (tests/README.md, "Set-up"); .ci/run runs it before the tests. The tests install nothing.
# Idempotent: with both already there it prints nothing and exits 0 at once. When it cannot install them it
# says why on stderr and exits 1.
set -euo pipefail
have_browser() {
    local b
    for b in chromium chromium-browser google-chrome; do
        command -v "$b" >/dev/null 2>&1 && return 0
    done
    return 1
}
font=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf
need=()
have_browser || need+=(chromium)
[ -e "$font" ] || need+=(fonts-dejavu-core)
[ ${#need[@]} -eq 0 ] && exit 0

fail() {
    echo "install-report-tools: cannot install ${need[*]}: $*" >&2
    exit 1
}
sudo=()
if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null 2>&1 || fail "not root, and no sudo"
    sudo=(sudo -n)
fi
command -v apt-get >/dev/null 2>&1 || fail "no apt-get: install them with this system's package manager"
export DEBIAN_FRONTEND=noninteractive
echo "install-report-tools: installing ${need[*]} (apt-get)" >&2
# A fresh container often has no package lists: try as is, then once more after apt-get update.
"${sudo[@]}" apt-get install -y -q --no-install-recommends "${need[@]}" >&2 \
    || { "${sudo[@]}" apt-get update -q >&2 && "${sudo[@]}" apt-get install -y -q --no-install-recommends "${need[@]}" >&2; } \
    || fail "apt-get failed (output above)"
have_browser || fail "apt-get succeeded, but no chromium is on the PATH"
[ -e "$font" ] || fail "apt-get succeeded, but $font is absent"
