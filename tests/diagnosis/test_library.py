"""The library of built-in effects: one module per effect, registered in the
order of :data:`BUILTIN_EFFECTS`, each vanishing at its null values.

(The physics of each effect against an independent simulation is in
tests/diagnosis/test_effects.py.)
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import numpy as np
import pytest

from hybridtable.effects import library
from hybridtable.effects.effect import Effect
from hybridtable.effects.library import BUILTIN_EFFECTS, builtin_effects
from hybridtable.effects.registry import EFFECTS, build_spec, default_effects, effect_names
from hybridtable.effects.spec import RigScale
from hybridtable.measurement.replay import replay
from hybridtable.measurement.rig import simulate_rig
from hybridtable.measurement.run_reader import read_run
from tests.generators.effectsim import simulate_hidden
from tests.generators.rigsim import NOMINAL, write_run

LIBRARY = Path(library.__file__).parent

#: The effect modules: every module of the package but the helpers and ``__init__``.
MODULES = sorted(p.stem for p in LIBRARY.glob("*.py") if p.stem not in ("_common", "__init__"))

#: What an effect module may import from this package (imports point down).
ALLOWED = {"hybridtable.effects.effect", "hybridtable.effects.library._common"}


def _module(name: str):
    return importlib.import_module(f"hybridtable.effects.library.{name}")


@pytest.mark.parametrize("name", MODULES)
def test_each_module_defines_one_effect_named_after_it(name):
    module = _module(name)
    effects = [v for v in vars(module).values() if isinstance(v, Effect)]
    assert effects == [module.EFFECT]
    assert module.EFFECT.name == name
    assert module.__all__ == ["EFFECT"]
    assert module.__doc__ and len(module.__doc__.split()) > 20
    for node in ast.walk(ast.parse((LIBRARY / f"{name}.py").read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module.startswith("hybridtable"):
            assert node.module in ALLOWED, f"{name} imports {node.module}"
        if isinstance(node, ast.Import):
            assert not any(a.name.startswith("hybridtable") for a in node.names)


def test_builtin_effects_list_each_module_once_in_registration_order():
    assert len(MODULES) >= 11  # the library of issue 6; a new effect adds a module
    assert sorted(e.name for e in BUILTIN_EFFECTS) == MODULES
    for name in MODULES:
        assert sum(e is _module(name).EFFECT for e in BUILTIN_EFFECTS) == 1
    names = tuple(e.name for e in BUILTIN_EFFECTS)
    assert effect_names()[: len(names)] == names
    assert all(EFFECTS[e.name] is e for e in BUILTIN_EFFECTS)
    # Registration order decides ties of the ranking: damping before the look-alikes.
    assert names[:2] == ("contact_damping", "hunt_crossley")
    # diagnose's eleven first (mass_error last), then the effects on a CoR table's conditions
    assert default_effects("diagnose")[-1] == "mass_error"
    assert names[: len(default_effects("diagnose"))] == default_effects("diagnose")
    listed = builtin_effects()
    assert listed == list(BUILTIN_EFFECTS)
    listed.pop()
    assert len(builtin_effects()) == len(BUILTIN_EFFECTS)  # a fresh list each call


# -- each effect vanishes at its null values -----------------------------------
@pytest.fixture(scope="module")
def nominal_run(tmp_path_factory):
    """A noiseless run of the nominal rig (tests/generators/effectsim.py)."""
    path = tmp_path_factory.mktemp("nominal")
    info = dict(NOMINAL, run_id="nominal-library")
    cols = simulate_hidden(info, "none", noise_f_n=0.0, noise_p_m=0.0, substeps=40)
    return read_run(write_run(path, info["run_id"], info, cols))


def _away_from_null(effect: Effect, null: dict[str, float], scale: RigScale) -> dict[str, float]:
    """Each parameter 20 typical changes from its null value, within the bounds."""
    out = {}
    for p in effect.parameters:
        lo, hi = p.bounds(scale)
        v = min(null[p.name] + 20.0 * p.typical(scale), hi)
        out[p.name] = v if v != null[p.name] else max(null[p.name] - 20.0 * p.typical(scale), lo)
    return out


def _outputs(run, effect: Effect, values: dict[str, float], scale: RigScale) -> np.ndarray:
    """What the effect's stage sees: replay f_mea (N) and p_act (m, x 1e4 so
    1e-4 m weighs like 1 N); closed loop v_des (m/s, x 1e4)."""
    spec = build_spec([(effect, values)], scale)
    if effect.stage == "closed_loop":
        sim = simulate_rig(spec.closed_loop_run(run), spec.physics())
        return 1e4 * np.asarray(sim.v_des_m_per_s)
    rep = replay(run, spec.physics())
    return np.concatenate([rep.f_mea_n, 1e4 * rep.p_act_m])


#: The effects of the 1-D loop (a six-axis rig's only: tests/six_dof/test_effects6.py).
ONE_D = [n for n in MODULES if _module(n).EFFECT.apply is not None]


@pytest.mark.parametrize("name", ONE_D)
def test_each_effect_at_its_null_values_is_the_nominal_model(nominal_run, name):
    effect = _module(name).EFFECT
    scale = RigScale.from_runs([nominal_run])
    null = effect.null_values(scale)
    if null is None:
        # A structural mode has no parameter value at which it vanishes (the
        # nominal table or sensor is a model without the mode); every other
        # effect has one.
        assert name in ("table_resonance", "mount_resonance")
        return
    for p in effect.parameters:
        lo, hi = p.bounds(scale)
        assert lo <= null[p.name] <= hi
    if effect.stage == "closed_loop":
        ref = 1e4 * np.asarray(simulate_rig(nominal_run).v_des_m_per_s)
    else:
        rep = replay(nominal_run)
        ref = np.concatenate([rep.f_mea_n, 1e4 * rep.p_act_m])
    at_null = _outputs(nominal_run, effect, null, scale)
    np.testing.assert_allclose(at_null, ref, rtol=0, atol=1e-9)
    # ... and the comparison sees the effect away from its null values.
    away = _outputs(nominal_run, effect, _away_from_null(effect, null, scale), scale)
    assert np.abs(away - ref).max() > 1e-3
