"""The kernel-free explorable of each chapter: its tested callback and the grid the book draws it
over (:func:`fdi_lib.explorables.explorable`), keyed by a name for readers. One list for the tests
of the explorables' texts and for ``benchmarks/bench_widgets.py``."""

from __future__ import annotations

from fdi_lib.widgets import bz, rosa2013, windturbine, zb2014, zb2014_pipeline, zhang2021

__all__ = ["EXPLORABLES"]

#: ``name: (callback, grid)`` as in the chapters' Explore sections.
EXPLORABLES = {
    "signature": (zb2014.explore_signature, zb2014.SIGNATURE_GRID),
    "GLR": (zb2014.explore_glr, zb2014.GLR_GRID),
    "pipeline": (zb2014_pipeline.explore_pipeline, zb2014_pipeline.GRID),
    "sparse": (zhang2021.explore_sparse, zhang2021.GRID),
    "parametric/non-parametric": (bz.explore_bz, bz.GRID),
    "SVO": (rosa2013.explore_svo, rosa2013.GRID),
    "wind turbine": (windturbine.explore_windturbine, windturbine.GRID),
}
