"""The papers' data, reproduced and fitted: wang2022 Tables 3-7 and wu2015 Eq 7.

`_table3`, `_tables4to7` and `_wu2015` reproduce the published tables; `_chain_fit` fits the
whole chain to wang2022's measured slips, `_robust_fit` does so with Student-t errors,
`_profile_likelihood` profiles that fit and `_fit_figure` draws the fits per cell.
"""
