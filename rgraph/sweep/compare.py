"""Every error metric of one rendering against the reference."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgraph.sweep import flip, metrics

LDR_METRICS = ("psnr", "ssim", "flip")
HDR_METRICS = ("hdr_rel_mse", "hdr_log_psnr", "hdr_flip")
METRICS = LDR_METRICS + HDR_METRICS

# (lower is better) per metric, for Pareto fronts and plot axes
LOWER_IS_BETTER = {"psnr": False, "ssim": False, "flip": True, "hdr_rel_mse": True, "hdr_log_psnr": False,
                   "hdr_flip": True}


@dataclass
class Images:
    """What a run gave back: display image (sRGB-encoded [0, 1]) and linear HDR image."""

    ldr: np.ndarray | None
    hdr: np.ndarray | None


def compare(reference: Images, test: Images) -> tuple[dict[str, float | None], list[str]]:
    """Metric name -> value (None where not computable) and notes on what was skipped."""
    values: dict[str, float | None] = dict.fromkeys(METRICS)
    notes: list[str] = []
    if reference.ldr is not None and test.ldr is not None:
        if reference.ldr.shape != test.ldr.shape:
            notes.append(f"image size {_size(test.ldr)} differs from the reference's {_size(reference.ldr)}: "
                         "no LDR metrics")
        else:
            values["psnr"] = metrics.psnr(reference.ldr, test.ldr)
            values["ssim"] = metrics.ssim(reference.ldr, test.ldr)
            out = flip.flip_ldr(reference.ldr, test.ldr)
            values["flip"] = None if out is None else out[1]
    if reference.hdr is not None and test.hdr is not None:
        if reference.hdr.shape != test.hdr.shape:
            notes.append(f"HDR size {_size(test.hdr)} differs from the reference's {_size(reference.hdr)}: "
                         "no HDR metrics")
        else:
            values["hdr_rel_mse"] = metrics.rel_mse(reference.hdr, test.hdr)
            values["hdr_log_psnr"] = metrics.log_psnr(reference.hdr, test.hdr)
            values["hdr_flip"] = flip.flip_hdr(reference.hdr, test.hdr)
    return values, notes


def _size(image: np.ndarray) -> str:
    return f"{image.shape[1]}x{image.shape[0]}"
