import os
import sys

import pytest

# The tests import their oracle (oracle.py); the demo's scene comes from the package (minkq.demo).
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import minkq  # noqa: E402


@pytest.fixture(scope="session")
def device():
    return minkq.Device("cpu")


@pytest.fixture(scope="session")
def wp():
    """Warp, initialised quietly (the tests that take it skip where it is not installed)."""
    warp = pytest.importorskip("warp")
    warp.config.quiet = True
    warp.init()
    return warp
