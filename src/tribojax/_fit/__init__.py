"""Fitting: the one least-squares engine and the fits of user records built on it.

Slip runs, loops, displacement histories, friction curves and D, G, μ_t from runs at several
loads. The fits of wang2022's published slips are in `tribojax._reproduce`.
"""
