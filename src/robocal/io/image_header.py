"""The pixel size of an image file from its header, before any decoding (issue 29: a 1 MB PNG of
32768 x 32768 pixels decodes to 1 GiB and more; a "decompression bomb").

PNG (IHDR), JPEG (the first SOF marker), BMP (BITMAPINFOHEADER and the old core header) and TIFF
(tags 256/257 of the first image directory) are read from their first bytes; other files return
``None`` (the decoder's own limits apply).
"""

from __future__ import annotations

import struct
from pathlib import Path

__all__ = ["image_size_from_header", "MAX_IMAGE_PIXELS"]

#: The largest image [pixels] robocal decodes: 100 megapixels (a 12000 x 8000 camera is 96 MP).
MAX_IMAGE_PIXELS = 100_000_000

_JPEG_SOF = {0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF}


def _png(head: bytes):
    if head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR" and len(head) >= 24:
        return struct.unpack(">II", head[16:24])
    return None


def _jpeg(fh):
    fh.seek(2)
    while True:
        b = fh.read(1)
        while b and b != b"\xff":
            b = fh.read(1)
        while b == b"\xff":
            b = fh.read(1)
        if not b:
            return None
        marker = b[0]
        if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:
            continue
        seg = fh.read(2)
        if len(seg) < 2:
            return None
        length = struct.unpack(">H", seg)[0]
        if marker in _JPEG_SOF:
            data = fh.read(5)
            if len(data) < 5:
                return None
            h, w = struct.unpack(">HH", data[1:5])
            return w, h
        if marker == 0xD9 or length < 2:
            return None
        fh.seek(length - 2, 1)


def _bmp(head: bytes):
    if head[:2] != b"BM" or len(head) < 26:
        return None
    size = struct.unpack("<I", head[14:18])[0]
    if size == 12:
        return struct.unpack("<HH", head[18:22])
    w, h = struct.unpack("<ii", head[18:26])
    return abs(w), abs(h)


def _tiff(fh, head: bytes):
    order = {b"II": "<", b"MM": ">"}.get(head[:2])
    if order is None or struct.unpack(order + "H", head[2:4])[0] != 42:
        return None
    fh.seek(struct.unpack(order + "I", head[4:8])[0])
    raw = fh.read(2)
    if len(raw) < 2:
        return None
    dims = {}
    for _ in range(min(struct.unpack(order + "H", raw)[0], 4096)):
        entry = fh.read(12)
        if len(entry) < 12:
            break
        tag, typ = struct.unpack(order + "HH", entry[:4])
        if tag in (256, 257):
            dims[tag] = struct.unpack(order + ("H" if typ == 3 else "I"), entry[8:10] if typ == 3 else entry[8:12])[0]
    return (dims[256], dims[257]) if len(dims) == 2 else None


def image_size_from_header(path):
    """``(width, height)`` [px] read from the header of ``path``, or ``None`` when the format is
    not recognised or the header is cut short."""
    with open(Path(path), "rb") as fh:
        head = fh.read(32)
        if head[:8] == b"\x89PNG\r\n\x1a\n":
            return _png(head)
        if head[:2] == b"\xff\xd8":
            return _jpeg(fh)
        if head[:2] == b"BM":
            return _bmp(head)
        if head[:2] in (b"II", b"MM"):
            return _tiff(fh, head)
    return None
