"""Figures, reader tables and prose helpers of the Zhang (2021) reproductions.

The computing side, with the reproductions' registrations, is :mod:`fdi_lib.reproduce.zhang2021`
(Example 1) and :mod:`fdi_lib.reproduce.zhang2021_example2` (Example 2).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from fdi_lib.plotting import figure, OURS_COLOR, PAPER_COLOR
from fdi_lib.reproduce.registry import ReproductionResult
from fdi_lib.reproduce.zhang2021 import GRID_SIZES, PAPER_TABLE1, PAPER_TABLE2, Q_VALUES, R_VALUES
from fdi_lib.reproduce.zhang2021_example2 import EX2_INTERVENTIONS, EX2_LEAK_SIZE
from fdi_lib.reproduce.zhang2021_lambda import RULE_READINGS, variant_columns


__all__ = [
    "lambda_rule_table",
    "initial_state_table",
    "paper_between_readings",
    "rate_table",
    "snr_table",
    "grid_rule_difference",
    "paper_outside_ci",
    "oracle_table",
    "intervention_table",
    "plot_fig2",
    "plot_fig3",
    "plot_table1",
    "plot_table2",
    "plot_fig6",
    "plot_fig7",
]


def plot_fig2(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 2: number of non-zero Lasso components against ``lambda`` (exact path, log axis)."""
    return _plot_support(result, fig, "Example 1: support size along the Lasso path")


def _plot_support(result: ReproductionResult, fig: Any, title: str):
    fig, ax = figure(fig=fig)
    ax = ax[0, 0]
    lam, sizes = result.data["lambdas"], result.data["sizes"]
    floor = 1e-4 * lam[0]
    edges = np.concatenate([np.clip(lam[::-1], floor, None), [3 * lam[0]]])
    ax.stairs(
        np.concatenate([sizes[::-1], [0]]),
        edges,
        color=OURS_COLOR,
        baseline=None,
        label=r"exact Lasso path: $\#\{j: \hat\theta_j(\lambda) \neq 0\}$",
    )
    ax.plot(
        result.data["grid"],
        np.full(result.data["grid"].size, result.headline["flat_size"]),
        "D",
        color=PAPER_COLOR,
        label=r"$\lambda$ in the flat range (log width)",
    )
    lo, hi = result.headline["flat_range_linear"]
    ax.axvspan(lo, hi, color="0.8", alpha=0.5, label="flat range (linear width)")
    ax.set(
        xscale="log",
        xlabel=r"$\lambda$ (normalisation of (39))",
        ylabel=r"non-zero components of $\hat\theta$",
        title=title,
    )
    ax.set_xlim(floor, lam[0] * 3)
    ax.legend(loc="upper right")
    return fig


def plot_fig3(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 3: Lasso diamonds (one colour per ``lambda`` in the flat range), LS circles, true asterisks."""
    return _plot_diamonds(result, fig, "Example 1: isolation and estimation")


def _plot_diamonds(result: ReproductionResult, fig: Any, title: str):
    fig, ax = figure(fig=fig)
    ax = ax[0, 0]
    lasso, grid = result.data["lasso"], result.data["grid"]
    idx = np.arange(1, lasso.shape[1] + 1)
    colors = __import__("matplotlib").colormaps["viridis"](np.linspace(0, 1, grid.size))
    for c, row in zip(colors, lasso):
        nz = row != 0
        ax.plot(idx[nz], row[nz], "D", color=c, ms=5, alpha=0.8)
    ls = result.data["theta_ls"]
    nz = ls != 0
    ax.plot(
        idx[nz],
        ls[nz],
        "o",
        mfc="none",
        mec="k",
        ms=10,
        label=r"least squares $\hat\theta^{\rm LS}_j$",
    )
    th = result.data["theta"]
    ax.plot(
        idx[th != 0], th[th != 0], "*", color=PAPER_COLOR, ms=10, label=r"true $\theta_j \neq 0$"
    )
    ax.plot(
        [],
        [],
        "D",
        color=colors[0],
        label=r"Lasso $\hat\theta_j(\lambda)$, one colour per $\lambda$",
    )
    ax.set(xlabel=r"component $j$ of $\theta$", ylabel=r"$\hat\theta_j$, $\theta_j$", title=title)
    ax.set_xlim(0, lasso.shape[1] + 1)
    ax.legend(loc="best")
    return fig


# --------------------------------------------------------------------------- Tables I-II
def _rate_table(
    values: Sequence[float],
    rates: dict[str, Any],
    paper: dict[Any, float],
    trials: int,
    xlabel: str,
    fig: Any,
    title: str,
    log_x: bool = False,
):
    fig, ax = figure(fig=fig)
    ax = ax[0, 0]
    x = np.asarray(values, dtype=float)
    p = rates["success_log"] / trials
    ci = rates["ci_log"]
    ax.fill_between(x, ci[:, 0], ci[:, 1], color=OURS_COLOR, alpha=0.2, lw=0)
    ax.plot(x, p, "o-", color=OURS_COLOR, ms=3, label=f"ours, log width ({trials} trials, 95 % CI)")
    ax.plot(
        x,
        rates["success_linear"] / trials,
        "s--",
        color="0.4",
        ms=3,
        lw=0.8,
        label="ours, linear width",
    )
    ax.plot(x, [paper[v] for v in values], "x:", color=PAPER_COLOR, label="paper")
    ax.set(xlabel=xlabel, ylabel=r"success rate $\hat p$", title=title, ylim=(-0.02, 1.02))
    ax.legend(loc="upper right" if not log_x else "lower left")
    return fig


def plot_table1(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 4: success rate against the number of faults q."""
    d = result.data
    return _rate_table(
        Q_VALUES,
        d,
        PAPER_TABLE1,
        result.settings["trials"],
        r"number of faults $q$",
        fig,
        r"Example 1: isolation rate against $q$ ($r = 0.5$)",
    )


def plot_table2(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 5: success rate against the noise factor r, and the mean SNR of each output."""
    d = result.data
    trials = result.settings["trials"]
    fig, axes = figure(1, 2, fig=fig, figsize=(8.5, 3.4))
    _rate_table_axes(axes[0, 0], R_VALUES, d, PAPER_TABLE2["success_rate"], trials)
    ax = axes[0, 1]
    snr = d["snr_db"]
    for i, mk in enumerate(("o", "s")):
        ax.plot(
            R_VALUES,
            snr[:, i],
            mk + "-",
            ms=3,
            color=OURS_COLOR,
            alpha=1 - 0.4 * i,
            label=f"ours, $Y^{{({i + 1})}}$",
        )
        ax.plot(
            R_VALUES,
            [PAPER_TABLE2["snr_db"][r][i] for r in R_VALUES],
            "x:",
            color=PAPER_COLOR,
            alpha=1 - 0.4 * i,
            label=f"paper, $Y^{{({i + 1})}}$",
        )
    ax.set(
        xlabel=r"noise factor $r$ ($R = r I_2$)",
        ylabel=r"mean SNR of $Y^{(i)}$ (dB)",
        title="SNR of the outputs",
    )
    ax.legend()
    return fig


def _rate_table_axes(
    ax: Any, values: Sequence[float], rates: dict[str, Any], paper: dict[Any, float], trials: int
) -> None:
    x = np.asarray(values, dtype=float)
    ci = rates["ci_log"]
    ax.fill_between(x, ci[:, 0], ci[:, 1], color=OURS_COLOR, alpha=0.2, lw=0)
    ax.plot(
        x,
        rates["success_log"] / trials,
        "o-",
        color=OURS_COLOR,
        ms=3,
        label=f"ours, log ({trials} trials)",
    )
    ax.plot(
        x, rates["success_linear"] / trials, "s--", color="0.4", ms=3, lw=0.8, label="ours, linear"
    )
    ax.plot(x, [paper[v] for v in values], "x:", color=PAPER_COLOR, label="paper")
    ax.set(
        xlabel=r"noise factor $r$ ($R = r I_2$)",
        ylabel=r"success rate $\hat p$",
        ylim=(-0.02, 1.02),
        title=r"Isolation rate ($q = 5$)",
    )
    ax.legend(loc="lower left")


#: Human labels of the readings of the rule (variants table).
RULE_LABELS = {
    "log": "exact path, log width (our rule)",
    "linear": "exact path, linear width",
    "grid20": "geometric grid, 20 points",
    "grid100": "geometric grid, 100 points",
    "standardised": "X scaled to unit RMS, log width",
    "matlab": "Matlab-style X (centred, unit variance), log width",
    "oracle": "oracle: true support on the path",
}


#: Human labels of the initialisations (:data:`INIT_VARIANTS`).
INIT_LABELS = {
    "paper": "paper's filter start, X₀ ~ N(0, I)",
    "spread": "X₀ ~ N(0, 100 I), P₀|₀ = 100 I",
}


def _table_columns() -> tuple[list[str], list[str]]:
    """The columns of the λ-rule study (``q5``, ..., ``r40``) and their headers for readers."""
    cols = [c for c, _, _ in variant_columns()]
    return cols, [f"q = {c[1:]}" if c[0] == "q" else f"r = {c[1:]} (q = 5)" for c in cols]


def lambda_rule_table(result: ReproductionResult):
    """The variants table for readers: rates in % with 95 % intervals, the paper's row last."""
    from fdi_lib.report import fmt_rate, table

    h, n = result.headline, result.settings["trials"]
    cols, heads = _table_columns()
    rows = {
        RULE_LABELS[k]: [fmt_rate(h["success_rate"][k][c], h["ci95"][k][c]) for c in cols]
        for k in RULE_READINGS + ("oracle",)
    }
    rows["paper (Tables I-II)"] = [
        fmt_rate(result.paper["success_rate"][c], digits=3) for c in cols
    ]
    return table(
        rows,
        heads,
        index_header="success rate (%)",
        notes=[
            f"{n} trials per column, the first {n} trials of the paper tables' "
            "columns; 95 % Clopper-Pearson intervals in brackets.",
            "q columns: r = 0.5 (Table I); r columns: q = 5 (Table II).",
        ],
    )


def initial_state_table(result: ReproductionResult):
    """Rates of the log rule and the oracle at q = 15 for each initialisation, for readers."""
    from fdi_lib.report import fmt_rate, table

    h, n = result.headline, result.settings["trials"]
    rows = {
        "our default (filter updated with Y₀)": [
            fmt_rate(h["success_rate"]["log"]["q15"], h["ci95"]["log"]["q15"]),
            fmt_rate(h["success_rate"]["oracle"]["q15"], h["ci95"]["oracle"]["q15"]),
        ]
    }
    for i, label in INIT_LABELS.items():
        rows[label] = [
            fmt_rate(h["init_success_rate"][i], h["init_ci95"][f"log_{i}"]),
            fmt_rate(h["init_oracle_rate"][i], h["init_ci95"][f"oracle_{i}"]),
        ]
    rows["paper (Table I)"] = [fmt_rate(PAPER_TABLE1[15], digits=3), "not given"]
    return table(
        rows,
        ["log rule", "oracle"],
        index_header="q = 15, r = 0.5",
        notes=[
            f"{n} trials, the same draws in every row except X₀; "
            "95 % Clopper-Pearson intervals in brackets."
        ],
    )


#: Human labels of the paths of the oracles (:data:`ORACLE_PATHS` and their union).
ORACLE_LABELS = {
    "raw": "raw X (as built)",
    "standardised": "X scaled to unit RMS",
    "matlab": "Matlab-style X (centred, unit variance)",
    "union": "any of the three paths",
}


def oracle_table(result: ReproductionResult):
    """The oracle of each path and of their union, for readers: rates in % with 95 % intervals."""
    from fdi_lib.report import fmt_rate, table

    h, n = result.headline, result.settings["trials"]
    cols, heads = _table_columns()
    rows = {
        ORACLE_LABELS[k]: [fmt_rate(h["oracle_rate"][k][c], h["oracle_ci95"][k][c]) for c in cols]
        for k in ORACLE_LABELS
    }
    rows["log rule on a scaled path, raw oracle false"] = [
        fmt_rate(max(h["beyond_raw_oracle"][k][c] for k in ("standardised", "matlab")))
        for c in cols
    ]
    rows["paper (Tables I-II)"] = [
        fmt_rate(result.paper["success_rate"][c], digits=3) for c in cols
    ]
    return table(
        rows,
        heads,
        index_header="true support on the path (%)",
        notes=[
            f"{n} trials per column, the trials of the variants table; 95 % "
            "Clopper-Pearson intervals in brackets.",
            "The row before the paper's: the larger of the two scaled readings.",
        ],
    )


#: Human labels of the interventions of the Example 2 study (:data:`EX2_INTERVENTIONS`).
INTERVENTION_LABELS = {
    "nominal": "daily demand (Figs 6-7)",
    "white": "× (1 + 0.3 e_k), e_k ~ N(0, 1) white",
    "white_uniform": "× (1 + 0.3 e_k), e_k uniform on [-1, 1] white",
    "steps": "× (1 + 0.3 s_k), s_k ~ N(0, 1) held 20-60 min",
    "steps_uniform": "× (1 + 0.3 s_k), s_k uniform on [-1, 1] held 20-60 min",
    "state_noise": "daily demand, Q × 1e-6",
    "output_noise": "daily demand, R × 1e-6",
}


def intervention_table(result: ReproductionResult):
    """The Example 2 intervention study for readers: counts of records, and the correlation."""
    from fdi_lib.report import fmt_number, table

    h = result.headline
    n = h["records"]
    rows = {
        INTERVENTION_LABELS[k]: [
            f"{h['isolated'][k]} / {n}",
            f"{h['on_path'][k]} / {n}",
            fmt_number(h["min_neighbour_correlation"][k], digits=6),
        ]
        for k in EX2_INTERVENTIONS
    }
    return table(
        rows,
        [
            "rule isolates {10, 15}",
            "{10, 15} on the path",
            "median min |corr| of neighbouring columns",
        ],
        index_header="input flow U_k (and noise)",
        notes=[
            f"{n} records per row (seed {result.settings['seed']}); record i has the same "
            "noise stream in every row. Rule: flat range, log width."
        ],
    )


def paper_between_readings(result: ReproductionResult) -> list[str]:
    """Columns of a rate table where the paper's rate lies between our linear and log rates (inclusive)."""
    h, pap = result.headline, result.paper["success_rate"]
    return [
        k
        for k in pap
        if min(h["success_rate"][k], h["success_rate_linear"][k])
        <= pap[k]
        <= max(h["success_rate"][k], h["success_rate_linear"][k])
    ]


def plot_fig6(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 6: support size along the Lasso path, Example 2 (surrogate pipeline)."""
    return _plot_support(result, fig, "Example 2 (surrogate pipeline): support size")


def plot_fig7(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 7: Lasso diamonds, LS circles, true asterisks, Example 2 (values in 1e-4)."""
    scaled = ReproductionResult(
        id=result.id,
        headline=result.headline,
        data={
            "lasso": result.data["lasso"] / EX2_LEAK_SIZE,
            "grid": result.data["grid"],
            "theta_ls": result.data["theta_ls"] / EX2_LEAK_SIZE,
            "theta": result.data["theta"] / EX2_LEAK_SIZE,
        },
    )
    fig = _plot_diamonds(scaled, fig, "Example 2 (surrogate pipeline): isolation")
    fig.axes[0].set_ylabel(r"value ($\times 10^{-4}$)")
    return fig


# --------------------------------------------------------------------------- tables for readers (Example 1)
def rate_table(result: ReproductionResult):
    """Table I or II for readers: the paper's rate, ours (log rule, 95 % interval), the linear rule.

    For ``zhang2021-table2`` the mean SNR of each output (ours / paper, dB) is added.
    """
    from fdi_lib.report import fmt_number, fmt_rate, table

    h, pap = result.headline, result.paper["success_rate"]
    is_t2 = "snr_db" in h
    cols = ["paper", "ours, log width", "ours, linear width", "paper in our interval"]
    if is_t2:
        cols += ["SNR output 1 (dB), ours / paper", "SNR output 2 (dB), ours / paper"]
    rows = {}
    for k in pap:
        cells = [
            fmt_rate(pap[k], digits=3),
            fmt_rate(h["success_rate"][k], h["ci95"][k], digits=3),
            fmt_rate(h["success_rate_linear"][k], digits=3),
            bool(h["ci95"][k][0] <= pap[k] <= h["ci95"][k][1]),
        ]
        if is_t2:
            cells += [
                f"{fmt_number(h['snr_db'][k][i], 4)} / {fmt_number(result.paper['snr_db'][k][i], 4)}"
                for i in range(2)
            ]
        rows[f"r = {k}" if is_t2 else f"q = {k}"] = cells
    n = result.settings["trials"]
    return table(
        rows,
        cols,
        index_header="",
        notes=[
            f"{n} trials per column, the same seeds in every column; 95 % Clopper-Pearson "
            "interval of the log-width rate in brackets."
        ],
    )


def _snr_tex(key: str) -> str:
    """A reading's key (``"sum Y^2 / sum V^2"``, a ratio of sums or of variances) as TeX, the
    SNR's row label."""
    tex = key.replace("sum ", "\\sum ").replace("var(", "\\operatorname{var}(")
    num, den = (f"{{{part}}}" for part in tex.split(" / "))
    return rf"10 \log_{{10}} \frac{num}{den}"


def snr_table(readings: dict[str, np.ndarray], r_values: Sequence[float] = (0.5, 100.0, 200.0)):
    """Mean SNR (dB, output 1 / output 2) of each reading of :func:`~fdi_lib.reproduce.zhang2021.snr_variants` beside Table II's."""
    from fdi_lib.report import fmt_number, table

    def cell(v: Sequence[float]) -> str:
        return " / ".join(fmt_number(float(x), 4) for x in v)

    # the readings' keys ("sum Y^2 / sum V^2") as maths, 10 log10 of a ratio of sums, after what
    # the ratio compares (a header of maths alone is empty to a screen reader's table navigation)
    rows = {
        f"{'variances' if k.startswith('var(') else 'sums of squares'}: ${_snr_tex(k)}$": [
            cell(v[i]) for i in range(len(r_values))
        ]
        for k, v in readings.items()
    }
    rows["paper (Table II)"] = [
        cell(PAPER_TABLE2["snr_db"][float(r) if r != int(r) else int(r)]) for r in r_values
    ]
    return table(rows, [f"r = {r:g}" for r in r_values], index_header="SNR reading (dB)")


def grid_rule_difference(result: ReproductionResult) -> float:
    """Largest ``|grid rate - exact log rate|`` over the columns and the grids of :data:`GRID_SIZES`."""
    h = result.headline
    return float(
        max(
            abs(h[f"success_rate_grid{g}"][k] - h["success_rate"][k])
            for g in GRID_SIZES
            for k in h["success_rate"]
        )
    )


def paper_outside_ci(result: ReproductionResult) -> tuple[int, int]:
    """``(outside, below)``: paper rates outside our 95 % intervals (log rule), and how many below them."""
    h, pap = result.headline, result.paper["success_rate"]
    cis = h["ci95"]
    return (
        int(sum(not cis[k][0] <= pap[k] <= cis[k][1] for k in pap)),
        int(sum(pap[k] < cis[k][0] for k in pap)),
    )
