#!/usr/bin/env python3
"""Linux portability edits for a copy of SmallUPBP's source (github.com/PetrVevoda/smallupbp).

Usage: port.py TREE, where TREE is a *copy* of the SmallUPBP checkout (build.sh makes it);
the files are edited in place. Each edit names the text it expects and fails loudly when that
text is missing, so a different SmallUPBP revision is reported instead of half-ported.
Only short fragments of SmallUPBP's code are quoted here, to find the places to change.
"""

import pathlib
import re
import sys


class PortError(Exception):
    pass


def replace(path, old, new, count):
    """Replace `old` by `new` in `path`, expecting exactly `count` occurrences."""
    text = path.read_text(encoding="latin-1")
    found = text.count(old)
    if found != count:
        raise PortError(f"{path}: expected {count} of {old!r}, found {found}")
    path.write_text(text.replace(old, new), encoding="latin-1")


def resub(path, pattern, new, count):
    """Regular-expression replacement in `path`, expecting exactly `count` matches."""
    text = path.read_text(encoding="latin-1")
    out, found = re.subn(pattern, new, text)
    if found != count:
        raise PortError(f"{path}: expected {count} matches of {pattern!r}, found {found}")
    path.write_text(out, encoding="latin-1")


INCLUDE = re.compile(r'^(\s*#\s*include\s*")([^"]*)(")', re.M)
OPENEXR_INCLUDE = re.compile(r'"(?:\.\./)+OpenEXR/([A-Za-z0-9_]+\.h)"')


def match_case(base, rel):
    """`rel` (relative to `base`) with each part spelt as on disk (Windows ignores case),
    or None when there is no such file."""
    here, parts = base, []
    for part in rel.split("/"):
        if part not in ("..", "."):
            names = {p.name.lower(): p.name for p in here.iterdir()} if here.is_dir() else {}
            if part.lower() not in names:
                return None
            part = names[part.lower()]
        here = here / part
        parts.append(part)
    return "/".join(parts) if here.is_file() else None


def fix_case(path, src, rel):
    """An include path whose case differs from the file on disk, corrected."""
    for base in (path.parent, src):
        if (base / rel).exists():
            return rel
    for base in (path.parent, src):
        fixed = match_case(base, rel)
        if fixed:
            return fixed
    return rel


def fix_includes(path, src):
    """Backslashes in #include paths become slashes and their letter case is the files' own;
    SmallUPBP's relative paths into the OpenEXR folder become <Header.h>, found through the
    build's include path (the Linux OpenEXR configuration, not the Windows one at the top of
    the OpenEXR folder)."""
    text = path.read_text(encoding="latin-1")

    def fixed(m):
        rel = fix_case(path, src, m.group(2).replace("\\", "/"))
        return m.group(1) + rel + m.group(3)

    new = INCLUDE.sub(fixed, text)
    new = OPENEXR_INCLUDE.sub(r"<\1>", new)
    if new != text:
        path.write_text(new, encoding="latin-1")


def port_smallupbp(src):
    """The edits to SmallUPBP's own sources (`src` = its SmallUPBP/src folder)."""
    for path in sorted(src.rglob("*")):
        if path.suffix in (".hxx", ".cxx", ".h"):
            fix_includes(path, src)
    # Windows headers: Timer.hxx only needs the performance counter (shimmed in linux_compat.h).
    replace(src / "Misc/Timer.hxx", "#include <winsock2.h>", "", 1)
    replace(src / "Misc/Timer.hxx", "#include <windows.h>", "", 1)
    # The render loop's time budget and reported time: wall clock, as clock() is on Windows.
    replace(src / "SmallUPBP.cxx", "clock()", "lg_wall_clock()", 3)
    # MSVC accepts what standard C++ does not:
    # a temporary std::string bound to a non-const reference (Save does not modify the name),
    replace(src / "Misc/Framebuffer.hxx", "void Save(std::string & aFilename,",
            "void Save(const std::string & aFilename,", 1)
    # a dependent type without `typename`,
    resub(src / "Path/PriorityStack.hxx",
          r"(?<!typename )(std::forward_list<std::pair<ElementType, int>>\s*::const_iterator)",
          r"typename \1", 6)
    # a temporary passed as a non-const reference or its address taken (it lives to the end of
    # the full expression),
    replace(src / "Scene/Scene.hxx", "Intersect(Ray(aPoint, aDir), Isect(aTMax), stackCopy,",
            "Intersect(Ray(aPoint, aDir), lg_lvalue(Isect(aTMax)), stackCopy,", 2)
    replace(src / "Beams/Grid.hxx", "*(Pos *)(&((pos - mAABB.point1) * mInvCellSize))",
            "*(Pos *)(&lg_lvalue((pos - mAABB.point1) * mInvCellSize))", 1)
    # a template that names a type declared after it, dependent types without `typename` and
    # explicit specialisations without `template<>`,
    bbox = src / "Structs/BoundingBox.hxx"
    replace(bbox, "BoundingBox3 result;", "BoundingBox result;", 1)
    resub(bbox, r"(?<!typename )TPoint::DirType(?!::)", "typename TPoint::DirType", 6)
    resub(bbox, r"(?m)^(INLINE \w+ (?:BoundingBox3|BoundingBox<Pos>)::)", r"template<> \1", 4)
    resub(bbox, r"(?m)^((?:float|Pos) BoundingBox3::)", r"template<> inline \1", 2)
    # and a C-style cast of an SSE temporary to float& (its first lane is meant).
    resub(src / "PrecompiledLibs/FastFloat/FastFloat.h",
          r"\(float&\)(FastPow::\w+\(_mm_set1_ps\(\w+\), _mm_set1_ps\(\w+\)\)|"
          r"FastPow::\w+\(_mm_set1_ps\(\w+\)\))",
          r"_mm_cvtss_f32(\1)", 3)


def port_embree(embree):
    """Embree 2.0 built for Linux with a current g++. Its own __rdtsc/__rdpmc clash with the
    compiler's intrinsics of the same names (which do the same), so they are renamed away."""
    intrinsics = embree / "sys/intrinsics.h"
    replace(intrinsics, "__forceinline uint64 __rdtsc()", "__forceinline uint64 embree_unused_rdtsc()", 1)
    replace(intrinsics, "__forceinline uint64 __rdpmc(int i) {\n  uint32 high,low;",
            "__forceinline uint64 embree_unused_rdpmc(int i) {\n  uint32 high,low;", 1)
    # A shuffle of a boolean mask gives an integer vector; the mask is built from a float one.
    replace(embree / "simd/sseb.h", "return _mm_shuffle_epi32(a, _MM_SHUFFLE(i3, i2, i1, i0));",
            "return _mm_castsi128_ps(_mm_shuffle_epi32(a, _MM_SHUFFLE(i3, i2, i1, i0)));", 1)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: port.py TREE (a copy of the SmallUPBP source tree)")
    tree = pathlib.Path(sys.argv[1])
    src = tree / "SmallUPBP/src"
    if not (src / "SmallUPBP.cxx").is_file():
        sys.exit(f"port.py: {src}/SmallUPBP.cxx not found: is {tree} a SmallUPBP checkout?")
    try:
        port_smallupbp(src)
        port_embree(tree / "embree-2.0/embree")
    except PortError as e:
        sys.exit(f"port.py: {e} (a SmallUPBP revision these edits were not written for?)")


if __name__ == "__main__":
    main()
