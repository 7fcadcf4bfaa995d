"""Image files: reading grey images and writing PNGs atomically (OpenCV's codecs; issue 14)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .atomic import atomic_write_bytes
from .header import FileFormatError

__all__ = ["ImageFileError", "IMAGE_SUFFIXES", "read_image_gray", "write_png", "encode_png", "list_images"]

#: file name endings read as images (case-insensitive)
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


class ImageFileError(FileFormatError):
    """An image file cannot be read or written."""


def read_image_gray(path) -> np.ndarray:
    """An 8-bit grey image (H, W) from a PNG/JPEG/BMP/TIFF file; :class:`ImageFileError` if unreadable
    or larger than :data:`~robocal.io.image_header.MAX_IMAGE_PIXELS` (checked from the header before
    decoding), ``FileNotFoundError`` if missing."""
    import cv2

    from .image_header import MAX_IMAGE_PIXELS, image_size_from_header

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"{p}: no such image file")
    size = image_size_from_header(p)  # before decoding: a small file may expand to gigabytes
    if size is not None and size[0] * size[1] > MAX_IMAGE_PIXELS:
        raise ImageFileError(p, f"{size[0]} x {size[1]} px is more than the {MAX_IMAGE_PIXELS / 1e6:g} megapixels "
                                "robocal decodes (a decompression bomb or the wrong file?); scale the image down")
    img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
    if img is None:
        raise ImageFileError(p, "not an image OpenCV can read (PNG, JPEG, BMP, TIFF expected)")
    return img


def write_png(path, image: np.ndarray, overwrite: bool = False) -> Path:
    """Write an 8-bit grey (H, W) or BGR (H, W, 3) image as PNG through a temporary file and a rename."""
    import cv2

    img = np.asarray(image)
    if img.dtype != np.uint8 or img.ndim not in (2, 3):
        raise ValueError(f"write_png: expected an 8-bit (H, W) or (H, W, 3) image, got {img.dtype} {img.shape}")
    ok, data = cv2.imencode(".png", img)
    if not ok:
        raise ImageFileError(path, "PNG encoding failed")
    return atomic_write_bytes(path, data.tobytes(), overwrite=overwrite)


def encode_png(image: np.ndarray) -> bytes:
    """PNG bytes of an 8-bit image (for reports)."""
    import cv2

    ok, data = cv2.imencode(".png", np.asarray(image))
    if not ok:
        raise ValueError("PNG encoding failed")
    return data.tobytes()


def list_images(folder) -> list[Path]:
    """The image files of ``folder`` (:data:`IMAGE_SUFFIXES`), sorted naturally by name (``2.png``
    before ``10.png``); ``FileNotFoundError`` / ``NotADirectoryError`` naming the folder, and
    :class:`ImageFileError` if it holds no images."""
    import re

    d = Path(folder)
    if not d.exists():
        raise FileNotFoundError(f"{d}: no such image folder")
    if not d.is_dir():
        raise NotADirectoryError(f"{d}: not a folder (expected a folder of images)")
    files = [p for p in d.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES]
    if not files:
        raise ImageFileError(d, f"no image files ({', '.join(IMAGE_SUFFIXES)}) in this folder")

    def natural(p: Path):
        return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", p.name)]

    return sorted(files, key=natural)
