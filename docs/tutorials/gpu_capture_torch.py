"""Tutorial: the captured step with PyTorch tensors (torch.cuda.graph) instead of Warp arrays.
CUDA only: PyTorch captures graphs on the GPU alone.

Run as a script (docs/build.sh --check runs every tutorial; without PyTorch or a GPU it is
skipped, with the reason): exits non-zero if a check fails.
"""
# needs: torch cuda
import numpy as np

# ---- tutorial
import torch

import minkq
from minkq.demo import derive_edges, mean_edge_length, twisted_sheet

rest_np, triangles = twisted_sheet(32)
r = 0.25 * mean_edge_length(rest_np, derive_edges(triangles))
rest = torch.tensor(rest_np, device="cuda:0")
x = rest.clone()
phase = torch.zeros(1, device="cuda:0")
capacity = 4 * len(rest_np)
pairs = torch.zeros((capacity, 2), dtype=torch.int32, device="cuda:0")
count = torch.zeros(1, dtype=torch.int64, device="cuda:0")

scene = minkq.Scene(x, triangles)  # on x's GPU
scene.reserve(refit=True)


def step():
    phase.add_(0.1)
    x.copy_(rest)
    x[:, 2] += 0.03 * torch.sin(8.0 * rest[:, 0] + phase)
    scene.refit_async(x)                    # on torch's current stream: the capture stream
    scene.query_async(pairs, count, "vt", r, leaf_exact=True)


side = torch.cuda.Stream()                  # warm up outside the capture, as PyTorch asks
with torch.cuda.stream(side):
    step()
torch.cuda.current_stream().wait_stream(side)
graph = torch.cuda.CUDAGraph()
with torch.cuda.graph(graph):
    step()
for k in range(5):
    graph.replay()
    torch.cuda.synchronize()
    scene.async_status(torch.cuda.current_stream())  # raises if a refit met a NaN
    n = int(count.item())
    assert n <= capacity
    print(f"step {k}: {n} VT contacts")
    # ---- end
    fresh = minkq.Scene(x.cpu().numpy(), triangles)
    expected = fresh.query("vt", r, leaf_exact=True, canonical=True)
    got = pairs[:n].cpu().numpy()
    got = got[np.lexsort((got[:, 1], got[:, 0]))]
    assert np.array_equal(got, expected), f"step {k}: the captured step's pairs differ"
print("checked: every replayed step equals a fresh blocking query")
