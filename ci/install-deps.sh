#!/usr/bin/env bash
# Installs every Debian package in ci/packages.txt (or in the list files
# given, e.g. ci/packages-peer.txt). Idempotent: does nothing when all are
# present. Not root: prints the exact apt-get line and exits 1.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
lists=("$@")
((${#lists[@]})) || lists=("$here/packages.txt")
mapfile -t pkgs < <(cat "${lists[@]}" | grep -v '^\s*#' | sed '/^\s*$/d')

missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi

cmd=(apt-get install -y --no-install-recommends "${missing[@]}")
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null && sudo -n true 2>/dev/null; then
    sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive "${cmd[@]}"
    exit 0
  fi
  echo "install-deps: missing packages; run as root:" >&2
  echo "  apt-get update && ${cmd[*]}" >&2
  exit 1
fi
echo "install-deps: installing ${missing[*]}"
apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${cmd[@]}"
