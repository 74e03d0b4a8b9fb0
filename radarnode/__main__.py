"""``python -m radarnode``: the same as the ``radarnode`` command."""

from radarnode.cli.main import main

raise SystemExit(main())
