"""Every exception of hybridtable, in one dependency-free module (the ground floor).

========================  ====================================================
exception                 raised when
========================  ====================================================
``ParameterError``        a parameter is out of its physical range (names the
                          field); the CLI prints one line and exits with 2
``MeasurementError``      a recorded run is malformed (names file and line or
                          key); exit 2
``WorkspaceError``        a commanded pose leaves the Stewart platform's
                          workspace or a leg's stroke; exit 2
``SpecError``             a sweep spec is malformed (names the file and the
                          key); exit 2
``CommandError``          any other bad command-line input; exit 2
``PluginError``           a user's plug-in raised, exited or returned a
                          non-finite number (names the plug-in); exit 2. Not
                          a ValueError: no fit takes it for a failed model
``SimulationError``       a simulation diverged or its contact never ended;
                          exit 1
``WriteError``            an output could not be written (a full disk, a file
                          another process wrote meanwhile); nothing of it is
                          left; exit 1
``DivergenceError``       the SimulationError of a loop whose force grew without
                          bound (a sweep records the run as ``diverged``)
``LinearizationError``    Drake could not linearize a system
``InterconnectionError``  the wiring of linear blocks is inconsistent
========================  ====================================================
"""

from __future__ import annotations

__all__ = [
    "ParameterError",
    "MeasurementError",
    "WorkspaceError",
    "SpecError",
    "CommandError",
    "PluginError",
    "SimulationError",
    "WriteError",
    "DivergenceError",
    "LinearizationError",
    "InterconnectionError",
]


class ParameterError(ValueError):
    """A parameter given by the user is out of its physical range."""


class MeasurementError(ParameterError):
    """A recorded run is malformed; the message is one line naming the file
    and the line or key (the CLI prints it and exits with code 2)."""


class WorkspaceError(ParameterError):
    """A commanded pose leaves the platform's workspace or a leg's stroke."""


class SpecError(ParameterError):
    """A sweep spec (``hybridtable sweep SPEC.toml``) is malformed; the message
    is one line naming the file and the key."""


class CommandError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


class PluginError(CommandError):
    """A user's plug-in failed (:mod:`hybridtable._plugins`): one line naming
    it, exit code 2; never taken for a model that failed to fit."""


class WriteError(Exception):
    """An output could not be written (:mod:`hybridtable._files`): one line
    naming it, nothing of it left behind, exit code 1."""


class SimulationError(RuntimeError):
    """The simulation diverged or the contact never ended."""


class DivergenceError(SimulationError):
    """The loop's force grew without bound: the loop is unstable for these
    parameters."""


class LinearizationError(RuntimeError):
    """Drake could not linearize a system, or a block's parameter structure
    did not hold."""


class InterconnectionError(ValueError):
    """The wiring is inconsistent (unknown channel, unwired input, algebraic loop)."""
