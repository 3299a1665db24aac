"""Identify the Stewart table's response as the loop's second-order model.

The table (plant + leg servo) is driven along the docking axis, away from the
passive device, by a step or a chirp of the commanded position; the device's
sampled position is fitted, in the time domain, by the response of
``p'' = w^2 (g p_des - p) - 2 zeta w p'`` to the same zero-order-held command
(exact discretisation). The fitted ``f = w / 2 pi`` and ``zeta`` are the
table parameters the 1-D loop needs to reproduce the Stewart loop.
:func:`tune_leg_gains` adjusts the servo gains until the identified response
has a target frequency and damping ratio.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, TrajectorySource, ZeroOrderHold
from pydrake.trajectories import PiecewisePolynomial
from scipy.optimize import least_squares
from scipy.signal import lfilter

from hybridtable._validation import check_nonnegative, check_positive
from hybridtable.errors import ParameterError
from hybridtable.laws.table import second_order_tick
from hybridtable.stewart.backend import StewartTable
from hybridtable.stewart.params import StewartParams, heave_servo_gains
from hybridtable.stewart.progress import add_progress_ticker
from hybridtable.systems.table import TableParams

__all__ = [
    "TableResponse",
    "drive_table",
    "fit_second_order",
    "identify_step",
    "identify_chirp",
    "tune_leg_gains",
    "tune_reference",
    "tune_table",
]


@dataclass(frozen=True)
class TableResponse:
    """A second-order model identified from the Stewart table.

    Attributes
    ----------
    response_frequency_hz, damping_ratio : float
        The fitted model (the loop's ``table_response_hz`` and
        ``table_damping_ratio``).
    static_gain : float
        Fitted steady-state gain (1 for a servo without offset).
    rms_error_m : float
        RMS of the fit residual.
    excitation : str
        ``"step"`` or ``"chirp"``.
    """

    response_frequency_hz: float
    damping_ratio: float
    static_gain: float
    rms_error_m: float
    excitation: str

    def table_params(self) -> TableParams:
        """The identified model as :class:`~hybridtable.systems.table.TableParams`."""
        return TableParams(self.response_frequency_hz, self.damping_ratio)

    def as_dict(self) -> dict[str, float | str]:
        return {
            "response_frequency_hz": self.response_frequency_hz,
            "damping_ratio": self.damping_ratio,
            "static_gain": self.static_gain,
            "rms_error_m": self.rms_error_m,
            "excitation": self.excitation,
        }


def drive_table(
    params: StewartParams,
    command_m: np.ndarray,
    initial_offset_m: float,
    contact_stiffness_n_per_m: float = 1e5,
    label: str = "Stewart table",
) -> np.ndarray:
    """Drive the table with a sampled command and return its sampled motion.

    Parameters
    ----------
    params : StewartParams
    command_m : array (n,)
        Commanded docking-axis position computed at ticks ``k h`` (``h`` the
        plant step) by a discrete "rig computer", as in the sampled hybrid
        loop: the servo acts on it from tick ``k + 1``; a continuous
        second-order table would follow it during ``(k h, (k + 1) h]``.
    initial_offset_m : float
        Initial position of the device (at rest).
    contact_stiffness_n_per_m : float
        Stiffness of the contact (the devices stay apart; it only builds the plant).
    label : str
        Name of the progress bar inside a
        :class:`~hybridtable.stewart.progress.SimulatedTimeProgress` block.

    Returns
    -------
    motion : array (n, 3)
        ``[p, v, a]`` at the ticks (before each tick's update).
    force : array (n,)
        The sensed contact force at the ticks (N, compression positive).
    """
    h = params.time_step_s
    u = np.asarray(command_m, dtype=float)
    n = len(u)
    builder = DiagramBuilder()
    table = builder.AddNamedSystem("table", StewartTable(params, contact_stiffness_n_per_m))
    times = h * np.arange(n + 1)
    values = np.vstack([np.append(u, u[-1]), np.zeros(n + 1)])
    source = builder.AddSystem(TrajectorySource(PiecewisePolynomial.ZeroOrderHold(times, values)))
    # The rig computer's view: the command computed at tick k (a discrete
    # update) reaches the table's servo at tick k + 1.
    computer = builder.AddSystem(ZeroOrderHold(h, 2))
    builder.Connect(source.get_output_port(), computer.get_input_port())
    builder.Connect(computer.get_output_port(), table.GetInputPort("commanded_state"))
    log = LogVectorOutput(table.GetOutputPort("motion"), builder, h)
    force_log = LogVectorOutput(table.GetOutputPort("sensed_force"), builder, h)
    add_progress_ticker(builder, label, (n - 1) * h)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    table.set_initial_state(table.GetMyMutableContextFromRoot(context), initial_offset_m, 0.0)
    computer.GetMyMutableContextFromRoot(context).SetDiscreteState([u[0], 0.0])
    unstable = (
        "the table does not follow its command: the leg servo is unstable with gains "
        f"{params.servo_gains()} N/m, N s/m at time step {h:g} s"
    )
    try:
        simulator.AdvanceTo((n - 1) * h + 0.5 * h)
    except (RuntimeError, SystemExit) as err:  # the SAP solver gives up on divergence
        raise ParameterError(f"{unstable} ({err})") from None
    motion = log.FindLog(context).data().T[:n]
    force = force_log.FindLog(context).data()[0, :n]
    span = np.ptp(np.append(u, initial_offset_m))
    if not np.all(np.isfinite(motion)) or np.max(np.abs(motion[:, 0] - u)) > 10.0 * span + 1e-3:
        raise ParameterError(unstable)
    return motion, force


def _simulate_model(frequency_hz, damping_ratio, gain, u, h):
    """y_k = x_k[0] with x_{k+1} = Ad x_k + Bd gain u_k, x_0 = 0 (as a filter)."""
    Ad, Bd = second_order_tick(frequency_hz, damping_ratio, h)
    # Transfer function y/u = z^-1 (b0 + b1 z^-1) / (1 + a1 z^-1 + a2 z^-2).
    a1 = -np.trace(Ad)
    a2 = np.linalg.det(Ad)
    b0 = Bd[0]
    b1 = Ad[0, 1] * Bd[1] - Ad[1, 1] * Bd[0]
    return lfilter([0.0, gain * b0, gain * b1], [1.0, a1, a2], u)


def fit_second_order(
    command_m: np.ndarray,
    position_m: np.ndarray,
    period_s: float,
    initial_guess: tuple[float, float] = (25.0, 0.8),
    excitation: str = "custom",
) -> TableResponse:
    """Fit ``(f, zeta, gain)`` of the second-order model to sampled data.

    ``command_m`` and ``position_m`` are deviations from a rest state at
    ticks ``k period_s``; the command is held over each tick.
    """
    u = np.asarray(command_m, dtype=float)
    y = np.asarray(position_m, dtype=float)
    if u.shape != y.shape or u.ndim != 1 or len(u) < 10:
        raise ParameterError("command and position must be equal-length series of >= 10 samples")
    scale = max(np.max(np.abs(u)), 1e-12)

    def residual(theta):
        f, z, gain = theta
        return (_simulate_model(f, z, gain, u, period_s) - y) / scale

    nyquist = 0.5 / period_s
    f0 = min(max(initial_guess[0], 0.1), 0.9 * nyquist)
    fit = least_squares(
        residual,
        [f0, max(initial_guess[1], 0.05), 1.0],
        bounds=([1e-3, 0.0, 0.5], [nyquist, 10.0, 2.0]),
        x_scale=[f0, 1.0, 1.0],
        xtol=1e-12,
        ftol=1e-12,
    )
    f, z, gain = fit.x
    rms = float(np.sqrt(np.mean((fit.fun * scale) ** 2)))
    return TableResponse(float(f), float(z), float(gain), rms, excitation)


def _settle_s(guess_hz: float) -> float:
    return max(0.05, 3.0 / guess_hz)


def identify_step(
    params: StewartParams,
    amplitude_m: float = 1e-3,
    duration_s: float | None = None,
    initial_guess: tuple[float, float] = (25.0, 0.8),
) -> TableResponse:
    """Identify the response from a step of the commanded position.

    The table starts at rest ``2 amplitude`` below the contact (home) and
    steps ``amplitude_m`` further away from it, so the devices never touch.
    """
    a = check_positive("amplitude_m", amplitude_m)
    h = params.time_step_s
    settle = _settle_s(initial_guess[0])
    duration = duration_s or settle + max(0.3, 12.0 / initial_guess[0])
    n0 = int(round(settle / h))
    n = int(round(duration / h))
    start = -2.0 * a
    u = np.full(n, start)
    u[n0:] -= a
    motion, _ = drive_table(params, u, start, label="Stewart table: step response")
    p = motion[:, 0]
    base = p[n0]
    return fit_second_order(u[n0:] - start, p[n0:] - base, h, initial_guess, "step")


def identify_chirp(
    params: StewartParams,
    amplitude_m: float = 5e-4,
    start_hz: float = 1.0,
    stop_hz: float = 60.0,
    duration_s: float = 3.0,
    initial_guess: tuple[float, float] = (25.0, 0.8),
) -> TableResponse:
    """Identify the response from a logarithmic chirp of the commanded position.

    The command oscillates ``amplitude_m`` around ``3 amplitude`` below the
    contact, sweeping ``start_hz`` to ``stop_hz`` in ``duration_s``.
    """
    a = check_positive("amplitude_m", amplitude_m)
    f0 = check_positive("start_hz", start_hz)
    f1 = check_positive("stop_hz", stop_hz)
    T = check_positive("duration_s", duration_s)
    h = params.time_step_s
    if f1 <= f0 or f1 >= 0.5 / h:
        raise ParameterError(f"need start_hz < stop_hz < Nyquist {0.5 / h:g} Hz")
    settle = _settle_s(initial_guess[0])
    n0 = int(round(settle / h))
    t = h * np.arange(int(round(T / h)))
    rate = math.log(f1 / f0) / T
    phase = 2.0 * math.pi * f0 * (np.exp(rate * t) - 1.0) / rate
    center = -3.0 * a
    u = np.concatenate([np.full(n0, center), center + a * np.sin(phase)])
    motion, _ = drive_table(params, u, center, label="Stewart table: chirp response")
    p = motion[:, 0]
    return fit_second_order(u[n0:] - center, p[n0:] - p[n0], h, initial_guess, "chirp")


def _tune(
    start: StewartParams,
    response_hz: float,
    damping_ratio: float,
    tolerance: float,
    max_iterations: int,
    knobs,
    make,
    jacobian0: np.ndarray,
) -> tuple[StewartParams, TableResponse]:
    """Broyden's method on ``x = log(knobs)`` for the residual
    ``[log(f / f_t), zeta - zeta_t]`` of the identified step response; one
    identification per iteration, ``jacobian0`` the first Jacobian guess."""
    f_t = check_positive("response_hz", response_hz)
    z_t = check_nonnegative("damping_ratio", damping_ratio)
    if f_t * start.time_step_s > 0.1:
        raise ParameterError(
            f"response_hz {f_t:g} is too fast for time step {start.time_step_s:g} s "
            "(need response_hz * time_step_s <= 0.1)"
        )
    current = start
    x = np.log(np.asarray(knobs(current), dtype=float))
    J = np.array(jacobian0, dtype=float)
    previous = None
    response = None
    for _ in range(max_iterations):
        response = identify_step(current, initial_guess=(f_t, max(z_t, 0.05)))
        f, z = response.response_frequency_hz, response.damping_ratio
        r = np.array([math.log(f / f_t), z - z_t])
        if abs(f / f_t - 1.0) < tolerance and abs(z - z_t) < tolerance * max(z_t, 1.0):
            return current, response
        if previous is not None:
            dx, dr = x - previous[0], r - previous[1]
            J = J + np.outer(dr - J @ dx, dx) / float(dx @ dx)
        try:
            step = -np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            break
        largest = float(np.max(np.abs(step)))
        if largest > 0.5:  # at most a factor e^0.5 per iteration
            step *= 0.5 / largest
        previous = (x, r)
        x = x + step
        current = make(current, np.exp(x))
    raise ParameterError(
        f"could not tune the table to {f_t:g} Hz, damping ratio {z_t:g} (last identified "
        f"{response.response_frequency_hz:.3f} Hz, {response.damping_ratio:.4f}): the leg servo "
        "is too slow for it, or the time step too long"
    )


@lru_cache(maxsize=32)
def tune_leg_gains(
    params: StewartParams,
    response_hz: float,
    damping_ratio: float,
    tolerance: float = 1e-3,
    max_iterations: int = 20,
) -> tuple[StewartParams, TableResponse]:
    """Leg servo gains whose identified step response (without a reference
    model) has ``response_hz`` and ``damping_ratio`` (relative tolerance
    ``tolerance`` on the frequency, absolute ``tolerance`` on the damping).

    Starts from the rigid-heave gains (:func:`~hybridtable.stewart.params.heave_servo_gains`)
    and solves for ``(Kp, Kd)`` by Broyden's method (first guess: ``f ~ Kp^1/2``,
    ``zeta ~ Kd / Kp^1/2``).

    Returns
    -------
    (StewartParams, TableResponse)
        ``params`` without reference model and with the tuned gains, and its
        identification.

    Raises
    ------
    ParameterError
        If the target is not reached.
    """
    kp, kd = heave_servo_gains(params.geometry, response_hz, max(damping_ratio, 0.05))
    start = params.with_reference(None, params.reference_damping_ratio).with_gains(kp, kd)
    z = max(damping_ratio, 0.05)
    return _tune(
        start,
        response_hz,
        damping_ratio,
        tolerance,
        max_iterations,
        lambda p: p.servo_gains(),
        lambda p, g: p.with_gains(float(g[0]), float(g[1])),
        np.array([[0.5, 0.0], [-0.5 * z, z]]),
    )


@lru_cache(maxsize=32)
def tune_reference(
    params: StewartParams,
    response_hz: float,
    damping_ratio: float,
    tolerance: float = 1e-3,
    max_iterations: int = 20,
) -> tuple[StewartParams, TableResponse]:
    """Reference model whose table (reference model + stiff leg servo) has an
    identified step response with ``response_hz`` and ``damping_ratio``.

    Starts from the target and solves for the reference's frequency and
    damping ratio by Broyden's method.

    Returns
    -------
    (StewartParams, TableResponse)
        ``params`` with the tuned reference model, and its identification.
    """
    start = params.with_reference(response_hz, max(damping_ratio, 1e-3))
    nyquist = 0.5 / params.time_step_s

    def make(current: StewartParams, knobs: np.ndarray) -> StewartParams:
        if knobs[0] >= 0.9 * nyquist:
            raise ParameterError(
                f"could not tune the table to {response_hz:g} Hz: the reference model would "
                "approach the Nyquist rate (the leg servo is too slow; raise servo_bandwidth_hz "
                "or shorten the time step)"
            )
        return current.with_reference(float(knobs[0]), float(knobs[1]))

    z = max(damping_ratio, 0.05)
    return _tune(
        start,
        response_hz,
        damping_ratio,
        tolerance,
        max_iterations,
        lambda p: (p.reference_response_hz, p.reference_damping_ratio),
        make,
        np.array([[1.0, 0.0], [0.0, z]]),
    )


def tune_table(
    params: StewartParams, response_hz: float, damping_ratio: float, **kwargs
) -> tuple[StewartParams, TableResponse]:
    """:func:`tune_reference` if ``params`` has a reference model, else
    :func:`tune_leg_gains`."""
    if math.isinf(response_hz):
        raise ParameterError(
            "the Stewart table has a finite response; give a finite table_response_hz"
        )
    if params.reference_response_hz is None:
        return tune_leg_gains(params, response_hz, damping_ratio, **kwargs)
    return tune_reference(params, response_hz, damping_ratio, **kwargs)
