"""``python -m fdi_lib reproduce ...``: see :mod:`fdi_lib.reproduce.cli`."""

try:
    from fdi_lib.reproduce.cli import main
except KeyboardInterrupt:  # Ctrl-C while the library is still being imported
    import sys

    print("interrupted", file=sys.stderr)
    raise SystemExit(130) from None

raise SystemExit(main())
