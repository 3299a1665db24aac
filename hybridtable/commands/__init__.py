"""Sub-commands of the ``hybridtable`` CLI, one module each (see :mod:`hybridtable.cli`).

A command module has ``register(subparsers)`` and ``run(args) -> exit code``; it
imports its heavy dependencies inside ``run`` so that ``--help`` starts fast.
:mod:`~hybridtable.commands._common` holds what every command uses.
"""

__all__: list[str] = []
