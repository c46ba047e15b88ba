"""Engine tests: the process settings come from tests/conftest.py (importing gfbjax); the analytic systems live
in cont_systems.py beside this file."""
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
