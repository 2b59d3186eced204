"""``rgraph run --out`` of a rendered float image (the ray tracing graphs' r16g16b16a16_sfloat
colour): its values clamped to [0, 1] as stored (was all zero and transparent)."""

from __future__ import annotations

import numpy as np

from rgraph.png import output_rgba


def test_rendered_half_float_image() -> None:
    values = np.array([[[0.5, 0.25, 2.0, 1.0], [np.nan, -1.0, 0.0, 0.0]]], dtype=np.float16)
    res = {"name": "color", "format": "r16g16b16a16_sfloat", "kind": "image"}
    rgba = output_rgba(res, values.tobytes(), 2, 1, implemented=True)
    assert rgba.tolist() == [[[128, 64, 255, 255], [0, 0, 0, 255]]]


def test_rendered_single_channel_float_is_grey() -> None:
    values = np.array([[0.2, 1.5]], dtype=np.float32)
    rgba = output_rgba({"name": "ao", "format": "r32_sfloat", "kind": "image"}, values.tobytes(), 2, 1, True)
    assert rgba[0, :, :3].tolist() == [[51, 51, 51], [255, 255, 255]]
