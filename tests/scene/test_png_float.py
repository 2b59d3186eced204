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


def test_layered_output_is_written_layer_after_layer_left_to_right(tmp_path) -> None:
    """``views=2``: the PNG holds both eyes side by side (was the left eye alone)."""
    import zlib

    from rgraph.png import write_output_png

    res = {"name": "color", "format": "r8g8b8a8_unorm", "kind": "image", "lifetime": "output",
           "extent": [2, 1], "mips": 1, "layers": 2}
    plan = {"resources": [res], "passes": [{"impl": "tonemap_filmic"}]}
    left, right = bytes([10, 20, 30, 0, 40, 50, 60, 0]), bytes([70, 80, 90, 0, 100, 110, 120, 0])
    path = tmp_path / "stereo.png"
    write_output_png(plan, {("color", 0, 0): left, ("color", 0, 1): right}, path)
    png = path.read_bytes()
    width, height = int.from_bytes(png[16:20], "big"), int.from_bytes(png[20:24], "big")
    assert (width, height) == (4, 1)
    start = png.index(b"IDAT") + 4
    raw = zlib.decompress(png[start:start + int.from_bytes(png[start - 8:start - 4], "big")])
    assert list(raw[1:]) == [10, 20, 30, 255, 40, 50, 60, 255, 70, 80, 90, 255, 100, 110, 120, 255]
