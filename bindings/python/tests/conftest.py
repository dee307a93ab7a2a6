import os
import sys

import pytest

# The tests import their oracle (oracle.py) and the Python demo (examples/python/demo.py).
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "examples", "python"))

import minkq  # noqa: E402


@pytest.fixture(scope="session")
def device():
    return minkq.Device("cpu")
