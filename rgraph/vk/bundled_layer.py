"""The Khronos validation layer that ``scripts/validation_layer.py`` installs into the venv.

Debian 12 ships layer 1.3.239, which crashes inside vkCreateRayTracingPipelinesKHR and misses
errors current layers report (it took the ray tracing structures' wrong ``sType`` values, see
``rgraph.vk.enum_fixes``). When the venv holds a newer one, ``--validate`` loads it: the loader is
pointed at it through ``VK_LAYER_PATH`` unless the user set ``VK_LAYER_PATH`` or
``VK_ADD_LAYER_PATH`` themselves.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

MANIFEST = "VkLayer_khronos_validation.json"


LAYER_DIR = Path(sys.prefix) / "share" / "rgraph" / "vulkan-layers"


def bundled_layer_dir() -> Path | None:
    """The venv's layer directory, when it holds the layer's manifest."""
    return LAYER_DIR if (LAYER_DIR / MANIFEST).is_file() else None


def why_unavailable() -> str | None:
    """Why setup could not install the layer (its note), or None."""
    marker = LAYER_DIR.with_name(LAYER_DIR.name + ".unavailable")
    return marker.read_text().strip() if marker.is_file() else None


def point_loader_at_bundled_layer() -> None:
    """Set ``VK_LAYER_PATH`` to the bundled layer (before the loader lists layers)."""
    if os.environ.get("VK_LAYER_PATH") or os.environ.get("VK_ADD_LAYER_PATH"):
        return
    directory = bundled_layer_dir()
    if directory is not None:
        os.environ["VK_LAYER_PATH"] = str(directory)
