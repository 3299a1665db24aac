"""Sub-commands of the ``hybridtable`` CLI, one module each (see :mod:`hybridtable.cli`)."""
