"""Pairing an image folder with a flange-pose file by name (issue 14, ``robocal handeye solve
IMAGES_DIR --poses POSES.csv``).

The pose file is a flange-pose CSV (:func:`robocal.io.tcp_files.read_flange_poses_csv`: declared
orientation convention and units); each row's ``pose`` label names its image: the image file's
name without its ending (``img_03`` for ``img_03.png``) or with it. Every image needs exactly one
pose and every pose one image; otherwise :class:`ImagePoseMismatch` says which names are unmatched
and how many of each there are.

A pose file of 4 x 4 matrices (:mod:`robocal.io.matrix_poses`: one row-major matrix per line as
``RobotPosesVec.txt``, or one per block of lines; the length unit declared) has no labels: its
poses pair with the images *by order*, the images sorted naturally by name (``2.png`` before
``10.png``), and the counts must agree.
"""

from __future__ import annotations
from ..errors import InputError

from dataclasses import dataclass

import numpy as np

from .images import list_images
from .matrix_poses import is_matrix_pose_file, read_matrix_poses
from .tcp_files import read_flange_poses_csv

__all__ = ["ImagePoseMismatch", "ImagePoses", "pair_images_with_poses", "pair_images_with_labels"]


class ImagePoseMismatch(InputError):
    """Images and flange poses do not match one to one (counts or names)."""


@dataclass(frozen=True, eq=False)
class ImagePoses:
    """image_paths: N images; labels: their pose labels; T_base_flange (N, 4, 4) [mm]; convention: the
    pose file's orientation convention."""

    image_paths: tuple
    labels: tuple
    T_base_flange: np.ndarray
    convention: str


def _some(names, k: int = 5) -> str:
    names = sorted(names)
    return ", ".join(repr(n) for n in names[:k]) + (f" and {len(names) - k} more" if len(names) > k else "")


def pair_images_with_labels(images_dir, labels, source) -> tuple[tuple, list]:
    """(image paths, index into ``labels`` per image) for the images of ``images_dir`` named by
    ``labels`` (the file name with or without its ending); :class:`ImagePoseMismatch` naming the
    unmatched ones otherwise. ``source`` names where the labels come from (for the message)."""
    images = list_images(images_dir)
    labels = list(labels)
    by_label = {lab: i for i, lab in enumerate(labels)}
    pairs, unmatched_images = [], []
    for p in images:
        key = p.stem if p.stem in by_label else (p.name if p.name in by_label else None)
        if key is None:
            unmatched_images.append(p.name)
        else:
            pairs.append((p, key))
    used = {k for _, k in pairs}
    unmatched_poses = [lab for lab in labels if lab not in used]
    if unmatched_images or unmatched_poses:
        parts = [f"{len(images)} images in {images_dir} and {len(labels)} poses in {source} do not match "
                 "by name (a pose label must be its image's file name, with or without the ending)"]
        if unmatched_images:
            parts.append(f"images without a pose: {_some(unmatched_images)}")
        if unmatched_poses:
            parts.append(f"poses without an image: {_some(unmatched_poses)}")
        raise ImagePoseMismatch("; ".join(parts))
    return tuple(p for p, _ in pairs), [by_label[k] for _, k in pairs]


def pair_images_with_poses(images_dir, poses_file, length_unit: str | None = None) -> ImagePoses:
    """Pair every image of ``images_dir`` with the row of ``poses_file`` that names it; a file of
    4 x 4 matrices pairs by order (module docstring; ``length_unit`` "m" | "mm" unless the file
    declares it)."""
    if is_matrix_pose_file(poses_file):
        T = read_matrix_poses(poses_file, length_unit)
        images = list_images(images_dir)
        if len(images) != len(T):
            raise ImagePoseMismatch(
                f"{len(images)} images in {images_dir} but {len(T)} poses in {poses_file}: a matrix pose file pairs "
                f"with the images by order (images sorted by name, 2 before 10), so the counts must agree")
        return ImagePoses(image_paths=tuple(images), labels=tuple(p.stem for p in images), T_base_flange=T,
                          convention="matrix")
    if length_unit is not None:
        raise ImagePoseMismatch(f"{poses_file}: --length-unit applies to matrix pose files; a flange-pose CSV "
                                "declares its unit in its '# length_unit:' line")
    poses = read_flange_poses_csv(poses_file, min_rows=1)
    paths, idx = pair_images_with_labels(images_dir, poses.labels, poses_file)
    return ImagePoses(image_paths=paths, labels=tuple(poses.labels[i] for i in idx),
                      T_base_flange=poses.T_base_flange[idx], convention=poses.convention)
