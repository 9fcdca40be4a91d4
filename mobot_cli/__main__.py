"""`python -m mobot_cli` is the `mobot` command."""

from mobot_cli.cli import main

main()
