"""Hand-made mutants of the core maths, and how many the unit tests kill (issue 15).

Usage::

    python benchmarks/mutation_check.py [REV [TEXT ...]]   # default HEAD; TEXT: only mutants containing one

The tree of git revision ``REV`` is exported to a temporary folder; each mutant replaces one
exact line fragment of one module (it must occur exactly once), then the unit tests that
belong to the module (:data:`OWN_TESTS`, plus the ``tests/test_robust_*.py`` files naming it) run
with ``-x``. A mutant is killed when pytest fails. Not a benchmark: a test-strength check,
kept here so that the score in the issue's closing note can be re-measured. About 10 minutes
on one core (``nice -n 10`` recommended).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# (module file, exact fragment, replacement)
MUTANTS = [
    # filters: Riccati recursion and data recursion
    ("fdi_lib/filters.py", "S = H @ Pk @ H.T + model.R[k]", "S = H @ Pk @ H.T + 2.0 * model.R[k]"),
    (
        "fdi_lib/filters.py",
        "Pf = IKH @ Pk @ IKH.T + Kk @ model.R[k] @ Kk.T",
        "Pf = IKH @ Pk @ IKH.T",
    ),
    ("fdi_lib/filters.py", "Pn = F @ Pf @ F.T + model.Q[k]", "Pn = F @ Pf @ F.T"),
    ("fdi_lib/filters.py", "F @ IKH, F @ Kk", "F @ IKH, Kk"),
    (
        "fdi_lib/filters.py",
        "xh[..., k + 1, :] = xf[..., k, :] @ model.F[k].T + Gu[..., k, :]",
        "xh[..., k + 1, :] = xf[..., k, :] @ model.F[k].T",
    ),
    (
        "fdi_lib/filters.py",
        'upd = ybar - np.einsum("kij,...kj->...ki", model.H, xf)',
        'upd = ybar - np.einsum("kij,...kj->...ki", model.H, xh[..., :-1, :])',
    ),
    # signatures
    (
        "fdi_lib/signatures.py",
        "drive = fault.Psi - gains.FK @ fault.Phi",
        "drive = fault.Psi + gains.FK @ fault.Phi",
    ),
    (
        "fdi_lib/signatures.py",
        "Gamma[k + 1] = gains.A[k] @ Gamma[k] + drive[k]",
        "Gamma[k + 1] = model.F[k] @ Gamma[k] + drive[k]",
    ),
    (
        "fdi_lib/signatures.py",
        "on_innovation=model.H @ Gamma[:N] + fault.Phi",
        "on_innovation=model.H @ Gamma[1:] + fault.Phi",
    ),
    (
        "fdi_lib/signatures.py",
        "xi[k + 1] = model.F[k] @ xi[k] + gains.K[k + 1] @ rho[k + 1]",
        "xi[k + 1] = model.F[k] @ xi[k]",
    ),
    (
        "fdi_lib/signatures.py",
        "gamma[k + 1] = gains.A[k] @ gamma[k]",
        "gamma[k + 1] = model.F[k] @ gamma[k]",
    ),
    # glr
    (
        "fdi_lib/glr.py",
        "np.sum(V * (q * inv)[..., None, :], axis=-1)",
        "np.sum(V * q[..., None, :], axis=-1)",
    ),
    ("fdi_lib/glr.py", "RANK_RTOL = 1e-10", "RANK_RTOL = 1e-1"),
    ("fdi_lib/glr.py", "sig = sig + fam.Phi_tilde[k]", "sig = sig + fam.Phi_tilde[k - 1]"),
    ("fdi_lib/glr.py", "(self._onset <= k - self.min_samples)", "(self._onset <= k)"),
    (
        "fdi_lib/glr.py",
        "s = -(-m // p) if min_samples is None else min_samples",
        "s = m // p if min_samples is None else min_samples",
    ),
    ("fdi_lib/glr.py", "best = np.argmax(stat, axis=0)", "best = np.argmin(stat, axis=0)"),
    ("fdi_lib/glr.py", "over[..., :start] = False", "over[..., :max(start - 1, 0)] = False"),
    (
        "fdi_lib/glr.py",
        "over = np.nan_to_num(stat, nan=-np.inf) > threshold",
        "over = np.nan_to_num(stat, nan=-np.inf) >= threshold",
    ),
    ("fdi_lib/glr.py", "and k > 0) else 0.0", "and k > 1) else 0.0"),
    # isolation
    (
        "fdi_lib/isolation.py",
        'za = za - np.einsum("...ij,...j->...i", T, zb)',
        'za = za + np.einsum("...ij,...j->...i", T, zb)',
    ),
    ("fdi_lib/isolation.py", "Faa = Faa - T @ np.swapaxes(Fab, -1, -2)", "Faa = Faa"),
    (
        "fdi_lib/isolation.py",
        "float(scipy.stats.chi2.ppf(1.0 - alpha, dof))",
        "float(scipy.stats.chi2.ppf(1.0 - alpha, dof + 1))",
    ),
    ("fdi_lib/isolation.py", "faulty=stat > thr", "faulty=stat < thr"),
    # kitanidis
    ("fdi_lib/kitanidis.py", "Kbar = Kk + Gam @ M  # (24g)", "Kbar = Kk  # (24g)"),
    ("fdi_lib/kitanidis.py", "Pf = Pf + GR @ GR.T", "Pf = Pf"),
    (
        "fdi_lib/kitanidis.py",
        "Rc = H @ Pf @ H.T + Rk - HK @ Rk - Rk @ HK.T",
        "Rc = H @ Pf @ H.T + Rk - HK @ Rk",
    ),
    ("fdi_lib/kitanidis.py", "- K[k + 1] @ Phi_c[k + 1]", "+ K[k + 1] @ Phi_c[k + 1]"),
    ("fdi_lib/kitanidis.py", "U[0] = -K[0] @ Phi_c[0]", "U[0] = 0.0 * Phi_c[0, :1]"),
    # nonparametric
    (
        "fdi_lib/nonparametric.py",
        "z[..., k + 1, :] = z[..., k, :] @ gains.A[k].T + drive[..., k, :]",
        "z[..., k + 1, :] = z[..., k, :] @ model.F[k].T + drive[..., k, :]",
    ),
    ("fdi_lib/nonparametric.py", "- e[..., k, :] @ Gamma[k + 1].T", "- e[..., k, :] @ Gamma[k].T"),
    ("fdi_lib/nonparametric.py", "model.H[k] @ Es[max(k - 1, 0)]", "model.H[k] @ Es[k]"),
    (
        "fdi_lib/nonparametric.py",
        "chi2.ppf(1.0 - alpha, window * p)",
        "chi2.ppf(1.0 - alpha, window + p)",
    ),
    (
        "fdi_lib/nonparametric.py",
        "((alarm < 0) | (e_alarm < alarm))",
        "((alarm >= 0) | (e_alarm < alarm))",
    ),
    (
        "fdi_lib/nonparametric.py",
        "M = -model.F[k] @ D[k] @ g.Sigma[k]",
        "M = model.F[k] @ D[k] @ g.Sigma[k]",
    ),
    # rls
    ("fdi_lib/rls.py", "S = lam * S_all[k] + Mk @ Pk @ Mk.T", "S = S_all[k] + Mk @ Pk @ Mk.T"),
    ("fdi_lib/rls.py", "Pn = (Pk - Lk @ Mk @ Pk) / lam", "Pn = (Pk - Lk @ Mk @ Pk)"),
    ("fdi_lib/rls.py", "th = th + e @ g.L[k].T", "th = th + 0.5 * e @ g.L[k].T"),
    # simulate
    ("fdi_lib/simulate.py", "+ noise.w[..., k, :] + state_fault[k]", "+ noise.w[..., k, :]"),
    # polytope and SVO
    ("fdi_lib/sets/polytope.py", "return bool(-res.fun < -tol)", "return bool(-res.fun < tol)"),
    ("fdi_lib/sets/polytope.py", "if np.any(m[~keep] < -1e-9):", "if np.any(m[~keep] < -1e9):"),
    (
        "fdi_lib/sets/polytope.py",
        "return Polytope(D, self.support(D))",
        "return Polytope(D, 1.01 * self.support(D))",
    ),
    (
        "fdi_lib/sets/polytope.py",
        "np.concatenate([self.m, b + y, b - y])",
        "np.concatenate([self.m, b + y, b + y])",
    ),
    (
        "fdi_lib/sets/svo.py",
        "h = h + self.margin * (1.0 + np.abs(h))",
        "h = h - self.margin * (1.0 + np.abs(h))",
    ),
]


# The unit tests of each module (plus, in any revision, the tests/test_robust_*.py files naming it).
OWN_TESTS = {
    "filters": ["tests/test_filters.py", "tests/test_signatures.py", "tests/test_glr.py"],
    "signatures": ["tests/test_signatures.py", "tests/test_glr.py"],
    "glr": ["tests/test_glr.py", "tests/test_calibration.py"],
    "isolation": ["tests/test_isolation.py", "tests/test_calibration.py"],
    "kitanidis": ["tests/test_kitanidis.py"],
    "nonparametric": ["tests/test_nonparametric.py"],
    "rls": ["tests/test_rls.py", "tests/test_nonparametric.py"],
    "simulate": ["tests/test_simulate.py"],
    "polytope": ["tests/sets/test_polytope_ops.py"],
    "svo": ["tests/sets/test_svo_props.py"],
}


def tests_for(tree: Path, module: str) -> list[str]:
    """The module's own unit tests and the tests/test_robust_*.py files that mention it."""
    stem = Path(module).stem
    out = [f for f in OWN_TESTS[stem] if (tree / f).exists()]
    for f in sorted((tree / "tests").glob("test_robust_*.py")):
        if re.search(rf"\b{stem}\b", f.read_text(), flags=re.I):
            out.append(f.relative_to(tree).as_posix())
    return out


def main(rev: str = "HEAD", *only: str) -> None:
    with tempfile.TemporaryDirectory(prefix="mutants-") as tmp:
        tree = Path(tmp)
        archive = subprocess.run(
            ["git", "-C", str(ROOT), "archive", rev], capture_output=True, check=True
        ).stdout
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
        env = {
            **os.environ,
            "PYTHONPATH": str(tree),
            "OPENBLAS_NUM_THREADS": "1",
            "OMP_NUM_THREADS": "1",
        }
        killed, total, survivors = 0, 0, []
        for module, old, new in MUTANTS:
            if only and not any(text in old for text in only):
                continue
            path = tree / module
            src = path.read_text()
            if src.count(old) != 1:
                print(f"SKIP  {module}: fragment found {src.count(old)} times: {old!r}")
                continue
            path.write_text(src.replace(old, new))
            try:
                files = tests_for(tree, module)
                proc = subprocess.run(
                    [
                        sys.executable,
                        "-m",
                        "pytest",
                        "-x",
                        "-q",
                        "-p",
                        "no:cacheprovider",
                        "-W",
                        "ignore::DeprecationWarning",
                        *files,
                    ],
                    cwd=tree,
                    env=env,
                    capture_output=True,
                    text=True,
                    timeout=900,
                )
                dead = proc.returncode != 0
            except subprocess.TimeoutExpired:
                dead = True
            finally:
                path.write_text(src)
            total += 1
            killed += dead
            if not dead:
                survivors.append((module, old, new))
            print(f"{'KILL' if dead else 'LIVE'}  {module}: {old!r} -> {new!r}", flush=True)
        print(f"\n{rev}: {killed}/{total} mutants killed ({100.0 * killed / max(total, 1):.1f} %)")
        for module, old, new in survivors:
            print(f"  survived: {module}: {old!r} -> {new!r}")


if __name__ == "__main__":
    main(*sys.argv[1:])
