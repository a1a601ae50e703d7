"""``python -m fdi_lib reproduce ...``: see :mod:`fdi_lib.reproduce.cli`."""

from fdi_lib.reproduce.cli import main

raise SystemExit(main())
