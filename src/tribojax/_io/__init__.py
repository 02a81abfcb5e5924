"""Records and files: tables, slip runs, hysteresis loops, sidecars and atomic writes.

`_files` (atomic writes, sidecars, CSV headers) and `_tables` are used by the records
`_slip_run` and `_loop`, which do not import each other; `_records` dispatches between them.
"""
