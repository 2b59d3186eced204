#!/usr/bin/env python3
"""Generate ``rgraph/formats/table.py`` from the Vulkan registry (the ``vulkan-object`` package).

Run at development time after upgrading ``vulkan-object``::

    .venv/bin/python tools/gen_formats.py            # rewrite rgraph/formats/table.py
    .venv/bin/python tools/gen_formats.py --check    # exit 1 if the checked-in table is stale

Every fact in the table comes from the registry's ``<format>`` elements and the ``VkFormat``
enum. The registry does not carry the specification's "mandatory format support" tables,
so the usage features are derived from registry fields by the rules in ``derive_features``
(documented again in the generated module's docstring). Devices report real support at run
time; these features are the compile-time guess used to reject obviously wrong graphs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

TABLE_PATH = Path(__file__).resolve().parent.parent / "rgraph" / "formats" / "table.py"
PREFIX = "VK_FORMAT_"

# Numeric formats that can be blended (float or normalized): integer formats cannot.
BLENDABLE_NUMERICS = frozenset({"UNORM", "SNORM", "SRGB", "SFLOAT", "UFLOAT"})
# Numeric formats that cannot be render targets (vertex-only scaled, vendor fixed point, bool).
NON_RENDERABLE_NUMERICS = frozenset({"USCALED", "SSCALED", "SFIXED5", "BOOL"})

FEATURE_RULES = """\
Usage features are derived from registry fields (the registry has no mandatory-support
tables), as follows:

- ``sampled``: no chroma subsampling (422/420/444 and multi-plane formats need a sampler
  Y'CbCr conversion) and the numeric type is not BOOL.
- ``color_attachment``: an uncompressed, non-chroma format with colour components only
  (no depth/stencil) whose numeric type is not USCALED/SSCALED/SFIXED5/BOOL.
- ``color_attachment_blend``: ``color_attachment`` and every component is
  UNORM/SNORM/SRGB/SFLOAT/UFLOAT (integer formats cannot blend).
- ``depth_attachment`` and ``depth_read``: the format has a depth component (D).
- ``storage_read``/``storage_write``/``storage_rw``: the registry maps the format to a SPIR-V
  image format (``spirvImageFormat``), i.e. a shader can declare it in ``layout(...)``.
- ``transfer_src``/``transfer_dst``: every format.
"""


def derive_features(fmt) -> list[str]:
    """Usage features of one registry ``Format`` (see FEATURE_RULES)."""
    types = {c.type for c in fmt.components}
    numerics = {c.numericFormat for c in fmt.components}
    has_depth = "D" in types
    has_stencil = "S" in types
    is_color = not (has_depth or has_stencil)
    features = {"transfer_src", "transfer_dst"}
    if fmt.chroma is None and "BOOL" not in numerics:
        features.add("sampled")
    if is_color and fmt.compressed is None and fmt.chroma is None and not numerics & NON_RENDERABLE_NUMERICS:
        features.add("color_attachment")
        if numerics <= BLENDABLE_NUMERICS:
            features.add("color_attachment_blend")
    if has_depth:
        features.update({"depth_attachment", "depth_read"})
    if fmt.spirvImageFormat is not None:
        features.update({"storage_read", "storage_write", "storage_rw"})
    return sorted(features)


def format_row(fmt, value: int) -> dict:
    """One table row (plain literals only) for a registry ``Format``."""
    vk_name = fmt.name.removeprefix(PREFIX)
    types = [c.type for c in fmt.components]
    numerics = [c.numericFormat for c in fmt.components]
    extent = tuple(int(x) for x in fmt.blockExtent) if fmt.blockExtent else (1, 1, 1)
    has_depth = "D" in types
    has_stencil = "S" in types
    return {
        "name": vk_name.lower(),
        "vk_name": vk_name,
        "value": value,
        "block_bytes": fmt.blockSize,
        "block_extent": extent,
        "texels_per_block": fmt.texelsPerBlock,
        "components": tuple(
            (c.type, 0 if c.bits == "compressed" else int(c.bits), c.numericFormat) for c in fmt.components
        ),
        "has_depth": has_depth,
        "has_stencil": has_stencil,
        "is_color": not (has_depth or has_stencil),
        "is_srgb": "SRGB" in numerics,
        "numeric": numerics[0],
        "compressed": fmt.compressed is not None,
        "compression": fmt.compressed,
        "packed_bits": fmt.packed,
        "chroma": fmt.chroma,
        "plane_count": max(1, len(fmt.planes)),
        "spirv_image_format": fmt.spirvImageFormat,
        "features": tuple(derive_features(fmt)),
    }


def collect(vk) -> tuple[list[dict], dict[str, str], str]:
    """Rows sorted by user name, alias map (alias user name -> user name), registry version."""
    enum = vk.enums["VkFormat"]
    rows = []
    aliases: dict[str, str] = {}
    for field in enum.fields:
        fmt = vk.formats.get(field.name)
        if fmt is None:  # VK_FORMAT_UNDEFINED has no <format> element
            continue
        row = format_row(fmt, field.value)
        rows.append(row)
        for alias in field.aliases:
            aliases[alias.removeprefix(PREFIX).lower()] = row["name"]
    rows.sort(key=lambda r: r["name"])
    return rows, dict(sorted(aliases.items())), vk.headerVersionComplete


def render(rows: list[dict], aliases: dict[str, str], version: str) -> str:
    """The module text: deterministic for the same registry."""
    rule_lines = "".join(f"{line}\n" if line else "\n" for line in FEATURE_RULES.splitlines())
    out = [
        '"""Vulkan format table: generated by tools/gen_formats.py; do not edit.\n',
        "\n",
        f"Source: the Vulkan registry (vk.xml {version}) as shipped by the vulkan-object package.\n",
        "\n",
        rule_lines,
        '"""\n',
        "\n",
        f"REGISTRY_VERSION = {version!r}\n",
        "\n",
        "FORMATS = (\n",
    ]
    out += [f"    {row!r},\n" for row in rows]
    out += [")\n", "\n", "ALIASES = {\n"]
    out += [f"    {alias!r}: {name!r},\n" for alias, name in aliases.items()]
    out += ["}\n"]
    return "".join(out)


def generate() -> str:
    """Parse the bundled registry and return the table module's text."""
    from vulkan_object import get_vulkan_object

    return render(*collect(get_vulkan_object()))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the checked-in table is stale")
    parser.add_argument("--output", type=Path, default=TABLE_PATH)
    args = parser.parse_args(argv)
    text = generate()
    if args.check:
        current = args.output.read_text() if args.output.exists() else ""
        if current != text:
            print(f"{args.output} is stale: run tools/gen_formats.py", file=sys.stderr)
            return 1
        return 0
    args.output.write_text(text)
    print(f"wrote {args.output} ({text.count(chr(10))} lines)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
