#!/usr/bin/env bash
# Peak memory and upload time of an 8192x4096 HDR dome map for a 32x24 render (issue 27 item 8).
# Run from the repository root after `cargo build --release`; writes into /tmp/dome8k.
set -euo pipefail
bin="$PWD/target/release/illum"
py="${PYTHON:-.venv-py/bin/python}"
mkdir -p /tmp/dome8k && cd /tmp/dome8k
# An uncompressed Radiance map: a smooth sky and a 10x10 texel sun of 5000.
"$py" - <<'PY'
import numpy as np
w, h = 8192, 4096
y = np.linspace(0, 1, h)[:, None]; x = np.linspace(0, 1, w)[None, :]
r = (0.5 + 0.5 * np.sin(6.28 * x) * y).astype(np.float32)
img = np.stack([r, r * 0.8 + 0 * x, 0.6 + 0 * x * y], -1).astype(np.float32)
img[1000:1010, 3000:3010] = 5000
m = img.max(-1); e = np.ceil(np.log2(np.maximum(m, 1e-32))); sc = np.where(m > 1e-32, 256.0 / np.exp2(e), 0)
rgbe = np.zeros((h, w, 4), np.uint8)
rgbe[..., :3] = np.clip(img * sc[..., None], 0, 255).astype(np.uint8)
rgbe[..., 3] = np.where(m > 1e-32, e + 128, 0).astype(np.uint8)
with open('sky.hdr', 'wb') as f:
    f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w)); f.write(rgbe.tobytes())
PY
cat > scene.json <<'JSON'
{
  "camera": {"position": [0, 1, 5], "look_at": [0, 0.5, 0], "fov_y": 40, "resolution": [32, 24]},
  "integrator": {"type": "direct"},
  "textures": {"sky": {"file": "sky.hdr"}},
  "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
  "shapes": {"ball": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "m"}},
  "lights": {"env": {"dome": {}, "texture": "sky"}}
}
JSON
for i in 1 2; do
  /usr/bin/time -f "%e s wall, %M KB peak RSS" "$bin" render scene.json --spp 1 -o o.exr 2>&1 |
    grep -o "upload [0-9.]* s\|^[0-9.]* s wall.*"
done
