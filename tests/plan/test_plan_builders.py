"""``rgraph.plan.builders.builder``: the fast constructors build objects equal to the
dataclasses' own, with the same defaults, keywords and immutability."""

from __future__ import annotations

import dataclasses

import pytest

from rgraph.plan import model as pm
from rgraph.plan.builders import _NATIVE, builder, builder_python

#: Every builder there is here: the Python one, and the compiled one where it is built.
BUILDERS = [builder_python] + ([_NATIVE.FastBuilder] if _NATIVE is not None else [])


@pytest.mark.parametrize("make", BUILDERS)
def test_builders_equal_the_dataclass_constructors(make) -> None:
    sub = pm.Subresource((0, 1), (0, 2))
    st = pm.State(("COMPUTE_SHADER",), ("SHADER_STORAGE_WRITE",), "GENERAL", "compute")
    cases = [
        (pm.Access, ("img", sub, "storage_write", ("A",), ("B",), "GENERAL", True), {}),
        (pm.Barrier, ("img", sub, st, st), {}),
        (pm.Barrier, ("img", None, st, st), {"aliases": ("old",)}),
        (pm.Wait, ("compute", 3, ("ALL_COMMANDS",)), {}),
        (pm.Signal, ("graphics", 1, ("ALL_COMMANDS",)), {"device": 1}),
        (pm.Culled, ("p", "reaches no output", ("r",), 256), {}),
        (pm.Wait, ("compute",), {"stages": ("ALL_COMMANDS",), "value": 2}),
        (pm.Signal, (), {"queue": "graphics", "value": 1, "stages": (), "device": None}),
    ]
    for cls, args, kwargs in cases:
        made = make(cls)(*args, **kwargs)
        assert type(made) is cls
        assert made == cls(*args, **kwargs)
        assert hash(made) == hash(cls(*args, **kwargs))
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(made, dataclasses.fields(cls)[0].name, "x")


def test_builder_refuses_classes_it_cannot_build() -> None:
    with pytest.raises(TypeError):
        builder(pm.Plan)  # no slots, default_factory fields


def test_every_built_class_takes_the_twin_path() -> None:
    """The emitted classes are built through a mutable twin of their layout (the fast path),
    and an object of the twin becomes one of the class."""
    from rgraph.plan.builders import _twin

    for cls in (pm.Access, pm.Barrier, pm.PlanPass, pm.PlanResource, pm.Wait, pm.Signal, pm.Culled):
        twin = _twin(cls)
        assert twin is not None, cls
        assert set(twin.__slots__) == {f.name for f in dataclasses.fields(cls)}


def test_builder_without_a_twin_still_builds_equal_objects() -> None:
    """A class whose slots are spread over two classes falls back to the slots' descriptors."""
    from rgraph.plan.builders import _twin

    @dataclasses.dataclass(frozen=True, slots=True)
    class Base:
        a: int

    @dataclasses.dataclass(frozen=True, slots=True)
    class Child(Base):
        b: int = 2

    assert _twin(Child) is None
    made = builder(Child)(1)
    assert type(made) is Child and made == Child(1, 2)


@pytest.mark.parametrize("make", BUILDERS)
def test_builders_refuse_wrong_arguments_as_the_constructor_does(make) -> None:
    build = make(pm.Wait)
    for args, kwargs in [((), {}), (("q", 1), {}), (("q", 1, (), None, 5), {}), (("q", 1, ()), {"colour": 1}),
                         (("q", 1, ()), {"queue": "r"})]:
        with pytest.raises(TypeError):
            pm.Wait(*args, **kwargs)
        with pytest.raises(TypeError):
            build(*args, **kwargs)


def test_the_compiled_builder_is_used_where_built() -> None:
    if _NATIVE is None:
        pytest.skip("rgraph.plan._builders not built (or RGRAPH_NATIVE=0)")
    assert isinstance(builder(pm.Barrier), _NATIVE.FastBuilder)
    with pytest.raises(TypeError):
        _NATIVE.FastBuilder(pm.Plan)  # no slots
