"""The built-in candidate effects of ``hybridtable diagnose``, one module each.

Each module of this package (apart from ``_common``, the shared helpers) is
named after its effect and defines one ``EFFECT = Effect(...)``: its
parameters with units, bounds and null values, what it changes in the
:class:`~hybridtable.effects.effect.ModelSpec`, and its signature in the
residuals. :data:`BUILTIN_EFFECTS` lists them in registration order, which
matters: a tie of the ranking goes to the effect registered first.

To add an effect:

1. copy a module, e.g. ``contact_damping.py``, to ``my_effect.py`` (the
   effect's name) and edit its docstring and ``EFFECT``;
2. add one line here: import the module and append its ``EFFECT`` to
   :data:`BUILTIN_EFFECTS`.

An effect module imports only :mod:`hybridtable.effects.effect`,
:mod:`hybridtable.effects.library._common`, the standard library and numpy;
never the registry. A package outside this repository provides effects
through the entry-point group ``hybridtable.effects`` instead
(:mod:`hybridtable.effects.registry`).
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect
from hybridtable.effects.library import (
    com_offset,
    compensator_stiffness_error,
    contact_damping,
    contact_damping_ratio,
    contact_frequency_error,
    coulomb_friction,
    extra_delay,
    force_bias,
    friction_across_face,
    hunt_crossley,
    lead_time_error,
    mass_error,
    mount_resonance,
    nonlinear_stiffness,
    sensor_crosstalk,
    sensor_filter,
    sensor_misalignment,
    series_compliance,
    stiffness_error,
    table_damping,
    table_misalignment,
    table_resonance,
    table_response,
)

__all__ = ["BUILTIN_EFFECTS", "builtin_effects"]


#: The built-in effects, in registration order (ties of the ranking go to the first).
BUILTIN_EFFECTS: tuple[Effect, ...] = (
    contact_damping.EFFECT,
    hunt_crossley.EFFECT,
    nonlinear_stiffness.EFFECT,
    stiffness_error.EFFECT,
    series_compliance.EFFECT,
    coulomb_friction.EFFECT,
    sensor_filter.EFFECT,
    extra_delay.EFFECT,
    table_resonance.EFFECT,
    force_bias.EFFECT,
    mass_error.EFFECT,
    contact_frequency_error.EFFECT,
    lead_time_error.EFFECT,
    table_response.EFFECT,
    table_damping.EFFECT,
    compensator_stiffness_error.EFFECT,
    contact_damping_ratio.EFFECT,
    # a six-axis rig's only (6-DoF runs)
    friction_across_face.EFFECT,
    sensor_misalignment.EFFECT,
    table_misalignment.EFFECT,
    sensor_crosstalk.EFFECT,
    com_offset.EFFECT,
    # both loops, tried by 1-D front ends when named
    mount_resonance.EFFECT,
)


def builtin_effects() -> list[Effect]:
    """The built-in effects, in registration order (ties of the ranking go to the first)."""
    return list(BUILTIN_EFFECTS)
