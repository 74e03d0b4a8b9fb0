"""``python -m radarnode``: the same as the ``radarnode`` command."""

from radarnode.cli import program

program()
