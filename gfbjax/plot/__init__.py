"""Figures: static analysis (:mod:`.static`, Figs. 4-5), branches, multipliers, energy and design schedules
(:mod:`.branch`), run-ups and spectra (:mod:`.transient`).  Every function returns the matplotlib ``Figure`` and
saves it when given ``path``."""
