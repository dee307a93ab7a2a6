// Stand-in for the CUDA backend where minkq is built without it.
#include "backend.h"

namespace minkq {

bool built_with_cuda() { return false; }
int cuda_device_count() { return 0; }
std::unique_ptr<Backend> make_cuda_backend(int) {
  fail(Status::kUnsupported, "minkq was built without the CUDA backend (no nvcc at configure time)");
}

}  // namespace minkq
