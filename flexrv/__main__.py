"""``python -m flexrv`` runs the CLI."""

from flexrv.cli import main

main()
