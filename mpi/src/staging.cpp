#include "staging.h"

#include <string>

#include "collective.h"

#ifdef MINKQ_MPI_CUDA
#include <cuda_runtime_api.h>
#endif

namespace minkq::mpi {

void stage_from_device(void* host, size_t size, const void* device, size_t stride, size_t count, const char* name) {
#ifdef MINKQ_MPI_CUDA
  // cudaMemcpyDefault: the runtime tells device, managed and pinned memory apart (UVA).
  const cudaError_t e = cudaMemcpy2D(host, size, device, stride, size, count, cudaMemcpyDefault);
  if (e != cudaSuccess)
    fail(MINKQ_ERROR_DEVICE, std::string("copying ") + name + " from the device: " + cudaGetErrorString(e));
#else
  (void)host, (void)size, (void)device, (void)stride, (void)count;
  fail(MINKQ_ERROR_UNSUPPORTED, std::string(name) + " is device memory but minkq_mpi was built without CUDA");
#endif
}

}  // namespace minkq::mpi
