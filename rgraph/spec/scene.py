"""The scene file (FORMAT.md section 2) and the features a graph's ``requires`` sees."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, ValidationError, model_validator

from rgraph.errors import RGraphError
from rgraph.spec.pydantic_errors import describe, translate
from rgraph.spec.vocabulary import SCENE_FEATURES
from rgraph.spec.yaml_source import SourceMap, load_yaml

SCENE_VERSION = 1
LARGE_WORLD_METERS = 1e5

Vec3 = list[float | int]
#: Coordinates (metres) and light radiance (colour x intensity) end up as float32 on the GPU,
#: camera-relative: beyond these they overflow it (inf transforms and tables, inf pixels), and
#: float64 itself resolves 1e18 m only to 128 m.
MAX_COORDINATE = 1e18
MAX_RADIANCE = 1e30
Coord = Annotated[float | int, Field(ge=-MAX_COORDINATE, le=MAX_COORDINATE)]
Point3 = list[Coord]


# Limits on generated geometry: a scene is procedural, so its size is a few numbers.
MAX_INSTANCES = 1 << 20  # per mesh (an instanced draw's positions are built on the CPU)
MAX_SHAPE_VERTICES = 1 << 20  # product of the resolution parameters a mesh gives
MAX_RESOLUTION = 4096  # any one of segments, rings, stacks, sides, subdivisions
MAX_COUNT = 1024  # copies inside one shape ('count' of segments, 'lobes' of blob)
_RESOLUTION_PARAMS = ("segments", "rings", "stacks", "sides", "subdivisions")
_COUNT_PARAMS = ("count", "lobes")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, allow_inf_nan=False)


class Camera(_Strict):
    position: Point3 = Field(default_factory=lambda: [0.0, 0.0, 1.0], min_length=3, max_length=3)
    look_at: Point3 = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3)
    up: Vec3 = Field(default_factory=lambda: [0.0, 1.0, 0.0], min_length=3, max_length=3)
    fov_y: float = Field(45.0, gt=0, lt=180)
    near: float = Field(0.01, gt=0)

    @model_validator(mode="after")
    def _looks_somewhere(self) -> Camera:
        forward = [a - b for a, b in zip(self.look_at, self.position, strict=True)]
        length = math.hypot(*forward)
        if not length > 0 or not math.isfinite(length):
            raise ValueError("camera 'look_at' must differ from 'position' (the camera looks nowhere)")
        if math.hypot(*self.up) == 0:
            raise ValueError("camera 'up' must not be zero")
        return self


class Light(_Strict):
    type: Literal["directional", "point", "spot"]
    direction: Vec3 | None = Field(None, min_length=3, max_length=3)
    position: Point3 | None = Field(None, min_length=3, max_length=3)
    color: Vec3 = Field(default_factory=lambda: [1.0, 1.0, 1.0], min_length=3, max_length=3)
    intensity: float = Field(1.0, ge=0)
    radius: float = Field(1.0, ge=0)  # metres: the light reaches exactly zero here (0: no reach)
    shadows: bool = False
    cone: list[float] = Field(default_factory=lambda: [30.0, 45.0], min_length=2, max_length=2)  # spot: inner, outer (deg)

    @model_validator(mode="after")
    def _cone_order(self) -> Light:
        inner, outer = self.cone
        if not 0 <= inner <= outer <= 90:
            raise ValueError(f"cone must be [inner, outer] degrees with 0 <= inner <= outer <= 90, got {self.cone}")
        radiance = max((abs(c) for c in self.color), default=0.0) * self.intensity
        if radiance > MAX_RADIANCE:
            raise ValueError(f"radiance (color x intensity) {radiance:.3g} is above {MAX_RADIANCE:g} "
                             "(it would overflow the GPU's float32 shading)")
        return self


class LightGenerator(_Strict):
    """FORMAT.md 7: ``count`` seeded random point lights (rgraph.scene.generate expands them)."""

    generate: Literal["point"]
    count: int = Field(ge=0, le=1 << 20)
    seed: int = 0
    bounds: list[Point3] = Field(min_length=2, max_length=2)
    radius: list[float] = Field(default_factory=lambda: [1.0, 1.0], min_length=2, max_length=2)
    intensity: list[Annotated[float, Field(le=MAX_RADIANCE)]] = Field(default_factory=lambda: [1.0, 1.0],
                                                                      min_length=2, max_length=2)
    color: Vec3 | None = Field(None, min_length=3, max_length=3)  # omitted: seeded random colours

    @model_validator(mode="after")
    def _ranges(self) -> LightGenerator:
        for name in ("radius", "intensity"):
            lo, hi = getattr(self, name)
            if not 0 <= lo <= hi:
                raise ValueError(f"{name} must be [low, high] with 0 <= low <= high, got {[lo, hi]}")
        for k in range(3):
            if len(self.bounds[k % 2]) != 3 or self.bounds[0][k] > self.bounds[1][k]:
                raise ValueError("bounds must be [[x0, y0, z0], [x1, y1, z1]] with x0 <= x1, y0 <= y1, z0 <= z1")
        return self


def _light_kind(value: Any) -> str:
    return "generator" if isinstance(value, dict) and "generate" in value else "light"


#: A ``lights:`` item: an authored light, or a generator (an item with ``generate:``).
LightItem = Annotated[Annotated[Light, Tag("light")] | Annotated[LightGenerator, Tag("generator")],
                      Discriminator(_light_kind)]


class Material(_Strict):
    base_color: Vec3 = Field(default_factory=lambda: [0.8, 0.8, 0.8], min_length=3, max_length=3)
    roughness: float = Field(0.5, ge=0, le=1)
    metallic: float = Field(0.0, ge=0, le=1)
    sss: float = Field(0.0, ge=0, le=1)
    reflective: float = Field(0.0, ge=0, le=1)
    refractive: float = Field(0.0, ge=0, le=1)
    ior: float = Field(1.5, gt=0)
    opacity: float = Field(1.0, ge=0, le=1)
    emissive: Vec3 = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3)
    baked_ao: float = Field(1.0, ge=0, le=1)


class Instances(_Strict):
    """FORMAT.md 7: ``{grid: [nx, ny, nz], spacing}`` or ``{count, seed, bounds: [lo, hi]}``
    (seeded uniform positions, ``numpy.random.default_rng(seed)``)."""

    grid: list[Annotated[int, Field(ge=1, le=MAX_INSTANCES)]] | None = Field(None, min_length=3, max_length=3)
    spacing: float = 1.0
    count: int | None = Field(None, ge=1, le=MAX_INSTANCES)
    seed: int = 0
    bounds: list[Point3] | None = Field(None, min_length=2, max_length=2)

    @model_validator(mode="after")
    def _bounded(self) -> Instances:
        if (self.grid is None) == (self.count is None):
            raise ValueError("instances need exactly one of 'grid' or 'count'")
        if self.count is not None:
            if self.bounds is None:
                raise ValueError("instances with 'count' need 'bounds': [[x0, y0, z0], [x1, y1, z1]]")
            if any(len(b) != 3 for b in self.bounds) or any(self.bounds[0][k] > self.bounds[1][k] for k in range(3)):
                raise ValueError("bounds must be [[x0, y0, z0], [x1, y1, z1]] with x0 <= x1, y0 <= y1, z0 <= z1")
            return self
        total = math.prod(self.grid or ())
        if total > MAX_INSTANCES:
            raise ValueError(f"an instance grid of {total:,} instances is over the limit of {MAX_INSTANCES:,}")
        return self

    @property
    def total(self) -> int:
        return self.count if self.count is not None else math.prod(self.grid or ())


class Skinned(_Strict):
    """FORMAT.md 7: a procedural skeleton animated by the scene's clock (rgraph.scene.animation)."""

    bones: int = Field(256, ge=1, le=256)
    speed: float = Field(1.0, ge=0, le=100)  # animation cycles per second (each character x 0.8..1.2)
    amplitude: float = Field(1.0, ge=0, le=10)  # multiplies the template's joint angles
    seed: int = 0  # per-character phases and speeds


class Mesh(_Strict):
    shape: Literal["box", "sphere", "cylinder", "capsule", "torus", "plane", "tube", "neck", "blob", "segments",
                   "character"]
    params: dict[str, float | int | list[float | int]] = Field(default_factory=dict)
    material: str
    deformable: bool = False
    position: Point3 = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3)
    rotation: Vec3 = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3)
    scale: float | Vec3 = 1.0
    instances: Instances | None = None
    unique: bool = False  # FORMAT.md 7: every instance its own vertex and index data (seeded sizes)
    seed: int = 0
    skinned: Skinned | None = None

    @model_validator(mode="after")
    def _skinned_character(self) -> Mesh:
        if self.skinned is not None and self.shape != "character":
            raise ValueError(f"skinned meshes must be 'shape: character' (the procedural rig), got {self.shape!r}")
        if self.skinned is not None and self.deformable:
            raise ValueError("a mesh is either skinned or deformable, not both")
        if self.skinned is not None and self.unique:
            raise ValueError("skinned meshes share one rig: 'unique: true' does not apply to them")
        return self


class Decal(_Strict):
    material: str
    position: Point3 = Field(min_length=3, max_length=3)
    size: Vec3 = Field(min_length=3, max_length=3)
    rotation: Vec3 = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3)


class SceneFile(_Strict):
    scene: int
    name: str | None = None
    camera: Camera = Field(default_factory=Camera)
    cameras: list[Camera] = Field(default_factory=list, description="camera presets; --camera N picks one")
    lights: list[LightItem] = Field(default_factory=list)
    materials: dict[str, Material] = Field(default_factory=dict)
    meshes: list[Mesh] = Field(default_factory=list)
    decals: list[Decal] = Field(default_factory=list)
    decal_materials: dict[str, Material] = Field(default_factory=dict)


@dataclass(frozen=True)
class Scene:
    name: str
    path: Path | None
    model: SceneFile
    features: dict[str, int]


def features_of(scene: SceneFile) -> dict[str, int]:
    """Scene features (FORMAT.md 1): counts, zero meaning absent. Material features count
    the materials some mesh actually uses."""
    used = {m.material for m in scene.meshes}
    mats = [mat for name, mat in sorted(scene.materials.items()) if name in used]
    far = max(
        [math.dist(scene.camera.position, (0, 0, 0))]
        + [math.dist(c.position, (0, 0, 0)) for c in scene.cameras]
        + [math.dist(m.position, (0, 0, 0)) for m in scene.meshes],
    )
    authored = [light for light in scene.lights if isinstance(light, Light)]
    generated = sum(g.count for g in scene.lights if isinstance(g, LightGenerator))
    feats = {
        "lights": len(authored) + generated,
        "point_lights": sum(1 for light in authored if light.type in ("point", "spot")) + generated,
        "shadow_lights": sum(1 for light in authored if light.type == "directional" and light.shadows),
        "sss_materials": sum(1 for m in mats if m.sss > 0),
        "decals": len(scene.decals),
        "reflective_materials": sum(1 for m in mats if m.reflective > 0 or m.metallic > 0.5),
        "refractive_materials": sum(1 for m in mats if m.refractive > 0),
        "transparent_materials": sum(1 for m in mats if m.opacity < 1),
        "deformable_meshes": sum(1 for m in scene.meshes if m.deformable),
        "large_world": int(far > LARGE_WORLD_METERS),
    }
    assert set(feats) == set(SCENE_FEATURES)
    return feats


ALL_PRESENT = {name: 1 for name in SCENE_FEATURES}


def load_scene(path: str | Path) -> Scene:
    """Load and validate a scene file; unknown materials are errors at the reference."""
    p = Path(path)
    data, smap = load_yaml(p, str(path))
    if not isinstance(data, dict):
        raise RGraphError.at(smap.value(()), "a scene file must be a mapping with 'scene: 1'")
    if "rgraph" in data and "scene" not in data:
        raise RGraphError.at(smap.key(("rgraph",)), "this is a graph file, not a scene file (expected 'scene: 1')")
    if data.get("scene") != SCENE_VERSION or isinstance(data.get("scene"), bool):
        where = smap.value(("scene",)) if "scene" in data else smap.value(())
        raise RGraphError.at(where, f"unsupported or missing scene version; expected 'scene: {SCENE_VERSION}'")
    try:
        model = SceneFile.model_validate(data)
    except ValidationError as exc:
        raise translate(exc, smap, SceneFile, data) from None
    _check_references(model, smap)
    _check_shapes(model, smap)
    return Scene(model.name or p.stem, p, model, features_of(model))


def _check_references(model: SceneFile, smap: SourceMap) -> None:
    from rgraph.spec.pydantic_errors import did_you_mean

    for i, mesh in enumerate(model.meshes):
        if mesh.material not in model.materials:
            raise RGraphError.at(
                smap.value(("meshes", i, "material")),
                f"unknown material '{mesh.material}'{did_you_mean(mesh.material, model.materials)}",
            )
    for i, decal in enumerate(model.decals):
        pool = {**model.materials, **model.decal_materials}
        if decal.material not in pool and decal.material != "blood":
            raise RGraphError.at(
                smap.value(("decals", i, "material")),
                f"unknown decal material '{decal.material}'{did_you_mean(decal.material, pool)}",
            )


def _check_shapes(model: SceneFile, smap: SourceMap) -> None:
    """Resolution parameters are integers in range and a shape stays under :data:`MAX_SHAPE_VERTICES`."""
    for i, mesh in enumerate(model.meshes):
        product = 1
        for name in (*_RESOLUTION_PARAMS, *_COUNT_PARAMS):
            if name not in mesh.params:
                continue
            value = mesh.params[name]
            limit = MAX_RESOLUTION if name in _RESOLUTION_PARAMS else MAX_COUNT
            low = 0 if name == "lobes" else 1
            where = smap.value(("meshes", i, "params", name))
            if isinstance(value, bool) or not isinstance(value, int | float) or value != int(value):
                raise RGraphError.at(where, f"shape parameter '{name}' must be an integer, got {describe(value)}")
            if not low <= value <= limit:
                raise RGraphError.at(where, f"shape parameter '{name}' must be in {low}..{limit}, got {int(value)}")
            product *= max(1, int(value))
        if product > MAX_SHAPE_VERTICES:
            raise RGraphError.at(
                smap.value(("meshes", i, "params")),
                f"mesh {i} ({mesh.shape}) is too finely divided: its resolution parameters multiply to "
                f"{product:,} (the limit is {MAX_SHAPE_VERTICES:,})")
