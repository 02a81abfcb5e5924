"""The generic fit engine: the one least-squares solve (`_engine`), its result and statistics
(`_result`), the Levenberg–Marquardt solver (`_solver`), the noise model (`_noise`) and the
measures (`_measures`). It knows no model: the record models and their fits are in
`tribojax._model`, the fits of wang2022's published slips in `tribojax._reproduce`.
"""
