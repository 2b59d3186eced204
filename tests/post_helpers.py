"""Running the post passes' small test graphs (tests/pass_graphs) on the Vulkan device."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

GRAPHS = Path(__file__).parent / "pass_graphs"


def run_graph(graph: str, size: tuple[int, int], inputs: dict[str, np.ndarray],
              params: dict[str, Any] | None = None) -> dict[str, np.ndarray]:
    """Compile ``pass_graphs/<graph>.yaml`` at ``size`` (w, h), run one frame under validation,
    assert no validation messages, and return the decoded outputs (float32 (h, w, c))."""
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / f"{graph}.yaml", size=size,
                         params={k: str(v) for k, v in (params or {}).items()})
    result = execute_plan(plan, validate=True, frames=1, inputs=inputs, read_outputs=True)
    assert [m.text for m in result.messages] == []
    return result.outputs


def half(x: np.ndarray) -> np.ndarray:
    """Values as an r16g16b16a16_sfloat upload stores them (float32 view of float16)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.asarray(x, dtype=np.float64).astype(np.float16).astype(np.float32)


def within(gpu: np.ndarray, ref: np.ndarray, rtol: float, atol: float) -> float:
    """The worst ``|gpu - ref| / (rtol |ref| + atol)`` over finite reference values (<= 1 passes)."""
    gpu, ref = np.asarray(gpu, dtype=np.float64), np.asarray(ref, dtype=np.float64)
    finite = np.isfinite(ref)
    assert np.isfinite(gpu[finite]).all(), "GPU is non-finite where the reference is finite"
    return float((np.abs(gpu[finite] - ref[finite]) / (rtol * np.abs(ref[finite]) + atol)).max())
