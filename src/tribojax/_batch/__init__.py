"""Many records at once: `tribojax batch` and `tribojax.batch` run the single `fit`, `discover`
or `predict` command on each record over a Dask cluster (local processes by default, or an
existing `dask.distributed` cluster), skip records whose outputs are complete, and write one
table row per record. The layer above the command line: it runs the commands."""

from ._run import batch

__all__ = ["batch"]
