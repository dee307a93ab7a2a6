// The VV job passes' CUDA runs (job_passes.cuh): compiled here, beside backend.cu.
#include "cuda/job_passes.cuh"

namespace minkq::cuda {
MINKQ_JOB_PASS_RUNS_VV(MINKQ_JOB_PASS_RUN_SIGNATURE)
}  // namespace minkq::cuda
