"""rgraph.scene.skinning / character / animation against the float64 matrix reference
(passes/skinning_ref.py): 256 bones, a 256-bone chain, shortest-arc interpolation near and at
180 degrees, zero and huge scales, half packing, NaN-free."""

from __future__ import annotations

import numpy as np
import pytest

from rgraph.resources import builtin_passes

builtin_passes()
from rgraph.passes import skinning_ref as ref  # noqa: E402

from rgraph.scene.animation import Animator, logic_tick  # noqa: E402
from rgraph.scene.character import build_rig, template  # noqa: E402
from rgraph.scene.skinning import (  # noqa: E402
    HALF_MAX,
    Pose,
    Skeleton,
    forward_kinematics,
    half_bits,
    interpolate,
    pack_bones,
    skin,
    skin_transforms,
    unpack_bones,
)


def _random_pose(rng, bones: int, chars: int, scale=(0.5, 1.5)) -> Pose:
    q = rng.normal(size=(4, bones, chars))
    q /= np.linalg.norm(q, axis=0)
    return Pose(q, rng.normal(size=(3, bones, chars)) * 0.3, rng.uniform(*scale, size=(bones, chars)))


def _ref_skins(skel: Skeleton, local: Pose, c: int) -> list[np.ndarray]:
    mats = ref.local_matrices(local.q[:, :, c].T, local.t[:, :, c].T, local.s[:, c])
    return ref.skin_matrices(skel.heads, ref.world_matrices(skel.parents, mats))


def _as_matrix(pose: Pose, b: int, c: int) -> np.ndarray:
    return ref.similarity(pose.q[:, b, c], pose.t[:, b, c], pose.s[b, c])


@pytest.mark.parametrize("shape", ["tree", "chain"])
def test_forward_kinematics_and_skin_transforms_match_matrices(shape):
    rng = np.random.default_rng(3)
    bones = 256
    if shape == "chain":  # the longest chain there can be: 256 bones, short random turns
        parents = np.arange(-1, bones - 1)
    else:
        parents = np.array([-1] + [int(rng.integers(0, b)) for b in range(1, bones)])
    skel = Skeleton(parents, rng.normal(size=(bones, 3)))
    local = _random_pose(rng, bones, 3, scale=(0.97, 1.03))
    if shape == "chain":
        local.q[:3] *= 0.05
        local.q /= np.linalg.norm(local.q, axis=0)
    skins = skin_transforms(skel, forward_kinematics(skel, local))
    for c in range(3):
        want = _ref_skins(skel, local, c)
        for b in range(bones):
            got = _as_matrix(skins, b, c)
            assert np.allclose(got, want[b], rtol=1e-9, atol=1e-9 * max(1.0, np.abs(want[b]).max())), (c, b)


def test_zero_and_huge_scales_stay_finite_and_clamp_to_half():
    rng = np.random.default_rng(4)
    skel = Skeleton(np.arange(-1, 7), rng.normal(size=(8, 3)))
    local = _random_pose(rng, 8, 2)
    local.s[2, 0] = 0.0  # collapses everything below bone 2 onto its joint
    local.s[:, 1] = 1e3  # 1e3^8 overflows half (and would overflow float32 as a scale product)
    skins = skin_transforms(skel, forward_kinematics(skel, local))
    want = _ref_skins(skel, local, 0)
    for b in range(8):
        assert np.allclose(_as_matrix(skins, b, 0), want[b], atol=1e-9)
    assert np.all(skins.s[2:, 0] == 0.0)
    packed = pack_bones(skins)
    back = unpack_bones(packed)
    assert np.isfinite(back.t).all() and np.isfinite(back.s).all() and np.isfinite(back.q).all()
    assert back.s[:, 1].max() == HALF_MAX and np.abs(back.t).max() <= HALF_MAX
    assert back.s.min() == 0.0


def test_pack_refuses_non_finite():
    pose = Pose(np.zeros((4, 1, 1)) + [[[0]], [[0]], [[0]], [[1]]], np.zeros((3, 1, 1)), np.ones((1, 1)))
    pose.t[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        pack_bones(pose)
    pose.t[0, 0, 0] = np.inf
    with pytest.raises(ValueError, match="finite"):
        pack_bones(pose)


def test_half_bits_match_numpy_rounding_within_one_ulp_and_exactly_on_representable_values():
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.normal(size=10000) * 10.0 ** rng.integers(-8, 5, size=10000),
                        [0.0, -0.0, 6.1e-5, 5.96e-8, 1e-9, HALF_MAX, -HALF_MAX, 1.0, -2.0]]).astype(np.float32)
    got = half_bits(x).view(np.float16).astype(np.float64)
    want = x.astype(np.float16).astype(np.float64)
    with np.errstate(over="ignore"):  # the spacing above HALF_MAX is infinite
        ulp = np.spacing(np.abs(want).astype(np.float16)).astype(np.float64)
    assert np.all(np.abs(got - want) <= ulp)
    exact = np.array([0.5, 1.0, 1.5, 65504.0, -3.25, 2.0 ** -24], dtype=np.float32)
    assert np.array_equal(half_bits(exact).view(np.float16), exact.astype(np.float16))


def test_interpolation_at_0_half_1_and_the_shortest_arc_near_180_degrees():
    rng = np.random.default_rng(6)
    a, b = _random_pose(rng, 16, 2), _random_pose(rng, 16, 2)
    # bone 0: 179.9 degrees apart, stored with a negative dot product (the long way round)
    a.q[:, 0, 0] = [0, 0, 0, 1]
    half = np.radians(179.9) / 2
    b.q[:, 0, 0] = -np.array([0, np.sin(half), 0, np.cos(half)])
    # bone 1: exactly 180 degrees (dot 0) and bone 2: the same rotation as -q (dot -1)
    a.q[:, 1, 0], b.q[:, 1, 0] = [0, 0, 0, 1], [0, 1, 0, 0]
    a.q[:, 2, 0] = [0.5, 0.5, 0.5, 0.5]
    b.q[:, 2, 0] = -a.q[:, 2, 0]
    for alpha in (0.0, 0.25, 0.5, 1.0):
        got = interpolate(a, b, alpha)
        assert np.isfinite(got.q).all()
        for bone in range(16):
            for c in range(2):
                want = ref.nlerp_matrix(a.q[:, bone, c], a.t[:, bone, c], a.s[bone, c], b.q[:, bone, c],
                                        b.t[:, bone, c], b.s[bone, c], alpha)
                assert np.allclose(_as_matrix(got, bone, c), want, atol=1e-12)
    mid = interpolate(a, b, 0.5)
    assert np.allclose(mid.q[:, 0, 0], [0, np.sin(half / 2), 0, np.cos(half / 2)])  # short way: 89.95 degrees
    assert np.allclose(mid.q[:, 2, 0], a.q[:, 2, 0])  # q and -q: no motion at all
    assert np.allclose(interpolate(a, b, 0.0).t, a.t) and np.allclose(interpolate(a, b, 1.0).t, b.t)
    assert np.allclose(np.abs(np.sum(interpolate(a, b, 1.0).q * b.q, axis=0)), 1.0)


def test_character_rig_and_skinned_vertices_match_the_reference():
    rig = build_rig(256)
    assert rig.skeleton.bones == 256 and rig.skeleton.depth == 12
    assert 3000 <= rig.mesh.triangle_count <= 8000
    assert np.all(rig.weights.astype(np.int64).sum(axis=1) == 255)
    assert rig.joints.max() == 255
    anim = Animator(rig, 3, dtype=np.float64, seed=2)
    local = anim.local_pose(0.7)
    skins = skin_transforms(rig.skeleton, forward_kinematics(rig.skeleton, local))
    w = rig.weights_f
    for c in range(3):
        want = ref.skin_vertices(rig.mesh.positions, rig.joints, w, _ref_skins(rig.skeleton, local, c))
        got, normals = skin(rig.mesh.positions, rig.mesh.normals, rig.joints, w, skins, c)
        assert np.abs(got - want).max() < 1e-9
        assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert np.abs(got - rig.mesh.positions).max() > 0.05  # the pose moved


@pytest.mark.parametrize("bones", [1, 2, 7, 53, 54, 255])
def test_truncated_templates_are_valid_trees(bones):
    rig = build_rig(bones)
    assert rig.skeleton.bones == bones and len(template(bones)) == bones
    assert rig.joints.max() < bones


def test_float32_logic_path_within_half_precision_of_float64():
    rig = build_rig(256)
    fast, exact = Animator(rig, 8, seed=1), Animator(rig, 8, seed=1, dtype=np.float64)
    got = unpack_bones(fast.state(37))
    want = exact.pose(37 / 60.0)
    assert np.abs(got.t - want.t).max() < 4e-3  # half spacing at 2 m is 2e-3
    assert np.abs(got.q - want.q).max() < 1e-3 and np.abs(got.s - want.s).max() < 1e-3


def test_states_advance_and_logic_ticks():
    anim = Animator(build_rig(64), 4)
    assert not np.array_equal(anim.state(1), anim.state(2))
    assert np.array_equal(anim.state(5), anim.state(5))
    assert logic_tick(0.0) == (0, 0.0)
    assert logic_tick(1.0 / 60.0)[0] == 1  # frame 1 at 60 Hz is tick 1, not 0.99999
    k, alpha = logic_tick(1.0 / 60.0, 30.0)
    assert k == 0 and alpha == pytest.approx(0.5)


def test_threaded_state_is_bit_identical():
    anim = Animator(build_rig(32), 200, seed=4)
    assert np.array_equal(anim.state(9, threads=3).view(np.uint16), anim.state(9).view(np.uint16))


@pytest.mark.parametrize("mesh, message", [
    ("{shape: box, material: body, skinned: {bones: 12}}", "5:5: error: skinned meshes must be 'shape: character'"),
    ("{shape: character, material: body, skinned: {bones: 300}}", "5:57: error: 'bones'"),
    ("{shape: character, material: body, deformable: true, skinned: {}}", "either skinned or deformable"),
    ("{shape: character, material: body, unique: true, skinned: {}}", "5:5: error: skinned meshes share one rig"),
])
def test_bad_skinned_keys_are_one_line_errors(tmp_path, mesh, message):
    from rgraph.errors import RGraphError
    from rgraph.spec.scene import load_scene

    p = tmp_path / "bad.yaml"
    p.write_text(f"scene: 1\nmaterials:\n  body: {{base_color: [0.7, 0.5, 0.4]}}\nmeshes:\n  - {mesh}\n")
    with pytest.raises(RGraphError) as info:
        load_scene(p)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_vr_skinned_scene_and_draw_packing():
    from locations import ROOT

    from rgraph.scene import packing
    from rgraph.scene.build import load_scene_data

    data = load_scene_data(ROOT / "graphs" / "scenes" / "vr_skinned.yaml", (64, 36))
    (mesh,) = data.skinned
    assert mesh.instances == 1024 and mesh.animator.bones == 256 and data.bone_count == 1024 * 256
    rows = np.frombuffer(packing.draws_bytes(data, 0), dtype=np.uint32).reshape(-1, packing.DRAW_BYTES // 4)
    info = rows[:, 32:36]
    skinned = info[mesh.first_draw:mesh.first_draw + 1024]
    assert np.all(skinned[:, 2] == (packing.DRAW_SKINNED | (1024 << 8)))
    assert np.array_equal(skinned[:, 3], mesh.bone_base + np.arange(1024))
    assert np.all(skinned[:, 1] == data.meshes.index(mesh))
    others = np.delete(info, np.s_[mesh.first_draw:mesh.first_draw + 1024], axis=0)
    assert np.all(others[:, 2] & packing.DRAW_SKINNED == 0) and np.all(others[:, 3] == 0)
    # the bounds hold every pose: a character's reach around its root joint
    pose = mesh.animator.pose(0.37)
    from rgraph.scene.skinning import skin, skin_transforms

    posed, _ = skin(mesh.data.positions, mesh.data.normals, mesh.animator.rig.joints, mesh.animator.rig.weights_f,
                    skin_transforms(mesh.animator.rig.skeleton, pose), 5)
    world = posed + mesh.positions[5]
    box = mesh.world_corners()[5 * 8:6 * 8]  # instance 5's bounding box
    assert np.all(world >= box.min(axis=0)) and np.all(world <= box.max(axis=0))
    assert np.abs(posed - mesh.data.positions).max() > 0.02


def test_gpu_instances_carry_skinning_and_spheres_hold_every_pose(tmp_path):
    """draw.mode=gpu: Instance.info (rgraph.scene.instances) equals the Draws' info (skinned flag,
    bone stride, first bone entry), and GPU culling's bounding sphere (and the CPU box) holds
    every character's posed vertices over a whole cycle, rotated and scaled in the scene."""
    from rgraph.scene import instances, packing
    from rgraph.scene.build import load_scene_data

    p = tmp_path / "chars.yaml"
    p.write_text("""scene: 1
name: chars
camera: {position: [0, 2, 6], look_at: [0, 1, 0]}
materials: {m: {base_color: [0.5, 0.5, 0.5]}}
meshes:
  - {shape: box, material: m, instances: {grid: [2, 1, 1], spacing: 2}}
  - {shape: character, material: m, rotation: [0, 40, 10], scale: 1.5, skinned: {bones: 64, amplitude: 3.0, seed: 2},
     instances: {grid: [3, 1, 2], spacing: 2.5}}
""")
    data = load_scene_data(p, (32, 32))
    (mesh,) = data.skinned
    draws = np.frombuffer(packing.draws_bytes(data, 0), dtype=np.uint32).reshape(-1, packing.DRAW_BYTES // 4)
    table = np.frombuffer(instances.instance_bytes(data), dtype=np.uint32).reshape(-1, instances.INSTANCE_BYTES // 4)
    assert np.array_equal(table[:, 32:36], draws[:, 32:36])
    assert np.all(table[mesh.first_draw:, 34] == (packing.DRAW_SKINNED | (mesh.instances << 8)))
    centre, radius = mesh.bounding_sphere()
    from rgraph.scene.camera import model_matrix

    m = model_matrix(np.zeros(3), mesh.rotation, mesh.scale)[:3, :3]
    rig, worst, moved = mesh.animator.rig, 0.0, 0.0
    boxes = mesh.world_corners().reshape(mesh.instances, 8, 3)
    for seconds in np.linspace(0.0, 1.5, 13):
        transforms = skin_transforms(rig.skeleton, mesh.animator.pose(seconds))
        for c in range(mesh.instances):
            posed, _ = skin(rig.mesh.positions, rig.mesh.normals, rig.joints, rig.weights_f, transforms, c)
            world = posed @ m.T  # relative to the instance's translation
            worst = max(worst, float(np.linalg.norm(world - centre, axis=1).max()) / radius)
            box = boxes[c] - mesh.positions[c]
            assert np.all(world >= box.min(axis=0) - 1e-9) and np.all(world <= box.max(axis=0) + 1e-9)
            moved = max(moved, float(np.abs(posed - rig.mesh.positions).max()))
    assert worst <= 1.0 and moved > 0.1  # inside the sphere, and the poses really move
    # the sphere is the tight one around the reach, not the box's (sqrt(3) larger)
    lo, hi = mesh.local_bounds()
    assert radius < 0.7 * 0.5 * float(np.linalg.norm(hi - lo)) * 1.5
