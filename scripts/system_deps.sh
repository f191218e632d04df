#!/usr/bin/env bash
# System libraries the Python wheels need at run time:
#   libusb-1.0-0  open3d's shared library links against it;
#   libosmesa6    offscreen MuJoCo rendering on a CPU (MUJOCO_GL=osmesa);
#   libgl1, libgomp1  open3d / torch runtime.
# Installs what is missing when we are root; otherwise says exactly what to install.
set -euo pipefail
need=()
for pkg in libusb-1.0-0 libosmesa6 libgl1 libgomp1; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || need+=("$pkg")
done
[ ${#need[@]} -eq 0 ] && exit 0
if ! command -v apt-get >/dev/null 2>&1; then
  echo "wrp-eval set-up: please install the system libraries: ${need[*]} (no apt-get here)" >&2
  exit 1
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "wrp-eval set-up: missing system libraries; run: sudo apt-get install -y ${need[*]}" >&2
  exit 1
fi
echo "wrp-eval set-up: installing ${need[*]}" >&2
apt-get update -qq >/dev/null
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
