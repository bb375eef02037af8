#!/usr/bin/env bash
# Installs what the experiment report's test needs and cachert's charts use, where it is missing: Debian's
# chromium (the report is loaded in headless Chromium) and a TrueType font (chart labels).
# tests/report.rs runs it when chromium is absent; run it by hand to install them once.
set -euo pipefail
need=()
command -v chromium >/dev/null 2>&1 || need+=(chromium)
[ -e /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || need+=(fonts-dejavu-core)
[ ${#need[@]} -eq 0 ] && exit 0
sudo=()
if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null 2>&1 || { echo "installing ${need[*]} needs root (or sudo)" >&2; exit 1; }
    sudo=(sudo -n)
fi
command -v apt-get >/dev/null 2>&1 || { echo "no apt-get: install ${need[*]} with this system's package manager" >&2; exit 1; }
export DEBIAN_FRONTEND=noninteractive
echo "installing ${need[*]} (apt-get)" >&2
"${sudo[@]}" apt-get install -y -q --no-install-recommends "${need[@]}" >&2 \
    || { "${sudo[@]}" apt-get update -q >&2 && "${sudo[@]}" apt-get install -y -q --no-install-recommends "${need[@]}" >&2; }
