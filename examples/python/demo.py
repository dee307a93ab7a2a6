#!/usr/bin/env python3
"""The cloth broad phase of `minkq demo`, from Python: the package's own demo (minkq.demo, also
installed as `minkq-demo` and run by `python -m minkq`), called from here.

    python3 examples/python/demo.py [--backend cpu|cuda|auto] [--size N] [--radius-factor F]
"""

import sys

# Re-exported for the examples beside this file (newton_detector.py) that build its scene.
from minkq.demo import (  # noqa: F401
    DEFAULT_FACTOR,
    DEFAULT_SIZE,
    REFERENCE_CONTACTS,
    derive_edges,
    grid_sheet,
    main,
    mean_edge_length,
    twisted_sheet,
)

if __name__ == "__main__":
    sys.exit(main())
