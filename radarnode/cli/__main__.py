from radarnode.cli import main

raise SystemExit(main())
