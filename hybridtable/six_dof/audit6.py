"""The audit of a six-axis rig computer's spacecraft: what mass, centre of
mass and inertia its model stepped with, solved from the record.

A 6-DoF record holds the rig computer's own arithmetic (``docs/run6-format.md``,
step 3): the compensated wrench ``[tau_P; f]`` (about the port, W) fed at
tick ``k`` and the model port's pose and twist after the update. With the
port at ``c`` from the centre of mass (body frame), ``R`` the attitude and
``omega_b = R^T omega`` the body rate, the format's step gives, for each
tick ``k`` with a wrench (rows ``k-1`` and ``k``), two linear equations in
``mu = 1/m``, ``c`` and the inertia tensor's six entries:

- translation (the centre of mass's velocity ``v_P - omega x R c``):
  ``v_P[k] - v_P[k-1] = mu h f + (omega[k]x R[k] - omega[k-1]x R[k-1]) c``;
- rotation (the moment about the centre of mass ``tau_P + R c x f``):
  ``I (omega_b[k] - omega_b[k-1]) / h + omega_b[k-1] x I omega_b[k-1]
  + (R^T f) x c = R^T tau_P`` at ``R = R[k-1]``.

They are solved by weighted least squares (each block weighted by its own
residual scatter, the columns by the scenario's magnitudes) as deviations
from the scenario's values, so a quantity the runs do not determine (the
inertia of a run without torque, the port's distance along a force through
it) stays the scenario's and is said to be undetermined. A value is a
finding when it differs from the JSON's by more than
:data:`~hybridtable.measurement.audit_findings.SIGNIFICANCE` standard errors *and* by more than
:data:`~hybridtable.measurement.audit_findings.RELATIVE_TOLERANCE` of its scale, as the 1-D audit decides
(:mod:`hybridtable.measurement.audit`): ``com_offset`` (the computer's
centre of mass, the scenario's port position less the solved one),
``mass_error`` (the mass over the JSON's) and ``inertia_error``; a residual
above :data:`LAW_RESIDUAL` of the signal says the computer does not step its
model by the format's rule (``spacecraft_model_error``). A model stepped by
another time step than the JSON's rate
(:func:`~hybridtable.six_dof.audit_law6.time_step`) is ``sample_rate_error``,
and its equations are written with the step it used.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from hybridtable.measurement.audit_findings import RELATIVE_TOLERANCE, SIGNIFICANCE, differs
from hybridtable.six_dof.audit_findings6 import AuditFinding6, CompensationAudit6
from hybridtable.six_dof.audit_law6 import audit_compensation6, law_key, time_step
from hybridtable.six_dof.run6 import Run6
from hybridtable.stewart.geometry import skew

__all__ = [
    "LAW_RESIDUAL",
    "Audit6",
    "SpacecraftAudit",
    "audit_runs6",
    "audit_spacecraft6",
]

#: The largest RMS residual, over the RMS of what it fits, of a computer that
#: steps by the format's rule (a CSV at six digits leaves ~1e-4).
LAW_RESIDUAL = 0.05

#: The inertia tensor's entries in the unknowns' order.
INERTIA_ENTRIES = ("xx", "yy", "zz", "xy", "xz", "yz")
_INERTIA_INDEX = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
_AXES = ("x", "y", "z")

#: Singular values below this fraction of the largest leave their direction undetermined.
_RANK_TOLERANCE = 1e-9


@dataclass(frozen=True)
class SpacecraftAudit:
    """What :func:`audit_runs6` solved (see the module); ``None`` where the
    runs do not determine a quantity."""

    run_ids: list[str]
    ticks: int
    stated_mass_kg: float
    stated_port_position_m: tuple[float, float, float]
    stated_inertia_kg_m2: tuple[float, ...]
    mass_kg: float | None
    mass_std_kg: float | None
    port_position_m: tuple[float | None, ...]
    port_position_std_m: tuple[float | None, ...]
    inertia_kg_m2: tuple[float | None, ...]
    inertia_std_kg_m2: tuple[float | None, ...]
    relative_residual: float
    findings: list[AuditFinding6] = field(default_factory=list)

    @property
    def effects(self) -> list[str]:
        """The findings' effect names."""
        return [f.effect for f in self.findings]

    def sentence(self) -> str:
        if not self.ticks:
            return "the rig computer's spacecraft: no tick with a wrench to audit"
        if not self.findings:
            return (
                f"the rig computer's spacecraft is the JSON's (mass, centre of mass, inertia; "
                f"{self.ticks} ticks, residual {self.relative_residual:.2g} of the signal)"
            )
        return "the rig computer's spacecraft: " + "; ".join(f.sentence for f in self.findings)

    def to_dict(self) -> dict:
        return {
            "runs": self.run_ids,
            "ticks": self.ticks,
            "sentence": self.sentence(),
            "stated": {
                "mass_kg": self.stated_mass_kg,
                "port_position_m": list(self.stated_port_position_m),
                "inertia_kg_m2": dict(zip(INERTIA_ENTRIES, self.stated_inertia_kg_m2, strict=True)),
            },
            "solved": {
                "mass_kg": self.mass_kg,
                "port_position_m": list(self.port_position_m),
                "inertia_kg_m2": dict(zip(INERTIA_ENTRIES, self.inertia_kg_m2, strict=True)),
            },
            "std": {
                "mass_kg": self.mass_std_kg,
                "port_position_m": list(self.port_position_std_m),
                "inertia_kg_m2": dict(zip(INERTIA_ENTRIES, self.inertia_std_kg_m2, strict=True)),
            },
            "relative_residual": self.relative_residual,
            "findings": [f.to_dict() for f in self.findings],
            "thresholds": {
                "sigmas": SIGNIFICANCE,
                "relative": RELATIVE_TOLERANCE,
                "law_residual": LAW_RESIDUAL,
            },
        }


def _inertia_columns(u: np.ndarray) -> np.ndarray:
    """``I u`` as a matrix on the inertia's entries (:data:`INERTIA_ENTRIES`)."""
    out = np.zeros((3, 6))
    for j, (a, b) in enumerate(_INERTIA_INDEX):
        out[a, j] += u[b]
        if a != b:
            out[b, j] += u[a]
    return out


def _equations(run: Run6, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The run's translation and rotation equations on the ticks with a
    wrench, for a model stepped by ``h``: ``(A_t, b_t, A_r, b_r)``, each 3
    rows a tick, 10 unknowns ``[mu, c (3), inertia (6)]``."""
    R = run.rotations("des")
    omega = run.blocks["w_des"]
    v = run.blocks["v_des"]
    w = run.wrench("comp")
    tau, f = w[:, :3], w[:, 3:]
    omega_b = np.einsum("nji,nj->ni", R, omega)
    ticks = [k for k in range(1, run.n) if np.any(w[k] != 0.0)]
    A_t, b_t, A_r, b_r = (np.zeros((3 * len(ticks), n)) for n in (10, 1, 10, 1))
    for i, k in enumerate(ticks):
        rows = slice(3 * i, 3 * i + 3)
        A_t[rows, 0] = h * f[k]
        A_t[rows, 1:4] = skew(omega[k]) @ R[k] - skew(omega[k - 1]) @ R[k - 1]
        b_t[rows, 0] = v[k] - v[k - 1]
        Rt = R[k - 1].T
        wb = omega_b[k - 1]
        A_r[rows, 1:4] = skew(Rt @ f[k])
        A_r[rows, 4:] = _inertia_columns((omega_b[k] - wb) / h) + skew(wb) @ _inertia_columns(wb)
        b_r[rows, 0] = Rt @ tau[k]
    return A_t, b_t[:, 0], A_r, b_r[:, 0]


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x * x))) if x.size else 0.0


def _finding(stated, solved, std, scale) -> bool:
    return solved is not None and std is not None and differs(solved, std, stated, scale)


@dataclass(frozen=True)
class Audit6:
    """:func:`audit_runs6`'s result: one :class:`SpacecraftAudit` for each
    spacecraft the runs' JSONs state (runs of one spacecraft are solved
    together), and one :class:`~hybridtable.six_dof.audit_findings6.CompensationAudit6`
    for each law the runs' JSONs state (``laws``)."""

    groups: list[SpacecraftAudit]
    laws: list[CompensationAudit6] = field(default_factory=list)

    @property
    def findings(self) -> list[AuditFinding6]:
        return [f for g in [*self.groups, *self.laws] for f in g.findings]

    @property
    def effects(self) -> list[str]:
        """The findings' effect names, each once."""
        return list(dict.fromkeys(f.effect for f in self.findings))

    def sentence(self) -> str:
        """Each part's sentence (with a finding: only the parts that have one,
        or that could not be audited)."""
        parts = [*self.groups, *self.laws]
        if self.findings:
            parts = [p for p in parts if p.findings or getattr(p, "not_audited", "")]
        if len(self.groups) <= 1 and len(self.laws) <= 1:
            return "; ".join(p.sentence() for p in parts)
        return "; ".join(f"{', '.join(p.run_ids)}: {p.sentence()}" for p in parts)

    def to_dict(self) -> dict:
        return {
            "sentence": self.sentence(),
            "findings": [
                {**f.to_dict(), "runs": g.run_ids}
                for g in [*self.groups, *self.laws]
                for f in g.findings
            ],
            "groups": [g.to_dict() for g in self.groups],
            "compensation": [c.to_dict() for c in self.laws],
        }


def audit_runs6(runs: Sequence[Run6]) -> Audit6:
    """Solve the rig computer from ``runs``: its spacecraft (see the module),
    the runs of each spacecraft their JSONs state together, and its
    compensation law (:func:`~hybridtable.six_dof.audit_law6.audit_compensation6`),
    the runs that state one law together (:func:`~hybridtable.six_dof.audit_law6.law_key`)."""
    bodies: dict = {}
    laws: dict = {}
    for run in runs:
        p = run.params
        bodies.setdefault(p.spacecraft, []).append(run)
        laws.setdefault(law_key(p), []).append(run)
    return Audit6(
        [audit_spacecraft6(group) for group in bodies.values()],
        [audit_compensation6(group) for group in laws.values()],
    )


def audit_spacecraft6(runs: Sequence[Run6]) -> SpacecraftAudit:
    """Solve the rig computer's spacecraft from ``runs`` whose JSONs state
    one spacecraft (see the module)."""
    body = runs[0].params.spacecraft
    inertia0 = body.inertia
    x0 = np.array(
        [1.0 / body.mass_kg, *body.port_position_m, *(inertia0[a, b] for a, b in _INERTIA_INDEX)]
    )
    lever = max(float(np.linalg.norm(body.port_position_m)), 0.1)
    i_scale = float(np.trace(inertia0)) / 3.0
    scale = np.array([x0[0], lever, lever, lever, *(i_scale,) * 6])
    # a model stepped by another time step than the JSON's rate: read with its own,
    # so that it does not pass for a mass and an inertia of its own
    steps, stepped = [], []
    for r in runs:
        h_json = r.params.sample_period_s
        h, se = time_step(r)
        off = differs(h, se, h_json, h_json)
        steps.append(h if off else h_json)
        if off:
            stepped.append(
                AuditFinding6(
                    "sample_rate_error",
                    {"sample_rate_hz": 1.0 / h},
                    {"sample_rate_hz": se / (h * h)},
                    f"sample_rate_error: {r.run_id}'s model steps by {h * 1e3:.6g} ms "
                    f"({1.0 / h:.6g} Hz), the JSON's rate {r.params.sample_rate_hz:g} Hz",
                )
            )
    parts = [_equations(r, h) for r, h in zip(runs, steps, strict=True)]
    A_t = np.vstack([p[0] for p in parts])
    b_t = np.concatenate([p[1] for p in parts])
    A_r = np.vstack([p[2] for p in parts])
    b_r = np.concatenate([p[3] for p in parts])
    ticks = len(b_t) // 3
    stated = (body.mass_kg, tuple(body.port_position_m), tuple(x0[4:]))
    if ticks == 0:
        return SpacecraftAudit(
            [r.run_id for r in runs], 0, stated[0], stated[1], stated[2],
            None, None, (None,) * 3, (None,) * 3, (None,) * 6, (None,) * 6, 0.0,
            findings=stepped,
        )  # fmt: skip
    # each block weighted first by its signal, then by its scatter about the solution
    x = None
    for _ in range(3):
        sigma = [
            max(_rms(b if x is None else b - A @ x), 1e-15 * max(_rms(b), _rms(A @ x0)), 1e-300)
            for A, b in ((A_t, b_t), (A_r, b_r))
        ]
        A = np.vstack([A_t / sigma[0], A_r / sigma[1]]) * scale
        b = np.concatenate([(b_t - A_t @ x0) / sigma[0], (b_r - A_r @ x0) / sigma[1]])
        U, S, Vt = np.linalg.svd(A, full_matrices=False)
        keep = S > _RANK_TOLERANCE * S[0]
        y = Vt[keep].T @ ((U[:, keep].T @ b) / S[keep])
        x = x0 + scale * y
    dof = max(len(b) - int(keep.sum()), 1)
    s2 = float(np.sum((b - A @ y) ** 2)) / dof
    cov = (Vt[keep].T / S[keep] ** 2) @ Vt[keep] * s2
    null = Vt[~keep]
    determined = [float(np.linalg.norm(null[:, j])) < 1e-6 for j in range(10)]
    std = [math.sqrt(cov[j, j]) * scale[j] if determined[j] else None for j in range(10)]
    value = [float(x[j]) if determined[j] else None for j in range(10)]
    residual = math.hypot(_rms(b_t - A_t @ x) / max(_rms(b_t), 1e-300),
                          _rms(b_r - A_r @ x) / max(_rms(b_r), 1e-300))  # fmt: skip
    mass = None if value[0] is None else 1.0 / value[0]
    mass_std = None if std[0] is None else std[0] / value[0] ** 2
    audit = SpacecraftAudit(
        [r.run_id for r in runs], ticks, stated[0], stated[1], stated[2],
        mass, mass_std, tuple(value[1:4]), tuple(std[1:4]), tuple(value[4:]), tuple(std[4:]),
        residual,
    )  # fmt: skip
    audit.findings.extend(stepped + _findings(audit, lever, i_scale))
    return audit


def _findings(audit: SpacecraftAudit, lever: float, i_scale: float) -> list[AuditFinding6]:
    out = []
    if audit.relative_residual > LAW_RESIDUAL:
        out.append(
            AuditFinding6(
                "spacecraft_model_error",
                {"relative_residual": audit.relative_residual},
                {"relative_residual": None},
                f"its commands do not follow the format's rigid-body step (residual "
                f"{audit.relative_residual:.2g} of the signal, at most {LAW_RESIDUAL:g})",
            )
        )
        return out  # the values below assume the format's step
    if _finding(audit.stated_mass_kg, audit.mass_kg, audit.mass_std_kg, audit.stated_mass_kg):
        ratio = audit.mass_kg / audit.stated_mass_kg
        out.append(
            AuditFinding6(
                "mass_error",
                {"mass_ratio": ratio},
                {"mass_ratio": audit.mass_std_kg / audit.stated_mass_kg},
                f"mass_error: {audit.mass_kg:.6g} +- {audit.mass_std_kg:.2g} kg, the JSON's "
                f"{audit.stated_mass_kg:.6g} (ratio {ratio:.5g})",
            )
        )
    port = zip(
        audit.stated_port_position_m, audit.port_position_m, audit.port_position_std_m, strict=True
    )
    if any(_finding(s, v, e, lever) for s, v, e in port):
        values = {
            f"com_{a}_m": 0.0 if v is None else s - v
            for a, s, v in zip(
                _AXES, audit.stated_port_position_m, audit.port_position_m, strict=True
            )
        }
        std = {f"com_{a}_m": e for a, e in zip(_AXES, audit.port_position_std_m, strict=True)}
        said = ", ".join(
            f"{k} = {v:.4g}" + (f" +- {std[k]:.2g}" if std[k] is not None else " (undetermined)")
            for k, v in values.items()
        )
        out.append(
            AuditFinding6(
                "com_offset",
                values,
                std,
                f"com_offset: its centre of mass is off the scenario's by {said} m (body frame)",
            )
        )
    entries = zip(
        audit.stated_inertia_kg_m2, audit.inertia_kg_m2, audit.inertia_std_kg_m2, strict=True
    )
    if any(_finding(s, v, e, i_scale) for s, v, e in entries):
        values = {
            f"i{n}_kg_m2": v for n, v in zip(INERTIA_ENTRIES, audit.inertia_kg_m2, strict=True)
        }
        std = {
            f"i{n}_kg_m2": e for n, e in zip(INERTIA_ENTRIES, audit.inertia_std_kg_m2, strict=True)
        }
        said = ", ".join(
            f"{k} = {v:.5g}" if v is not None else f"{k} undetermined" for k, v in values.items()
        )
        out.append(
            AuditFinding6(
                "inertia_error",
                values,
                std,
                f"inertia_error: its inertia is {said} (the JSON's {audit.stated_inertia_kg_m2})",
            )
        )
    return out
