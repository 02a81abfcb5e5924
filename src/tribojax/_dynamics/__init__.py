"""Dynamics: drive profiles, the slip simulation, harmonic balance and the Rodas4 solver."""
