"""One run of a compensator sweep as ``--json`` writes it (both sweeps: the
paper's grid and a model's rig)."""

from __future__ import annotations

from typing import Any

__all__ = ["run_json"]


def run_json(run: dict[str, Any]) -> dict[str, Any]:
    """``run`` for ``--json``: ``error`` is "" when the run did not fail; a
    failed run's NaN figures are noted with its error."""
    out = {**run, "error": run.get("error") or ""}
    if out["error"]:
        out["note"] = f"the run failed, so it has no figures: {out['error']}"
    return out
