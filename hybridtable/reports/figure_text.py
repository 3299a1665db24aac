"""Text a user gave (run ids, effect and compensator names) shown literally in a figure.

Matplotlib reads the text between two ``$`` as mathematics (mathtext): a run
id such as ``run$1$`` or ``cost $5 and $6`` would be typeset, or crash the
figure with a parser error. :func:`literal` escapes it.
"""

from __future__ import annotations

__all__ = ["literal"]


def literal(text: object) -> str:
    """``text`` as a string matplotlib draws as written (``$`` escaped)."""
    return str(text).replace("$", r"\$")
