"""``python -m ehatp.cli ...``: the ``ehatp`` command."""

from .app import main

main()
