"""Kernel side of the grader (``tools/grader.py``): imported into the kernel that runs a submission.

The grader copies this file beside the student package in the kernel's scratch folder (the
kernel's import path holds the student package, this file and the pinned environment, nothing of
the repository) and runs, around the submission's cells:

* ``install(config)`` once per kernel, before any submission cell: installs a Python audit hook
  (:func:`sys.addaudithook`: it cannot be removed)
  and a profile function (:func:`sys.setprofile`, which the hook then forbids to change).
* ``begin(exercise_id, run, one_call)`` before an exercise's cells, ``end(exercise_id, run)``
  after them: ``end`` reports the notebook's ``answer``.

What the hooks report, as ``application/vnd.fdi-grader+json`` display outputs of the cell where it
happens (an IOPub message the submission cannot take back once sent), is a *violation*: the
grader scores the exercise 0 on that run and names the attempt in the log. Violations:

* a call, from the submission's code, of a library function that answers the exercise in one
  call (``one_call``). The profiler compares code objects, by identity and by bytecode, so the
  function's ``__wrapped__``, an alias, a copy made with ``types.FunctionType`` and a copy of its
  source are the same function (and a module of the library runs once: a reload or re-import
  is itself a violation); calls made by the library itself (building the exercise data, or
  inside another library function) are allowed;
* reading the grader's files, the repository (which holds the reference answers), another
  process's ``/proc`` entries (the grader's environment and arguments), writing outside the
  scratch folder, re-executing or recompiling the library's code, starting a process or a thread,
  changing the profile or trace function, ``ctypes``, and walking the garbage collector's objects
  (where the hooks' own state lives).

What they do not stop: a submission that works against these hooks from inside the kernel with
means not listed here. The grader also scans each submission's code (in its own process) for the
names these attacks need (:data:`grader.SUSPICIOUS`), and the expected answers are computed and
compared only in the grader's process: the kernel never holds a reference answer.
"""

from __future__ import annotations

import os
import sys

__all__ = ["GraderViolation", "install", "begin", "end"]

MIME = "application/vnd.fdi-grader+json"


class GraderViolation(PermissionError):
    """What the submission tried is not allowed while grading (the grader logs it)."""


_S: dict = {
    "run": None,
    "codes": {},
    "allowed_read": (),
    "denied_read": (),
    "scratch": "",
    "package": "",
    "installed": False,
}


def _report(kind: str, **fields) -> None:
    from IPython.display import display

    display({MIME: {"kind": kind, "run": _S["run"], **fields}}, raw=True)


def _violate(what: str) -> None:
    _report("violation", what=what)
    raise GraderViolation(f"not allowed while grading: {what}")


def _under(path: str, roots) -> bool:
    return any(path == r or path.startswith(r.rstrip(os.sep) + os.sep) for r in roots)


_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC
_BLOCKED_EVENTS = {
    "os.fork": "starting a process (os.fork)",
    "os.forkpty": "starting a process (os.forkpty)",
    "os.posix_spawn": "starting a process (os.posix_spawn)",
    "os.spawn": "starting a process",
    "os.exec": "replacing the kernel (os.exec)",
    "os.system": "running a shell command (os.system)",
    "subprocess.Popen": "starting a process (subprocess)",
    "os.kill": "sending a signal (os.kill)",
    "os.killpg": "sending a signal (os.killpg)",
    "_thread.start_new_thread": "starting a thread",
    "sys.setprofile": "changing the profile function",
    "sys.settrace": "changing the trace function",
    "ctypes.dlopen": "loading a library with ctypes",
    "ctypes.dlsym": "ctypes",
    "ctypes.cdata": "reading memory with ctypes",
    "ctypes.call_function": "ctypes",
    "gc.get_objects": "walking the garbage collector's objects",
    "gc.get_referrers": "walking the garbage collector's objects",
    "gc.get_referents": "walking the garbage collector's objects",
    "sys._current_frames": "reading other threads' frames",
}


def _audit(event: str, args: tuple) -> None:
    if not _S["installed"]:
        return
    if event in _BLOCKED_EVENTS:
        _violate(_BLOCKED_EVENTS[event])
    elif event == "open":
        path, mode, flags = args
        if isinstance(path, int) or path is None:
            return
        path = os.path.realpath(os.fsdecode(path))
        writing = bool(flags & _WRITE_FLAGS) or (
            mode is not None and any(c in str(mode) for c in "wax+")
        )
        if writing and not _under(path, (_S["scratch"], os.devnull)):
            _violate(f"writing {path} (outside the kernel's scratch folder)")
        own = ("/proc/self/", f"/proc/{os.getpid()}/")
        if path.startswith("/proc/") and not path.startswith(own):
            _violate(f"reading {path} (another process)")
        if _under(path, _S["denied_read"]) and not _under(path, _S["allowed_read"]):
            _violate(f"reading {path} (the grader's or the repository's files)")
    elif event == "exec":  # (compiling is allowed: tracebacks parse the library's source)
        filename = getattr(args[0], "co_filename", None)
        if filename and _under(os.path.realpath(filename), (_S["package"],)):
            if os.path.realpath(filename) in _S["executed"]:  # a module runs once: its import
                _violate(f"re-executing the library's code ({filename})")
            _S["executed"].add(os.path.realpath(filename))


def _profile(frame, event, arg):
    if event != "call":
        return
    code = frame.f_code
    name = _S["codes"].get(code) or _S["codes"].get((code.co_name, code.co_code))
    if name is None or _S["run"] is None:
        return
    caller = frame.f_back
    if caller is not None and _under(os.path.realpath(caller.f_code.co_filename), (_S["package"],)):
        return  # the library calls it (exercise data, another library function)
    _report("violation", what=f"calling {name}, which answers this exercise in one call")


def install(config: dict) -> None:
    """Install the hooks (once per kernel, before any submission cell).

    Matplotlib is imported first: on its first import in a fresh ``MPLCONFIGDIR`` its font
    manager runs ``fc-list`` in a process, which the hooks would report against the first
    exercise whose library code draws (pipe-3 lost its point so), and swallow (matplotlib
    catches the error and goes on without the system's fonts). The grader hands every kernel a
    font cache built once (:func:`grader.font_cache`); this import then starts nothing, and
    without the cache it builds it here, before the hooks.
    """
    import matplotlib.font_manager  # noqa: F401 -- see above: before the hooks
    import fdi_lib
    import IPython.display  # noqa: F401 -- the reports need it, imported before the hooks

    package = os.path.realpath(os.path.dirname(fdi_lib.__file__))
    loaded = {
        os.path.realpath(m.__file__)
        for m in list(sys.modules.values())
        if getattr(m, "__file__", None) and _under(os.path.realpath(m.__file__), (package,))
    }
    _S.update(
        scratch=os.path.realpath(config["scratch"]),
        package=package,
        executed=loaded,
        denied_read=tuple(os.path.realpath(p) for p in config["denied_read"]),
        allowed_read=(os.path.realpath(sys.prefix), package, os.path.realpath(config["scratch"])),
    )
    sys.addaudithook(_audit)
    sys.setprofile(_profile)
    _S["installed"] = True


def begin(exercise_id: str, run: str, student: str, one_call: list[str]) -> None:
    """Start a graded run: the data are ``student``'s (``FDI_STUDENT_ID``), no ``answer`` yet,
    and the exercise's one-call functions are watched."""
    import importlib

    os.environ["FDI_STUDENT_ID"] = student

    codes = {}
    for dotted in one_call:
        module_name, attr = dotted.rsplit(".", 1)
        code = getattr(importlib.import_module(module_name), attr).__code__
        codes[code] = codes[code.co_name, code.co_code] = dotted
    from IPython import get_ipython

    get_ipython().user_ns.pop("answer", None)
    _S.update(run=f"{exercise_id}/{run}", codes=codes)


def end(exercise_id: str, run: str) -> None:
    """Report the notebook's ``answer`` (JSON numbers, or why it cannot be read)."""
    import numpy as np
    from IPython import get_ipython

    answer = get_ipython().user_ns.get("answer", None)
    fields = {"exercise": exercise_id}
    try:
        fields["answer"] = None if answer is None else np.asarray(answer, dtype=float).tolist()
    except (TypeError, ValueError) as exc:
        fields["answer"], fields["unreadable"] = None, f"{type(answer).__name__}: {exc}"
    _report("answer", **fields)
    _S.update(run=None, codes={})
