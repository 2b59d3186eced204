"""The golden-image helper itself: PNG reading, comparisons, failure artefacts, updating."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest
from golden_images import UPDATE_ENV, assert_image_close, read_png, to_rgba8

from rgraph.png import write_png


def _filtered_png(pixels: np.ndarray, colour_type: int, filters: list[int]) -> bytes:
    """A PNG whose rows use the given filter types (an independent encoder for the reader's test)."""
    h, w, bpp = pixels.shape
    stride = w * bpp
    rows, prev = [], np.zeros(stride, dtype=np.int32)
    for y in range(h):
        cur = pixels[y].reshape(stride).astype(np.int32)
        kind = filters[y % len(filters)]
        left = np.concatenate([np.zeros(bpp, dtype=np.int32), cur[:-bpp]])
        up_left = np.concatenate([np.zeros(bpp, dtype=np.int32), prev[:-bpp]])
        if kind == 0:
            pred = np.zeros(stride, dtype=np.int32)
        elif kind == 1:
            pred = left
        elif kind == 2:
            pred = prev
        elif kind == 3:
            pred = (left + prev) >> 1
        else:
            p = left + prev - up_left
            pa, pb, pc = np.abs(p - left), np.abs(p - prev), np.abs(p - up_left)
            pred = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, prev, up_left))
        rows.append(bytes([kind]) + ((cur - pred) & 0xFF).astype(np.uint8).tobytes())
        prev = cur

    def chunk(tag: bytes, payload: bytes) -> bytes:
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", zlib.crc32(tag + payload))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour_type, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"".join(rows))) + chunk(b"IEND", b""))


def test_png_round_trip(tmp_path):
    rgba = np.random.default_rng(3).integers(0, 256, (7, 11, 4), dtype=np.uint8)
    write_png(tmp_path / "x.png", rgba)
    np.testing.assert_array_equal(read_png(tmp_path / "x.png"), rgba)


@pytest.mark.parametrize("colour_type,channels", [(2, 3), (6, 4), (0, 1), (4, 2)])
def test_png_reader_handles_every_filter_and_colour_type(tmp_path, colour_type, channels):
    pixels = np.random.default_rng(colour_type).integers(0, 256, (10, 9, channels), dtype=np.uint8)
    (tmp_path / "f.png").write_bytes(_filtered_png(pixels, colour_type, [0, 1, 2, 3, 4]))
    np.testing.assert_array_equal(read_png(tmp_path / "f.png"), to_rgba8(pixels))


def test_png_reader_rejects_corruption(tmp_path):
    write_png(tmp_path / "x.png", np.zeros((2, 2, 4), dtype=np.uint8))
    data = bytearray((tmp_path / "x.png").read_bytes())
    data[20] ^= 0xFF  # inside IHDR: its CRC no longer matches
    (tmp_path / "bad.png").write_bytes(bytes(data))
    with pytest.raises(ValueError, match="bad CRC"):
        read_png(tmp_path / "bad.png")


def test_float_images_are_srgb_encoded_unless_linear():
    linear = np.array([[[0.0, 0.5, 1.0, 1.0]]])
    assert to_rgba8(linear).tolist() == [[[0, 188, 255, 255]]]
    assert to_rgba8(linear, encoding="linear").tolist() == [[[0, 128, 255, 255]]]
    assert to_rgba8(np.array([[np.nan, 2.0]]), encoding="linear").tolist() == [[[0, 0, 0, 255], [255, 255, 255, 255]]]


def test_identical_and_within_tolerance_pass(tmp_path, monkeypatch):
    monkeypatch.delenv(UPDATE_ENV, raising=False)
    img = np.random.default_rng(5).integers(2, 250, (16, 24, 4), dtype=np.uint8)
    write_png(tmp_path / "ramp.png", img)
    assert_image_close("ramp", img, 0, golden_dir=tmp_path)
    nudged = img.copy()
    nudged[3, 4, 1] += 2
    assert_image_close("ramp", nudged, 2, golden_dir=tmp_path)
    assert_image_close("ramp", nudged, 1, max_fraction_over=1 / img[..., 0].size, golden_dir=tmp_path)
    assert not (tmp_path / "failures").exists()


def test_perturbed_image_fails_and_writes_actual_and_diff(tmp_path, monkeypatch):
    monkeypatch.delenv(UPDATE_ENV, raising=False)
    img = np.random.default_rng(6).integers(20, 230, (16, 24, 4), dtype=np.uint8)
    write_png(tmp_path / "ramp.png", img)
    bad = img.copy()
    bad[:4, :6, 0] += 10  # 24 of 384 pixels, by 10 levels
    with pytest.raises(AssertionError) as info:
        assert_image_close("ramp", bad, 1, golden_dir=tmp_path)
    text = str(info.value)
    assert "max abs error 10" in text and "6.25% of pixels over tolerance 1" in text
    assert f"{UPDATE_ENV}=1" in text
    np.testing.assert_array_equal(read_png(tmp_path / "failures" / "ramp.actual.png"), bad)
    diff = read_png(tmp_path / "failures" / "ramp.diff.png")
    assert (diff[:4, :6] == (255, 0, 0, 255)).all()
    assert (diff[4:, :, :3] == 0).all() and (diff[:, 6:, :3] == 0).all()


def test_missing_golden_and_size_mismatch_fail_clearly(tmp_path, monkeypatch):
    monkeypatch.delenv(UPDATE_ENV, raising=False)
    img = np.zeros((4, 4, 4), dtype=np.uint8)
    with pytest.raises(AssertionError, match="does not exist.*RGRAPH_UPDATE_GOLDEN=1"):
        assert_image_close("absent", img, golden_dir=tmp_path)
    assert (tmp_path / "failures" / "absent.actual.png").exists()
    write_png(tmp_path / "small.png", np.zeros((2, 2, 4), dtype=np.uint8))
    with pytest.raises(AssertionError, match="size 4x4 differs from the golden's 2x2"):
        assert_image_close("small", img, golden_dir=tmp_path)


def test_update_env_rewrites_the_golden(tmp_path, monkeypatch):
    img = np.full((3, 5, 4), 77, dtype=np.uint8)
    write_png(tmp_path / "g.png", np.zeros((3, 5, 4), dtype=np.uint8))
    monkeypatch.setenv(UPDATE_ENV, "1")
    assert_image_close("g", img, 0, golden_dir=tmp_path)
    np.testing.assert_array_equal(read_png(tmp_path / "g.png"), img)
    monkeypatch.delenv(UPDATE_ENV)
    assert_image_close("g", img, 0, golden_dir=tmp_path)
