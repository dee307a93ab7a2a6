"""``python -m minkq``: the demo (minkq.demo, also installed as ``minkq-demo``)."""

import sys

from .demo import main

sys.exit(main())
