from rgraph.cli import main

raise SystemExit(main())
