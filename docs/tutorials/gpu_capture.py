"""Tutorial: Warp arrays inside a captured step. The positions live in a Warp array, a Warp
kernel moves them, and the refit and the query are enqueued on the same stream, so that on a
GPU the whole step is one CUDA graph, replayed every step with no copy to the host. The same
calls run on the CPU (at once, on host memory), which is what runs where there is no GPU.

Run as a script (docs/build.sh --check runs every tutorial): exits non-zero if a check fails.
"""
# needs: warp
import numpy as np

# ---- tutorial
import warp as wp

import minkq
from minkq.demo import derive_edges, mean_edge_length, twisted_sheet

wp.config.quiet = True
wp.init()
on_gpu = minkq.cuda_device_count() > 0 and wp.is_cuda_available()
device = "cuda:0" if on_gpu else "cpu"


@wp.kernel
def advance(time: wp.array(dtype=float)):
    time[0] = time[0] + 0.1


@wp.kernel
def wave(rest: wp.array(dtype=wp.vec3), time: wp.array(dtype=float), x: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    p = rest[i]
    x[i] = p + wp.vec3(0.0, 0.0, 0.03 * wp.sin(8.0 * p[0] + time[0]))


rest_np, triangles = twisted_sheet(32)
r = 0.25 * mean_edge_length(rest_np, derive_edges(triangles))
rest = wp.array(rest_np, dtype=wp.vec3, device=device)
x = wp.clone(rest)
time = wp.zeros(1, dtype=float, device=device)
capacity = 4 * len(rest_np)
pairs = wp.zeros((capacity, 2), dtype=wp.int32, device=device)  # written on the device
count = wp.zeros(1, dtype=wp.uint64, device=device)            # the exact count, on the device

scene = minkq.Scene(x, triangles)  # on x's device
scene.reserve(refit=True)            # the refit's scratch, allocated now: none inside the graph


def step():
    wp.launch(advance, 1, inputs=[time], device=device)
    wp.launch(wave, len(rest_np), inputs=[rest, time, x], device=device)
    scene.refit_async(x)                                      # on Warp's current stream
    scene.query_async(pairs, count, "vt", r, leaf_exact=True)


if on_gpu:
    with wp.ScopedCapture(device) as capture:   # recorded once ...
        step()
for k in range(5):
    if on_gpu:
        wp.capture_launch(capture.graph)        # ... replayed each step
    else:
        step()                                  # CPU: the same calls run at once
    scene.async_status()                        # between steps: waits, raises on a NaN
    n = int(count.numpy()[0])
    assert n <= capacity, "grow pairs (and capture again) when the count exceeds the capacity"
    print(f"step {k}: {n} VT contacts on {device}")
    # ---- end
    # Check: the same contacts as a blocking query on a scene built afresh on the host.
    fresh = minkq.Scene(x.numpy(), triangles)
    expected = fresh.query("vt", r, leaf_exact=True, canonical=True)
    got = pairs.numpy()[:n]
    got = got[np.lexsort((got[:, 1], got[:, 0]))]
    assert np.array_equal(got, expected), f"step {k}: the captured step's pairs differ"
print("checked: every step equals a fresh blocking query" + ("" if on_gpu else
      "; SKIPPED the graph capture: no CUDA GPU (minkq.cuda_device_count() == 0), ran on the CPU"))
