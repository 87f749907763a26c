#!/usr/bin/env python3
"""Reads the OpenEXR images SmallUPBP writes (scanline, float or half channels, compression
none, ZIPS or ZIP: the library's default) with numpy alone, and reports them.

  exr_image.py IMAGE.exr [--png OUT.png]

prints the size, the channels and per channel the mean, min, max and count of non-finite
values, and exits with status 1 when the image has a non-finite value or is all zero; --png
writes an sRGB preview (clamped at 1). As a module: `read(path)` -> {channel: H x W float64}.
"""
import argparse
import struct
import sys
import zlib

import numpy as np

MAGIC = 20000630
PIXEL_TYPES = {1: (np.float16, 2), 2: (np.float32, 4)}  # HALF, FLOAT (UINT=0 unsupported)
LINES_PER_BLOCK = {0: 1, 2: 1, 3: 16}  # NO, ZIPS, ZIP compression


class ExrError(Exception):
    pass


def read_header(data):
    """(attributes {name: (type, bytes)}, offset after the header)."""
    magic, version = struct.unpack_from("<ii", data, 0)
    if magic != MAGIC:
        raise ExrError("not an OpenEXR file")
    if version & 0x200 or version & 0x1000:
        raise ExrError("tiled or multi-part EXR: not supported")
    pos, attrs = 8, {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        end2 = data.index(b"\0", end + 1)
        kind = data[end + 1:end2].decode()
        (size,) = struct.unpack_from("<i", data, end2 + 1)
        attrs[name] = (kind, data[end2 + 5:end2 + 5 + size])
        pos = end2 + 5 + size
    return attrs, pos + 1


def channels(raw):
    """[(name, pixel type)] in file order (alphabetical)."""
    out, pos = [], 0
    while raw[pos] != 0:
        end = raw.index(b"\0", pos)
        (ptype,) = struct.unpack_from("<i", raw, end + 1)
        out.append((raw[pos:end].decode(), ptype))
        pos = end + 1 + 16
    return out


def unzip(block, expected):
    """OpenEXR's ZIP/ZIPS: zlib, then undo the byte predictor and the two-halves split."""
    d = np.frombuffer(zlib.decompress(block), dtype=np.uint8).astype(np.int64)
    if d.size != expected:
        raise ExrError(f"a ZIP block holds {d.size} bytes, expected {expected}")
    d[1:] -= 128  # each byte was stored as the difference from the previous one, + 128
    t = (np.cumsum(d) & 0xFF).astype(np.uint8)
    half = (t.size + 1) // 2
    out = np.empty_like(t)
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return out.tobytes()


def read(path):
    """{channel name: H x W float64} of a scanline EXR."""
    with open(path, "rb") as f:
        data = f.read()
    attrs, pos = read_header(data)
    xmin, ymin, xmax, ymax = struct.unpack("<4i", attrs["dataWindow"][1])
    width, height = xmax - xmin + 1, ymax - ymin + 1
    comp = attrs["compression"][1][0]
    if comp not in LINES_PER_BLOCK:
        raise ExrError(f"compression {comp}: only none, ZIPS and ZIP are supported")
    chans = channels(attrs["channels"][1])
    for name, ptype in chans:
        if ptype not in PIXEL_TYPES:
            raise ExrError(f"channel {name}: pixel type {ptype} not supported")
    lines = LINES_PER_BLOCK[comp]
    blocks = (height + lines - 1) // lines
    offsets = struct.unpack_from(f"<{blocks}Q", data, pos)
    images = {name: np.zeros((height, width)) for name, _ in chans}
    line_bytes = sum(PIXEL_TYPES[p][1] for _, p in chans) * width
    for offset in offsets:
        y, size = struct.unpack_from("<ii", data, offset)
        n = min(lines, ymax + 1 - y)
        block = data[offset + 8:offset + 8 + size]
        if comp != 0 and size < n * line_bytes:
            block = unzip(block, n * line_bytes)
        at = 0
        for row in range(y - ymin, y - ymin + n):
            for name, ptype in chans:
                dtype, nbytes = PIXEL_TYPES[ptype]
                images[name][row] = np.frombuffer(block, dtype=dtype, count=width, offset=at)
                at += nbytes * width
    return images


def write_png(path, rgb):
    """An 8-bit sRGB PNG of linear `rgb` (H x W x 3), clamped to [0, 1]."""
    c = np.clip(np.nan_to_num(rgb), 0.0, 1.0)
    c = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    img = (c * 255 + 0.5).astype(np.uint8)
    raw = b"".join(b"\0" + row.tobytes() for row in img)

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    h, w = img.shape[:2]
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("image")
    ap.add_argument("--png", help="write an sRGB preview here")
    args = ap.parse_args()
    try:
        images = read(args.image)
    except (OSError, ExrError, KeyError, struct.error, zlib.error) as e:
        sys.exit(f"exr_image.py: {args.image}: {e}")
    first = next(iter(images.values()))
    print(f"{args.image}: {first.shape[1]}x{first.shape[0]}, channels {', '.join(images)}")
    bad = False
    for name, img in images.items():
        finite = np.isfinite(img)
        print(f"  {name}: mean {img[finite].mean():.6g} min {img[finite].min():.6g} "
              f"max {img[finite].max():.6g} non-finite {int((~finite).sum())}")
        bad |= not finite.all()
    zero = all(not np.any(img) for img in images.values())
    if args.png and all(c in images for c in "RGB"):
        write_png(args.png, np.dstack([images[c] for c in "RGB"]))
    if bad or zero:
        sys.exit(f"exr_image.py: {args.image}: " + ("non-finite values" if bad else "all zero"))


if __name__ == "__main__":
    main()
