#!/usr/bin/env bash
# Installs the system libraries MuJoCo needs for headless rendering (EGL and OSMesa, from
# Debian's Mesa packages) when they are missing. Safe to run repeatedly.
set -euo pipefail
have() { ldconfig -p 2>/dev/null | grep -q "$1"; }
if have libEGL.so.1 && have libOSMesa.so && ldconfig -p | grep -q libGL.so.1; then
  exit 0
fi
pkgs="libegl1 libgl1 libgl1-mesa-dri libosmesa6"
if [ "$(id -u)" = 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO="sudo"; else
  echo "setup: headless GL libraries missing and no root: install $pkgs" >&2; exit 1
fi
echo "setup: installing $pkgs"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $pkgs >/dev/null
