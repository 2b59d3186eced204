"""The checked-in JSON Schema matches the models; bundled graphs carry the modeline."""


from locations import ROOT

from rgraph.commands.schema import schema_text
from rgraph.resources import bundled_graphs

ROOT = ROOT


def test_checked_in_schema_is_current() -> None:
    checked_in = (ROOT / "schema" / "rgraph.schema.json").read_text()
    assert checked_in == schema_text(), "schema/rgraph.schema.json is stale: run `make schema`"


def test_bundled_graphs_have_the_modeline() -> None:
    graphs = bundled_graphs()
    assert graphs
    for path in graphs.values():
        assert path.read_text().startswith("# yaml-language-server: $schema=../schema/rgraph.schema.json")
