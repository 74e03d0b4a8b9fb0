from radarnode.cli import program

program()
