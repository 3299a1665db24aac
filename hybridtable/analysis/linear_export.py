"""The linear loop as a file python-control loads: ``margins --export-linear``.

:func:`linear_model_document` describes one
:class:`~hybridtable.analysis.linearize.LinearLoop` (the open loop ``G``,
broken at the spacecraft model's force input, see
:mod:`hybridtable.analysis.robustness`): its matrices ``A, B, C, D``, its
sample period ``dt`` (0: continuous), the names and units of its states,
input and output, the operating point and every parameter it was built from.
:func:`save_linear_model` writes it as JSON (``.json``) or as a NumPy archive
(``.npz``: the matrices and name lists as arrays, the rest as one JSON string
``metadata``). Either loads with python-control alone::

    d = json.load(open("loop.json"))           # or d = np.load("loop.npz")
    G = control.ss(d["A"], d["B"], d["C"], d["D"], float(d["dt"]))
    poles = control.feedback(G, 1, sign=1).poles()   # the rig closes u = y

The state names come from the blocks the model is assembled from
(:meth:`~hybridtable.analysis.blockwise.ContactLoopLinearizer.blocks`, or
:meth:`~hybridtable.analysis.sampled.SampledLoopLinearizer.blocks` when sampled),
in the order of the model's states.
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np

from hybridtable._files import write_bytes_atomic, write_text_atomic
from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.interconnect import StateSpaceBlock
from hybridtable.analysis.linearize import LinearLoop
from hybridtable.analysis.robustness import BROKEN_AT
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.errors import ParameterError
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "LINEAR_FORMAT",
    "EXPORT_SUFFIXES",
    "state_labels",
    "linear_model_document",
    "save_linear_model",
    "load_linear_model",
]

#: The ``format`` key of an exported linear model.
LINEAR_FORMAT = "hybridtable-linear-loop/1"

#: The file types :func:`save_linear_model` writes.
EXPORT_SUFFIXES = (".json", ".npz")

_ARRAY_KEYS = ("A", "B", "C", "D")
_NAME_KEYS = (
    "state_names",
    "state_units",
    "state_blocks",
    "input_names",
    "input_units",
    "output_names",
    "output_units",
)


def _block_labels(block: StateSpaceBlock, sampled: bool) -> list[tuple[str, str]]:
    """``(name, unit)`` of each state of one block, in its state order."""
    n = block.num_states
    name = block.name
    if name == "spacecraft" and n == 2:
        return [("p_des", "m"), ("v_des", "m/s")]
    if name == "table" and n == 2:
        return [("p_act", "m"), ("v_act", "m/s")]
    if name == "plant" and n in (2, 4):  # sampled: table [p, v], then the held command
        held = [("p_des_held", "m"), ("v_des_held", "m/s")]
        return ([("p_act", "m"), ("v_act", "m/s")] if n == 4 else []) + held
    if name == "force_sensor" and sampled:  # a shift register: x[i] = f_act at tick k - M + i
        return [(f"f_act_k-{n - i}", "N") for i in range(n)]
    if name == "force_sensor" and n % 2 == 0:  # Pade realizations of f, then of df/dt
        half = n // 2
        return [
            (f"pade_f_{i + 1}", "internal (Pade realization of the delayed f)") for i in range(half)
        ] + [
            (f"pade_df_{i + 1}", "internal (Pade realization of the delayed df/dt)")
            for i in range(half)
        ]
    if name == "compensator" and sampled and n == 1:
        return [("f_mea_prev", "N")]
    return [(f"{name}_x{i + 1}", "internal") for i in range(n)]


def state_labels(
    params: HybridLoopParams,
    pade_order: int = 3,
    linearizer: ContactLoopLinearizer | None = None,
) -> list[tuple[str, str, str]]:
    """``(name, unit, block)`` of every state of the model at ``params``
    (sampled when ``params.sample_rate_hz`` is set), in the model's order;
    ``linearizer``: one to reuse (its Pade order then counts)."""
    lin = linearizer or ContactLoopLinearizer(pade_order)
    sampled = params.sample_rate_hz is not None
    blocks = SampledLoopLinearizer(lin).blocks(params) if sampled else lin.blocks(params)
    return [(n, u, b.name) for b in blocks for n, u in _block_labels(b, sampled)]


def _plain(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return x


def linear_model_document(
    loop: LinearLoop,
    compensator: str,
    operating_point: dict,
    labels: list[tuple[str, str, str]] | None = None,
    extra: dict | None = None,
) -> dict:
    """The exported model of ``loop`` (see the module doc).

    Parameters
    ----------
    loop : LinearLoop
        The open loop ``G``.
    compensator : str
    operating_point : dict
        E.g. ``{"sensor_delay_s": 0.005, "table_response_hz": 25.0}``.
    labels : list of (name, unit, block), optional
        The states' labels (default :func:`state_labels` of ``loop.params``).
    extra : dict, optional
        More keys (e.g. the model's margins at the point).
    """
    p = loop.params
    if labels is None:
        labels = state_labels(p, loop.pade_order or 3)
    if len(labels) != loop.A.shape[0]:
        raise ParameterError("the state labels do not match the model's states")
    poles = loop.closed_loop_poles()
    doc = {
        "format": LINEAR_FORMAT,
        "description": "the open loop G of the in-contact hybrid loop, broken " + BROKEN_AT,
        "closed_loop": "control.feedback(G, 1, sign=1) (u = y); margins of L = -G",
        "A": loop.A.tolist(),
        "B": loop.B.tolist(),
        "C": loop.C.tolist(),
        "D": loop.D.tolist(),
        "dt": float(loop.dt),
        "state_names": [n for n, _, _ in labels],
        "state_units": [u for _, u, _ in labels],
        "state_blocks": [b for _, _, b in labels],
        "input_names": ["force_on_spacecraft"],
        "input_units": ["N"],
        "output_names": ["compensated_force"],
        "output_units": ["N"],
        "compensator": compensator,
        "model": {
            "kind": "sampled" if loop.is_discrete else "continuous",
            "pade_order": loop.pade_order,
            "sample_rate_hz": p.sample_rate_hz,
        },
        "operating_point": {k: _plain(v) for k, v in operating_point.items()},
        "parameters": {k: _plain(v) for k, v in p.quantities().items()},
        "closed_loop_poles": [[float(z.real), float(z.imag)] for z in poles],
        "notes": list(loop.notes),
    }
    for k, v in (extra or {}).items():
        doc[k] = {a: _plain(b) for a, b in v.items()} if isinstance(v, dict) else _plain(v)
    return doc


def save_linear_model(path: str | Path, doc: dict) -> Path:
    """Write ``doc`` (:func:`linear_model_document`) as ``.json`` or ``.npz``
    (by the suffix), through a temporary file and a rename.

    Raises
    ------
    ParameterError
        For another suffix.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise ParameterError(f"{path}: the linear model is written as .json or .npz")
    if suffix == ".json":
        write_text_atomic(path, json.dumps(doc, indent=1) + "\n")
        return path
    arrays = {k: np.asarray(doc[k], dtype=float) for k in _ARRAY_KEYS}
    arrays["dt"] = np.asarray(doc["dt"], dtype=float)
    for k in _NAME_KEYS:
        arrays[k] = np.asarray(doc[k], dtype=str)
    rest = {k: v for k, v in doc.items() if k not in arrays}
    arrays["metadata"] = np.asarray(json.dumps(rest))
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    write_bytes_atomic(path, buf.getvalue())
    return path


def load_linear_model(path: str | Path) -> dict:
    """Read a file of :func:`save_linear_model` back as the document (the
    matrices as arrays)."""
    path = Path(path)
    if path.suffix.lower() == ".npz":
        with np.load(path) as z:
            doc = json.loads(str(z["metadata"]))
            for k in (*_ARRAY_KEYS, "dt"):
                doc[k] = np.asarray(z[k], dtype=float)
            for k in _NAME_KEYS:
                doc[k] = [str(s) for s in z[k]]
        doc["dt"] = float(doc["dt"])
        return doc
    doc = json.loads(path.read_text())
    for k in _ARRAY_KEYS:
        doc[k] = np.asarray(doc[k], dtype=float)
    return doc
