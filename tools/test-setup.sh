#!/usr/bin/env bash
# Everything the tests need beyond `pip install .`: Python test packages and the optional
# face detector (MediaPipe, for `autobones landmarks`), Chromium (the viewer's browser test), Blender 3.4
# (a real glTF client, headless) with the numpy its glTF importer needs, Xvfb (Blender's window), and the Khronos
# glTF validator (npm). Idempotent; run as root (or with sudo) on Debian/Ubuntu.
set -euo pipefail
cd "$(dirname "$0")/.."
python -m pip install -q -e '.[test,landmarks]'
need=()
command -v blender >/dev/null || need+=(blender)
dpkg -s python3-numpy >/dev/null 2>&1 || need+=(python3-numpy)
# a display for Blender's window (tests/test_blender_addon.py presses the add-on's Rig button in it)
command -v xvfb-run >/dev/null || need+=(xvfb xauth)
command -v node >/dev/null || need+=(nodejs npm)
# headless Chromium for tests/test_view.py (playwright drives this one; it never downloads its own)
command -v chromium >/dev/null || need+=(chromium)
if ((${#need[@]})); then
  SUDO=$([ "$(id -u)" = 0 ] && echo "" || echo sudo)
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
[ -d tools/gltf-validator/node_modules/gltf-validator ] || \
  npm install --prefix tools/gltf-validator --no-audit --no-fund --silent >/dev/null
