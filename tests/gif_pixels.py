"""Counting a colour's pixels in each frame of a GIF (the ghost of the initial motion)."""
from __future__ import annotations

import numpy as np
from PIL import Image


def colour_pixels(path, rgb: np.ndarray, tolerance: int = 6) -> list[int]:
    """Per frame of the GIF at ``path``, the pixels within ``tolerance`` of colour ``rgb`` in every channel."""
    with Image.open(path) as im:
        counts = []
        for k in range(im.n_frames):
            im.seek(k)
            frame = np.asarray(im.convert("RGB")).astype(int)
            counts.append(int(np.sum(np.all(np.abs(frame - rgb) <= tolerance, axis=2))))
    return counts
