"""vesicle: shapes of lipid vesicles with the phase-field model of Campelo & Hernández-Machado,
driven from Python.

The engine is the Rust library behind the ``vesicle`` command line; this package runs it in
process and hands every field and time series back as NumPy arrays::

    import vesicle
    scene = vesicle.Scene("runs/prolate3d.json", overrides={"max_steps": 200})
    sim = vesicle.Simulation(scene)
    why = sim.run()                      # the scene's stop rules, as `vesicle run`
    print(why, sim.t, sim.reduced_energy, sim.residual)
    phi = sim.phi                        # full box, read-only float64 array
    e = sim.history["reduced_energy"]    # the time series, one array per column

Names:

* :class:`Scene` -- a scene from a dict or a scene file, with overrides, validated as the
  command line validates it;
* :class:`Simulation` -- run / step / checkpoint / resume, state, ``phi`` (read and set),
  ``history``, the scene's output schedules (``run(out=...)``, ``take_snapshots()``),
  ``surface()``, writers (``.npy``, ``.vti``, ``.ply``, PNG, charts);
* :class:`StepView` -- what a callback is given: the step's record (a mapping) and its ``phi``;
* :mod:`vesicle.axisym` -- the axisymmetric sharp-interface reference (any c̄0);
* :func:`study` -- the command line's studies (``STUDIES``), their tables typed;
* :exc:`InvalidInput` (a ``ValueError`` with ``field``), :exc:`BlowUp` (``step``, ``t``,
  ``dt``, ``check``, ``cause``), :exc:`DeviceError` (a GPU that failed during a run: ``step``,
  ``t``); file errors are ``OSError``.
"""

from collections.abc import Mapping as _Mapping

from ._vesicle import BlowUp, DeviceError, InvalidInput, Scene, Simulation, StepView, __version__
from . import axisym, commands
from .commands import STUDIES, cli, diagram, diagram_merge, read_tables, studies, study

_Mapping.register(StepView)

__all__ = [
    "Scene",
    "Simulation",
    "StepView",
    "InvalidInput",
    "BlowUp",
    "DeviceError",
    "axisym",
    "commands",
    "cli",
    "STUDIES",
    "studies",
    "study",
    "diagram",
    "diagram_merge",
    "read_tables",
    "__version__",
]
