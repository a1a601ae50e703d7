"""What the reproductions show: figures, reader tables and helpers for the prose, one module per paper.

``fdi_lib.reproduce.<paper>`` computes (its registered functions return
:class:`~fdi_lib.reproduce.registry.ReproductionResult`); ``fdi_lib.reproduce.views.<paper>``
draws and tabulates those results for the book, the widgets and ``--plot``. Views import the
computing modules, never the reverse (``tests/test_layers.py``): a registration names its figure
by its dotted path (:class:`~fdi_lib.reproduce.registry.DeferredPlot`), so a ``--json`` run
loads no view. A new figure touches its paper's view (the drawing), its paper's module (the
registration's ``plot=`` path) and its chapter.
"""
