#!/usr/bin/env bash
# Installs the Debian packages groupwise needs when they are missing: an offscreen GL
# library for MuJoCo (EGL from Mesa; OSMesa as the fallback) and ffmpeg's needs are covered
# by imageio-ffmpeg's bundled binary. Further packages come as arguments (the Makefile's
# dev setup: chromium for the browser tests; postgresql for the storage and server tests on
# PostgreSQL, whose server programs Debian keeps in /usr/lib/postgresql/<version>/bin, off
# PATH, where tests/postgres.py looks for them). Runs apt-get only as root; otherwise it
# names the packages and stops.
set -euo pipefail

packages=(libegl1 libgl1 libgl1-mesa-dri libosmesa6)
for extra in "$@"; do packages+=("$extra"); done

missing=()
for pkg in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

if ! command -v apt-get >/dev/null 2>&1; then
  echo "groupwise needs these system packages (Debian names): ${missing[*]}" >&2
  echo "install them with your package manager, then run make again" >&2
  exit 1
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "groupwise needs these Debian packages: ${missing[*]}" >&2
  echo "run: sudo apt-get install -y ${missing[*]}   then run make again" >&2
  exit 1
fi
echo "installing system packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
