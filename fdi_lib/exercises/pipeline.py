"""Exercises of "Leak detection on a gas pipeline" (zb2014/pipeline): statements and data.

A student's variant draws the test level, the inflow gains of the designed surrogate, the
samples of the collinearity window, the end of the isolation test's window and its threshold, and
the false-alarm count and the number of runs.
"""

from __future__ import annotations

from fdi_lib.exercises._core import Exercise, uniform

CHAPTER = "zb2014/pipeline"


def _pipe1_data(rng):
    # a level on a continuum (four decimals, never the book's 0.01): classmates' thresholds differ
    alpha = 0.01 if rng is None else uniform(rng, 0.011, 0.1, 4)
    return {"alpha": alpha, "dim_theta_a": 1}


def pipe2_gain_factors(rng) -> tuple[float, float]:
    """Factors on the designed surrogate's ``G0`` and ``Gp`` (1, 1 for the book's data)."""
    return (1.0, 1.0) if rng is None else (uniform(rng, 1.05, 1.5), uniform(rng, 0.5, 1.5))


def _pipe2_data(rng):
    from fdi_lib.systems import gas_pipeline as gp

    mats = gp.pipeline_matrices("designed")
    a, b = pipe2_gain_factors(rng)
    return {"F": mats.F0.copy(), "H": mats.H0.copy(), "G0": a * mats.G0, "Gp": b * mats.Gp}


def _pipe3_data(rng):
    from fdi_lib.reproduce import zb2014_pipeline as zp

    st = zp.pipeline_setup()
    # the window starts after the onset: before it the signature is zero, and a window that
    # holds one non-zero sample makes F singular (cos^2 = 0 / 0, the reference lost pipe-3)
    first = 300 if rng is None else int(rng.integers(zp.FAULT_ONSET + 5, 401))
    last = first + (49 if rng is None else int(rng.integers(30, 80)))
    return {"signature": st.known_signature, "Sigma": st.gains.Sigma, "first": first, "last": last}


def _pipe4_data(rng):
    from fdi_lib.reproduce import zb2014_pipeline as zp
    from fdi_lib.systems import gas_pipeline as gp

    st = zp.pipeline_setup()
    stop = gp.N_STEPS - (0 if rng is None else int(rng.integers(1, 120)))
    return {
        "signature": st.known_signature,
        "Sigma": st.gains.Sigma,
        "start": zp.FAULT_ONSET,
        "stop": stop,
        "theta": zp.fault_theta(2),
        # a threshold on a continuum: classmates with the same stop still get other powers
        "threshold": zp.MINMAX_THRESHOLD if rng is None else uniform(rng, 5.0, 9.0, 3),
    }


def _pipe5_data(rng):
    if rng is None:
        return {"false_alarms": 7, "runs": 2000}
    runs = int(rng.integers(1000, 5001))  # thousands of values: classmates' intervals differ
    false_alarms = int(rng.integers(2, 20))
    return {"false_alarms": false_alarms + (runs == 2000 and false_alarms == 7), "runs": runs}


EXERCISES = [
    Exercise(
        "pipe-1",
        CHAPTER,
        "Where 6.6349 comes from",
        "warm-up",
        5,
        answer="the threshold of the level-alpha test on one component (a number)",
        rtol=1e-6,
        data=_pipe1_data,
    ),
    Exercise(
        "pipe-2",
        CHAPTER,
        "Mass balance fixes the feed-through",
        "warm-up",
        10,
        answer="array of shape (2,): [J_0, J_p]",
        rtol=1e-9,
        data=_pipe2_data,
    ),
    Exercise(
        "pipe-3",
        CHAPTER,
        "How collinear are the two leaks?",
        "core",
        15,
        answer="a number: 1 - cos^2 over k = first..last",
        rtol=1e-6,
        data=_pipe3_data,
        time_keys=("first", "last"),
    ),
    Exercise(
        "pipe-4",
        CHAPTER,
        "Power of the isolation test with the onset known",
        "core",
        20,
        answer="array of shape (2,): [non-centrality, power] for fault 2",
        rtol=1e-6,
        data=_pipe4_data,
        time_keys=("stop",),
    ),
    Exercise(
        "pipe-5",
        CHAPTER,
        "Are 7 false alarms in 2000 runs surprising?",
        "core",
        10,
        answer="array of shape (2,): [low, high], fractions",
        rtol=1e-6,
        data=_pipe5_data,
    ),
    Exercise("pipe-6", CHAPTER, "Why centring the pressure helps isolation", "challenge", 25),
]
