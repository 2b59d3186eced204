"""Bring a sweeps folder (benchmarks/sweeps.py -o DIR) back in a few files, and unpack it.

    python3 benchmarks/sweep_bundle.py pack DIR OUT     # OUT/sweeps_text.txt, OUT/pareto_all.png
    python3 benchmarks/sweep_bundle.py unpack FILE DIR  # the text files back into DIR

``sweeps_text.txt`` holds every ``.md``/``.csv`` under DIR, each after a line
``==> RELATIVE/PATH <==``; ``pareto_all.png`` tiles every group's ``pareto_<knob>.png``
(the knob's error against the GPU ms of the passes it changes), three a row, each titled
with its group. The GPU machines bring back at most 8 files, text or PNG.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

HEADER = re.compile(r"^==> (.+) <==\n", re.MULTILINE)


def pack_text(folder: Path) -> str:
    parts = []
    for path in sorted(p for p in folder.rglob("*") if p.is_file() and p.suffix in (".md", ".csv")):
        with path.open(newline="") as f:  # CSV rows end in \r\n: kept as they are
            text = f.read()
        parts.append(f"==> {path.relative_to(folder).as_posix()} <==\n{text}")
    return "".join(parts)


def unpack_text(text: str, folder: Path) -> list[Path]:
    """The files of :func:`pack_text`'s ``text`` written under ``folder``."""
    pieces = HEADER.split(text)  # ["", name, body, name, body, ...]
    written: list[Path] = []
    for name, body in zip(pieces[1::2], pieces[2::2], strict=True):
        if ".." in Path(name).parts or Path(name).is_absolute():
            raise SystemExit(f"sweep_bundle: refusing path {name!r}")
        target = folder / name
        target.parent.mkdir(parents=True, exist_ok=True)
        with target.open("w", newline="") as f:
            f.write(body)
        written.append(target)
    return written


def tile_plots(folder: Path, out: Path, columns: int = 3) -> int:
    """Every ``*/pareto_*.png`` under ``folder`` in one PNG; returns how many."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt

    plots = sorted(folder.glob("*/pareto_*.png"))
    if not plots:
        return 0
    rows = (len(plots) + columns - 1) // columns
    fig, axes = plt.subplots(rows, columns, figsize=(6 * columns, 4.5 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, path in zip(axes.flat, plots, strict=False):  # more axes than plots: the rest stay blank
        ax.imshow(mpimg.imread(path))
        ax.set_title(f"{path.parent.name}: {path.stem.removeprefix('pareto_')}", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    plt.close(fig)
    return len(plots)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    pack = sub.add_parser("pack")
    pack.add_argument("folder", type=Path)
    pack.add_argument("out", type=Path)
    unpack = sub.add_parser("unpack")
    unpack.add_argument("file", type=Path)
    unpack.add_argument("folder", type=Path)
    args = parser.parse_args(argv)
    if args.what == "pack":
        args.out.mkdir(parents=True, exist_ok=True)
        with (args.out / "sweeps_text.txt").open("w", newline="") as f:
            f.write(pack_text(args.folder))
        count = tile_plots(args.folder, args.out / "pareto_all.png")
        print(f"sweep_bundle: {args.out / 'sweeps_text.txt'}, {count} plot(s) in {args.out / 'pareto_all.png'}",
              file=sys.stderr)
    else:
        with args.file.open(newline="") as f:
            written = unpack_text(f.read(), args.folder)
        print(f"sweep_bundle: {len(written)} file(s) into {args.folder}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
