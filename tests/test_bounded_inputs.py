"""Issue 29: bounded inputs. Counts beyond a stated limit are refused at once with an error naming
the option and the limit (they ran away past 4 GiB before); an image's pixel count is read from its
header and a decompression bomb is refused before decoding."""

from __future__ import annotations

import struct
import zlib

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.main import main
from robocal.io.image_header import MAX_IMAGE_PIXELS, image_size_from_header
from robocal.io.images import ImageFileError, read_image_gray


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize("args, option", [
    (("plan-poses", "ur10", "--count", 10, "--candidates", 50_000_000, "--out", "x.csv"), "--candidates"),
    (("ik-train", "ur10", "--samples", 100_000_000), "--samples"),
    (("demo", "--out", "d", "--poses", 50_000_000), "--poses"),
    (("simulate", "camera", "--out", "c", "--images", 1_000_000), "--images"),
    (("simulate", "tracker", "ur10", "--poses", 50_000_000, "--out", "t.csv"), "--poses"),
    (("fleet", "study", "pose-sets", "ur10", "--candidates", 50_000_000), "--candidates"),
])
def test_counts_beyond_their_limit_are_refused_at_once(tmp_path, monkeypatch, args, option):
    monkeypatch.chdir(tmp_path)
    r = run(*args)
    assert r.exit_code == 2, r.output
    assert option in r.output and "not in the range" in r.output and "Traceback" not in r.output
    assert not any(tmp_path.iterdir())  # nothing started, nothing written


def _png_bomb(path, side: int):
    """A valid all-black grey PNG of side x side pixels: ~1 kB per megapixel on disk."""
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    c = zlib.compressobj(9)
    row = b"\x00" * (side + 1)
    data = b"".join(c.compress(row) for _ in range(side)) + c.flush()
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", side, side, 8, 0, 0, 0, 0))
                     + chunk(b"IDAT", data) + chunk(b"IEND", b""))
    return path


def test_header_sizes_of_every_format(tmp_path):
    img = np.zeros((37, 53), np.uint8)
    for ext in ("png", "jpg", "bmp", "tif"):
        cv2.imwrite(str(tmp_path / f"a.{ext}"), img)
        assert image_size_from_header(tmp_path / f"a.{ext}") == (53, 37), ext
    (tmp_path / "x.png").write_bytes(b"not an image")
    assert image_size_from_header(tmp_path / "x.png") is None


def test_a_decompression_bomb_is_refused_before_decoding(tmp_path):
    side = 10_050  # 101 megapixels, 0.1 MB on disk
    assert side * side > MAX_IMAGE_PIXELS
    bomb = _png_bomb(tmp_path / "imgs" / "bomb.png" if (tmp_path / "imgs").mkdir() is None else None, side)
    assert bomb.stat().st_size < 200_000
    with pytest.raises(ImageFileError, match="10050 x 10050 px is more than the 100 megapixels"):
        read_image_gray(bomb)
    r = run("camera", "calibrate", tmp_path / "imgs", "--board", "charuco:9x7:30mm:22mm:DICT_5X5_100",
            "--out", tmp_path / "cam")
    assert r.exit_code == 1 and "bomb.png" in r.output and "megapixels" in r.output and "Traceback" not in r.output
