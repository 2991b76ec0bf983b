"""Runs pytest on the given test files; exit 77 (CTest's skip) when pytest or numpy
is missing on this machine."""
import sys

if __name__ == "__main__":  # Dask's worker processes start by importing this file again
    try:
        import numpy  # noqa: F401
        import pytest
    except ImportError as e:
        print("python tests skipped: %s (install python3-pytest and python3-numpy)" % e)
        sys.exit(77)
    # A test stuck for 5 minutes prints every thread's stack (then CTest's timeout ends it).
    sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", "-o", "faulthandler_timeout=300"] + sys.argv[1:]))
