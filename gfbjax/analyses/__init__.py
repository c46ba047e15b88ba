"""Analyses of the GFB-rotor system, each on the one vector field of :mod:`gfbjax.model`.

* :mod:`.static` -- static equilibria under load, load-displacement curves, stability (Figs. 4-5);
* :mod:`.cycles` -- the GFB problems on the continuation engine: unbalance-response cycles, balanced equilibria,
  Hopf-born self-excited cycles (Fig. 7, Table 1);
* :mod:`.transient` -- diffrax time integration at constant speed and through a run-up (Eq. 15a/b);
* :mod:`.signals` -- steady state, Poincare sections, spectra, run-up STFT;
* :mod:`.energy` -- the works W_fu, W_B, W_cf, W_cb of a cycle (Sect. 3.3);
* :mod:`.plain` -- the plain rigid 360-degree gas bearing, for validation against analytic results;
* :mod:`.coefficients` -- linearised stiffness and damping of one bearing, the rotor assembled from them, export to
  ROSS.
"""
