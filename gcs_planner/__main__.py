"""``python -m gcs_planner``: the command line, with a Ctrl-C during its own imports ending as any
other does (one line, exit 130; the installed ``gcs-planner`` script imports less first)."""

try:
    from gcs_planner.cli import main
except KeyboardInterrupt:
    import sys

    from gcs_planner.runtime.interrupt import EXIT_CODE, MESSAGE

    print(MESSAGE, file=sys.stderr)
    raise SystemExit(EXIT_CODE) from None

raise SystemExit(main())
