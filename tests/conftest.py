"""Test-session set-up: gfbjax's process defaults (x64, XLA scheduler flag, single-threaded BLAS) before any
JAX computation.  Importing gfbjax sets them."""

import gfbjax  # noqa: F401
