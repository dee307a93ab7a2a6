// The CUDA runs of the job passes (jobs.h), compiled in translation units of their own
// (job_passes_*.cu, one per kind) so that nvcc compiles them beside backend.cu, in parallel: a job
// pass's kernel holds the self, cross and reversed walks of its kind, for each shape and work
// type. backend.cu sees them declared only (extern template); MINKQ_JOB_PASS_RUNS(kind, X) calls
// X(Work, Shape, Job) for each run the mesh store makes of that kind's jobs.
#pragma once

#include "cuda/passes.cuh"
#include "jobs.h"

// The shapes a kind's job passes take (store.h's with_shape): point kinds their point shapes and,
// swept, the segment shapes; EE the segment shapes.
#define MINKQ_JOB_PASS_VERTEX_SHAPES(X, Work, Job) \
  X(Work, BoxShape, Job) X(Work, SphereShape, Job) X(Work, CapsuleRayShape, Job) X(Work, CapsuleExactShape, Job)
#define MINKQ_JOB_PASS_SEGMENT_SHAPES(X, Work, Job) \
  X(Work, BoxShape, Job) X(Work, CapsuleRayShape, Job) X(Work, CapsuleExactShape, Job)
#define MINKQ_JOB_PASS_RUNS_OF(X, SHAPES, Job) SHAPES(X, NoWork, Job) SHAPES(X, WorkCounts, Job)
#define MINKQ_JOB_PASS_RUNS_VT(X) MINKQ_JOB_PASS_RUNS_OF(X, MINKQ_JOB_PASS_VERTEX_SHAPES, VertexTriangleJob)
#define MINKQ_JOB_PASS_RUNS_EV(X) MINKQ_JOB_PASS_RUNS_OF(X, MINKQ_JOB_PASS_VERTEX_SHAPES, VertexEdgeJob)
#define MINKQ_JOB_PASS_RUNS_VV(X) MINKQ_JOB_PASS_RUNS_OF(X, MINKQ_JOB_PASS_VERTEX_SHAPES, VertexVertexJob)
#define MINKQ_JOB_PASS_RUNS_EE(X) MINKQ_JOB_PASS_RUNS_OF(X, MINKQ_JOB_PASS_SEGMENT_SHAPES, EdgeEdgeJob)

// One run: cuda::run_passes of one job pass and, without work counts, its stream-ordered form
// run_passes_async, declared (extern) or defined (instantiated).
#define MINKQ_JOB_PASS_RUN_OF(prefix, Work, Shape, Job)                                              \
  prefix template std::array<uint64_t, 1> run_passes<Work, JobPass<Shape, Job>>(                     \
      QueryWorkspace&, const std::array<WorkCounts*, 1>&, const JobPass<Shape, Job>&);               \
  MINKQ_JOB_PASS_ASYNC_##Work(prefix, Shape, Job)
#define MINKQ_JOB_PASS_ASYNC_NoWork(prefix, Shape, Job) \
  prefix template void run_passes_async<NoWork, JobPass<Shape, Job>>(QueryWorkspace&, const JobPass<Shape, Job>&);
#define MINKQ_JOB_PASS_ASYNC_WorkCounts(prefix, Shape, Job)
#define MINKQ_JOB_PASS_RUN_SIGNATURE(Work, Shape, Job) MINKQ_JOB_PASS_RUN_OF(, Work, Shape, Job)
#define MINKQ_JOB_PASS_RUN_EXTERN(Work, Shape, Job) MINKQ_JOB_PASS_RUN_OF(extern, Work, Shape, Job)

namespace minkq::cuda {
MINKQ_JOB_PASS_RUNS_VT(MINKQ_JOB_PASS_RUN_EXTERN)
MINKQ_JOB_PASS_RUNS_EV(MINKQ_JOB_PASS_RUN_EXTERN)
MINKQ_JOB_PASS_RUNS_VV(MINKQ_JOB_PASS_RUN_EXTERN)
MINKQ_JOB_PASS_RUNS_EE(MINKQ_JOB_PASS_RUN_EXTERN)
}  // namespace minkq::cuda
