"""The spacecraft numerical model, Eq. 1 of the paper: m d2p_des/dt2 = -f_sim.

Sign convention (``docs/run-format.md``): ``p > 0`` is penetration,
the spacecraft approaches with positive velocity, and a compression force
``f_sim > 0`` pushes the spacecraft back, so its acceleration is ``-f_sim / m``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LinearSystem

from hybridtable._components import Block, Component
from hybridtable._validation import check_finite, check_positive
from hybridtable.laws.spacecraft import DEFAULT_INTEGRATOR, computer_step

__all__ = ["SpacecraftParams", "Spacecraft", "spacecraft_matrices"]


@dataclass(frozen=True)
class SpacecraftParams:
    """Parameters of the spacecraft model.

    Parameters
    ----------
    mass_kg : float
        Mass (or inertia along the docking axis) of the spacecraft model, > 0.
    """

    mass_kg: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "mass_kg", check_positive("mass_kg", self.mass_kg))


def spacecraft_matrices(
    mass_kg: float, sample_period_s: float | None = None, integrator: str = DEFAULT_INTEGRATOR
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """State-space matrices (A, B, C, D) of the spacecraft, state ``[p_des, v_des]``.

    Continuous: ``d/dt [p, v] = [v, -f/m]``. Sampled with period ``h``: the
    rig computer's step (:func:`~hybridtable.laws.spacecraft.computer_step`),
    by default semi-implicit Euler, ``v+ = v - f h / m`` then ``p+ = p + v+ h``.
    """
    m = check_positive("mass_kg", mass_kg)
    C = np.eye(2)
    D = np.zeros((2, 1))
    if sample_period_s is None:
        A = np.array([[0.0, 1.0], [0.0, 0.0]])
        B = np.array([[0.0], [-1.0 / m]])
    else:
        A, B = computer_step(m, check_positive("sample_period_s", sample_period_s), integrator)
    return A, B, C, D


class Spacecraft(Component):
    """The spacecraft model as a Drake system (a ``LinearSystem``; a component
    the loop adds flat, :mod:`hybridtable._components`).

    Ports
    -----
    Input ``force`` (size 1, N)
        The simulated contact force f_sim (compression positive); the
        spacecraft is pushed by ``-force``.
    Output ``state`` (size 2: m, m/s)
        ``[p_des, v_des]``, the desired relative position sent to the table as
        its command, and the spacecraft velocity. No direct feedthrough.

    Parameters
    ----------
    params : SpacecraftParams
    sample_period_s : float, optional
        ``None`` (default) for the continuous model of the paper; a period for
        the rig computer's integration, whose state output is then held
        between ticks (the zero-order-held command).
    initial_position_m, initial_velocity_m_per_s : float
        Default state.
    integrator : str
        The sampled rig computer's rule (:data:`~hybridtable.laws.spacecraft.INTEGRATORS`;
        default the format's semi-implicit Euler).
    """

    def __init__(
        self,
        params: SpacecraftParams,
        sample_period_s: float | None = None,
        initial_position_m: float = 0.0,
        initial_velocity_m_per_s: float = 0.0,
        integrator: str = DEFAULT_INTEGRATOR,
    ) -> None:
        Component.__init__(self)
        self.params = params
        self.sample_period_s = sample_period_s
        self.integrator = integrator
        self._x0 = np.array(
            [
                check_finite("initial_position_m", initial_position_m),
                check_finite("initial_velocity_m_per_s", initial_velocity_m_per_s),
            ]
        )
        self._build("double_integrator")

    def _add(self, builder: DiagramBuilder, name: str) -> Block:
        A, B, C, D = spacecraft_matrices(self.params.mass_kg, self.sample_period_s, self.integrator)
        h = self.sample_period_s
        linear = builder.AddNamedSystem(name, LinearSystem(A, B, C, D, 0.0 if h is None else h))
        return Block(
            self, {"force": [linear.get_input_port()]}, {"state": linear.get_output_port()}, linear
        )

    def _write_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        x = np.array([position_m, velocity_m_per_s])
        if self.sample_period_s is None:
            context.SetContinuousState(x)
        else:
            context.SetDiscreteState(x)

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        """Set ``[p_des, v_des]`` in this system's (sub)context."""
        Component.set_initial_state(self, context, position_m, velocity_m_per_s)

    def set_default_state(self, context) -> None:
        """Apply the constructor's initial position and velocity."""
        self.set_initial_state(context, *self._x0)
