"""NVIDIA FLIP through the optional ``flip-evaluator`` package (``pip install rgraph[sweep]``).

Without the package every FLIP value is ``None`` and :func:`missing_note` says why.
"""

from __future__ import annotations

import contextlib
import io
from functools import cache
from typing import Any

import numpy as np

INSTALL_HINT = "pip install flip-evaluator, or rgraph[sweep]"


@cache
def _module() -> Any | None:
    try:
        import flip_evaluator
    except ImportError:
        return None
    return flip_evaluator


def available() -> bool:
    return _module() is not None


def missing_note() -> str | None:
    """A one-line note when FLIP cannot be computed, else None."""
    return None if available() else f"FLIP not computed: the flip-evaluator package is missing ({INSTALL_HINT})"


def _evaluate(reference: np.ndarray, test: np.ndarray, dynamic_range: str,
              magma: bool) -> tuple[np.ndarray, float] | None:
    module = _module()
    if module is None:
        return None
    if reference.shape != test.shape:
        raise ValueError(f"images differ in shape: {reference.shape} vs {test.shape}")
    ref = np.ascontiguousarray(reference, dtype=np.float32)
    tst = np.ascontiguousarray(test, dtype=np.float32)
    with contextlib.redirect_stdout(io.StringIO()):
        error_map, mean, _params = module.evaluate(ref, tst, dynamic_range, inputsRGB=dynamic_range == "LDR",
                                                   applyMagma=magma, computeMeanError=True)
    return np.asarray(error_map), float(mean)


def flip_ldr(reference: np.ndarray, test: np.ndarray, magma: bool = False) -> tuple[np.ndarray, float] | None:
    """(error map, mean FLIP) of sRGB-encoded images in [0, 1], or None without the package.

    The map is ``H x W`` in [0, 1], or ``H x W x 3`` magma colours with ``magma``."""
    out = _evaluate(np.clip(reference, 0.0, 1.0), np.clip(test, 0.0, 1.0), "LDR", magma)
    if out is None:
        return None
    error_map, mean = out
    return (error_map if magma else error_map[..., 0]), mean


def flip_hdr(reference: np.ndarray, test: np.ndarray) -> float | None:
    """Mean HDR-FLIP of linear radiance images (negative values clamped), or None."""
    out = _evaluate(np.maximum(reference, 0.0), np.maximum(test, 0.0), "HDR", False)
    return None if out is None else out[1]
