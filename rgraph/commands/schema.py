"""``rgraph schema``: the JSON Schema of graph files (for editors' yaml-language-server)."""

from __future__ import annotations

import argparse
import json


def schema_text() -> str:
    from rgraph.spec.models import GraphFile

    schema = GraphFile.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "rgraph graph file, version 1"
    return json.dumps(schema, indent=2, sort_keys=True) + "\n"


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("schema", help="print the JSON Schema of graph files")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    print(schema_text(), end="")
    return 0
