// Device buffers staged through the host: minkq_mpi reads every input on the host (it checks
// it and sends parts of it to other ranks), so a CUDA rank's device arrays are copied down
// first. Built with CUDA (MINKQ_MPI_CUDA), else device memory never gets here (a CPU device
// rejects it).
#pragma once

#include <cstddef>

namespace minkq::mpi {

// Copies `count` records of `size` bytes, `stride` apart on the device, to `host`, packed.
// Fails with MINKQ_ERROR_DEVICE naming the buffer.
void stage_from_device(void* host, size_t size, const void* device, size_t stride, size_t count, const char* name);

}  // namespace minkq::mpi
