"""`python -m tribojax ...`: the `tribojax` command (docs/cli.md)."""

from ._cli._main import entry

if __name__ == "__main__":
    entry()
