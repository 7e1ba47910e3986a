#!/bin/bash
# Packs what drape's GPU benchmarks need on a lent GPU host beside warp (run after
# ../shared/tools/gpu-warp/prepare, which empties .gpu/): the pure wheels the host lacks go in
# .gpu/c/wheels (its `activate` installs them), and Ray (too large for one upload) as an xz tarball
# split in two parts added to .gpu/a and .gpu/b, unpacked on the host with
#   cat /root/stash/raypart00 /root/stash/raypart01 | tar xJ -C /tmp/site
# Ray's Java jars, RLlib and its bundled dashboard client are left out (drape uses Ray core only).
#   .venv/bin/python is used for the versions when it exists: bash benchmarks/gpu_pack.sh
set -euo pipefail
root=$(git rev-parse --show-toplevel)
[ -x "$root/.venv/bin/python" ] && export PATH="$root/.venv/bin:$PATH"
[ -d "$root/.gpu/c/wheels" ] || { echo "run ../shared/tools/gpu-warp/prepare first" >&2; exit 2; }
dl() {  # binary wheels for the host's Python 3.12
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
    --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d "$1" "${@:2}"
}
pin() {  # NAME==VERSION as installed here (the GPU host then runs what the tests ran), else NAME
  for n in "$@"; do
    v=$(python3 -c "import importlib.metadata as m; print(m.version('$n'))" 2>/dev/null) && echo "$n==$v" || echo "$n"
  done
}
dl "$root/.gpu/c/wheels" $(pin zarr numcodecs donfig google-crc32c trimesh rtree tensorboardX jsonschema \
  jsonschema-specifications referencing rpds-py pytest pluggy iniconfig)
tmp=$(mktemp -d)
dl "$tmp" $(pin ray)
mkdir "$tmp/site" && (cd "$tmp/site" && unzip -q "$tmp"/ray-*.whl && rm -rf ray/jars ray/rllib ray/dashboard/client)
tar cf - -C "$tmp/site" . | xz -T0 -6 > "$tmp/ray.tar.xz"
split -n 2 -d "$tmp/ray.tar.xz" "$tmp/raypart"
cp "$tmp/raypart00" "$root/.gpu/a/"; cp "$tmp/raypart01" "$root/.gpu/b/"
rm -rf "$tmp"
du -sh "$root/.gpu/a" "$root/.gpu/b" "$root/.gpu/c"
