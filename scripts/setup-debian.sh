#!/usr/bin/env bash
# Installs what a fresh Debian 12 (bookworm) machine lacks to build and test illum.
# Idempotent: safe to run again. Needs root (or sudo).
#   - bookworm-backports (deb822) for Mesa 25's lavapipe, which has VK_KHR_ray_query
#   - libvulkan1, vulkan-validationlayers, g++, libshaderc-dev (linked statically by build.rs),
#     libvulkan-dev (Vulkan headers for the C API test, tests/capi.rs)
#   - slurm-wlm and munge, for the single-node Slurm that scripts/test-slurm.sh starts (no
#     daemon is enabled or started here; Debian's packages start none without a slurm.conf)
#   - xvfb, xdotool and the X11 libraries winit loads (libxkbcommon-x11, libXcursor, libXrandr,
#     libXi), for `illum view` and its tests under a virtual display
#   - python3-venv, and kubernetes-validate (PyPI, pinned) in .venv-k8s/ for scripts/test-k8s.sh
#   - maturin, numpy, pytest and OpenEXR (PyPI, pinned) in .venv-py/ for the Python module;
#     usd-core for the USD tests; pyoidn for Open Image Denoise's libraries (--denoise)
#   - Debian's stock Mesa 22.3.6 lavapipe (no ray query) unpacked under .vk/mesa-stock, so the
#     compute-BVH path can be tested on a real device that lacks the extension.
set -euo pipefail

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

# Same mirror as the machine's own bookworm entry.
mirror="http://deb.debian.org/debian"
if [ -f /etc/apt/sources.list.d/debian.sources ]; then
  m=$(awk '/^URIs:/ {print $2; exit}' /etc/apt/sources.list.d/debian.sources)
  [ -n "$m" ] && mirror="$m"
elif [ -f /etc/apt/sources.list ]; then
  m=$(awk '$1=="deb" && $3 ~ /^bookworm$/ {print $2; exit}' /etc/apt/sources.list)
  [ -n "$m" ] && mirror="$m"
fi

bp=/etc/apt/sources.list.d/bookworm-backports.sources
want="Types: deb
URIs: $mirror
Suites: bookworm-backports
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg"
if [ ! -f "$bp" ] || [ "$(cat "$bp")" != "$want" ]; then
  echo "$want" | $SUDO tee "$bp" >/dev/null
  updated=0
fi

need_pkgs=()
for p in libvulkan1 libvulkan-dev vulkan-validationlayers g++ libshaderc-dev glslang-dev slurm-wlm munge python3-venv \
         xvfb xauth xdotool libxkbcommon-x11-0 libxcursor1 libxrandr2 libxi6; do
  dpkg -s "$p" >/dev/null 2>&1 || need_pkgs+=("$p")
done
mesa_ver=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
case "$mesa_ver" in
  25.*|2[6-9].*) ;;
  *) need_mesa=1 ;;
esac

if [ "${#need_pkgs[@]}" -gt 0 ] || [ "${need_mesa:-0}" = 1 ] || [ "${updated:-1}" = 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  if [ "${#need_pkgs[@]}" -gt 0 ]; then
    $SUDO apt-get install -y -qq --no-install-recommends "${need_pkgs[@]}"
  fi
  if [ "${need_mesa:-0}" = 1 ]; then
    $SUDO apt-get install -y -qq --no-install-recommends -t bookworm-backports mesa-vulkan-drivers
  fi
fi

# Stock bookworm lavapipe (Mesa 22.3.6, no ray query) beside the backports one.
here=$(cd "$(dirname "$0")/.." && pwd)
stock="$here/.vk/mesa-stock"
if [ ! -f "$stock/icd.json" ]; then
  tmp=$(mktemp -d)
  (cd "$tmp" && apt-get download -qq mesa-vulkan-drivers/bookworm >/dev/null 2>&1 ||
     { $SUDO apt-get update -qq && apt-get download -qq mesa-vulkan-drivers/bookworm; })
  mkdir -p "$stock/root"
  dpkg -x "$tmp"/mesa-vulkan-drivers_*.deb "$stock/root"
  lib=$(find "$stock/root" -name 'libvulkan_lvp.so' | head -n 1)
  cat >"$stock/icd.json" <<JSON
{ "file_format_version": "1.0.0",
  "ICD": { "library_path": "$lib", "api_version": "1.3.230" } }
JSON
  rm -rf "$tmp"
fi
# The Kubernetes manifest's schema check (scripts/test-k8s.sh): Kubernetes' own API schemas,
# bundled by kubernetes-validate, offline once installed.
venv="$here/.venv-k8s"
if [ ! -x "$venv/bin/kubernetes-validate" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --disable-pip-version-check kubernetes-validate==1.37.0
fi
# The Python module (python/, `import illum`): maturin builds it, pytest runs its tests against
# the CLI, OpenEXR reads both renders' files (scripts/test.sh builds and installs the wheel);
# Pixar's usd-core authors the USD stages of the USD tests (an independent writer and reader).
pyvenv="$here/.venv-py"
if [ ! -x "$pyvenv/bin/maturin" ]; then
  python3 -m venv "$pyvenv"
  "$pyvenv/bin/pip" install -q --disable-pip-version-check maturin==1.16.0 numpy==2.4.6 \
    pytest==9.2.0 OpenEXR==3.5.3
fi
if ! "$pyvenv/bin/python" -c "import pxr" 2>/dev/null; then
  "$pyvenv/bin/pip" install -q --disable-pip-version-check usd-core==26.11
fi
# Intel Open Image Denoise 2.5.1 (Debian 12 has no package): the pyoidn wheel ships its shared
# libraries, which illum loads for --denoise and the view's denoised preview (src/denoise.rs
# finds them in .venv-py).
if ! ls "$pyvenv"/lib/python3*/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2 >/dev/null 2>&1; then
  "$pyvenv/bin/pip" install -q --disable-pip-version-check pyoidn==2.5.1.0
fi
echo "setup-debian: ok (mesa $(dpkg-query -W -f='${Version}' mesa-vulkan-drivers); stock lavapipe at $stock)"
