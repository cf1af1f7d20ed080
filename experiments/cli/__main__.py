from racf.experiments.cli import main

raise SystemExit(main())
