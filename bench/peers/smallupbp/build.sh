#!/usr/bin/env bash
# Builds SmallUPBP (github.com/PetrVevoda/smallupbp, Windows/Visual Studio only) on Linux with
# g++ and OpenMP, from an unmodified checkout, into BUILD_DIR/SmallUPBP.
#
#   bench/peers/smallupbp/build.sh SMALLUPBP_CHECKOUT [BUILD_DIR]
#
# BUILD_DIR defaults to bench/peers/smallupbp/build (git-ignored). The checkout is not touched:
# its SmallUPBP, embree-2.0/embree and OpenEXR/src/OpenEXR folders are copied to
# BUILD_DIR/tree and port.py edits the copy. Environment: JOBS (parallel compiles, default
# nproc), CXX/CC (default g++/gcc), OPT (default "-O3 -msse4.2": the SIMD level Embree 2.0's
# own Linux build defaults to; SmallUPBP needs SSE4.1), NICE (default 10).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
usage="usage: $0 SMALLUPBP_CHECKOUT [BUILD_DIR]"
[ $# -ge 1 ] && [ $# -le 2 ] || { echo "$usage" >&2; exit 2; }
src=$(cd "$1" 2>/dev/null && pwd) || { echo "build.sh: $1: no such folder" >&2; exit 2; }
build=${2:-$here/build}
case "$here$src$build" in
    *[[:space:]]*) echo "build.sh: the checkout, build and script paths must not contain spaces" >&2; exit 2 ;;
esac
for f in SmallUPBP/src/SmallUPBP.cxx embree-2.0/embree/embree.cpp \
         OpenEXR/src/OpenEXR/IlmImf/ImfRgbaFile.cpp; do
    [ -f "$src/$f" ] || { echo "build.sh: $src/$f missing: not a SmallUPBP checkout?" >&2; exit 2; }
done
CXX=${CXX:-g++}
CC=${CC:-gcc}
JOBS=${JOBS:-$(nproc)}
OPT=${OPT:-"-O3 -msse4.2"}
NICE=${NICE:-10}
for tool in "$CXX" "$CC" python3; do
    command -v "$tool" >/dev/null || { echo "build.sh: $tool not found" >&2; exit 2; }
done
echo 'int main(){return 0;}' | "$CXX" -fopenmp -x c++ - -o /dev/null 2>/dev/null \
    || { echo "build.sh: $CXX cannot build with -fopenmp (install libgomp)" >&2; exit 2; }

# --- copy and port ------------------------------------------------------------------------
tree=$build/tree
rm -rf "$tree" "$build/obj" "$build/gen"
mkdir -p "$tree/embree-2.0" "$tree/OpenEXR/src" "$build/obj" "$build/gen"
cp -r "$src/SmallUPBP" "$tree/"
cp -r "$src/embree-2.0/embree" "$tree/embree-2.0/"
cp -r "$src/OpenEXR/src/OpenEXR" "$tree/OpenEXR/src/"
python3 "$here/port.py" "$tree"
# Embree's CMake would generate this; openLibrary (unused by SmallUPBP) needs the name.
echo '#define CMAKE_BUILD_DIR "."' > "$build/gen/CMakeDefines.h"

sup=$tree/SmallUPBP/src
emb=$tree/embree-2.0/embree
exr=$tree/OpenEXR/src/OpenEXR
EXR_INC="-I$exr/config -I$exr/Half -I$exr/Iex -I$exr/IexMath -I$exr/IlmThread -I$exr/Imath -I$exr/IlmImf -I$exr/zlib"
# -w: these are third-party sources; their warnings are not ours to fix.
# -fno-strict-aliasing: SmallUPBP reads values through pointers of other types (Pos as Dir, ...),
# which MSVC never optimises against; with g++ -O3's strict aliasing its photon beams (bb1d)
# come out 15% dark in scene 1 (smoke.sh catches it). Embree gets it too, for the same reason.
CXXFLAGS_EXR="-std=c++11 $OPT -DNDEBUG -w $EXR_INC"
CFLAGS_ZLIB="$OPT -DNDEBUG -w -I$exr/zlib"
CXXFLAGS_EMB="-std=c++11 $OPT -fno-strict-aliasing -DNDEBUG -w -flax-vector-conversions -include x86intrin.h -I$emb -I$build/gen"
CXXFLAGS_SUP="-std=c++11 $OPT -fno-strict-aliasing -DNDEBUG -fopenmp -w -Wno-narrowing -flax-vector-conversions \
 -include $here/linux_compat.h -I$sup -I$emb $EXR_INC"

# compile OUT_DIR LIST_FILE COMPILER FLAGS...: each source named in LIST_FILE (relative to
# the current folder) to OUT_DIR/<lib>_<path>.o, JOBS at a time; stops at the first failure.
compile() {
    local out=$1 list=$2; shift 2
    local cmd="$*" prefix
    prefix=$(basename "$(pwd)")
    mkdir -p "$out"
    export out prefix NICE cmd
    xargs -a "$list" -P "$JOBS" -I{} sh -c '
        o="$out/${prefix}_$(echo {} | tr / _).o"
        nice -n "$NICE" $cmd -c "{}" -o "$o" || { echo "build.sh: compiling {} failed" >&2; exit 255; }'
}

# --- Embree 2.0: the file lists of its CMakeLists (Xeon, no AVX) ---------------------------
cd "$emb"
cat > "$build/gen/embree.list" <<'LIST'
sys/platform.cpp
sys/sysinfo.cpp
sys/filename.cpp
sys/library.cpp
sys/thread.cpp
sys/network.cpp
sys/taskscheduler.cpp
sys/taskscheduler_sys.cpp
sys/sync/mutex.cpp
sys/sync/condition.cpp
sys/stl/string.cpp
embree.cpp
common/alloc.cpp
common/stat.cpp
common/accel.cpp
common/registry_accel.cpp
common/registry_builder.cpp
common/registry_intersector.cpp
geometry/triangle_mesh.cpp
geometry/virtual_scene.cpp
builders/primrefgen.cpp
builders/heuristic_binning.cpp
builders/heuristic_spatial.cpp
builders/splitter.cpp
builders/splitter_parallel.cpp
builders/splitter_fallback.cpp
bvh2/bvh2.cpp
bvh2/bvh2_intersector1.cpp
bvh2/bvh2_intersector4.cpp
bvh2/bvh2_intersector8.cpp
bvh4/bvh4.cpp
bvh4/bvh4_intersector1.cpp
bvh4/bvh4_intersector4_single.cpp
bvh4/bvh4_intersector4_chunk.cpp
bvh4/bvh4_intersector4_hybrid.cpp
bvh4/bvh4_intersector8_single.cpp
bvh4/bvh4_intersector8_chunk.cpp
bvh4/bvh4_intersector8_hybrid.cpp
bvh4i/bvh4i.cpp
bvh4i/bvh4i_intersector1.cpp
bvh4mb/bvh4mb.cpp
bvh4mb/bvh4mb_builder.cpp
bvh4mb/bvh4mb_intersector1.cpp
bvh4mb/bvh4mb_intersector4.cpp
bvh4mb/bvh4mb_intersector8.cpp
LIST
echo "build.sh: Embree ($(wc -l < "$build/gen/embree.list") files)"
compile "$build/obj" "$build/gen/embree.list" "$CXX" $CXXFLAGS_EMB

# --- SmallUPBP: the five translation units of its Visual Studio project -------------------
cd "$sup"
printf '%s\n' SmallUPBP.cxx Bre/Bre.cxx Scene/Geometry.cxx Misc/ObjReader.cxx \
    Beams/PhBeams.cxx > "$build/gen/smallupbp.list"
echo "build.sh: SmallUPBP (5 files)"
compile "$build/obj" "$build/gen/smallupbp.list" "$CXX" $CXXFLAGS_SUP

# --- OpenEXR 2.2 (static, Linux configuration in config/) --------------------------------
cd "$exr"
# (Not IlmImfUtil, which the Visual Studio project also compiles: SmallUPBP does not use it.)
ls Half/half.cpp Iex/*.cpp IexMath/*.cpp Imath/*.cpp IlmImf/Imf*.cpp IlmThread/*.cpp \
    | grep -v Win32 > "$build/gen/exr.list"
ls zlib/*.c > "$build/gen/zlib.list"
if [ ! -f IlmImf/dwaLookups.h ]; then
    # A generated table that the repository ships; regenerate it when a copy lacks it.
    echo "build.sh: generating OpenEXR's dwaLookups.h"
    ls Half/half.cpp Iex/*.cpp IlmThread/*.cpp | grep -v Win32 > "$build/gen/dwa.list"
    compile "$build/gen/dwa" "$build/gen/dwa.list" "$CXX" $CXXFLAGS_EXR
    nice -n "$NICE" "$CXX" $CXXFLAGS_EXR IlmImf/dwaLookups.cpp "$build"/gen/dwa/*.o -lpthread \
        -o "$build/gen/dwaLookups"
    # (it reports its progress on stderr)
    "$build/gen/dwaLookups" > IlmImf/dwaLookups.h.tmp 2> "$build/gen/dwaLookups.log" \
        || { echo "build.sh: dwaLookups failed, see $build/gen/dwaLookups.log" >&2; exit 1; }
    mv IlmImf/dwaLookups.h.tmp IlmImf/dwaLookups.h
fi
echo "build.sh: OpenEXR ($(wc -l < "$build/gen/exr.list") C++ + $(wc -l < "$build/gen/zlib.list") C files)"
compile "$build/obj" "$build/gen/exr.list" "$CXX" $CXXFLAGS_EXR
compile "$build/obj" "$build/gen/zlib.list" "$CC" $CFLAGS_ZLIB

nice -n "$NICE" "$CXX" -fopenmp "$build"/obj/*.o -lpthread -ldl -o "$build/SmallUPBP"
echo "build.sh: built $build/SmallUPBP"
