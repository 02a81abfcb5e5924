"""Records and files: tables, slip runs, hysteresis loops, sidecars and atomic writes.

`_files` (atomic writes, sidecars, CSV headers) and `tribojax._tables` (the validating CSV reader,
`DataFileError` and the bundled published tables, one layer below the physics) are used by the
records `_slip_run` and `_loop`, which do not import each other; `_records` dispatches between
them (every record is an `_record.AbstractRecord`). The table reader's names are re-exported here.
"""

from .._tables import DataFileError as DataFileError
from .._tables import data_dir as data_dir
from .._tables import read_table as read_table
from .._tables import read_text as read_text
from .._tables import wang2022_table as wang2022_table
from .._tables import wu2015_table as wu2015_table
