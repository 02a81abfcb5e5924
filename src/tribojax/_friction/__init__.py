"""Friction elements: the common interface, LuGre and the rate-independent elements."""
