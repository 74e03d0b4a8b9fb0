from radarnode.cli.main import main

raise SystemExit(main())
