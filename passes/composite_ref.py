"""NumPy float64 reference of ``composite`` (importable without Vulkan).

``hdr.rgb = diffuse.rgb + specular.rgb``, ``hdr.a = 1``. A sum of finite inputs beyond the
half-float range is clamped to +-65504 (finite inputs never make Inf); non-finite inputs pass
through unchanged (NaN stays NaN, Inf stays Inf): bloom's bright pass and the tonemap sanitize.
The result is then stored as float16.

Tolerance (GPU vs reference, after float16 storage): exact up to one float16 ulp,
``|gpu - ref| <= 2**-10 * |ref| + 1e-7``.
"""

from __future__ import annotations

import numpy as np

from .post_common_ref import HALF_MAX, to_half

RTOL = 2.0 ** -10
ATOL = 1e-7


def reference(diffuse: np.ndarray, specular: np.ndarray) -> np.ndarray:
    """(h, w, 4) float64 hdr values (already float16-rounded) from (h, w, >=3) inputs."""
    d = np.asarray(diffuse, dtype=np.float64)[..., :3]
    s = np.asarray(specular, dtype=np.float64)[..., :3]
    with np.errstate(invalid="ignore", over="ignore"):
        total = d + s
        finite_in = np.isfinite(d) & np.isfinite(s)
        rgb = np.where(finite_in, np.clip(total, -HALF_MAX, HALF_MAX), total)
    out = np.concatenate([rgb, np.ones(rgb.shape[:-1] + (1,))], axis=-1)
    return to_half(out)
