"""Fitting: the least-squares engine, slip-run, loop, surface and chain fits, sensitivities."""
