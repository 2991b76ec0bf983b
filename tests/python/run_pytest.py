"""Runs the Python module's tests with pytest; exit 77 (CTest's skip) when pytest
or numpy is missing on this machine."""
import sys

try:
    import numpy  # noqa: F401
    import pytest
except ImportError as e:
    print("python tests skipped: %s (install python3-pytest and python3-numpy)" % e)
    sys.exit(77)

sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", sys.argv[1]]))
