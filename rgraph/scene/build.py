"""Scene build: the parsed scene file -> meshes, draws, materials, lights, decals, camera.

Everything here is float64 in world space; per-frame quantities (camera, camera-relative
model matrices, deformed vertices) are functions of the frame index. ``rgraph.scene.packing``
turns them into the GPU structs of ``shaders/scene/scene.glsl``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rgraph.scene.animation import Animator
from rgraph.scene.camera import (
    CameraState,
    camera_state,
    model_matrix,
    normal_matrix,
    shadow_view_proj,
    unit_or,
)
from rgraph.scene.character import build_rig
from rgraph.scene.deform import FRAME_SECONDS, Deformer
from rgraph.scene.generate import expand_lights
from rgraph.scene.shapes import MeshData, make_shape
from rgraph.spec.scene import MAX_COORDINATE, Material, SceneFile, load_scene

MAX_SHADOW_LIGHTS = 4
LIGHT_TYPES = {"directional": 0, "point": 1, "spot": 2}
#: Decal materials every scene knows (a scene's ``decal_materials`` or ``materials`` override them).
BUILTIN_DECALS = {
    "blood": Material(base_color=[0.30, 0.015, 0.02], roughness=0.15, metallic=0.0, opacity=0.92),
}
AMBIENT = (0.03, 0.03, 0.035)


class SceneBuildError(ValueError):
    """A scene file item the builder cannot make; ``where`` is its key path in the file
    (``load_scene_data`` turns it into a located ``RGraphError``)."""

    def __init__(self, where: tuple, message: str) -> None:
        super().__init__(message)
        self.where = where


@dataclass
class SceneMesh:
    """One mesh of the scene file: its geometry and the world placement of each instance."""

    name: str
    data: MeshData
    material: int
    rotation: tuple[float, float, float]
    scale: np.ndarray
    positions: np.ndarray  # (instances, 3) world float64
    deformer: Deformer | None = None
    first_draw: int = 0
    animator: Animator | None = None  # skinned meshes: one skeleton per instance
    bone_base: int = 0  # the first entry of this mesh's bones in a logic state (rgraph.scene.skin_states)

    @property
    def instances(self) -> int:
        return len(self.positions)

    def local_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) object-space box holding every frame: deformation padded; a skinned mesh in
        any pose stays within the rest mesh's reach around the root joint (the root bobs 2 cm
        and breathes 1%: rgraph.scene.animation)."""
        lo, hi = self.data.bounds()
        if self.deformer is not None:
            pad = self.deformer.max_displacement
            lo, hi = lo - pad, hi + pad
        if self.animator is not None:
            root, reach = self._skin_reach()
            lo, hi = root - reach, root + reach
        return lo, hi

    def _skin_reach(self) -> tuple[np.ndarray, float]:
        root = self.animator.rig.skeleton.heads[0].astype(np.float64)
        return root, 1.02 * float(np.linalg.norm(self.data.positions - root, axis=1).max()) + 0.05

    def world_corners(self) -> np.ndarray:
        """Corners of every instance's world bounding box (instances * 8, 3), any pose or deformation."""
        lo, hi = self.local_bounds()
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        m = model_matrix(np.zeros(3), self.rotation, self.scale)
        local = corners @ m[:3, :3].T
        return (self.positions[:, None, :] + local[None, :, :]).reshape(-1, 3)

    def bounding_sphere(self) -> tuple[np.ndarray, float]:
        """(centre offset from an instance's translation in world axes, radius): the sphere
        around the rotated, scaled local bounding box (deformation included); for a skinned mesh
        the sphere of its reach around the root joint (every pose)."""
        m = model_matrix(np.zeros(3), self.rotation, self.scale)[:3, :3]
        if self.animator is not None:
            root, reach = self._skin_reach()
            return m @ root, reach * float(np.abs(self.scale).max())
        lo, hi = self.local_bounds()
        centre = m @ ((lo + hi) / 2.0)
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        radius = float(np.linalg.norm(corners @ m.T - centre, axis=1).max())
        return centre, radius


@dataclass
class SceneLightData:
    type: int
    position: np.ndarray  # world float64 (0 for directional)
    direction: np.ndarray  # unit, the direction light travels
    radiance: np.ndarray
    intensity: float
    radius: float
    shadow_layer: int  # -1 without a shadow map
    cos_inner: float = 1.0  # spot lights: cosines of the cone's inner (full) and outer (zero) half-angles
    cos_outer: float = 0.0


@dataclass
class DecalData:
    position: np.ndarray  # world float64
    size: np.ndarray
    rotation: tuple[float, float, float]
    material: Material


@dataclass
class SceneData:
    name: str
    model: SceneFile
    extent: tuple[int, int]
    meshes: list[SceneMesh]
    material_names: list[str]
    materials: list[Material]
    lights: list[SceneLightData]
    decals: list[DecalData]
    world_corners: np.ndarray = field(repr=False)

    # ------------------------------------------------------------- counts
    @property
    def draw_count(self) -> int:
        return sum(m.instances for m in self.meshes)

    @property
    def shadow_lights(self) -> list[SceneLightData]:
        return [li for li in self.lights if li.shadow_layer >= 0]

    @property
    def point_light_count(self) -> int:
        return sum(1 for li in self.lights if li.type != LIGHT_TYPES["directional"])

    @property
    def deformable(self) -> list[SceneMesh]:
        return [m for m in self.meshes if m.deformer is not None]

    @property
    def skinned(self) -> list[SceneMesh]:
        return [m for m in self.meshes if m.animator is not None]

    @property
    def bone_count(self) -> int:
        """Bone transforms in one logic state (every skinned instance's skeleton)."""
        return sum(m.animator.bones * m.instances for m in self.skinned)

    @property
    def rigid(self) -> list[SceneMesh]:
        return [m for m in self.meshes if m.deformer is None]

    # ------------------------------------------------------------- per frame
    @staticmethod
    def seconds(frame: int) -> float:
        return frame * FRAME_SECONDS

    def camera(self, frame: int = 0) -> CameraState:
        """The camera of ``frame`` (static: the scene file's; computed once)."""
        cached = self.__dict__.get("_camera")
        if cached is None:
            c = self.model.camera
            w, h = self.extent
            cached = self.__dict__["_camera"] = camera_state(c.position, c.look_at, c.up, c.fov_y, c.near, w / h)
        return cached

    def draw_models(self, camera_position: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, int, int, int]]:
        """Per draw, in draw order: (camera-relative model, normal matrix, material, mesh index,
        flags) in float64; translation = world position - camera, formed in float64."""
        cam = np.asarray(camera_position, dtype=np.float64)
        out = []
        for k, mesh in enumerate(self.meshes):
            flags = 1 if mesh.deformer is not None else 0
            base = model_matrix(np.zeros(3), mesh.rotation, mesh.scale)
            normal = normal_matrix(base)
            for p in mesh.positions - cam:
                m = base.copy()
                m[:3, 3] = p
                out.append((m, normal, mesh.material, k, flags))
        return out

    def bounds_rel(self, camera_position: np.ndarray) -> np.ndarray:
        """Bounding-box corners of the whole scene, camera-relative (float64)."""
        return self.world_corners - np.asarray(camera_position, dtype=np.float64)

    def bounding_sphere_rel(self, camera_position: np.ndarray) -> tuple[np.ndarray, float]:
        """(centre, radius) of the sphere around the scene's bounding box, camera-relative."""
        pts = self.bounds_rel(camera_position)
        centre = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
        return centre, float(np.linalg.norm(pts - centre, axis=1).max())

    def shadow_matrices(self, camera_position: np.ndarray) -> list[np.ndarray]:
        pts = self.bounds_rel(camera_position)
        return [shadow_view_proj(li.direction, pts) for li in self.shadow_lights]

    def deformed(self, mesh: SceneMesh, frame: int) -> MeshData:
        assert mesh.deformer is not None
        return mesh.deformer.at_frame(frame)

    def decal_matrices(self, camera_position: np.ndarray) -> list[np.ndarray]:
        """Camera-relative world -> decal box [-0.5, 0.5]^3 (float64)."""
        cam = np.asarray(camera_position, dtype=np.float64)
        return [np.linalg.inv(model_matrix(d.position - cam, d.rotation, d.size)) for d in self.decals]


def _vec(v) -> np.ndarray:
    return np.asarray(v, dtype=np.float64).reshape(3)


def _instance_positions(mesh) -> np.ndarray:
    base = _vec(mesh.position)
    inst = mesh.instances
    if inst is None:
        return base[None]
    if inst.count is not None:
        lo, hi = np.asarray(inst.bounds, dtype=np.float64)
        return base + np.random.default_rng(inst.seed).uniform(lo, hi, (inst.count, 3))
    g = inst.grid
    axes = [(np.arange(n) - (n - 1) / 2) * inst.spacing for n in g]
    offs = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return base + offs


#: Unique instances (``unique: true``): each instance's geometry is the shape scaled per axis by
#: a seeded factor in this range (its own vertex and index data).
UNIQUE_SCALE = (0.6, 1.4)


def _unique_meshes(name: str, data: MeshData, material: int, rotation, scale, positions: np.ndarray,
                   seed: int, first_draw: int) -> list[SceneMesh]:
    """One single-instance mesh per instance, its vertices scaled by seeded per-axis factors
    (``numpy.random.default_rng(seed)``, (instances, 3) factors in ``UNIQUE_SCALE``)."""
    factors = np.random.default_rng(seed).uniform(*UNIQUE_SCALE, (len(positions), 3))
    out = []
    for i, (p, f) in enumerate(zip(positions, factors, strict=True)):
        normals = data.normals / f
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        own = MeshData(data.positions * f, normals, data.indices.copy())
        out.append(SceneMesh(f"{name}#{i}", own, material, rotation, scale, p[None], None, first_draw + i))
    return out


def pick_camera(model: SceneFile, camera: int) -> SceneFile:
    """``model`` seen from its camera preset ``camera`` (FORMAT.md 7: index into ``cameras``;
    0 is ``camera`` when there is no list)."""
    if not model.cameras:
        if camera != 0:
            what = "an empty 'cameras' list" if "cameras" in model.model_fields_set else "no 'cameras' list"
            raise ValueError(f"camera {camera}: the scene has {what} (only camera 0, its 'camera')")
        return model
    if not 0 <= camera < len(model.cameras):
        raise ValueError(f"camera {camera} out of range: the scene has {len(model.cameras)} cameras")
    return model.model_copy(update={"camera": model.cameras[camera]})


def _check_shadow_lights(model: SceneFile) -> None:
    """At most :data:`MAX_SHADOW_LIGHTS` directional lights with ``shadows: true`` (shadow map layers)."""
    shadowed = [j for j, li in enumerate(model.lights)
                if getattr(li, "type", None) == "directional" and getattr(li, "shadows", False)]
    if len(shadowed) > MAX_SHADOW_LIGHTS:
        raise SceneBuildError(("lights", shadowed[MAX_SHADOW_LIGHTS]),
                              f"at most {MAX_SHADOW_LIGHTS} shadow-casting lights are supported; this is shadow "
                              f"light {MAX_SHADOW_LIGHTS + 1} of {len(shadowed)} (set 'shadows: false' on the rest)")


def build_scene(model: SceneFile, extent: tuple[int, int] = (64, 64), name: str | None = None,
                camera: int = 0) -> SceneData:
    """Geometry and tables of a scene file for an output of ``extent`` (w, h), seen from camera
    preset ``camera``."""
    model = pick_camera(model, camera)
    material_names = list(model.materials)
    materials = [model.materials[n] for n in material_names]
    meshes, draw, bones = [], 0, 0
    for i, m in enumerate(model.meshes):
        positions = _instance_positions(m)
        animator = None
        try:
            if m.skinned is not None:
                rig = build_rig(m.skinned.bones)
                data = rig.mesh
                animator = Animator(rig, len(positions), m.skinned.speed, m.skinned.amplitude, m.skinned.seed)
            else:
                data = make_shape(m.shape, dict(m.params), seed=m.seed)
        except (ValueError, TypeError) as exc:
            raise SceneBuildError(("meshes", i), f"mesh {i} ({m.shape}): {exc}") from None
        scale = np.broadcast_to(np.asarray(m.scale, dtype=np.float64), (3,)).copy()
        if m.unique:
            if m.deformable or animator is not None:
                raise SceneBuildError(("meshes", i), f"mesh {i} ({m.shape}): unique meshes cannot be deformable or "
                                                     "skinned")
            group = _unique_meshes(f"{i}:{m.shape}", data, material_names.index(m.material), tuple(m.rotation),
                                   scale, positions, m.seed, draw)
            draw += len(group)
            meshes.extend(group)
            continue
        mesh = SceneMesh(f"{i}:{m.shape}", data, material_names.index(m.material), tuple(m.rotation), scale,
                         positions, Deformer(data) if m.deformable else None, draw, animator, bones)
        draw += mesh.instances
        bones += animator.bones * mesh.instances if animator is not None else 0
        meshes.append(mesh)
    _check_shadow_lights(model)
    lights, layer = [], 0
    for li in expand_lights(model.lights):
        kind = LIGHT_TYPES[li.type]
        direction = unit_or(_vec(li.direction if li.direction is not None else (0, -1, 0)), (0.0, -1.0, 0.0))
        shadow = -1
        if li.type == "directional" and li.shadows:
            shadow, layer = layer, layer + 1
        cos_inner, cos_outer = (float(np.cos(np.radians(a))) for a in li.cone)
        lights.append(SceneLightData(kind, _vec(li.position if li.position is not None else (0, 0, 0)), direction,
                                     _vec(li.color) * li.intensity, float(li.intensity), float(li.radius), shadow,
                                     cos_inner, cos_outer))
    pool = {**BUILTIN_DECALS, **model.materials, **model.decal_materials}
    decals = [DecalData(_vec(d.position), _vec(d.size), tuple(d.rotation), pool[d.material]) for d in model.decals]
    corners = (np.concatenate([m.world_corners() for m in meshes]) if meshes
               else np.zeros((1, 3)) + _vec(model.camera.look_at))
    _check_reach(meshes, corners)
    return SceneData(name or model.name or "scene", model, extent, meshes, material_names, materials, lights,
                     decals, corners)


def _check_reach(meshes: list[SceneMesh], corners: np.ndarray) -> None:
    """A mesh whose instances (scale, size and spacing applied) reach past ``MAX_COORDINATE``
    is refused at the mesh, as a position past it is by the scene model."""
    if np.abs(corners).max() <= MAX_COORDINATE:
        return
    mesh = next(m for m in meshes if not np.abs(m.world_corners()).max() <= MAX_COORDINATE)
    index, shape = mesh.name.split(":", 1)
    raise SceneBuildError(("meshes", int(index)), f"mesh {index} ({shape.split('#')[0]}) reaches past "
                                                  f"{MAX_COORDINATE:g} m from the origin (the limit of coordinates)")


def load_scene_data(path: str | Path, extent: tuple[int, int] = (64, 64), camera: int = 0) -> SceneData:
    """:func:`build_scene` of the scene file at ``path``; an item it cannot build is a located
    ``RGraphError`` (bad input), not a ValueError."""
    scene = load_scene(path)
    try:
        return build_scene(scene.model, extent, scene.name, camera)
    except SceneBuildError as exc:
        from rgraph.errors import RGraphError
        from rgraph.spec.yaml_source import load_yaml

        _, smap = load_yaml(Path(path), str(path))
        raise RGraphError.at(smap.value(exc.where), str(exc)) from None
