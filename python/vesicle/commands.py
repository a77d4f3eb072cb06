"""The command line's studies and shape diagram from Python: each runs in this process, writes
its folder (CSV files, charts, text) exactly as the ``vesicle`` program does, and returns its
tables as NumPy arrays.

The studies are the command line's own list (``STUDIES``, read from the library's registry),
and a study's tables come back from the library typed, from the rows its CSV files are written
from.
"""

from __future__ import annotations

import csv
import json
import os
import pathlib
from typing import Any

import numpy as np

from ._vesicle import cli as _cli
from ._vesicle import studies as _studies
from ._vesicle import study as _study

PathLike = str | os.PathLike[str]
Tables = dict[str, dict[str, np.ndarray]]

#: The studies of ``vesicle study NAME``, in the command line's order (from the library).
STUDIES: tuple[str, ...] = tuple(name for name, _ in _studies())


def studies() -> dict[str, str]:
    """The studies the command line runs: {name: its one-line description}, in its order."""
    return dict(_studies())


def cli(*args: str | os.PathLike[str]) -> int:
    """Run ``vesicle ARGS...`` in this process (e.g. ``cli("axisym", "--out", "out/axisym")``)
    and return its exit code: 0, or 128 + the signal that ended a run (Ctrl-C on a run stops
    it after its step, writing its outputs). Invalid arguments or input raise InvalidInput, a
    run that blows up BlowUp, file errors OSError. The engine runs with the GIL released;
    Ctrl-C during a study or the diagram raises KeyboardInterrupt only once it has finished.
    """
    return _cli([os.fspath(a) for a in args])


def read_tables(folder: PathLike) -> Tables:
    """Every ``*.csv`` of ``folder`` as {file stem: {column: array}}: a column of numbers as a
    float64 array (empty cells as NaN), any other as an array of str."""
    tables: Tables = {}
    for path in sorted(pathlib.Path(folder).glob("*.csv")):
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
        if not rows:
            continue
        header, body = rows[0], rows[1:]
        columns = {}
        for i, name in enumerate(header):
            cells = [r[i] if i < len(r) else "" for r in body]
            try:
                columns[name] = np.array([float(c) if c != "" else np.nan for c in cells])
            except ValueError:
                columns[name] = np.array(cells)
        tables[path.stem] = columns
    return tables


def study(kind: str, file: PathLike, out: PathLike, quick: bool = False, force: bool = False,
          overrides: Any = None) -> Tables:
    """Run ``vesicle study KIND FILE --out OUT`` in this process (the engine with the GIL
    released) and return its tables: {CSV file stem: {column: array}}, counts as int64,
    numbers as float64 (an empty cell NaN), names as str arrays.

    ``kind`` is one of ``STUDIES`` (see studies()): ``file`` is a study file (e.g.
    runs/studies/stability.json; ``quick`` runs its quick block), or for "stationary" also a
    scene file, with ``overrides`` (a dict or "key=value" strings, as ``--set``). ``force``
    replaces an existing ``out``. Raises InvalidInput (field "study") for an unknown kind, and
    as the command line for a bad file or argument.
    """
    return _study(kind, file, out, quick, force, overrides)


def diagram(file: PathLike, out: PathLike, case: int | None = None, jobs: int | None = None,
            force: bool = False) -> Any:
    """Run the phase-field shape diagram of the diagram file ``file`` into ``out``.

    Without ``case``: every case (``jobs`` at a time, one thread each), merged; returns the
    tables (diagram, cases, transitions, reference) as read_tables(out). With ``case=K``: that
    case only, into OUT/cases/<case>/, returning its result (result.json) as a dict; merge the
    finished cases with diagram_merge(). ``force`` redoes what exists.
    """
    args = ["diagram", file, "--out", out]
    if case is not None:
        args += ["--case", str(case)]
    if jobs is not None:
        args += ["--jobs", str(jobs)]
    if force:
        args.append("--force")
    cli(*args)
    if case is None:
        return read_tables(out)
    results = list(pathlib.Path(out, "cases").glob(f"*/result.json"))
    for path in results:
        result = json.loads(path.read_text())
        if result.get("index") == case:
            return result
    raise FileNotFoundError(f"case {case} wrote no result.json under {out}/cases")


def diagram_merge(file: PathLike, out: PathLike, force: bool = False) -> Tables:
    """Merge the finished cases of OUT/cases/ into the diagram's CSV files and charts, and
    return the tables."""
    args = ["diagram", file, "--out", out, "--merge"]
    if force:
        args.append("--force")
    cli(*args)
    return read_tables(out)


__all__ = ["STUDIES", "cli", "diagram", "diagram_merge", "read_tables", "studies", "study"]
