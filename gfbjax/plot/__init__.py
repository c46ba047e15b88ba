"""Figures: static analysis (:mod:`.static`, Figs. 4-5), branches, multipliers, energy and design schedules
(:mod:`.branch`), run-ups and spectra (:mod:`.transient`), bearing coefficients (:mod:`.coefficients`).  Figures
against speed get a secondary rpm axis on top when the conversion is known (``spec=``, ``rpm_per_omega_bar=`` or
a branch's ``meta``).  Every function returns the matplotlib ``Figure`` and
saves it when given ``path``; given ``ax`` (the Axes of an existing figure, one per panel) it draws into them and
returns their figure.  The branch figures also overlay several branches given as ``{label: branch}`` or
``(label, branch)`` pairs."""
