"""Text output of ``rgraph inspect`` on hand-written plans: summary, barriers, memory."""

from __future__ import annotations

import json

from report_plans.helpers import FORWARD, MINIMAL, inspect, load


def lines_of(text: str) -> list[str]:
    return [line.rstrip() for line in text.splitlines()]


def row(text: str, first_cell: str) -> list[str]:
    """The cells (split on runs of spaces) of the table row whose first cell is ``first_cell``."""
    for line in lines_of(text):
        cells = line.split()
        if cells and cells[0] == first_cell:
            return cells
    raise AssertionError(f"no row starting with {first_cell!r} in:\n{text}")


def test_summary_header_and_schedule(capsys):
    code, out, err = inspect(capsys, str(FORWARD))
    assert code == 0 and err == ""
    lines = lines_of(out)
    assert "graph    forward (tests/report_plans/forward.yaml)" in lines
    assert "scene    cct" in lines
    assert "size     1920x1080" in lines
    assert "params   bloom.enabled=true hbao.directions=8 shadow.size=2048" in lines
    assert "device   lavapipe" in lines
    assert "policy   aliased" in lines
    assert "Schedule (8 passes)" in lines
    assert row(out, "0") == ["0", "light_cull", "compute", "graphics", "probe", "1", "0"]
    assert row(out, "1")[:5] == ["1", "shadow", "raster", "graphics", "shadow_map"]
    assert row(out, "2") == ["2", "depth_prepass", "raster", "graphics", "probe", "1", "1+1", "rel",
                             "signal", "graphics=1"]
    assert " ".join(row(out, "3")) == "3 hbao compute compute hbao 2 2+2 rel wait graphics>=1, signal compute=1"
    assert " ".join(row(out, "4")) == "4 lighting raster graphics probe 6 5 wait compute>=1"


def test_summary_culled_dropped_and_stats(capsys):
    _, out, _ = inspect(capsys, str(FORWARD))
    lines = lines_of(out)
    assert "Culled passes (2)" in lines
    assert " ".join(row(out, "sss_blur_h")) == "sss_blur_h scene has no sss_materials"
    assert " ".join(row(out, "debug_overlay")) == "debug_overlay reaches no output"
    assert "Dropped optional reads (1)" in lines
    assert " ".join(row(out, "lighting")) == "lighting ssr optional read with no producer"
    assert "barriers     16 + 3 queue-family releases" in lines
    assert "semaphores   2" in lines
    assert "peak         71.8 MiB (75301120 B) in 3 allocations" in lines
    assert "lower bound  71.8 MiB (75301120 B), peak/lower bound 1.000" in lines
    assert "unaliased    75.8 MiB (79495424 B)" in lines
    assert "saving       5.3% (4.0 MiB) vs unaliased" in lines


def test_summary_of_a_minimal_plan(capsys):
    code, out, _ = inspect(capsys, str(MINIMAL))
    assert code == 0
    lines = lines_of(out)
    assert "scene    (none)" in lines and "size     -" in lines and "params   (defaults)" in lines
    assert "Dropped optional reads (0)" in lines and "  (none)" in lines
    assert "barriers     3" in lines and "semaphores   -" in lines
    assert "peak         17.0 MiB (17825792 B) in 1 allocation" in lines
    assert "saving       0.0% (0 B) vs unaliased" in lines


def test_plain_output_is_ascii_without_escapes_or_trailing_spaces(capsys):
    _, out, _ = inspect(capsys, str(FORWARD), "--barriers", "--memory")
    _, summary, _ = inspect(capsys, str(FORWARD))
    for text in (out, summary):
        assert "\x1b" not in text
        assert text.isascii()
        assert all(line == line.rstrip() for line in text.splitlines())


def test_barriers_in_execution_order(capsys):
    code, out, _ = inspect(capsys, str(FORWARD), "--barriers")
    assert code == 0
    lines = lines_of(out)
    assert lines[0] == "Barriers (execution order)"
    body = lines[1:]
    expected = [
        "before shadow: shadow_maps[mips 0:1 layers 0:2] NONE/NONE/UNDEFINED -> "
        "EARLY_FRAGMENT_TESTS|LATE_FRAGMENT_TESTS/DEPTH_STENCIL_ATTACHMENT_READ|DEPTH_STENCIL_ATTACHMENT_WRITE"
        "/DEPTH_ATTACHMENT_OPTIMAL",
        "before depth_prepass: depth[mips 0:1 layers 0:1] NONE/NONE/UNDEFINED -> "
        "EARLY_FRAGMENT_TESTS|LATE_FRAGMENT_TESTS/DEPTH_STENCIL_ATTACHMENT_READ|DEPTH_STENCIL_ATTACHMENT_WRITE"
        "/DEPTH_ATTACHMENT_OPTIMAL",
        "after depth_prepass: depth[mips 0:1 layers 0:1] "
        "EARLY_FRAGMENT_TESTS|LATE_FRAGMENT_TESTS/DEPTH_STENCIL_ATTACHMENT_WRITE/DEPTH_ATTACHMENT_OPTIMAL -> "
        "COMPUTE_SHADER/SHADER_SAMPLED_READ/DEPTH_READ_ONLY_OPTIMAL release graphics->compute",
        "signal after depth_prepass: graphics timeline = 1 (src EARLY_FRAGMENT_TESTS|LATE_FRAGMENT_TESTS)",
        "wait before hbao: graphics timeline >= 1 (dst COMPUTE_SHADER)",
        "before hbao: ao[mips 0:1 layers 0:1] NONE/NONE/UNDEFINED -> COMPUTE_SHADER/SHADER_STORAGE_WRITE/GENERAL",
        "before hbao: depth[mips 0:1 layers 0:1] "
        "EARLY_FRAGMENT_TESTS|LATE_FRAGMENT_TESTS/DEPTH_STENCIL_ATTACHMENT_WRITE/DEPTH_ATTACHMENT_OPTIMAL -> "
        "COMPUTE_SHADER/SHADER_SAMPLED_READ/DEPTH_READ_ONLY_OPTIMAL acquire graphics->compute",
    ]
    assert body[: len(expected)] == expected
    # a buffer barrier has no range and no layout; an aliasing barrier names the previous occupant
    assert "before lighting: lights COMPUTE_SHADER/SHADER_STORAGE_WRITE -> FRAGMENT_SHADER/UNIFORM_READ" in body
    assert (
        "before bloom: bloom_tex[mips 0:1 layers 0:1] FRAGMENT_SHADER/NONE/UNDEFINED -> "
        "COMPUTE_SHADER/SHADER_STORAGE_WRITE/GENERAL (aliases shadow_maps)"
    ) in body
    # waits precede the pass's barriers; releases and signals follow them
    assert body.index("wait before lighting: compute timeline >= 1 "
                      "(dst EARLY_FRAGMENT_TESTS|FRAGMENT_SHADER|LATE_FRAGMENT_TESTS)") < min(
        i for i, line in enumerate(body) if line.startswith("before lighting:"))
    assert body[-1] == "16 barriers, 3 releases, 2 waits, 2 signals"
    assert sum(line.startswith("before ") for line in body) == 16
    assert sum(line.startswith("after ") for line in body) == 3


def test_memory_resources_heaps_and_culling(capsys):
    code, out, _ = inspect(capsys, str(FORWARD), "--memory")
    assert code == 0
    lines = lines_of(out)
    assert "Resources (8)" in lines
    assert " ".join(row(out, "depth")) == (
        "depth image D32_SFLOAT 1920x1080 8294400 7.9 MiB 65536 transient "
        "2..4 (depth_prepass..lighting) 0 33554432 device_local_optimal"
    )
    assert " ".join(row(out, "shadow_maps")) == (
        "shadow_maps image D32_SFLOAT 2048x2048 (2 layers) 33554432 32.0 MiB 65536 transient "
        "1..4 (shadow..lighting) 0 0 device_local_optimal"
    )
    assert " ".join(row(out, "lights")) == (
        "lights buffer - 128 B requested 128 128 B 256 transient 0..4 (light_cull..lighting) 2 0 device_local_linear"
    )
    assert " ".join(row(out, "history")).startswith("history image R8G8B8A8_SRGB 1920x1080 8294400 7.9 MiB 65536 persistent")
    assert "Heaps (3)" in lines
    # heap 0: 5 residents whose aligned sizes add to 62849024 B, placed in 58654720 B by aliasing
    assert " ".join(row(out, "0")) == (
        "0 device_local_optimal 55.9 MiB (58654720 B) 65536 5 59.9 MiB (62849024 B) "
        "ao, bloom_tex, depth, hdr, shadow_maps"
    )
    assert "device_local_linear      256 B in 1 heap" in lines
    assert "device_local_optimal     71.8 MiB (75300864 B) in 2 heaps" in lines
    assert "Saved by culling (2 culled passes)" in lines
    assert " ".join(row(out, "sss_blur_h")) == "sss_blur_h scene has no sss_materials sss_tmp 8.0 MiB (8388608 B)"
    assert " ".join(row(out, "debug_overlay")) == "debug_overlay reaches no output (none) 0 B"
    assert "culling saved 8.0 MiB (8388608 B)" in lines


def test_memory_without_culled_resource_lists(capsys):
    code, out, _ = inspect(capsys, str(MINIMAL), "--memory")
    assert code == 0
    assert " ".join(row(out, "sss_blur_h")) == "sss_blur_h scene has no sss_materials (not listed) -"
    assert "culling saved" not in out
    assert " ".join(row(out, "preview")) == "preview image - - 1048576 1.0 MiB 65536 output 1..1 (blit..blit) 0 16777216 -"


def test_views_combine(capsys):
    _, both, _ = inspect(capsys, str(FORWARD), "--barriers", "--memory")
    _, barriers, _ = inspect(capsys, str(FORWARD), "--barriers")
    _, memory, _ = inspect(capsys, str(FORWARD), "--memory")
    assert both == barriers + "\n" + memory
    assert "Schedule" not in both


def test_aliases_may_be_a_list_and_extra_header_keys_show(capsys, tmp_path):
    plan = load(FORWARD)
    plan["passes"][5]["barriers"][0]["aliases"] = ["depth", "shadow_maps"]
    plan["outputs"] = ["color"]
    plan["features"] = {"lights": 2, "sss_materials": 0}
    path = tmp_path / "listed.json"
    path.write_text(json.dumps(plan))
    _, out, _ = inspect(capsys, str(path), "--barriers")
    assert any(line.endswith("(aliases depth, shadow_maps)") for line in lines_of(out))
    _, out, _ = inspect(capsys, str(path))
    assert "outputs  color" in lines_of(out)
    assert "features lights=2 sss_materials=0" in lines_of(out)
