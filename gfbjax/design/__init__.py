"""Foil design: the cycle at one speed as a function of the bump foil (:mod:`.evaluate`), the optimisers (the
paper's pattern search and gradient methods, :mod:`.optimizers`), the optimum at one speed and the optimised
continuation in speed (:mod:`.schedule`), and maps of W_cb / W_cf over the foil properties (:mod:`.maps`)."""
