"""Bad inputs across the public wind-turbine API (issue 36.2): each gets a typed error naming it.

Every case below is a hostile or mistaken call of :mod:`fdi_lib.systems.wind_turbine`,
:mod:`fdi_lib.windturbine` or the CLI of the two wind-turbine reproductions. Each must raise an
:class:`fdi_lib.errors.FDIError` whose message names the argument (``expect``); a generic error
(``TypeError`` from numpy, scipy's root finder, ...) or a silent acceptance fails. No case runs a
simulation longer than a few samples, so the module takes about a second.

``python tests/systems/test_wind_turbine_bad_inputs.py`` runs the same cases as a probe, each in a
forked child with a time limit and a memory rlimit, and prints a table by category and by function
(typed / documented acceptance / generic / accepted / hang-or-memory).
"""

from __future__ import annotations

import dataclasses
import io
import sys
from collections.abc import Callable
from contextlib import redirect_stderr, redirect_stdout
from typing import Any, NamedTuple

import numpy as np
import pytest

from fdi_lib import windturbine as W
from fdi_lib.errors import FDIError
from fdi_lib.systems import wind_turbine as wt

NAN, INF = float("nan"), float("inf")
F1 = wt.FAULTS[0]


def _cli(*argv: str) -> None:
    """The CLI as a user runs it: a usage error (exit 2) is re-raised as the typed error it reports."""
    from fdi_lib.reproduce.cli import main

    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        try:
            code = main(list(argv))
        except SystemExit as exc:
            code = exc.code
    if code == 0:
        return
    text = err.getvalue().strip()
    if code == 2 and text and "Traceback" not in text and len(text.splitlines()) <= 3:
        raise FDIError(text)
    raise RuntimeError(f"exit {code}: {text[-300:]}")


def _board(*argv: str) -> None:
    _cli("reproduce", "windturbine-scoreboard", "--json", *argv)


def _acc(*argv: str) -> None:
    _cli("reproduce", "windturbine-accommodation", "--json", *argv)


def _fault(**kw: Any) -> wt.Fault:
    return dataclasses.replace(F1, **kw)


def _params(**kw: Any) -> wt.WindTurbineParams:
    return dataclasses.replace(wt.PARAMS, **kw)


def _sim(**kw: Any) -> Any:
    kw.setdefault("seed", 0)
    kw.setdefault("faults", ())
    kw.setdefault("duration_s", 0.05)
    return wt.simulate(**kw)


def _ws(t: Any = None, **kw: Any) -> Any:
    kw.setdefault("seed", 0)
    return wt.wind_speed(np.arange(0.0, 1.0, 0.01) if t is None else t, **kw)


def _step(**kw: Any) -> Any:
    kw.setdefault("beta_r", 0.0)
    kw.setdefault("tau_g_r", 1e4)
    kw.setdefault("v", 8.0)
    x = kw.pop("x", wt.operating_point(8.0).state)
    return wt.plant_step(x, **kw)


_X_NAN = np.zeros(10)
_X_NAN[3] = NAN
_T_NAN = np.arange(0.0, 1.0, 0.01)
_T_NAN[7] = NAN
_WIND_INF = np.full(5, 8.0)
_WIND_INF[2] = INF


class Case(NamedTuple):
    function: str
    category: str
    expect: str  # the argument the error must name
    call: Callable[[], Any]


CASES: dict[str, Case] = {
    # simulate
    "simulate-seed-negative": Case("simulate", "out-of-range", "seed", lambda: _sim(seed=-1)),
    "simulate-seed-str": Case("simulate", "type", "seed", lambda: _sim(seed="a")),
    "simulate-seed-empty": Case("simulate", "empty", "seed", lambda: _sim(seed=[])),
    "simulate-duration-zero": Case("simulate", "size", "duration_s", lambda: _sim(duration_s=0)),
    "simulate-duration-negative": Case(
        "simulate", "size", "duration_s", lambda: _sim(duration_s=-1)
    ),
    "simulate-duration-nan": Case(
        "simulate", "nan-inf", "duration_s", lambda: _sim(duration_s=NAN)
    ),
    "simulate-duration-inf": Case(
        "simulate", "nan-inf", "duration_s", lambda: _sim(duration_s=INF)
    ),
    "simulate-duration-str": Case("simulate", "type", "duration_s", lambda: _sim(duration_s="10")),
    "simulate-duration-huge": Case("simulate", "size", "duration_s", lambda: _sim(duration_s=1e12)),
    "simulate-duration-tiny": Case("simulate", "size", "duration_s", lambda: _sim(duration_s=1e-9)),
    "simulate-n-zero": Case("simulate", "size", "n_realisations", lambda: _sim(n_realisations=0)),
    "simulate-n-huge": Case(
        "simulate", "size", "n_realisations", lambda: _sim(n_realisations=10**6, duration_s=1.0)
    ),
    "simulate-n-float": Case(
        "simulate", "type", "n_realisations", lambda: _sim(n_realisations=2.5)
    ),
    "simulate-faults-int": Case("simulate", "type", "faults", lambda: _sim(faults=[1])),
    "simulate-faults-dup": Case("simulate", "duplicate", "faults", lambda: _sim(faults=(F1, F1))),
    "simulate-wind-nan": Case("simulate", "nan-inf", "wind", lambda: _sim(wind=NAN)),
    "simulate-wind-inf-index": Case("simulate", "nan-inf", "wind", lambda: _sim(wind=_WIND_INF)),
    "simulate-wind-tiny": Case("simulate", "out-of-range", "wind", lambda: _sim(wind=1e-6)),
    "simulate-wind-huge": Case("simulate", "out-of-range", "wind", lambda: _sim(wind=1e4)),
    "simulate-wind-shape": Case("simulate", "shape", "wind", lambda: _sim(wind=np.full(3, 8.0))),
    "simulate-dtype": Case("simulate", "unknown-name", "dtype", lambda: _sim(dtype="int32")),
    "simulate-schedule": Case(
        "simulate", "unknown-name", "schedule", lambda: _sim(schedule="gale")
    ),
    "simulate-params": Case("simulate", "type", "params", lambda: _sim(params="x")),
    "simulate-accommodation": Case(
        "simulate",
        "unknown-name",
        "accommodation",
        lambda: _sim(faults=(F1,), accommodation={99: 1.0}),
    ),
    # Fault
    "Fault-kind": Case("Fault", "unknown-name", "kind", lambda: _fault(kind="melted")),
    "Fault-component": Case(
        "Fault", "unknown-name", "component", lambda: _fault(component=("nacelle",))
    ),
    "Fault-component-empty": Case("Fault", "empty", "component", lambda: _fault(component=())),
    "Fault-start-after-stop": Case(
        "Fault", "out-of-range", "start_s", lambda: _fault(start_s=10.0, stop_s=5.0)
    ),
    "Fault-start-nan": Case("Fault", "nan-inf", "start_s", lambda: _fault(start_s=NAN)),
    "Fault-stop-inf": Case("Fault", "nan-inf", "stop_s", lambda: _fault(stop_s=INF)),
    "Fault-start-negative": Case("Fault", "out-of-range", "start_s", lambda: _fault(start_s=-5.0)),
    "Fault-magnitude-len": Case(
        "Fault", "shape", "magnitude", lambda: _fault(magnitude=(1.0, 2.0, 3.0))
    ),
    "Fault-magnitude-nan": Case("Fault", "nan-inf", "magnitude", lambda: _fault(magnitude=(NAN,))),
    "Fault-magnitude-str": Case("Fault", "type", "magnitude", lambda: _fault(magnitude=("a",))),
    "Fault-ramp-negative": Case("Fault", "out-of-range", "ramp_s", lambda: _fault(ramp_s=-1.0)),
    "Fault-id-str": Case("Fault", "type", "id", lambda: _fault(id="one")),
    "Fault-required-negative": Case(
        "Fault", "out-of-range", "required_detection_s", lambda: _fault(required_detection_s=-1.0)
    ),
    # wind_speed
    "wind_speed-t-short": Case("wind_speed", "size", "t", lambda: _ws(np.array([0.0]))),
    "wind_speed-t-uneven": Case(
        "wind_speed", "out-of-range", "t", lambda: _ws(np.array([0.0, 1.0, 3.0]))
    ),
    "wind_speed-t-nan-index": Case("wind_speed", "nan-inf", "t", lambda: _ws(_T_NAN)),
    "wind_speed-t-2d": Case("wind_speed", "shape", "t", lambda: _ws(np.zeros((3, 3)))),
    "wind_speed-t-constant": Case(
        "wind_speed", "out-of-range", "t", lambda: _ws(np.array([1.0, 1.0, 1.0]))
    ),
    "wind_speed-seed-negative": Case("wind_speed", "out-of-range", "seed", lambda: _ws(seed=-1)),
    "wind_speed-ti-negative": Case(
        "wind_speed", "out-of-range", "turbulence_intensity", lambda: _ws(turbulence_intensity=-0.1)
    ),
    "wind_speed-ti-nan": Case(
        "wind_speed", "nan-inf", "turbulence_intensity", lambda: _ws(turbulence_intensity=NAN)
    ),
    "wind_speed-model": Case("wind_speed", "unknown-name", "model", lambda: _ws(model="vonkarman")),
    "wind_speed-length-zero": Case(
        "wind_speed", "out-of-range", "length_scale_m", lambda: _ws(length_scale_m=0.0)
    ),
    "wind_speed-schedule": Case(
        "wind_speed", "unknown-name", "schedule", lambda: _ws(schedule="gale")
    ),
    # operating_point, linearise
    "operating_point-nan": Case("operating_point", "nan-inf", "v", lambda: wt.operating_point(NAN)),
    "operating_point-tiny": Case(
        "operating_point", "out-of-range", "v", lambda: wt.operating_point(1e-6)
    ),
    "operating_point-huge": Case(
        "operating_point", "out-of-range", "v", lambda: wt.operating_point(1e4)
    ),
    "operating_point-str": Case(
        "operating_point", "type", "v", lambda: wt.operating_point("eight")
    ),
    "operating_point-region": Case(
        "operating_point", "out-of-range", "region", lambda: wt.operating_point(8.0, region=3)
    ),
    "operating_point-params": Case(
        "operating_point", "type", "params", lambda: wt.operating_point(8.0, params="x")
    ),
    "linearise-negative": Case("linearise", "out-of-range", "v", lambda: wt.linearise(-1.0)),
    "linearise-region": Case(
        "linearise", "type", "region", lambda: wt.linearise(8.0, region="two")
    ),
    "linearise-params": Case("linearise", "type", "params", lambda: wt.linearise(8.0, params=None)),
    # lpv_schedule
    "lpv_schedule-reversed": Case(
        "lpv_schedule", "out-of-range", "v_min", lambda: wt.lpv_schedule(9.0, 8.0)
    ),
    "lpv_schedule-grid-one": Case(
        "lpv_schedule", "size", "n_grid", lambda: wt.lpv_schedule(n_grid=1)
    ),
    "lpv_schedule-grid-huge": Case(
        "lpv_schedule", "size", "n_grid", lambda: wt.lpv_schedule(n_grid=10**9)
    ),
    "lpv_schedule-out-of-table": Case(
        "lpv_schedule", "out-of-range", "v_min", lambda: wt.lpv_schedule(1e-6, 1e-5, n_grid=3)
    ),
    "lpv_schedule-nan": Case("lpv_schedule", "nan-inf", "v_max", lambda: wt.lpv_schedule(5.0, NAN)),
    # plant_step
    "plant_step-x-shape": Case("plant_step", "shape", "x", lambda: _step(x=np.zeros(9))),
    "plant_step-x-nan-index": Case("plant_step", "nan-inf", "x", lambda: _step(x=_X_NAN)),
    "plant_step-v-huge": Case("plant_step", "out-of-range", "v", lambda: _step(v=1e4)),
    "plant_step-beta-nan": Case("plant_step", "nan-inf", "beta_r", lambda: _step(beta_r=NAN)),
    "plant_step-tau-inf": Case("plant_step", "nan-inf", "tau_g_r", lambda: _step(tau_g_r=INF)),
    "plant_step-eta-zero": Case("plant_step", "out-of-range", "eta_dt", lambda: _step(eta_dt=0.0)),
    "plant_step-offset-nan": Case("plant_step", "nan-inf", "offset", lambda: _step(offset=NAN)),
    "plant_step-params": Case("plant_step", "type", "params", lambda: _step(params="x")),
    # fault_profiles
    "fault_profiles-n-zero": Case(
        "fault_profiles", "size", "n_steps", lambda: wt.fault_profiles([F1], 0)
    ),
    "fault_profiles-n-huge": Case(
        "fault_profiles", "size", "n_steps", lambda: wt.fault_profiles([F1], 10**12)
    ),
    "fault_profiles-faults-int": Case(
        "fault_profiles", "type", "faults", lambda: wt.fault_profiles([1], 10)
    ),
    "fault_profiles-ts-zero": Case(
        "fault_profiles", "out-of-range", "ts", lambda: wt.fault_profiles([F1], 10, ts=0.0)
    ),
    # aerodynamic coefficients
    "torque_coefficient-nan-index": Case(
        "torque_coefficient", "nan-inf", "lam", lambda: wt.torque_coefficient([5.0, NAN], 0.0)
    ),
    "torque_coefficient-shapes": Case(
        "torque_coefficient", "shape", "lam", lambda: wt.torque_coefficient(np.ones(3), np.ones(2))
    ),
    "torque_coefficient-str": Case(
        "torque_coefficient", "type", "lam", lambda: wt.torque_coefficient("a", 0.0)
    ),
    "aero_torque-v-negative": Case(
        "aero_torque", "out-of-range", "v", lambda: wt.aero_torque(-1.0, 2.0, np.zeros(3))
    ),
    "aero_torque-beta-shape": Case(
        "aero_torque", "shape", "beta_deg", lambda: wt.aero_torque(8.0, 2.0, np.zeros(2))
    ),
    "aero_torque-omega-nan": Case(
        "aero_torque", "nan-inf", "omega_r", lambda: wt.aero_torque(8.0, NAN, np.zeros(3))
    ),
    # discretisations
    "pitch_discretisation-omega-zero": Case(
        "pitch_discretisation", "out-of-range", "omega_n", lambda: wt.pitch_discretisation(0.0, 0.6)
    ),
    "pitch_discretisation-zeta-nan": Case(
        "pitch_discretisation", "nan-inf", "zeta", lambda: wt.pitch_discretisation(11.1, NAN)
    ),
    "pitch_discretisation-ts-negative": Case(
        "pitch_discretisation",
        "out-of-range",
        "ts",
        lambda: wt.pitch_discretisation(11.1, 0.6, ts=-1),
    ),
    "drive_train_discretisation-eta": Case(
        "drive_train_discretisation",
        "out-of-range",
        "eta_dt",
        lambda: wt.drive_train_discretisation(eta_dt=-1.0),
    ),
    "drive_train_discretisation-params": Case(
        "drive_train_discretisation", "type", "params", lambda: wt.drive_train_discretisation("x")
    ),
    # parameters
    "benchmark_params-noise": Case(
        "benchmark_params",
        "unknown-name",
        "noise_reading",
        lambda: wt.benchmark_params(noise_reading="loud"),
    ),
    "WindTurbineParams-beta": Case(
        "WindTurbineParams",
        "out-of-range",
        "beta_min",
        lambda: _params(beta_min=10.0, beta_max=0.0),
    ),
    "WindTurbineParams-ts-zero": Case(
        "WindTurbineParams", "out-of-range", "ts", lambda: _params(ts=0.0)
    ),
    "WindTurbineParams-J-nan": Case(
        "WindTurbineParams", "nan-inf", "J_r", lambda: _params(J_r=NAN)
    ),
    "WindTurbineParams-J-negative": Case(
        "WindTurbineParams", "out-of-range", "J_r", lambda: _params(J_r=-1.0)
    ),
    "WindTurbineParams-actuator": Case(
        "WindTurbineParams",
        "unknown-name",
        "actuator_faults",
        lambda: _params(actuator_faults="bent"),
    ),
    # fault_regions
    "fault_regions-run": Case("fault_regions", "type", "run", lambda: wt.fault_regions("run")),
    "fault_regions-before-negative": Case(
        "fault_regions",
        "out-of-range",
        "before_s",
        lambda: wt.fault_regions(_sim(faults=(_fault(start_s=0.0, stop_s=0.04),)), before_s=-1.0),
    ),
    # fdi_lib.windturbine
    "Settings-pre-zero": Case("Settings", "size", "pre_s", lambda: W.Settings(pre_s=0.0)),
    "Settings-window-zero": Case("Settings", "size", "window", lambda: W.Settings(window=0)),
    "Settings-window-float": Case("Settings", "type", "window", lambda: W.Settings(window=2.5)),
    "Settings-window-huge": Case("Settings", "size", "window", lambda: W.Settings(window=10**9)),
    "Settings-alpha-one": Case(
        "Settings", "out-of-range", "isolation_alpha", lambda: W.Settings(isolation_alpha=1.0)
    ),
    "Settings-warmup": Case(
        "Settings", "out-of-range", "warmup_s", lambda: W.Settings(warmup_s=8.0)
    ),
    "Settings-post-inf": Case("Settings", "nan-inf", "post_s", lambda: W.Settings(post_s=INF)),
    "Settings-rate-nan": Case(
        "Settings",
        "nan-inf",
        "false_alarms_per_hour",
        lambda: W.Settings(false_alarms_per_hour=NAN),
    ),
    "records-run": Case("records", "type", "run", lambda: W.records("run")),
    "calibrate-c": Case("calibrate", "type", "c", lambda: W.calibrate("c", None)),
    "calibrate-margin": Case(
        "calibrate",
        "out-of-range",
        "margin",
        lambda: W.calibrate(W.plant_constants(), None, margin=-1.0),
    ),
    "design-c": Case("design", "type", "c", lambda: W.design("c", None, np.zeros(10))),
    "design-settings": Case(
        "design", "type", "settings", lambda: W.design(W.plant_constants(), None, np.zeros(10), "x")
    ),
    "run_methods-d": Case(
        "run_methods",
        "type",
        "d",
        lambda: W.run_methods("d", np.zeros((1, 5, 11)), np.zeros((1, 5, 4))),
    ),
    "stream_alarms-d": Case(
        "stream_alarms",
        "type",
        "d",
        lambda: W.stream_alarms("d", np.zeros((1, 5, 11)), np.zeros((1, 5, 4)), 0),
    ),
    "stream_counts-d": Case(
        "stream_counts",
        "type",
        "d",
        lambda: W.stream_counts("d", np.zeros((5, 11)), np.zeros((5, 4)), 0),
    ),
    "expected_candidates-fault": Case(
        "expected_candidates", "type", "fault", lambda: W.expected_candidates("F1")
    ),
    "fault_records-fault": Case(
        "fault_records", "type", "fault", lambda: W.fault_records("F1", [np.random.SeedSequence(0)])
    ),
    "fault_records-seeds-empty": Case(
        "fault_records", "empty", "seeds", lambda: W.fault_records(F1, [])
    ),
    "fault_records-seeds-int": Case(
        "fault_records", "type", "seeds", lambda: W.fault_records(F1, [3])
    ),
    "fault_records-settle-negative": Case(
        "fault_records",
        "out-of-range",
        "settle_s",
        lambda: W.fault_records(F1, [np.random.SeedSequence(0)], settle_s=-1.0),
    ),
    "fault_records-settings": Case(
        "fault_records",
        "type",
        "settings",
        lambda: W.fault_records(F1, [np.random.SeedSequence(0)], settings="x"),
    ),
    # the CLI of the two reproductions
    "scoreboard-trials-zero": Case(
        "windturbine-scoreboard",
        "size",
        "trials",
        lambda: _board("--trials", "0"),
    ),
    "scoreboard-trials-negative": Case(
        "windturbine-scoreboard",
        "size",
        "trials",
        lambda: _board("--trials", "-3"),
    ),
    "scoreboard-trials-huge": Case(
        "windturbine-scoreboard",
        "size",
        "trials",
        lambda: _board("--trials", str(10**12)),
    ),
    "scoreboard-trials-str": Case(
        "windturbine-scoreboard",
        "type",
        "trials",
        lambda: _board("--trials", "ten"),
    ),
    "scoreboard-option-unknown": Case(
        "windturbine-scoreboard",
        "unknown-name",
        "option",
        lambda: _board(
            "--trials",
            "1",
            "--option",
            "speed=fast",
        ),
    ),
    "accommodation-trials-zero": Case(
        "windturbine-accommodation",
        "size",
        "trials",
        lambda: _acc("--trials", "0"),
    ),
    "accommodation-trials-huge": Case(
        "windturbine-accommodation",
        "size",
        "trials",
        lambda: _acc("--trials", str(10**12)),
    ),
    "accommodation-method-unknown": Case(
        "windturbine-accommodation",
        "unknown-name",
        "method",
        lambda: _acc(
            "--trials",
            "2",
            "--option",
            "method=oracle",
        ),
    ),
    "accommodation-option-unknown": Case(
        "windturbine-accommodation",
        "unknown-name",
        "option",
        lambda: _acc(
            "--trials",
            "1",
            "--option",
            "speed=fast",
        ),
    ),
    "accommodation-option-malformed": Case(
        "windturbine-accommodation",
        "type",
        "option",
        lambda: _acc(
            "--trials",
            "1",
            "--option",
            "method",
        ),
    ),
}

#: Inputs outside the usual range whose acceptance is documented and has a meaning: the
#: aerodynamic table is extrapolated linearly outside its grid, as the benchmark's Simulink block
#: does (:func:`~fdi_lib.systems.wind_turbine.torque_coefficient`), so the coefficients are finite.
DOCUMENTED: dict[str, Case] = {
    "power_coefficient-negative": Case(
        "power_coefficient", "out-of-range", "lam", lambda: wt.power_coefficient(-1.0, 0.0)
    ),
    "power_coefficient-beta-huge": Case(
        "power_coefficient", "out-of-range", "beta_deg", lambda: wt.power_coefficient(5.0, 1e9)
    ),
    "torque_coefficient-beyond-table": Case(
        "torque_coefficient", "out-of-range", "lam", lambda: wt.torque_coefficient(40.0, 95.0)
    ),
}


def classify(case: Case) -> tuple[str, str]:
    """``(outcome, message)``: ``typed`` (an FDIError naming the argument), ``unnamed`` (an FDIError
    that does not name it), ``generic`` (any other exception) or ``accepted`` (no error)."""
    try:
        case.call()
    except FDIError as exc:
        return ("typed" if case.expect in str(exc) else "unnamed"), f"{type(exc).__name__}: {exc}"
    except Exception as exc:  # noqa: BLE001 - a generic error is what the probe looks for
        return "generic", f"{type(exc).__name__}: {exc}"
    return "accepted", ""


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input_gets_a_typed_error_naming_it(name: str) -> None:
    outcome, message = classify(CASES[name])
    assert outcome == "typed", f"{name}: {outcome} {message[:300]}"


@pytest.mark.parametrize("name", list(DOCUMENTED))
def test_documented_acceptance_is_finite(name: str) -> None:
    assert np.all(np.isfinite(DOCUMENTED[name].call()))


def _probe(timeout_s: float = 60.0, memory_bytes: int = 3 * 2**30) -> None:  # pragma: no cover
    """Each case in a forked child (time limit, address-space rlimit); a table on stdout."""
    import os
    import resource
    import signal
    import time
    from collections import Counter, defaultdict

    rows = []
    for name, case in {**CASES, **DOCUMENTED}.items():
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(r)
            resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))
            try:
                outcome, message = classify(case)
            except MemoryError as exc:
                outcome, message = "hang/memory", repr(exc)
            os.write(w, f"{outcome}\t{message[:160]}".encode())
            os._exit(0)
        os.close(w)
        start, status = time.monotonic(), None
        while time.monotonic() - start < timeout_s:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            time.sleep(0.02)
        else:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        text = os.read(r, 4096).decode() if status is not None else ""
        os.close(r)
        outcome, _, message = text.partition("\t") if text else ("hang/memory", "", "killed")
        if outcome == "generic" and message.startswith("MemoryError"):
            outcome = "hang/memory"
        if outcome == "accepted" and name in DOCUMENTED:
            outcome = "documented"
        rows.append((name, case, outcome, message.replace("\n", " ")))
        print(
            f"{outcome:12s} {name:40s} {time.monotonic() - start:6.2f}s {message[:110]}", flush=True
        )
    outcomes = ("typed", "documented", "unnamed", "generic", "accepted", "hang/memory")
    for key in ("category", "function"):
        table: dict[str, Counter] = defaultdict(Counter)
        for _, case, outcome, _ in rows:
            table[getattr(case, key)][outcome] += 1
        print(f"\n{key:28s}" + "".join(f"{o:>12s}" for o in outcomes))
        for k in sorted(table):
            print(f"{k:28s}" + "".join(f"{table[k][o]:12d}" for o in outcomes))
    total = Counter(outcome for *_, outcome, _ in rows)
    print(f"{'total (' + str(len(rows)) + ')':28s}" + "".join(f"{total[o]:12d}" for o in outcomes))


if __name__ == "__main__":  # pragma: no cover
    _probe(float(sys.argv[1]) if len(sys.argv) > 1 else 60.0)
