"""The command line (``ehatp``): :mod:`ehatp.cli.app` and one module per command. Importing this
package loads no command."""
