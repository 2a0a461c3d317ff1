"""Deprecated (goes in the next release): the command line is :mod:`ehatp.cli.app`, each command in
its module under :mod:`ehatp.cli`."""

from .._deprecated import moved

moved(__name__,
      "ehatp.cli.app",
      "ehatp.cli.solve",
      "ehatp.cli.common",
      "ehatp.cli.show",
      "ehatp.cli.validate",
      "ehatp.cli.bench")

if __name__ == "__main__":  # python -m ehatp.tools.cli
    from ..cli.app import main

    main()
