#!/usr/bin/env bash
# Pack what a comparison carries to the GPU machine into one xz tarball, .peers.tar.xz at the repo
# root (git-ignored): the .gpu bundle and the wheels of .whl/ unpacked (xz packs the shared
# libraries in them much tighter than the wheels' zip does: ~42 MiB of wheels become ~23 MiB).
# The Sponza comparison needs it: working tree (~9 MiB) + .gpu with CrytekSponza (~35 MiB) + .whl
# (~42 MiB) is over the 64 MiB one device call carries; packed it is about 48 MiB. Run HERE:
#
#   bash bench/peers/prepare_wheels.sh
#   cargo build --release && ../shared/tools/gpu-bundle.sh --scene CrytekSponza && strip .gpu/bin/lightgraph
#   bash bench/peers/pack.sh
#
# then carry [".peers.tar.xz"] only: run_gpu.sh unpacks it (.gpu/ and .peers-site/, which it puts
# on PYTHONPATH) before it starts. XZ_LEVEL (default 9) trades packing time (~3 min) for size.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root"
die() { echo "pack.sh: $*" >&2; exit 1; }
[ -f .gpu/run.sh ] || die ".gpu/run.sh missing: bundle with ../shared/tools/gpu-bundle.sh (Sponza: --scene CrytekSponza)"
ls .whl/*.whl >/dev/null 2>&1 || die "no wheels in .whl/: run bench/peers/prepare_wheels.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/.peers-site"
for w in .whl/*.whl; do
  python3 -c 'import sys, zipfile; zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])' "$w" "$tmp/.peers-site" \
    || die "cannot unpack $w"
done
tar -cf - .gpu -C "$tmp" .peers-site | xz -T0 "-${XZ_LEVEL:-9}" > .peers.tar.xz.part
mv .peers.tar.xz.part .peers.tar.xz
exclude=$(git rev-parse --path-format=absolute --git-path info/exclude)
mkdir -p "$(dirname "$exclude")"
for pattern in /.peers.tar.xz /.peers-site/; do
  grep -qx "$pattern" "$exclude" 2>/dev/null || echo "$pattern" >> "$exclude"
done
tree=$(git ls-files -z | xargs -0 du -cb 2>/dev/null | tail -1 | cut -f1)
packed=$(stat -c %s .peers.tar.xz)
awk -v t="$tree" -v p="$packed" 'BEGIN {
  printf ".peers.tar.xz: %.1f MiB; with the tracked working tree (%.1f MiB): %.1f MiB of the 64 MiB a call carries\n", p / 1048576, t / 1048576, (t + p) / 1048576
  if ((t + p) / 1048576 > 62) { print "pack.sh: warning: that leaves under 2 MiB for untracked files" > "/dev/stderr" }
}'
