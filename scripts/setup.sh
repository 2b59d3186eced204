#!/usr/bin/env bash
# Idempotent setup for a Debian 12 machine: Vulkan (Mesa lavapipe from bookworm-backports,
# validation layers, glslc, spirv-tools, graphviz, headless chromium for the HTML report's
# screenshot test) when missing, then .venv with rgraph editable, then Debian 13's validation
# layer made to load on Debian 12 in .venv (scripts/validation_layer.py).
set -euo pipefail
cd "$(dirname "$0")/.."

need_pkgs=()
for p in libvulkan1 mesa-vulkan-drivers vulkan-validationlayers glslc spirv-tools spirv-headers graphviz chromium; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need_pkgs+=("$p")
done
mesa_ok() {  # lavapipe from Mesa >= 25 (Vulkan 1.4, ray tracing)
  v=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
  [ -n "$v" ] && dpkg --compare-versions "$v" ge 25
}
if [ ${#need_pkgs[@]} -gt 0 ] || ! mesa_ok; then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
    echo "deb http://deb.debian.org/debian bookworm-backports main" | $SUDO tee /etc/apt/sources.list.d/backports.list >/dev/null
  fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq -t bookworm-backports \
    libvulkan1 mesa-vulkan-drivers >/dev/null
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq \
    vulkan-validationlayers glslc spirv-tools spirv-headers graphviz chromium >/dev/null
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then "$PY" -m venv .venv; fi
stamp=.venv/.rgraph-installed
# again when pyproject.toml, setup.py or a compiled accelerator's source changed (rgraph/**/*.pyx,
# *.pxi, *.pxd, and the modules setup.py's TWINS compiles as they are)
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ] || [ setup.py -nt "$stamp" ] \
   || [ -n "$(find rgraph \( -name '*.pyx' -o -name '*.pxi' -o -name '*.pxd' -o -path rgraph/compiler/sync.py \) -newer "$stamp" -print -quit)" ]; then
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -e ".[dev,ray]"  # ray: the tests of rgraph sweep --ray
  touch "$stamp"
fi
# a current Khronos validation layer in the venv (Debian 12's 1.3.239 crashes on ray tracing
# pipelines); on failure --validate keeps the system layer
.venv/bin/python scripts/validation_layer.py || true
