"""Reading calibration frames: one clear error per bad file, never a traceback."""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import cv2
import numpy as np

from ..errors import CalibrationError


def load_image(path: str | Path) -> np.ndarray:
    """(H, W, 3) uint8 BGR frame from a file; CalibrationError naming the file otherwise."""
    path = Path(path)
    if not path.is_file():
        raise CalibrationError(f"{path}: no such image file")
    data = np.fromfile(str(path), dtype=np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if image is None:
        raise CalibrationError(f"{path}: not a readable image (expected JPEG or PNG)")
    return image


def load_images(paths: Sequence[str | Path]) -> list[np.ndarray]:
    return [load_image(p) for p in paths]


def image_labels(images: Sequence[np.ndarray], labels: Sequence[str] | None) -> list[str]:
    if labels is None:
        return [f"image {i + 1}" for i in range(len(images))]
    if len(labels) != len(images):
        raise CalibrationError(f"{len(labels)} labels for {len(images)} images")
    return [str(label) for label in labels]


def common_size(images: Sequence[np.ndarray], labels: Sequence[str]) -> tuple[int, int]:
    """(width, height) shared by all images; CalibrationError naming the odd one out."""
    sizes = []
    for image, label in zip(images, labels):
        image = np.asarray(image)
        if image.ndim not in (2, 3) or image.shape[0] < 8 or image.shape[1] < 8:
            raise CalibrationError(f"{label}: not an image (array of shape {image.shape})")
        sizes.append((image.shape[1], image.shape[0]))
    first = sizes[0]
    for size, label in zip(sizes, labels):
        if size != first:
            raise CalibrationError(f"{label}: image is {size[0]}x{size[1]} but {labels[0]} is "
                                   f"{first[0]}x{first[1]}; all views of one camera must have the same size")
    return first
