"""Reproductions of the papers' tables: wang2022 Tables 3-7 and wu2015 Eq 7."""
