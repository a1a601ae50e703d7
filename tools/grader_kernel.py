"""Kernel side of the grader (``tools/grader.py``): imported into the kernel that runs a submission.

Between the submission's cells the grader runs ``begin(...)`` and ``end(...)``:

* ``begin(exercise_id, student, one_call, record)`` points the exercise data at ``student``
  (``FDI_STUDENT_ID``), removes any previous ``answer``, makes every library function in
  ``one_call`` raise :class:`GraderBlocked` when the student's code calls it (in every loaded
  module of ``fdi_lib`` and in the notebook's namespace; the library's own calls made while
  building the exercise data still work), and replaces ``check`` by a stub that gives no
  feedback (a graded run must not be a bisection oracle).
* ``end(exercise_id, run)`` writes the notebook's ``answer`` (or why there is none) as one JSON
  line to ``record`` and undoes the blocks.
"""

from __future__ import annotations

import functools
import importlib
import json
import os
import sys

import numpy as np

__all__ = ["GraderBlocked", "begin", "end"]


class GraderBlocked(RuntimeError):
    """A library function that answers the exercise in one call was called by the submission."""


_state: dict = {"patched": [], "inside_data": 0, "record": None}


def _ns() -> dict:
    from IPython import get_ipython

    return get_ipython().user_ns


def _stub(name: str, original):
    @functools.wraps(original)
    def blocked(*args, **kwargs):
        if _state["inside_data"]:
            return original(*args, **kwargs)
        raise GraderBlocked(f"{name} answers this exercise in one call: it is unavailable while grading")
    return blocked


def _replace(original, replacement) -> None:
    """Replace ``original`` by ``replacement`` wherever a loaded module of fdi_lib or the notebook
    holds it by name."""
    holders = [m.__dict__ for name, m in list(sys.modules.items())
               if m is not None and (name == "fdi_lib" or name.startswith("fdi_lib."))] + [_ns()]
    for space in holders:
        for key, value in list(space.items()):
            if value is original:
                space[key] = replacement
                _state["patched"].append((space, key, original))


def _no_feedback(exercise_id, answer=None, **kwargs):
    from fdi_lib.exercises import CheckResult

    return CheckResult(str(exercise_id), False, f"{exercise_id}: submitted (graded by the instructor).")


def begin(exercise_id: str, student: str, one_call: list[str], record: str) -> None:
    import fdi_lib.exercises as E

    os.environ["FDI_STUDENT_ID"] = student
    _state["record"] = record
    _ns().pop("answer", None)
    for dotted in one_call:
        module_name, attr = dotted.rsplit(".", 1)
        original = getattr(importlib.import_module(module_name), attr)
        _replace(original, _stub(dotted, original))
    _replace(E.check, _no_feedback)
    data = E.exercise_data

    @functools.wraps(data)
    def exercise_data(*args, **kwargs):
        _state["inside_data"] += 1
        try:
            return data(*args, **kwargs)
        finally:
            _state["inside_data"] -= 1

    _replace(data, exercise_data)


def end(exercise_id: str, run: str) -> None:
    answer = _ns().get("answer", None)
    line = {"exercise": exercise_id, "run": run}
    try:
        line["answer"] = None if answer is None else np.asarray(answer, dtype=float).tolist()
    except (TypeError, ValueError) as exc:
        line["answer"], line["unreadable"] = None, f"{type(answer).__name__}: {exc}"
    for space, key, original in reversed(_state["patched"]):
        space[key] = original
    _state["patched"].clear()
    with open(_state["record"], "a") as f:
        f.write(json.dumps(line) + "\n")
