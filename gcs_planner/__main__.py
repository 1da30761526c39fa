from gcs_planner.cli import main

raise SystemExit(main())
