"""The words of a verdict about one contact: CoR, energy and what they mean.

A rig engineer reads a coefficient of restitution as "the spacecraft leaves
faster (or slower) than it came in", and the energy the loop created as a
percentage of the approach's kinetic energy: ``CoR^2 - 1``.
"""

from __future__ import annotations

__all__ = [
    "CONSERVED_COR_TOLERANCE",
    "compensator_label",
    "cor_phrase",
    "energy_change_percent",
    "contact_verdict",
]

#: |CoR - 1| below which a contact of an undamped spring "keeps its energy"
#: in a verdict (0.5 %, the spread of the paper's compensated CoRs).
CONSERVED_COR_TOLERANCE = 0.005


def energy_change_percent(cor: float) -> float:
    """The kinetic energy after the contact relative to before, in percent:
    ``100 (CoR^2 - 1)``."""
    return 100.0 * (cor * cor - 1.0)


def cor_phrase(cor: float) -> str:
    """``"CoR 1.161, energy +35%"``: the CoR and the energy change."""
    e = energy_change_percent(cor)
    energy = f"{e:+.0f}%" if abs(e) >= 10 else f"{e:+.1f}%"
    return f"CoR {cor:.3f}, energy {energy}"


def compensator_label(name: str) -> str:
    """``"no compensation"`` for ``none``, else the compensator's name."""
    return "no compensation" if name == "none" else name


def contact_verdict(compensator: str, cor: float, damped: bool = False) -> str:
    """One sentence on one simulated contact, e.g. ``"With no compensation the
    loop adds energy: the spacecraft leaves 16.1% faster than it came in (CoR
    1.161, energy +35%)."``

    Parameters
    ----------
    compensator
        The compensator's name (``none`` reads "no compensation").
    cor
        The contact's coefficient of restitution [1].
    damped
        Whether the contact itself dissipates energy (then a CoR below 1 is
        the contact's, not the loop's).
    """
    label = compensator_label(compensator)
    change = abs(cor - 1.0) * 100.0
    if abs(cor - 1.0) <= CONSERVED_COR_TOLERANCE:
        what = "the contact keeps its energy"
        if damped:
            what = "the loop puts back about what the damped contact dissipates"
        return f"With {label} {what} ({cor_phrase(cor)})."
    if cor > 1.0:
        return (
            f"With {label} the loop adds energy: the spacecraft leaves {change:.1f}% faster "
            f"than it came in ({cor_phrase(cor)})."
        )
    cause = "the contact's damping and the loop take" if damped else "the loop takes"
    return (
        f"With {label} {cause} energy out: the spacecraft leaves {change:.1f}% slower "
        f"than it came in ({cor_phrase(cor)})."
    )
