#!/usr/bin/env bash
# Prepare the Python wheels that the Mitsuba comparison needs on the GPU machine (which has
# Python 3.12 + numpy but no network). Run HERE (x86_64, with access to PyPI), from anywhere:
#
#   bash bench/peers/prepare_wheels.sh
#
# It downloads mitsuba==3.9.1 and drjit==1.5.0 (cp312, manylinux x86_64) into a cache folder
# outside the repo (WHEEL_CACHE, default /tmp/lightgraph-peer-wheels; the full wheels stay there,
# e.g. for a local smoke test with the scalar_rgb variant), repacks mitsuba keeping only the
# cuda_ad_rgb and llvm_ad_rgb variants and without the spectral upsampling table
# (../shared/tools/slim_mitsuba_wheel.py), and leaves exactly the slim mitsuba wheel and the
# drjit wheel in .whl/ at the repo root (git-ignored through .git/info/exclude). The full pair is
# ~64 MiB, over what one device call carries; the slim pair is ~40 MiB.
set -euo pipefail

MITSUBA_VERSION=3.9.1
DRJIT_VERSION=1.5.0
KEEP_VARIANTS=${KEEP_VARIANTS:-cuda_ad_rgb,llvm_ad_rgb}
MAX_MIB=${MAX_MIB:-45}

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
slim=$root/../shared/tools/slim_mitsuba_wheel.py
cache=${WHEEL_CACHE:-/tmp/lightgraph-peer-wheels}
py=${PYTHON:-python3}

die() { echo "prepare_wheels: $*" >&2; exit 1; }
[ -f "$slim" ] || die "missing $slim (the shared/ folder beside the repo)"
"$py" -m pip --version >/dev/null 2>&1 || die "'$py -m pip' does not work; set PYTHON=/path/to/python3"
mkdir -p "$cache/full" "$cache/slim"

# pip matches each --platform tag exactly: start with the usual manylinux tags, then add
# manylinux_2_N for other N (the device README's advice) if pip finds no matching distribution.
base_tags=(manylinux_2_28_x86_64 manylinux_2_27_x86_64 manylinux_2_17_x86_64 manylinux2014_x86_64 manylinux1_x86_64)
extra_tags=()
for n in $(seq 5 39); do
  case " ${base_tags[*]} " in *" manylinux_2_${n}_x86_64 "*) ;; *) extra_tags+=("manylinux_2_${n}_x86_64") ;; esac
done

download() { # $1 = requirement
  local req=$1 tags args
  for tags in "${base_tags[*]}" "${base_tags[*]} ${extra_tags[*]}"; do
    args=()
    for t in $tags; do args+=(--platform "$t"); done
    if "$py" -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
         --implementation cp "${args[@]}" -d "$cache/full" "$req"; then
      return 0
    fi
    echo "prepare_wheels: no wheel of $req for tags: $tags; retrying with more manylinux tags" >&2
  done
  die "pip could not download a cp312 manylinux x86_64 wheel of $req"
}

ls "$cache/full"/mitsuba-$MITSUBA_VERSION-cp312-*.whl >/dev/null 2>&1 || download "mitsuba==$MITSUBA_VERSION"
ls "$cache/full"/drjit-$DRJIT_VERSION-cp312-*.whl >/dev/null 2>&1 || download "drjit==$DRJIT_VERSION"
mitsuba_full=$(ls "$cache/full"/mitsuba-$MITSUBA_VERSION-cp312-*.whl | head -1)
drjit_full=$(ls "$cache/full"/drjit-$DRJIT_VERSION-cp312-*.whl | head -1)

rm -f "$cache/slim"/*.whl
"$py" "$slim" "$mitsuba_full" --keep "$KEEP_VARIANTS" --drop-spectral-data --out-dir "$cache/slim"
mitsuba_slim=$(ls "$cache/slim"/mitsuba-*.whl | head -1)

# .whl/ holds exactly one mitsuba and one drjit wheel (two versions of one package stop the
# install on the device). Other wheels found there are left alone but reported: run_gpu.sh
# installs every wheel in .whl/.
mkdir -p "$root/.whl"
rm -f "$root/.whl"/mitsuba-*.whl "$root/.whl"/drjit-*.whl
cp "$mitsuba_slim" "$drjit_full" "$root/.whl/"
others=$(cd "$root/.whl" && ls | grep -v -e '^mitsuba-' -e '^drjit-' || true)
[ -z "$others" ] || echo "prepare_wheels: warning: .whl/ also holds (left as they are, installed too): $others" >&2

# git's exclude file (in a worktree, the main repository's: .git is then a file)
if exclude=$(cd "$root" && git rev-parse --path-format=absolute --git-path info/exclude 2>/dev/null); then
  mkdir -p "$(dirname "$exclude")"
  grep -qx '/.whl/' "$exclude" 2>/dev/null || echo '/.whl/' >> "$exclude"
fi

echo "wheels in $root/.whl:"
(cd "$root/.whl" && for f in *; do
  awk -v f="$f" -v b="$(stat -c %s "$f")" 'BEGIN { printf "  %-70s %6.2f MiB\n", f, b / 1048576 }'
done)
total=$(du -cb "$root/.whl"/* | tail -1 | cut -f1)
awk -v b="$total" -v max="$MAX_MIB" 'BEGIN {
  printf "total: %.2f MiB (everything one device call carries must stay under 64 MiB; aim: < %s MiB)\n", b / 1048576, max
  if (b / 1048576 > max) { printf "prepare_wheels: warning: .whl/ is over %s MiB\n", max > "/dev/stderr" }
}'
