"""The `tribojax` command line: one module per subcommand group."""

from ._main import entry as entry
from ._main import main as main
