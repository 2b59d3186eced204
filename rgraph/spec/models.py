"""Pydantic v2 models of the graph file (FORMAT.md section 1), exactly as users write it.

Values that may be ``"${...}"`` expressions are typed ``int | str`` here; their syntax is
checked by :mod:`rgraph.spec.semantics` and they are evaluated by
:mod:`rgraph.spec.specialize`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field

from rgraph.spec.vocabulary import Lifetime, PassKind, QueueName, SceneFeature, ShaderStage, UsageName

IntExpr = int | str
NumExpr = int | float | str


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)


class ScaleSize(_Strict):
    """A size relative to the output size."""

    scale: NumExpr = Field(description="Factor of the output size, e.g. 0.25 for quarter resolution.")


ImageSize = Literal["output"] | list[IntExpr] | ScaleSize


class ImageResource(_Strict):
    kind: Literal["image"]
    format: str = Field(description="Vulkan format without VK_FORMAT_, lower case, e.g. r16g16b16a16_sfloat.")
    size: ImageSize = Field("output", description="`output`, `[w, h]` or `{scale: s}`.")
    layers: IntExpr = 1
    mips: IntExpr = 1
    samples: IntExpr = 1
    lifetime: Lifetime = "transient"
    description: str | None = None


class BufferResource(_Strict):
    kind: Literal["buffer"]
    bytes: IntExpr
    lifetime: Lifetime = "transient"
    description: str | None = None


class AccelResource(_Strict):
    kind: Literal["accel"]
    bytes: IntExpr = 1 << 20
    lifetime: Lifetime = "transient"
    description: str | None = None


Resource = Annotated[ImageResource | BufferResource | AccelResource, Field(discriminator="kind")]


class UsageEntry(_Strict):
    """The long form of a usage: ``{usage: sampled, stages: [vertex], optional: true}``."""

    usage: UsageName
    stages: list[ShaderStage] | None = None
    optional: bool = False


def _usage_list(value: Any) -> Any:
    """Normalize a usage, a list of usages or long forms into a list of long forms."""
    items = value if isinstance(value, list) else [value]
    return [{"usage": item} if isinstance(item, str) else item for item in items]


UsageValue = Annotated[
    list[UsageEntry],
    BeforeValidator(_usage_list, json_schema_input_type=UsageName | UsageEntry | list[UsageName | UsageEntry]),
]


class Pass(_Strict):
    for_: dict[str, list[IntExpr]] | None = Field(
        None, alias="for",
        description="Repeat this pass: {VAR: [first, stop]} (half-open, values may be expressions); "
                    "${VAR} may appear in the pass name and in its reads/writes keys.")
    kind: PassKind
    impl: str | None = Field(None, description="A registered implementation; omitted -> the probe.")
    queue: QueueName = "graphics"
    requires: list[SceneFeature] = Field(default_factory=list)
    side_effects: bool = False
    reads: dict[str, UsageValue] = Field(default_factory=dict)
    writes: dict[str, UsageValue] = Field(default_factory=dict)
    params: dict[str, int | float | bool | str] = Field(default_factory=dict)
    description: str | None = None


class GraphFile(_Strict):
    """One graph file (includes are separate GraphFile instances, merged later)."""

    rgraph: int = Field(description="Format version; this rgraph reads version 1.")
    name: str | None = None
    description: str | None = None
    include: list[str] = Field(default_factory=list)
    scene: str | None = Field(None, description="Default scene file, relative to this file.")
    memory_policy: str | None = Field(None, description="Default placement policy (aliased, dedicated, blocks:16MiB, tlsf).")
    params: dict[str, int | float | bool | str] = Field(default_factory=dict)
    resources: dict[str, Resource] = Field(default_factory=dict)
    passes: dict[str, Pass] = Field(default_factory=dict)
    outputs: list[str] = Field(default_factory=list)
