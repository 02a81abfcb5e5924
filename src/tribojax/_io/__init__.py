"""Records and files: tables, slip runs, hysteresis loops, sidecars and atomic writes."""
