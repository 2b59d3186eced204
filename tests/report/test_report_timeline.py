"""The memory timeline PNG and the HTML report."""

from __future__ import annotations

import re
import shutil

import pytest
from report_plans.helpers import FORWARD, MINIMAL, inspect, load

from rgraph.report.html import plan_html
from rgraph.report.timeline import (
    class_layout,
    live_bytes,
    placed_blocks,
    timeline_title,
    to_memory_model,
    write_timeline_png,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == PNG_MAGIC
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def test_blocks_from_the_plan():
    plan = load(FORWARD)
    blocks = {b.name: b for b in placed_blocks(plan)}
    assert set(blocks) == {r["name"] for r in plan["resources"]}
    depth = blocks["depth"]
    assert (depth.start, depth.end, depth.heap, depth.offset, depth.aligned_size) == (2, 4, 0, 33554432, 8323072)
    # non-transient resources hold their memory for the whole frame
    assert (blocks["history"].start, blocks["history"].end, blocks["history"].aliasable) == (0, 7, False)
    heap0 = [b for b in blocks.values() if b.heap == 0]
    live = live_bytes(heap0, len(plan["passes"]))
    assert max(live) == 58654720 == plan["heaps"][0]["bytes"]  # heap 0 is as small as it can be
    assert live[4] == 58654720 and live[0] == 0


def test_heaps_stack_per_memory_class():
    assert class_layout(load(FORWARD)) == {
        "device_local_linear": [(2, 0, 256)],
        "device_local_optimal": [(0, 0, 58654720), (1, 58654720, 16646144)],
    }


def test_title():
    assert timeline_title(load(FORWARD)) == (
        "forward: aliased placement, peak 71.8 MiB, lower bound 71.8 MiB, saving 5.3% of 75.8 MiB"
    )


@pytest.mark.parametrize("fixture", [FORWARD, MINIMAL])
def test_own_drawing_writes_a_png(tmp_path, fixture):
    path = tmp_path / "t.png"
    assert write_timeline_png(load(fixture), path) == "report"
    data = path.read_bytes()
    width, height = png_size(data)
    assert width >= 800 and height >= 300 and len(data) > 10_000


def test_memory_library_drawing_of_the_transient_blocks(tmp_path):
    plan = load(FORWARD)
    blocks, placement = to_memory_model(plan)
    assert sorted(b.name for b in blocks) == ["ao", "bloom_tex", "depth", "hdr", "lights", "shadow_maps"]
    assert [h.id for h in placement.heaps] == [0, 2]
    assert placement.offsets["bloom_tex"] == (0, 0) and placement.offsets["hdr"] == (0, 42008576)
    stats = placement.stats
    assert (stats.peak_bytes, stats.lower_bound_bytes, stats.unaliased_bytes) == (58654976, 58654976, 62849280)
    path = tmp_path / "m.png"
    assert write_timeline_png(plan, path, drawer="memory") == "memory"
    png_size(path.read_bytes())


def test_timeline_flag_writes_a_png(capsys, tmp_path):
    path = tmp_path / "timeline.png"
    code, _, err = inspect(capsys, str(FORWARD), "--timeline", str(path))
    assert code == 0 and err.strip() == f"wrote {path}"
    png_size(path.read_bytes())


def test_html_is_self_contained_with_every_section(capsys, tmp_path):
    path = tmp_path / "report.html"
    code, _, _ = inspect(capsys, str(FORWARD), "--html", str(path))
    assert code == 0
    page = path.read_text()
    assert page.startswith("<!DOCTYPE html>")
    for section in ("summary", "gpu", "graph", "memory", "passes", "culled", "resources"):
        assert page.count(f'<h2 id="{section}">') == 1, section
    headings = re.findall(r"<h[23][^>]*>(.*?)</h[23]>", page)
    assert len(headings) == len(set(headings)), "duplicate headings"
    ids = re.findall(r'\sid="([^"]+)"', page)
    assert len(ids) == len(set(ids)), "duplicate ids"
    plan = load(FORWARD)
    for p in plan["passes"]:  # every pass has an anchor and every resource link resolves
        assert f'id="pass-{p["name"]}"' in page
    for target in re.findall(r'href="#([^"]+)"', page):
        assert target in ids, target
    assert "<td>Heaps (3)</td>" not in page and "<h3>Heaps (3)</h3>" in page
    assert "<pre>" not in page  # tables, not clipped text blocks
    assert page.count("data-tip=") >= len(plan["passes"]) + len(plan["resources"])
    assert not re.search(r'(src|href)="(https?:)?//', page)  # nothing fetched from elsewhere


def test_html_without_graphviz_embeds_the_dot_text():
    page = plan_html(load(MINIMAL), with_svg=False)
    assert '<div class="graph">' not in page
    assert "digraph &quot;shadow_only&quot;" in page


@pytest.mark.skipif(shutil.which("dot") is None, reason="graphviz is not installed")
def test_html_with_graphviz_embeds_svg():
    page = plan_html(load(FORWARD), with_svg=True)
    assert page.count('<div class="graph"><svg') == 1 and "<?xml" not in page
    assert page.count("<svg") == 4  # the pass graph, the GPU timeline, placement and lifetimes
