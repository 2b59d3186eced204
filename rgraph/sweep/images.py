"""Getting images out of a run, and their display (LDR) and radiance (HDR) forms.

:func:`output_arrays` is the one place that knows how the runtime hands images back.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rgraph.sweep.metrics import linear_to_srgb


def output_image_resources(plan: dict) -> list[dict]:
    """The plan's output images, in the plan's ``outputs`` order."""
    by_name = {r["name"]: r for r in plan["resources"]}
    names = plan.get("outputs") or [r["name"] for r in plan["resources"] if r["lifetime"] == "output"]
    return [by_name[n] for n in names if n in by_name and by_name[n]["kind"] == "image"]


def output_arrays(result: Any) -> dict[str, np.ndarray]:
    """Float ``H x W x C`` arrays of the run's read-back images, by resource name.

    From ``RunResult.outputs`` (``execute_plan(..., read_outputs=True)``): shader-visible
    values, sRGB decoded to linear. Integer images and buffers are left out; a layered
    image gives its layer 0."""
    out: dict[str, np.ndarray] = {}
    for name, array in (getattr(result, "outputs", None) or {}).items():
        if isinstance(array, np.ndarray) and array.dtype.kind == "f" and array.ndim in (2, 3, 4):
            out[name] = np.asarray(array[0] if array.ndim == 4 else array, dtype=np.float32)
    return out


def is_srgb(vk_format: str | None) -> bool:
    return bool(vk_format) and "SRGB" in str(vk_format).upper()


def rgb(image: np.ndarray) -> np.ndarray:
    """The first three channels as float64 ``H x W x 3`` (grey replicated, missing ones 0)."""
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    if a.shape[-1] == 1:
        return np.repeat(a, 3, axis=-1)
    if a.shape[-1] == 2:
        return np.concatenate([a, np.zeros(a.shape[:-1] + (1,))], axis=-1)
    return a[..., :3]


def display(image: np.ndarray, vk_format: str | None) -> np.ndarray:
    """What the screen shows: sRGB-encoded values in [0, 1] (encoded here for sRGB formats,
    clamped as stored for UNORM/float ones)."""
    values = rgb(image)
    return linear_to_srgb(values) if is_srgb(vk_format) else np.clip(values, 0.0, 1.0)


def png_bytes(display_rgb: np.ndarray) -> bytes:
    """Display values in [0, 1] (``H x W x 3``) as an 8-bit PNG file's bytes."""
    import io

    import matplotlib.image

    pixels = np.clip(np.rint(np.asarray(display_rgb) * 255.0), 0, 255).astype(np.uint8)
    buffer = io.BytesIO()
    matplotlib.image.imsave(buffer, pixels, format="png")
    return buffer.getvalue()


def save_png(path: Path, display_rgb: np.ndarray | bytes) -> None:
    """Write display values in [0, 1] (``H x W x 3``), or :func:`png_bytes`, as an 8-bit PNG."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(display_rgb if isinstance(display_rgb, bytes) else png_bytes(display_rgb))
