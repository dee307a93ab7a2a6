"""Runs a Newton example through ``python -m minkq.newton.examples`` in this process and prints,
as the last line, a JSON summary of the minkq detectors it built (for test_newton_capture.py):

    python newton_example_probe.py <example_name> [example options]
"""

import json
import sys

import minkq.newton as mn
import minkq.newton.examples as runner

detectors = []
_init = mn.TriMeshCollisionDetector.__init__


def _tracking_init(self, *args, **kwargs):
    _init(self, *args, **kwargs)
    detectors.append(self)


mn.TriMeshCollisionDetector.__init__ = _tracking_init
status = runner.main(sys.argv[1:])
summary = []
for d in detectors:
    summary.append(
        dict(
            recorded=sum(1 for entry in mn._recorded.values() if entry[0]() is d),
            replayed_calls=d.replayed_calls,
            replay_failures=d.replay_failures,
            vt=int(d.vertex_colliding_triangles_count.numpy().sum()) if d.collision_info is not None else 0,
            ee=int(d.edge_colliding_edges_count.numpy().sum()) if d.collision_info is not None else 0,
        )
    )
print(json.dumps(dict(status=status, detectors=summary)))
